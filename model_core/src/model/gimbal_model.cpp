#include "gimbal/model/gimbal_model.hpp"

#include <Eigen/LU>

#include <cmath>
#include <limits>

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
    layout.canonical = slot == kStateSize;
    return layout;
}

void ModelParameters::finalize() {
    layout = StateLayout::from(fidelity, energy_accounting);
    for (int body = 0; body < 4; ++body)
        coordinate_friction[body] = fidelity.dry_friction ? dry_friction[body] : DryFrictionParameters{};
    for (int axis = 0; axis < 2; ++axis) {
        rotor_friction_share[axis] = 0.0;
        if (fidelity.gear[axis] != GearModel::rigid || !fidelity.dry_friction) continue;
        // docs/physics.md section 6 (rigid gear): a rigid axis has no unique static split of friction between rotor and
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

Mat4 coordinate_reduction(const ModelParameters& params) {
    Mat4 reduction = Mat4::Identity();
    for (int axis = 0; axis < 2; ++axis) {
        if (params.fidelity.gear[axis] != GearModel::rigid) continue;
        reduction(rotor_index(axis), rotor_index(axis)) = 0.0;
        reduction(rotor_index(axis), load_index(axis)) = params.gear[axis].ratio;
    }
    return reduction;
}

double applied_voltage(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, int axis,
                       double time) {
    if (inputs.voltage_rate[axis] == 0.0) return inputs.voltage[axis];
    if (modes.voltage_clamped[axis] != 0) return modes.voltage_clamped[axis] * params.motor[axis].voltage_limit;
    return ramped_voltage(inputs, axis, time);
}

FullState expand_state(const ModelParameters& params, const Modes& modes, const StepInputs& inputs, double time,
                       const double* state) {
    const StateLayout& layout = params.layout;
    FullState full;
    if (layout.canonical) {
        for (int body = 0; body < 4; ++body) {
            full.angle[body] = state[kAngles + body];
            full.rate[body] = state[kRates + body];
        }
        for (int axis = 0; axis < 2; ++axis) {
            const int limited = modes.motor_limited[axis];
            full.current[axis] = limited != 0 ? limited * params.motor[axis].current_limit : state[kCurrents + axis];
            full.backlash[axis] = state[kBacklash + axis];
        }
        return full;
    }
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
            full.current[axis] =
                unlimited_steady_current(motor, applied_voltage(params, inputs, modes, axis, time), full.rate[rotor]);
        }
        full.backlash[axis] = layout.backlash_slot[axis] >= 0 ? state[layout.backlash_slot[axis]] : 0.0;
    }
    return full;
}

void evaluate_dynamics(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                       double time, const double* state, const Modes& modes, Dynamics& out) {
    const StateLayout& layout = params.layout;
    out.full = expand_state(params, modes, inputs, time, state);
    const Vec4& q = out.full.angle;
    const Vec4& qd = out.full.rate;

    // Assembled in place: the reduced model's padding below changes it, keeping J itself only then.
    Mat4& reduced_mass = out.reduced_mass;
    Vec4 bias;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, reduced_mass, bias);

    Vec4 force;  // generalized forces on the four bodies, without dry friction
    for (int body = 0; body < 4; ++body) force[body] = -params.viscous_friction[body] * qd[body];
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
            // No shaft state: the rotor follows the load (coordinate_reduction).
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

        const double voltage = applied_voltage(params, inputs, modes, axis, time);
        out.voltage[axis] = voltage;
        out.steady_current[axis] = unlimited_steady_current(motor, voltage, qd[rotor]);
        out.current_rate[axis] = 0.0;
        if (layout.current_slot[axis] >= 0 && modes.motor_limited[axis] == 0)
            out.current_rate[axis] = armature_current_rate(motor, voltage, out.full.current[axis], qd[rotor]);
        force[load] += shaft_torque;
        force[rotor] += electromagnetic_torque(motor, out.full.current[axis]) - shaft_torque / gear.ratio;
    }

    const bool reduced = params.fidelity.gear[0] == GearModel::rigid || params.fidelity.gear[1] == GearModel::rigid;
    Mat4 mass_matrix;
    if (reduced) mass_matrix = reduced_mass;
    Vec4 applied = force + bias;
    // T^T J T and T^T (force + bias) for each rigid axis, written out: T only adds N times the rotor's
    // row and column to the load's, and the rotor's become the padding identity (a trivial equation).
    for (int axis = 0; axis < 2 && reduced; ++axis) {
        if (params.fidelity.gear[axis] != GearModel::rigid) continue;
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double ratio = params.gear[axis].ratio;
        const double rotor_inertia = reduced_mass(rotor, rotor), cross = reduced_mass(load, rotor);
        for (int k = 0; k < 4; ++k) {
            if (k == rotor || k == load) continue;
            reduced_mass(load, k) += ratio * reduced_mass(rotor, k);
            reduced_mass(k, load) = reduced_mass(load, k);
        }
        reduced_mass(load, load) += 2.0 * ratio * cross + ratio * ratio * rotor_inertia;
        for (int k = 0; k < 4; ++k) reduced_mass(rotor, k) = reduced_mass(k, rotor) = 0.0;
        reduced_mass(rotor, rotor) = 1.0;
        applied[load] += ratio * applied[rotor];
        applied[rotor] = 0.0;
    }

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
    // A rigid gear keeps J's arrow pattern: its rotor's row and column become the padding identity, and
    // the load's gain only the reflected inertia N^2 J_rotor on the diagonal.
    out.acceleration = solve_mass_matrix(reduced_mass, Vec4(applied + out.friction_torque));
    out.full_acceleration = out.acceleration;
    for (int axis = 0; axis < 2 && reduced; ++axis)
        if (params.fidelity.gear[axis] == GearModel::rigid)
            out.full_acceleration[rotor_index(axis)] = params.gear[axis].ratio * out.acceleration[load_index(axis)];

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

