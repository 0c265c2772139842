#include "gimbal/gimbal_model.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>

namespace gimbal {

BaseKinematics base_kinematics_at(const ModelParameters& params, const StepInputs& inputs, double time) {
    return evaluate_base_kinematics(inputs.base.advanced(time - inputs.step_start_time), params.multibody.gravity);
}

Vec4 other_torques(const Mat4& mass_matrix, const Vec4& applied_torque, const Modes& modes,
                   const ModelParameters& params) {
    Mat4 modified = mass_matrix;
    Vec4 rhs = applied_torque;
    for (int body = 0; body < 4; ++body) {
        const FrictionMode mode = modes.friction[body];
        if (low_speed(mode)) {
            modified.col(body) = Vec4::Unit(body);
        } else if (mode == FrictionMode::slip_positive) {
            rhs[body] -= params.dry_friction[body].slip_torque;
        } else if (mode == FrictionMode::slip_negative) {
            rhs[body] += params.dry_friction[body].slip_torque;
        }
    }
    // Column replacement keeps the matrix invertible (its determinant is that of J's free block).
    return modified.partialPivLu().solve(rhs);
}

void evaluate_dynamics(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                       const double* state, const Modes& modes, Dynamics& out) {
    const Eigen::Map<const Vec4> q(state + kAngles);
    const Eigen::Map<const Vec4> qd(state + kRates);

    Mat4 mass_matrix;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, mass_matrix, out.bias);

    for (int body = 0; body < 4; ++body) out.generalized_force[body] = -params.viscous_friction[body] * qd[body];
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double deflection = gear_deflection(gear, q[rotor], q[load]);
        const double deflection_rate = gear_deflection(gear, qd[rotor], qd[load]);
        const double backlash = state[kBacklash + axis];
        const int contact = modes.gear_contact[axis];
        out.deflection[axis] = deflection;
        out.deflection_rate[axis] = deflection_rate;

        double shaft_torque, backlash_rate = 0.0;
        if (gear.half_backlash == 0.0) {
            shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, 0.0, 0.0);
            out.free_backlash_rate[axis] = 0.0;
        } else if (dead_zone_gear(gear)) {
            // theta_b = clamp(theta_d, -eta, eta): it moves with theta_d inside the gap.
            out.free_backlash_rate[axis] = deflection_rate;
            if (contact == 0) {
                shaft_torque = 0.0;
                backlash_rate = deflection_rate;
            } else {
                shaft_torque = gear.stiffness * (deflection - contact * gear.half_backlash);
            }
        } else {
            const double x = free_backlash_rate(gear, deflection, deflection_rate, backlash);
            out.free_backlash_rate[axis] = x;
            if (contact == 0) {
                shaft_torque = 0.0;  // (2.77) with dtheta_b = X cancels exactly: write the exact zero
                backlash_rate = x;
            } else {
                shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, backlash, 0.0);
            }
        }
        out.shaft_torque[axis] = shaft_torque;
        out.backlash_rate[axis] = backlash_rate;

        const double current = state[kCurrents + axis];
        const double voltage = inputs.voltage[axis];
        out.steady_current[axis] = unlimited_steady_current(motor, voltage, qd[rotor]);
        const int limited = modes.motor_limited[axis];
        const double held_current = limited == 0 ? current : limited * motor.current_limit;
        out.current_rate[axis] = limited == 0 ? armature_current_rate(motor, voltage, current, qd[rotor]) : 0.0;
        out.generalized_force[load] += shaft_torque;
        out.generalized_force[rotor] += electromagnetic_torque(motor, held_current) - shaft_torque / gear.ratio;
    }

    const Vec4 applied = out.generalized_force + out.bias;
    bool any_low_speed = false;
    for (int body = 0; body < 4; ++body) any_low_speed = any_low_speed || low_speed(modes.friction[body]);
    out.other_torque = any_low_speed ? other_torques(mass_matrix, applied, modes, params) : Vec4::Zero();
    for (int body = 0; body < 4; ++body) {
        const DryFrictionParameters& friction = params.dry_friction[body];
        double torque = 0.0;
        switch (modes.friction[body]) {
            case FrictionMode::none: break;
            case FrictionMode::slip_positive: torque = -friction.slip_torque; break;
            case FrictionMode::slip_negative: torque = friction.slip_torque; break;
            case FrictionMode::hold: torque = -out.other_torque[body] - friction.numerical_damping() * qd[body]; break;
            case FrictionMode::at_max_positive: torque = friction.breakaway_torque; break;
            case FrictionMode::at_max_negative: torque = -friction.breakaway_torque; break;
        }
        out.friction_torque[body] = torque;
    }
    out.acceleration = mass_matrix.llt().solve(applied + out.friction_torque);
}

