#include "gimbal/gimbal_model.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>

namespace gimbal {

StateLayout StateLayout::from(const Fidelity& fidelity, bool energy_accounting) {
    StateLayout layout;
    int coordinates = 0;
    for (int body = 0; body < 4; ++body) {
        const bool rigid_rotor = (body == rotor_index(0) && fidelity.gear[0] == GearModel::rigid) ||
                                 (body == rotor_index(1) && fidelity.gear[1] == GearModel::rigid);
        layout.angle_slot[body] = rigid_rotor ? -1 : coordinates++;
    }
    for (int body = 0; body < 4; ++body)
        layout.rate_slot[body] = layout.angle_slot[body] < 0 ? -1 : coordinates + layout.angle_slot[body];
    int slot = 2 * coordinates;
    for (int axis = 0; axis < 2; ++axis)
        layout.current_slot[axis] = fidelity.motor[axis] == MotorModel::inductive ? slot++ : -1;
    for (int axis = 0; axis < 2; ++axis)
        layout.backlash_slot[axis] = fidelity.gear[axis] == GearModel::backlash ? slot++ : -1;
    layout.energy_slot = energy_accounting ? slot : -1;
    layout.size = slot + (energy_accounting ? kEnergyFlowCount : 0);
    return layout;
}

void ModelParameters::finalize() {
    layout = StateLayout::from(fidelity, energy_accounting);
    for (int body = 0; body < 4; ++body)
        coordinate_friction[body] = fidelity.dry_friction ? dry_friction[body] : DryFrictionParameters{};
    for (int axis = 0; axis < 2; ++axis) {
        rotor_friction_share[axis] = 0.0;
        if (fidelity.gear[axis] != GearModel::rigid || !fidelity.dry_friction) continue;
        // MODEL.md section 5: a rigid axis has no unique static split of friction between rotor and
        // load; one element on the load axis carries both, the rotor's reflected through N.
        const double ratio = std::fabs(gear[axis].ratio);
        const DryFrictionParameters& load = dry_friction[load_index(axis)];
        const DryFrictionParameters& rotor = dry_friction[rotor_index(axis)];
        DryFrictionParameters merged;
        merged.slip_torque = load.slip_torque + ratio * rotor.slip_torque;
        merged.breakaway_torque = load.breakaway_torque + ratio * rotor.breakaway_torque;
        merged.stick_speed = load.present() ? load.stick_speed : rotor.stick_speed / ratio;
        merged.damping_factor = load.present() ? load.damping_factor : rotor.damping_factor;
        coordinate_friction[load_index(axis)] = merged;
        coordinate_friction[rotor_index(axis)] = DryFrictionParameters{};
        if (merged.present()) rotor_friction_share[axis] = ratio * rotor.breakaway_torque / merged.breakaway_torque;
    }
}

BaseKinematics base_kinematics_at(const ModelParameters& params, const StepInputs& inputs, double time) {
    if (params.fidelity.fixed_base) return evaluate_base_kinematics(BaseMotion{}, params.multibody.gravity);
    return evaluate_base_kinematics(inputs.base.advanced(time - inputs.step_start_time), params.multibody.gravity);
}

Vec4 other_torques(const Mat4& mass_matrix, const Vec4& applied_torque, const Modes& modes,
                   const DryFrictionParameters (&friction)[4]) {
    Mat4 modified = mass_matrix;
    Vec4 rhs = applied_torque;
    for (int k = 0; k < 4; ++k) {
        const FrictionMode mode = modes.friction[k];
        if (low_speed(mode)) {
            modified.col(k) = Vec4::Unit(k);
        } else if (mode == FrictionMode::slip_positive) {
            rhs[k] -= friction[k].slip_torque;
        } else if (mode == FrictionMode::slip_negative) {
            rhs[k] += friction[k].slip_torque;
        }
    }
    // Column replacement keeps the matrix invertible (its determinant is that of J's free block).
    return modified.partialPivLu().solve(rhs);
}

FullState expand_state(const ModelParameters& params, const Modes& modes, const StepInputs& inputs,
                       const double* state) {
    const StateLayout& layout = params.layout;
    FullState full;
    for (int body = 0; body < 4; ++body) {
        if (layout.independent(body)) {
            full.angle[body] = state[layout.angle_slot[body]];
            full.rate[body] = state[layout.rate_slot[body]];
        }
    }
    for (int axis = 0; axis < 2; ++axis) {
        const int rotor = rotor_index(axis), load = load_index(axis);
        if (!layout.independent(rotor)) {
            full.angle[rotor] = params.gear[axis].ratio * full.angle[load];
            full.rate[rotor] = params.gear[axis].ratio * full.rate[load];
        }
        const MotorParameters& motor = params.motor[axis];
        const int limited = modes.motor_limited[axis];
        if (limited != 0) {
            full.current[axis] = limited * motor.current_limit;
        } else if (layout.current_slot[axis] >= 0) {
            full.current[axis] = state[layout.current_slot[axis]];
        } else {
            full.current[axis] = unlimited_steady_current(motor, inputs.voltage[axis], full.rate[rotor]);
        }
        full.backlash[axis] = layout.backlash_slot[axis] >= 0 ? state[layout.backlash_slot[axis]] : 0.0;
    }
    return full;
}

void evaluate_dynamics(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                       const double* state, const Modes& modes, Dynamics& out) {
    const StateLayout& layout = params.layout;
    out.full = expand_state(params, modes, inputs, state);
    const Vec4& q = out.full.angle;
    const Vec4& qd = out.full.rate;

    Mat4 mass_matrix;
    Vec4 bias;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, mass_matrix, bias);

