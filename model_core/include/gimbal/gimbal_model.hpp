// The constant model (parameters) and the continuous dynamics of the 12-state gimbal.
#pragma once

#include <string>

#include "gimbal/drive_train.hpp"
#include "gimbal/rigid_body.hpp"

namespace gimbal {

// Layout of the state vector (MODEL.md section 4).
enum StateIndex : int {
    kAngles = 0,      // alpha, alpha_m, beta, beta_m
    kRates = 4,       // their time derivatives
    kCurrents = 8,    // i_R1, i_R2
    kBacklash = 10,   // theta_b1, theta_b2
    kStateSize = 12
};

using StateVector = Eigen::Matrix<double, kStateSize, 1>;

struct ModelParameters {
    MultibodyModel multibody;
    MotorParameters motor[2];
    GearParameters gear[2];
    double viscous_friction[4] = {0, 0, 0, 0};  // per body, q order
    double relative_tolerance = 1e-6;
    double absolute_tolerance = 1e-8;
};

// Inputs held over one communication step.
struct StepInputs {
    double voltage[2] = {0, 0};  // already clamped to +-U_L
    BaseMotion base;             // at the step start
    double step_start_time = 0.0;
};

// Quantities derived from the state for outputs and diagnostics.
struct ModelOutputs {
    double shaft_torque[2] = {0, 0};
    Vec3 payload_angular_velocity = Vec3::Zero();
    double kinetic_energy = 0.0;
    double potential_energy = 0.0;
    double spring_energy = 0.0;
};

// Rotor coordinate of axis j in q order (alpha_m, beta_m) and its load coordinate (alpha, beta).
constexpr int rotor_index(int axis) { return axis == 0 ? 1 : 3; }
constexpr int load_index(int axis) { return axis == 0 ? 0 : 2; }

void evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, double time,
                               const StateVector& state, StateVector& derivative);

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, double time,
                              const StateVector& state);

}  // namespace gimbal
