// The continuous model linearized at one point, within the modes in force there:
//   d(dx)/dt = A dx + B du,   dy = C dx + D du.
// A is the right-hand side's Jacobian (evaluate_jacobian, the one the implicit methods use); B, C and D
// are central differences of the right-hand side and of the outputs, which are cheap and smooth
// within a mode. Control design starts from these matrices (docs/linearization.md).
#pragma once

#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

// u: the FMU's Real inputs in value-reference order (voltages, base attitude, its rates and
// accelerations, point a's velocity and acceleration). y: the outputs a control loop uses (angles,
// rates, currents, backlash positions, shaft torques, payload angular velocity).
constexpr RealVariable kLinearFirstInput = vr_u_R1;
constexpr int kLinearInputCount = vr_base_a_a_3 - vr_u_R1 + 1;
constexpr RealVariable kLinearFirstOutput = vr_alpha;
constexpr int kLinearOutputCount = vr_los_omega_3 - vr_alpha + 1;
// The integrated states without the energy accumulators: at most the 12 of the full model and the two
// current amplifiers' integrators.
constexpr int kLinearMaxStates = kStateSize + kAmplifierIntegratorCount;

struct LinearModel {
    // The integrated states without the energy accumulators (they feed nothing back), each named by
    // the output variable that carries it.
    int state_count = 0;
    RealVariable state_variable[kLinearMaxStates] = {};
    // The input of each column of B and D: the FMU's Real inputs from u_R1 on, but a current-driven
    // motor's column is its current command i_R<j>_cmd instead of its voltage.
    RealVariable input_variable[kLinearInputCount] = {};
    // Row-major with the maximal sizes as leading dimensions; only state_count rows/columns are used.
    double A[kLinearMaxStates][kLinearMaxStates] = {};
    double B[kLinearMaxStates][kLinearInputCount] = {};
    double C[kLinearOutputCount][kLinearMaxStates] = {};
    double D[kLinearOutputCount][kLinearInputCount] = {};
    // In force at the point: the model holds until one of them switches. voltage_clamped also marks a
    // held voltage at or beyond +-U_L (the core's own mode covers ramps only).
    Modes modes;
};

// `inputs` as a step starting at `time` would hold them (voltage ramps are ignored: they last one
// step). `modes` must be those the hybrid system selects at (time, state, inputs).
void linearize(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
               const double* state, LinearModel& out);

}  // namespace gimbal