    Vec4 force;  // generalized forces on the four bodies, without dry friction
    for (int body = 0; body < 4; ++body) force[body] = -params.viscous_friction[body] * qd[body];
    // q_full = reduction * q_padded: a rigid axis's rotor follows its load.
    Mat4 reduction = Mat4::Identity();
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        const int rotor = rotor_index(axis), load = load_index(axis);
        const GearModel model = params.fidelity.gear[axis];
        const double deflection = model == GearModel::rigid ? 0.0 : gear_deflection(gear, q[rotor], q[load]);
        const double deflection_rate = model == GearModel::rigid ? 0.0 : gear_deflection(gear, qd[rotor], qd[load]);
        const double backlash = out.full.backlash[axis];
        const int contact = modes.gear_contact[axis];
        out.deflection[axis] = deflection;
        out.deflection_rate[axis] = deflection_rate;
        out.free_backlash_rate[axis] = 0.0;

        double shaft_torque = 0.0, backlash_rate = 0.0;
        if (model == GearModel::rigid) {
            reduction(rotor, rotor) = 0.0;
            reduction(rotor, load) = gear.ratio;
        } else if (model == GearModel::compliant || gear.half_backlash == 0.0) {
            shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, 0.0, 0.0);
        } else if (dead_zone_gear(gear)) {
            // theta_b = clamp(theta_d, -eta, eta): it moves with theta_d inside the gap.
            out.free_backlash_rate[axis] = deflection_rate;
            if (contact == 0) {
                backlash_rate = deflection_rate;
            } else {
                shaft_torque = gear.stiffness * (deflection - contact * gear.half_backlash);
            }
        } else {
            const double x = free_backlash_rate(gear, deflection, deflection_rate, backlash);
            out.free_backlash_rate[axis] = x;
            if (contact == 0) {
                backlash_rate = x;  // and T_E = 0 exactly: (2.77) with dtheta_b = X cancels
            } else {
                shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, backlash, 0.0);
            }
        }
        out.shaft_torque[axis] = shaft_torque;
        out.backlash_rate[axis] = backlash_rate;

        const double voltage = inputs.voltage[axis];
        out.steady_current[axis] = unlimited_steady_current(motor, voltage, qd[rotor]);
        out.current_rate[axis] = 0.0;
        if (layout.current_slot[axis] >= 0 && modes.motor_limited[axis] == 0)
            out.current_rate[axis] = armature_current_rate(motor, voltage, out.full.current[axis], qd[rotor]);
        force[load] += shaft_torque;
        force[rotor] += electromagnetic_torque(motor, out.full.current[axis]) - shaft_torque / gear.ratio;
    }

    Mat4 reduced_mass = reduction.transpose() * mass_matrix * reduction;
    for (int body = 0; body < 4; ++body)
        if (!layout.independent(body)) reduced_mass(body, body) = 1.0;  // padding: a trivial equation
    const Vec4 applied = reduction.transpose() * (force + bias);

    bool any_low_speed = false;
    for (int k = 0; k < 4; ++k) any_low_speed = any_low_speed || low_speed(modes.friction[k]);
    out.other_torque =
        any_low_speed ? other_torques(reduced_mass, applied, modes, params.coordinate_friction) : Vec4::Zero();
    for (int k = 0; k < 4; ++k) {
        const DryFrictionParameters& friction = params.coordinate_friction[k];
        double torque = 0.0;
        switch (modes.friction[k]) {
            case FrictionMode::none: break;
            case FrictionMode::slip_positive: torque = -friction.slip_torque; break;
            case FrictionMode::slip_negative: torque = friction.slip_torque; break;
            case FrictionMode::hold: torque = -out.other_torque[k] - friction.numerical_damping() * qd[k]; break;
            case FrictionMode::at_max_positive: torque = friction.breakaway_torque; break;
            case FrictionMode::at_max_negative: torque = -friction.breakaway_torque; break;
        }
        out.friction_torque[k] = torque;
    }
    out.acceleration = reduced_mass.llt().solve(applied + out.friction_torque);
    out.full_acceleration = reduction * out.acceleration;

    // A rigid gear still transmits a torque: the one that makes the rotor follow, from its own equation.
    for (int axis = 0; axis < 2; ++axis) {
        if (params.fidelity.gear[axis] != GearModel::rigid) continue;
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double ratio = params.gear[axis].ratio;
        const double rotor_friction = params.rotor_friction_share[axis] * out.friction_torque[load] / ratio;
        const double inertial = mass_matrix.row(rotor).dot(out.full_acceleration);
        out.shaft_torque[axis] = ratio * (force[rotor] + bias[rotor] + rotor_friction - inertial);
    }
}

