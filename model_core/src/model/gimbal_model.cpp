#include "gimbal/model/gimbal_model.hpp"

#include <Eigen/LU>

#include <cmath>
#include <limits>

namespace gimbal {

namespace {

// The angles' and rates' slots (a rigid gear's rotor has none); returns the number of coordinates kept.
int assign_coordinate_slots(const Fidelity& fidelity, StateLayout& layout) {
    int coordinates = 0;
    for (int body = 0; body < 4; ++body) {
        const bool rigid_rotor = (body == rotor_index(0) && fidelity.gear[0] == GearModel::rigid) ||
                                 (body == rotor_index(1) && fidelity.gear[1] == GearModel::rigid);
        layout.angle_slot[body] = rigid_rotor ? -1 : coordinates++;
    }
    for (int body = 0; body < 4; ++body)
        layout.rate_slot[body] = layout.angle_slot[body] < 0 ? -1 : coordinates + layout.angle_slot[body];
    return coordinates;
}

// One element state per axis where `has_state(axis)`, in the next free slots; -1 elsewhere.
template <class HasState>
void assign_axis_slots(int (&slots)[2], int& slot, HasState has_state) {
    for (int axis = 0; axis < 2; ++axis) slots[axis] = has_state(axis) ? slot++ : -1;
}

}  // namespace

StateLayout StateLayout::from(const Fidelity& fidelity, bool energy_accounting) {
    StateLayout layout;
    int slot = 2 * assign_coordinate_slots(fidelity, layout);
    assign_axis_slots(layout.current_slot, slot, [&](int axis) { return fidelity.motor[axis] == MotorModel::inductive; });
    assign_axis_slots(layout.backlash_slot, slot, [&](int axis) { return fidelity.gear[axis] == GearModel::backlash; });
    assign_axis_slots(layout.amplifier_slot, slot, [&](int axis) { return amplifier_integrates(fidelity, axis); });
    layout.energy_slot = energy_accounting ? slot : -1;
    layout.size = slot + (energy_accounting ? kEnergyFlowCount : 0);
    layout.canonical = slot == kStateSize && layout.amplifier_slot[0] < 0 && layout.amplifier_slot[1] < 0;
    return layout;
}

void ModelParameters::finalize() {
    layout = StateLayout::from(fidelity, energy_accounting);
    assign_coordinate_friction(*this);
    disturbances.active = disturbances.any_present();
}

BaseKinematics base_kinematics_at(const ModelParameters& params, const StepInputs& inputs, double time) {
    if (params.fidelity.fixed_base) return evaluate_base_kinematics(BaseMotion{}, params.multibody.gravity);
    return evaluate_base_kinematics(inputs.base.advanced(time - inputs.step_start_time), params.multibody.gravity);
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
            full.amplifier_integrator[axis] = 0.0;
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
        full.amplifier_integrator[axis] = layout.amplifier_slot[axis] >= 0 ? state[layout.amplifier_slot[axis]] : 0.0;
        full.current[axis] = armature_current(params, modes, inputs, time, axis, state, full.rate[rotor]);
        full.backlash[axis] = layout.backlash_slot[axis] >= 0 ? state[layout.backlash_slot[axis]] : 0.0;
    }
    return full;
}