bool evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                               double time, const double* state, double* derivative) {
    Dynamics d;
    evaluate_dynamics(params, inputs, base_kinematics_at(params, inputs, time), state, modes, d);
    for (int k = 0; k < 4; ++k) {
        derivative[kAngles + k] = state[kRates + k];
        derivative[kRates + k] = d.acceleration[k];
    }
    for (int axis = 0; axis < 2; ++axis) {
        derivative[kCurrents + axis] = d.current_rate[axis];
        derivative[kBacklash + axis] = d.backlash_rate[axis];
    }
    if (params.energy_accounting) {
        double* flow = derivative + kEnergyFlows;
        for (int k = 0; k < kEnergyFlowCount; ++k) flow[k] = 0.0;
        for (int axis = 0; axis < 2; ++axis) {
            const MotorParameters& motor = params.motor[axis];
            const int limited = modes.motor_limited[axis];
            const double current = limited == 0 ? state[kCurrents + axis] : limited * motor.current_limit;
            const double rotor_speed = state[kRates + rotor_index(axis)];
            // Terminal voltage: what the circuit takes, which differs from u while the limiter holds i.
            const double terminal_voltage = motor.resistance * current + motor.inductance * d.current_rate[axis] +
                                            motor.back_emf_constant * rotor_speed;
            flow[kElectricalIn] += terminal_voltage * current;
            flow[kResistive] += motor.resistance * current * current;
            const double slip = d.deflection_rate[axis] - d.backlash_rate[axis];
            flow[kShaftDamping] += params.gear[axis].damping * slip * slip;
        }
        for (int body = 0; body < 4; ++body) {
            const double rate = state[kRates + body];
            flow[kViscous] += params.viscous_friction[body] * rate * rate;
            flow[kDryFriction] -= d.friction_torque[body] * rate;
        }
    }
    for (int k = 0; k < params.state_size(); ++k)
        if (!std::isfinite(derivative[k])) return false;
    return true;
}

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                              double time, const double* state) {
    const BaseMotion base_motion = inputs.base.advanced(time - inputs.step_start_time);
    const BaseKinematics base = evaluate_base_kinematics(base_motion, params.multibody.gravity);
    const Eigen::Map<const Vec4> q(state + kAngles);
    const Eigen::Map<const Vec4> qd(state + kRates);
    Dynamics d;
    evaluate_dynamics(params, inputs, base, state, modes, d);

    ModelOutputs out;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        out.shaft_torque[axis] = d.shaft_torque[axis];
        const double stretch = d.deflection[axis] - state[kBacklash + axis];
        out.spring_energy += 0.5 * gear.stiffness * stretch * stretch;
        const int limited = modes.motor_limited[axis];
        const double current = limited == 0 ? state[kCurrents + axis] : limited * motor.current_limit;
        out.magnetic_energy += 0.5 * motor.inductance * current * current;
    }
    out.payload_angular_velocity = payload_angular_velocity(base, q, qd);
    const MultibodyEnergy energy = compute_energy(params.multibody, base, base_motion.velocity_a, q, qd);
    out.kinetic_energy = energy.kinetic;
    out.potential_energy = energy.potential;
    return out;
}

}  // namespace gimbal