bool evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                               double time, const double* state, double* derivative) {
    const StateLayout& layout = params.layout;
    Dynamics d;
    evaluate_dynamics(params, inputs, base_kinematics_at(params, inputs, time), state, modes, d);
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        derivative[layout.angle_slot[body]] = d.full.rate[body];
        derivative[layout.rate_slot[body]] = d.acceleration[body];
    }
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) derivative[layout.current_slot[axis]] = d.current_rate[axis];
        if (layout.backlash_slot[axis] >= 0) derivative[layout.backlash_slot[axis]] = d.backlash_rate[axis];
    }
    if (layout.energy_slot >= 0) {
        double* flow = derivative + layout.energy_slot;
        for (int k = 0; k < kEnergyFlowCount; ++k) flow[k] = 0.0;
        for (int axis = 0; axis < 2; ++axis) {
            const MotorParameters& motor = params.motor[axis];
            const double current = d.full.current[axis];
            // Terminal voltage: what the circuit takes, which differs from u while the limiter holds i.
            const double terminal_voltage = motor.resistance * current + motor.inductance * d.current_rate[axis] +
                                            motor.back_emf_constant * d.full.rate[rotor_index(axis)];
            flow[kElectricalIn] += terminal_voltage * current;
            flow[kResistive] += motor.resistance * current * current;
            const double slip = d.deflection_rate[axis] - d.backlash_rate[axis];
            flow[kShaftDamping] += params.gear[axis].damping * slip * slip;
        }
        for (int body = 0; body < 4; ++body) {
            const double rate = d.full.rate[body];
            flow[kViscous] += params.viscous_friction[body] * rate * rate;
            flow[kDryFriction] -= d.friction_torque[body] * rate;
        }
    }
    for (int k = 0; k < layout.size; ++k)
        if (!std::isfinite(derivative[k])) return false;
    return true;
}

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                              double time, const double* state) {
    const BaseMotion base_motion = params.fidelity.fixed_base
                                       ? BaseMotion{}
                                       : inputs.base.advanced(time - inputs.step_start_time);
    const BaseKinematics base = evaluate_base_kinematics(base_motion, params.multibody.gravity);
    Dynamics d;
    evaluate_dynamics(params, inputs, base, state, modes, d);

    ModelOutputs out;
    out.full = d.full;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        out.shaft_torque[axis] = d.shaft_torque[axis];
        if (params.fidelity.gear[axis] != GearModel::rigid) {
            const double stretch = d.deflection[axis] - d.full.backlash[axis];
            out.spring_energy += 0.5 * gear.stiffness * stretch * stretch;
        }
        if (params.layout.current_slot[axis] >= 0)
            out.magnetic_energy += 0.5 * params.motor[axis].inductance * d.full.current[axis] * d.full.current[axis];
    }
    out.payload_angular_velocity = payload_angular_velocity(base, d.full.angle, d.full.rate);
    const MultibodyEnergy energy = compute_energy(params.multibody, base, base_motion.velocity_a, d.full.angle, d.full.rate);
    out.kinetic_energy = energy.kinetic;
    out.potential_energy = energy.potential;
    return out;
}

}  // namespace gimbal