void evaluate_jacobian(const ModelParameters& params, const Modes& modes, const BaseKinematics& base,
                       const Dynamics& d, double* column_major) {
    using Mat4x12 = Eigen::Matrix<double, 4, 12>;
    const StateLayout& layout = params.layout;
    const int n = layout.size;

    // Derivatives of the full generalized forces: columns q (0-3), qd (4-7), currents (8-9), theta_b (10-11).
    Mat4x12 force = Mat4x12::Zero();
    for (int body = 0; body < 4; ++body) force(body, 4 + body) -= params.viscous_friction[body];
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        const int rotor = rotor_index(axis), load = load_index(axis);
        const GearModel model = params.fidelity.gear[axis];
        const int contact = modes.gear_contact[axis];
        double stiffness = 0.0, damping = 0.0, backlash = 0.0;  // d T_E / d(theta_d, dtheta_d, theta_b)
        if (model == GearModel::compliant || (model == GearModel::backlash && gear.half_backlash == 0.0)) {
            stiffness = gear.stiffness, damping = gear.damping;
        } else if (model == GearModel::backlash && contact != 0) {
            stiffness = gear.stiffness;
            damping = dead_zone_gear(gear) ? 0.0 : gear.damping;
            backlash = dead_zone_gear(gear) ? 0.0 : -gear.stiffness;
        }
        Eigen::Matrix<double, 1, 12> torque = Eigen::Matrix<double, 1, 12>::Zero();
        torque(rotor) = stiffness / gear.ratio;
        torque(load) = -stiffness;
        torque(4 + rotor) = damping / gear.ratio;
        torque(4 + load) = -damping;
        torque(10 + axis) = backlash;
        force.row(load) += torque;
        force.row(rotor) -= torque / gear.ratio;
        if (modes.motor_limited[axis] == 0) {
            if (layout.current_slot[axis] >= 0) {
                force(rotor, 8 + axis) += motor.torque_constant;
            } else {
                force(rotor, 4 + rotor) -= motor.torque_constant * motor.back_emf_constant / motor.resistance;
            }
        }
    }
    // The rigid-body terms, which vary slowly with the configuration and the rates (gravity, carrier
    // motion, gyroscopic and centripetal forces, the mass matrix's dependence on the angles), by forward
    // differences of J(q) and f(q, qd): a Rosenbrock method keeps its order only with the whole Jacobian.
    Mat4 inertia_derivative[4];  // dJ/dq_j, full coordinates
    {
        const Vec4& q = d.full.angle;
        const Vec4& qd = d.full.rate;
        Mat4 mass_matrix, perturbed_mass;
        Vec4 bias, perturbed_bias;
        compute_mass_matrix_and_bias(params.multibody, base, q, qd, mass_matrix, bias);
        const double root_epsilon = std::sqrt(std::numeric_limits<double>::epsilon());
        for (int j = 0; j < 4; ++j) {
            Vec4 shifted = q;
            inertia_derivative[j].setZero();
            if (depends_on_angle(params.multibody, j)) {
                const double step = root_epsilon * std::max(1.0, std::fabs(q[j]));
                shifted[j] += step;
                compute_mass_matrix_and_bias(params.multibody, base, shifted, qd, perturbed_mass, perturbed_bias);
                inertia_derivative[j] = (perturbed_mass - mass_matrix) / step;
                force.col(j) += (perturbed_bias - bias) / step;
            }
            shifted = qd;
            const double rate_step = root_epsilon * std::max(1.0, std::fabs(qd[j]));
            shifted[j] += rate_step;
            compute_mass_matrix_and_bias(params.multibody, base, q, shifted, perturbed_mass, perturbed_bias);
            force.col(4 + j) += (perturbed_bias - bias) / rate_step;
        }
    }

    // To padded coordinates: q_full = T q_padded, forces projected with T^T.
    const Mat4 T = coordinate_reduction(params);
    Mat4x12 applied;
    applied.block<4, 4>(0, 0) = T.transpose() * force.block<4, 4>(0, 0) * T;
    applied.block<4, 4>(0, 4) = T.transpose() * force.block<4, 4>(0, 4) * T;
    applied.block<4, 4>(0, 8) = T.transpose() * force.block<4, 4>(0, 8);
    // d(T^T J T)/dq_padded,k = sum_j T(j, k) T^T dJ/dq_j T.
    Mat4 padded_inertia_derivative[4];
    for (int k = 0; k < 4; ++k) {
        Mat4 full = Mat4::Zero();
        for (int j = 0; j < 4; ++j)
            if (T(j, k) != 0.0) full += T(j, k) * inertia_derivative[j];
        padded_inertia_derivative[k] = T.transpose() * full * T;
    }

    // A held coordinate's friction cancels the other torques (2.101), which depend on the state too.
    Mat4x12 friction = Mat4x12::Zero();
    bool any_hold = false;
    for (int k = 0; k < 4; ++k) any_hold = any_hold || modes.friction[k] == FrictionMode::hold;
    if (any_hold) {
        Mat4 modified = d.reduced_mass;
        for (int k = 0; k < 4; ++k)
            if (low_speed(modes.friction[k])) modified.col(k) = Vec4::Unit(k);
        // T_outros = M^-1 applied, with M the mass matrix whose low-speed columns are unit vectors.
        Mat4x12 other_rhs = applied;
        for (int k = 0; k < 4; ++k) {
            Mat4 modified_derivative = padded_inertia_derivative[k];
            for (int c = 0; c < 4; ++c)
                if (low_speed(modes.friction[c])) modified_derivative.col(c).setZero();
            other_rhs.col(k) -= modified_derivative * d.other_torque;
        }
        const Mat4x12 other = modified.partialPivLu().solve(other_rhs);
        for (int k = 0; k < 4; ++k) {
            if (modes.friction[k] != FrictionMode::hold) continue;
            friction.row(k) = -other.row(k);
            friction(k, 4 + k) -= params.coordinate_friction[k].numerical_damping();
        }
    }
    Mat4x12 acceleration_rhs = applied + friction;
    for (int k = 0; k < 4; ++k) acceleration_rhs.col(k) -= padded_inertia_derivative[k] * d.acceleration;
    const Mat4x12 acceleration = solve_mass_matrix<12>(d.reduced_mass, acceleration_rhs);

    // Column of the padded-derivative matrices that a state slot stands for.
    int column_of_slot[kMaxStateSize];
    for (int k = 0; k < n; ++k) column_of_slot[k] = -1;
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        column_of_slot[layout.angle_slot[body]] = body;
        column_of_slot[layout.rate_slot[body]] = 4 + body;
    }
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) column_of_slot[layout.current_slot[axis]] = 8 + axis;
        if (layout.backlash_slot[axis] >= 0) column_of_slot[layout.backlash_slot[axis]] = 10 + axis;
    }
    Eigen::Map<Eigen::MatrixXd> jac(column_major, n, n);
    jac.setZero();
    auto fill_row = [&](int row, const Eigen::Matrix<double, 1, 12>& derivative) {
        for (int slot = 0; slot < n; ++slot)
            if (column_of_slot[slot] >= 0) jac(row, slot) = derivative(column_of_slot[slot]);
    };
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        jac(layout.angle_slot[body], layout.rate_slot[body]) = 1.0;
        fill_row(layout.rate_slot[body], acceleration.row(body));
    }
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        const int rotor = rotor_index(axis), load = load_index(axis);
        // theta_d = (e_r / N - e_l) q_full = (e_r / N - e_l) T q_padded, likewise its rate.
        const Eigen::Matrix<double, 1, 4> deflection =
            (Vec4::Unit(rotor) / gear.ratio - Vec4::Unit(load)).transpose() * T;
        if (layout.current_slot[axis] >= 0 && modes.motor_limited[axis] == 0) {
            Eigen::Matrix<double, 1, 12> row = Eigen::Matrix<double, 1, 12>::Zero();
            row.segment<4>(4) = -motor.back_emf_constant / motor.inductance * T.row(rotor);
            row(8 + axis) = -motor.resistance / motor.inductance;
            fill_row(layout.current_slot[axis], row);
        }
        if (layout.backlash_slot[axis] >= 0 && modes.gear_contact[axis] == 0 && gear.half_backlash > 0.0) {
            Eigen::Matrix<double, 1, 12> row = Eigen::Matrix<double, 1, 12>::Zero();
            row.segment<4>(4) = deflection;
            if (!dead_zone_gear(gear)) {
                const double rate = gear.stiffness / gear.damping;
                row.segment<4>(0) = rate * deflection;
                row(10 + axis) = -rate;
            }
            fill_row(layout.backlash_slot[axis], row);
        }
    }
}

