// The dynamics of the gimbal within a mode, assembled from the multibody terms (multibody/) and one
// pass per switching element (switching_elements/: each element's force and Jacobian contributions),
// and the outputs derived from them.
#pragma once

#include "gimbal/model/model_types.hpp"
#include "gimbal/switching_elements/amplifier_saturation.hpp"
#include "gimbal/switching_elements/axis_stop.hpp"
#include "gimbal/switching_elements/current_limiter.hpp"
#include "gimbal/switching_elements/dry_friction.hpp"
#include "gimbal/switching_elements/gear_backlash.hpp"
#include "gimbal/switching_elements/voltage_clamp.hpp"

namespace gimbal {

// q_full = coordinate_reduction * q_padded: a rigid axis's rotor follows its load (N times its angle).
Mat4 coordinate_reduction(const ModelParameters& params);

FullState expand_state(const ModelParameters& params, const Modes& modes, const StepInputs& inputs, double time,
                       const double* state);

void evaluate_dynamics(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                       double time, const double* state, const Modes& modes, Dynamics& out);

// d(dx/dt)/dx at the point where `dynamics` was evaluated, column-major. Analytic for the drive train,
// the backlash, the motor circuits and the friction modes (everything that makes the system stiff);
// the slowly varying rigid-body terms (gravity, carrier motion, gyroscopic forces, the configuration
// dependence of J) by forward differences of J and f. The rows of the energy accumulators are left at 0:
// they integrate flows and feed nothing back.
void evaluate_jacobian(const ModelParameters& params, const Modes& modes, const BaseKinematics& base,
                       const Dynamics& dynamics, double* column_major);

BaseKinematics base_kinematics_at(const ModelParameters& params, const StepInputs& inputs, double time);

// dx/dt within the current modes, from the dynamics evaluated at (t, x); false if it is not finite.
bool state_derivative(const ModelParameters& params, const Dynamics& dynamics, double* derivative);

// The same from scratch.
bool evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                               const BaseKinematics& base, double time, const double* state, double* derivative);

// Quantities derived from the state for outputs and diagnostics.
struct ModelOutputs {
    FullState full;
    double shaft_torque[2] = {0, 0};
    Vec3 payload_angular_velocity = Vec3::Zero();
    double kinetic_energy = 0.0;
    double potential_energy = 0.0;
    double spring_energy = 0.0;
    double magnetic_energy = 0.0;
    double cable_energy = 0.0;    // the cable restraints' springs
    double cogging_energy = 0.0;  // the motors' cogging potentials, 0 at a detent
};

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                              double time, const double* state);
// The same from the dynamics already evaluated at (time, state) with `base` = the kinematics there.
ModelOutputs outputs_from(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                          double time, const Dynamics& dynamics);

}  // namespace gimbal