namespace {

// The drive train's passes of one axis, in this order: the gear (gear_backlash.hpp), the motor circuit
// (current_limiter.hpp, with the voltage of voltage_clamp.hpp), and their torques on the load and the
// rotor, added to `force` in one expression each (the order of the sums is the results' bits).
inline void add_drive_train_forces(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                                   double time, int axis, Dynamics& out, Vec4& force) {
    const int rotor = rotor_index(axis), load = load_index(axis);
    const double shaft_torque = gear_coupling(params, modes, axis, out);
    const double motor_torque = motor_circuit(params, inputs, modes, time, axis, out);
    force[load] += shaft_torque;
    force[rotor] += motor_torque - shaft_torque / params.gear[axis].ratio;
}

// The disturbance elements (disturbance_torques.hpp), each on its own coordinate: the cable of axis j on
// the load's joint angle, the cogging of motor j on its rotor's angle relative to the stator. The
// reactions on the inner bodies need no term: the coordinates are relative angles. A rigid axis's rotor
// angle is N q_l (expand_state), and the reduction below reflects its cogging torque to the load.
inline void add_disturbance_forces(const DisturbanceParameters& disturbances, const Vec4& q, const Vec4& qd,
                                   Vec4& force) {
    for (int axis = 0; axis < 2; ++axis) {
        const int rotor = rotor_index(axis), load = load_index(axis);
        force[load] += cable_torque(disturbances.cable[axis], q[load], qd[load]);
        force[rotor] += cogging_torque(disturbances.cogging[axis], q[rotor]);
    }
}

// T^T J T and T^T (force + bias) for each rigid axis, written out: T only adds N times the rotor's
// row and column to the load's, and the rotor's become the padding identity (a trivial equation).
inline void reduce_rigid_axes(const ModelParameters& params, Mat4& reduced_mass, Vec4& applied) {
    for (int axis = 0; axis < 2; ++axis) {
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
}

// A rigid axis's rotor: its acceleration follows the load's, and its gear still transmits a torque,
// the one that makes the rotor follow, from the rotor's own equation (J the unreduced mass matrix).
inline void rigid_axis_outputs(const ModelParameters& params, const Mat4& mass_matrix, const Vec4& force,
                               const Vec4& bias, Dynamics& out) {
    for (int axis = 0; axis < 2; ++axis)
        if (params.fidelity.gear[axis] == GearModel::rigid)
            out.full_acceleration[rotor_index(axis)] = params.gear[axis].ratio * out.acceleration[load_index(axis)];
    for (int axis = 0; axis < 2; ++axis) {
        if (params.fidelity.gear[axis] != GearModel::rigid) continue;
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double ratio = params.gear[axis].ratio;
        const double rotor_friction = params.rotor_friction_share[axis] * out.friction_torque[load] / ratio;
        const double inertial = mass_matrix.row(rotor).dot(out.full_acceleration);
        out.shaft_torque[axis] = ratio * (force[rotor] + bias[rotor] + rotor_friction - inertial);
    }
}

}  // namespace

void evaluate_dynamics(const ModelParameters& params, const StepInputs& inputs, const BaseKinematics& base,
                       double time, const double* state, const Modes& modes, Dynamics& out) {
    out.full = expand_state(params, modes, inputs, time, state);
    const Vec4& q = out.full.angle;
    const Vec4& qd = out.full.rate;

    // The multibody part: J(q) and the bias f(q, qd, base motion). Assembled in place: the reduced
    // model's padding below changes it, keeping J itself only then.
    Mat4& reduced_mass = out.reduced_mass;
    Vec4 bias;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, reduced_mass, bias);

    Vec4 force;  // generalized forces on the four bodies, without dry friction
    for (int body = 0; body < 4; ++body) force[body] = -params.viscous_friction[body] * qd[body];
    for (int axis = 0; axis < 2; ++axis) add_drive_train_forces(params, inputs, modes, time, axis, out, force);
    if (params.disturbances.active) add_disturbance_forces(params.disturbances, q, qd, force);

    const bool reduced = params.fidelity.gear[0] == GearModel::rigid || params.fidelity.gear[1] == GearModel::rigid;
    Mat4 mass_matrix;
    if (reduced) mass_matrix = reduced_mass;
    Vec4 applied = force + bias;
    if (reduced) reduce_rigid_axes(params, reduced_mass, applied);

    // The dry friction pass (dry_friction.hpp), then the accelerations. A rigid gear keeps J's arrow
    // pattern: its rotor's row and column become the padding identity, and the load's gain only the
    // reflected inertia N^2 J_rotor on the diagonal.
    friction_torques(params, modes, reduced_mass, applied, qd, out);
    out.acceleration = solve_mass_matrix(reduced_mass, Vec4(applied + out.friction_torque));
    hold_at_axis_stops(modes, out);  // the end stops' reactions while a body rests on one
    out.full_acceleration = out.acceleration;
    if (reduced) rigid_axis_outputs(params, mass_matrix, force, bias, out);
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
            if (layout.amplifier_slot[axis] >= 0) derivative[layout.amplifier_slot[axis]] = d.amplifier_rate[axis];
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
        // The cable dampers' loss is viscous too: it goes into the same accumulator.
        if (params.disturbances.active)
            for (int axis = 0; axis < 2; ++axis) {
                const double rate = d.full.rate[load_index(axis)];
                flow[kViscous] += params.disturbances.cable[axis].damping * rate * rate;
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
    if (params.disturbances.active) {
        for (int axis = 0; axis < 2; ++axis) {
            out.cable_energy += cable_energy(params.disturbances.cable[axis], d.full.angle[load_index(axis)]);
            out.cogging_energy += cogging_energy(params.disturbances.cogging[axis], d.full.angle[rotor_index(axis)]);
        }
    }
    return out;
}

}  // namespace gimbal
