#include "gimbal/gimbal_model.hpp"

#include <Eigen/Cholesky>

namespace gimbal {
namespace {

BaseKinematics base_at(const ModelParameters& params, const StepInputs& inputs, double time) {
    return evaluate_base_kinematics(inputs.base.advanced(time - inputs.step_start_time), params.multibody.gravity);
}

struct GearKinematics {
    double deflection;
    double deflection_rate;
};

GearKinematics gear_kinematics(const GearParameters& gear, const StateVector& state, int axis) {
    const int rotor = rotor_index(axis), load = load_index(axis);
    return {gear_deflection(gear, state[kAngles + rotor], state[kAngles + load]),
            gear_deflection(gear, state[kRates + rotor], state[kRates + load])};
}

}  // namespace

void evaluate_state_derivative(const ModelParameters& params, const StepInputs& inputs, double time,
                               const StateVector& state, StateVector& derivative) {
    const BaseKinematics base = base_at(params, inputs, time);
    const Vec4 q = state.segment<4>(kAngles);
    const Vec4 qd = state.segment<4>(kRates);

    Mat4 mass_matrix;
    Vec4 bias;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, mass_matrix, bias);

    Vec4 generalized_force;
    for (int body = 0; body < 4; ++body) generalized_force[body] = -params.viscous_friction[body] * qd[body];
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const MotorParameters& motor = params.motor[axis];
        const GearKinematics g = gear_kinematics(gear, state, axis);
        // No backlash yet: theta_b is held at zero.
        const double shaft_torque = gear_shaft_torque(gear, g.deflection, g.deflection_rate, 0.0, 0.0);
        const double current = state[kCurrents + axis];
        const double rotor_speed = qd[rotor_index(axis)];
        generalized_force[load_index(axis)] += shaft_torque;
        generalized_force[rotor_index(axis)] += electromagnetic_torque(motor, current) - shaft_torque / gear.ratio;
        derivative[kCurrents + axis] = armature_current_rate(motor, inputs.voltage[axis], current, rotor_speed);
        derivative[kBacklash + axis] = 0.0;
    }

    derivative.segment<4>(kAngles) = qd;
    derivative.segment<4>(kRates) = mass_matrix.llt().solve(generalized_force + bias);
}

ModelOutputs evaluate_outputs(const ModelParameters& params, const StepInputs& inputs, double time,
                              const StateVector& state) {
    const BaseMotion base_motion = inputs.base.advanced(time - inputs.step_start_time);
    const BaseKinematics base = evaluate_base_kinematics(base_motion, params.multibody.gravity);
    const Vec4 q = state.segment<4>(kAngles);
    const Vec4 qd = state.segment<4>(kRates);

    ModelOutputs out;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params.gear[axis];
        const GearKinematics g = gear_kinematics(gear, state, axis);
        const double backlash = state[kBacklash + axis];
        out.shaft_torque[axis] = gear_shaft_torque(gear, g.deflection, g.deflection_rate, backlash, 0.0);
        out.spring_energy += 0.5 * gear.stiffness * (g.deflection - backlash) * (g.deflection - backlash);
    }
    out.payload_angular_velocity = payload_angular_velocity(base, q, qd);
    const MultibodyEnergy energy = compute_energy(params.multibody, base, base_motion.velocity_a, q, qd);
    out.kinetic_energy = energy.kinetic;
    out.potential_energy = energy.potential;
    return out;
}

}  // namespace gimbal