bool evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                               const BaseKinematics& base, double time, const double* state, double* derivative) {
    Dynamics d;
    evaluate_dynamics(params, inputs, base, time, state, modes, d);
    return state_derivative(params, d, derivative);
}

bool state_derivative(const ModelParameters& params, const Dynamics& d, double* derivative) {
    const StateLayout& layout = params.layout;
    if (layout.canonical) {
        for (int body = 0; body < 4; ++body) {
            derivative[kAngles + body] = d.full.rate[body];
            derivative[kRates + body] = d.acceleration[body];
        }
        for (int axis = 0; axis < 2; ++axis) {
            derivative[kCurrents + axis] = d.current_rate[axis];
            derivative[kBacklash + axis] = d.backlash_rate[axis];
        }
    } else {
        for (int body = 0; body < 4; ++body) {
            if (!layout.independent(body)) continue;
            derivative[layout.angle_slot[body]] = d.full.rate[body];
            derivative[layout.rate_slot[body]] = d.acceleration[body];
        }
        for (int axis = 0; axis < 2; ++axis) {
            if (layout.current_slot[axis] >= 0) derivative[layout.current_slot[axis]] = d.current_rate[axis];
            if (layout.backlash_slot[axis] >= 0) derivative[layout.backlash_slot[axis]] = d.backlash_rate[axis];
        }
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
    // x * 0 is NaN exactly when x is not finite: one test instead of one per component.
    double finite_check = 0.0;
    for (int k = 0; k < layout.size; ++k) finite_check += derivative[k] * 0.0;
    return finite_check == 0.0;
}

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                              double time, const double* state) {
    const BaseMotion base_motion = params.fidelity.fixed_base
                                       ? BaseMotion{}
                                       : inputs.base.advanced(time - inputs.step_start_time);
    const BaseKinematics base = evaluate_base_kinematics(base_motion, params.multibody.gravity);
    Dynamics d;
    evaluate_dynamics(params, inputs, base, time, state, modes, d);
    return outputs_from(params, inputs, base, time, d);
}

ModelOutputs outputs_from(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                          double time, const Dynamics& d) {
    const Vec3 velocity_a = params.fidelity.fixed_base
                                ? Vec3::Zero()
                                : Vec3(inputs.base.velocity_a + inputs.base.acceleration_a * (time - inputs.step_start_time));
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
    const MultibodyEnergy energy = compute_energy(params.multibody, base, velocity_a, d.full.angle, d.full.rate);
    out.kinetic_energy = energy.kinetic;
    out.potential_energy = energy.potential;
    return out;
}

}  // namespace gimbal
