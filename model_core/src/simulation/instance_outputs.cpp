#include "gimbal/simulation/instance_outputs.hpp"

#include <algorithm>
#include <limits>

#include "gimbal/model/variable_groups.hpp"

namespace gimbal {
namespace {

int saturated(std::int64_t count) { return static_cast<int>(std::min<std::int64_t>(count, 2147483647)); }

void publish_counters(const OutputPoint& point, double (&reals)[kRealVariableCount],
                      int (&integers)[kIntegerVariableCount]) {
    const EventCounters& events = point.system.counters();
    const IntegratorStatistics stats = point.integrator.statistics();
    reals[vr_events_last_time] = point.epoch + events.last_event_time;
    integers[vi_events_total] = static_cast<int>(events.total);
    integers[vi_events_backlash1] = static_cast<int>(events.backlash[0]);
    integers[vi_events_backlash2] = static_cast<int>(events.backlash[1]);
    integers[vi_events_current_limit1] = static_cast<int>(events.current_limit[0]);
    integers[vi_events_current_limit2] = static_cast<int>(events.current_limit[1]);
    integers[vi_events_stick_slip] = static_cast<int>(events.stick_slip);
    integers[vi_events_zeno_guard] = saturated(stats.zeno_holds + point.zeno_holds);
    integers[vi_solver_states] = point.params.layout.size;
    integers[vi_solver_steps] = saturated(stats.steps);
    integers[vi_solver_rhs_evaluations] = saturated(stats.rhs_evaluations);
    integers[vi_solver_jacobian_evaluations] = saturated(stats.jacobian_evaluations);
    integers[vi_solver_method_switches] = saturated(stats.method_switches);
}

}  // namespace

void publish_outputs(const OutputPoint& point, double (&reals)[kRealVariableCount],
                     int (&integers)[kIntegerVariableCount]) {
    const ModelParameters& params = point.params;
    const Modes& modes = point.system.modes();
    const double now = point.clock;
    const Dynamics& dynamics = point.system.dynamics_at(now, point.state);
    const ModelOutputs out =
        outputs_from(params, point.system.inputs(), point.system.base_kinematics_at_time(now), now, dynamics);
    for (int k = 0; k < 4; ++k) {
        reals[kBodyAngle[k]] = out.full.angle[k];
        reals[kBodyRate[k]] = out.full.rate[k];
    }
    reals[vr_i_R1] = out.full.current[0];
    reals[vr_i_R2] = out.full.current[1];
    reals[vr_theta_b1] = out.full.backlash[0];
    reals[vr_theta_b2] = out.full.backlash[1];
    reals[vr_T_E1] = out.shaft_torque[0];
    reals[vr_T_E2] = out.shaft_torque[1];
    for (int k = 0; k < 3; ++k) reals[kPayloadAngularVelocity[k]] = out.payload_angular_velocity[k];
    reals[vr_energy_kinetic] = out.kinetic_energy;
    reals[vr_energy_potential] = out.potential_energy;
    reals[vr_energy_spring] = out.spring_energy;
    reals[vr_energy_magnetic] = out.magnetic_energy;
    reals[vr_energy_cable] = out.cable_energy;
    reals[vr_energy_cogging] = out.cogging_energy;
    reals[vr_amplifier1_u] = dynamics.voltage[0];
    reals[vr_amplifier2_u] = dynamics.voltage[1];
    reals[vr_amplifier1_x_I] = dynamics.full.amplifier_integrator[0];
    reals[vr_amplifier2_x_I] = dynamics.full.amplifier_integrator[1];
    const bool accounting = params.layout.energy_slot >= 0;
    const double* flows = point.state + (accounting ? params.layout.energy_slot : 0);
    reals[vr_energy_electrical_in] = accounting ? flows[kElectricalIn] : 0.0;
    reals[vr_energy_resistive] = accounting ? flows[kResistive] : 0.0;
    reals[vr_energy_viscous] = accounting ? flows[kViscous] : 0.0;
    reals[vr_energy_shaft_damping] = accounting ? flows[kShaftDamping] : 0.0;
    reals[vr_energy_dry_friction] = accounting ? flows[kDryFriction] : 0.0;
    double integrated[kMaxStateSize], derivative[kContinuousStateCount];
    if (state_derivative(params, dynamics, integrated)) {
        full_state_derivative(params, modes, dynamics, integrated, derivative);
        for (int k = 0; k < kContinuousStateCount; ++k) reals[kStateDerivatives[k]] = derivative[k];
    } else {
        for (int k = 0; k < kContinuousStateCount; ++k)
            reals[kStateDerivatives[k]] = std::numeric_limits<double>::quiet_NaN();
    }

    integers[vi_gear1_contact] = modes.gear_contact[0];
    integers[vi_gear2_contact] = modes.gear_contact[1];
    integers[vi_motor1_limited] = modes.motor_limited[0];
    integers[vi_motor2_limited] = modes.motor_limited[1];
    for (int stop = 0; stop < kAxisStopCount; ++stop) integers[kAxisStops[stop].contact] = modes.axis_stop[stop];
    integers[vi_motor1_amplifier_saturated] = modes.amplifier_saturated[0];
    integers[vi_motor2_amplifier_saturated] = modes.amplifier_saturated[1];
    for (int body = 0; body < 4; ++body)
        integers[kBodyStickSlip[body]] = friction_mode_indicator(modes.friction[body], out.full.rate[body]);
    publish_counters(point, reals, integers);
}

void full_state_vector(const ModelParameters& params, const Dynamics& d, const double* state, double* states) {
    const StateLayout& layout = params.layout;
    for (int body = 0; body < 4; ++body) {
        states[body] = d.full.angle[body];
        states[kRates + body] = d.full.rate[body];
    }
    for (int axis = 0; axis < 2; ++axis) {
        states[kCurrents + axis] = d.full.current[axis];
        states[kBacklash + axis] = d.full.backlash[axis];
    }
    for (int k = 0; k < kEnergyFlowCount; ++k)
        states[kStateSize + k] = layout.energy_slot >= 0 ? state[layout.energy_slot + k] : 0.0;
    for (int axis = 0; axis < 2; ++axis) states[kAmplifierStates + axis] = d.full.amplifier_integrator[axis];
}

void full_state_derivative(const ModelParameters& params, const Modes& modes, const Dynamics& d,
                           const double* derivative, double* out) {
    const StateLayout& layout = params.layout;
    for (int body = 0; body < 4; ++body) {
        out[body] = d.full.rate[body];
        out[kRates + body] = d.full_acceleration[body];
    }
    for (int axis = 0; axis < 2; ++axis) {
        const int slot = layout.current_slot[axis];
        if (slot >= 0) {
            out[kCurrents + axis] = derivative[slot];
        } else if (modes.motor_limited[axis] != 0) {
            out[kCurrents + axis] = 0.0;
        } else if (current_driven(params, axis)) {
            // The commanded current is held; the bus-limited one (u = +-U_L) moves with the rotor's speed.
            const MotorParameters& motor = params.motor[axis];
            out[kCurrents + axis] = modes.amplifier_saturated[axis] == 0
                                        ? 0.0
                                        : -motor.back_emf_constant * d.full_acceleration[rotor_index(axis)] /
                                              motor.resistance;
        } else {
            // A quasi-static motor's current (u - k_e w) / R moves with its rotor's speed (u is held).
            const MotorParameters& motor = params.motor[axis];
            out[kCurrents + axis] = -motor.back_emf_constant * d.full_acceleration[rotor_index(axis)] / motor.resistance;
        }
        out[kBacklash + axis] = layout.backlash_slot[axis] >= 0 ? derivative[layout.backlash_slot[axis]] : 0.0;
    }
    for (int k = 0; k < kEnergyFlowCount; ++k)
        out[kStateSize + k] = layout.energy_slot >= 0 ? derivative[layout.energy_slot + k] : 0.0;
    for (int axis = 0; axis < 2; ++axis)
        out[kAmplifierStates + axis] = layout.amplifier_slot[axis] >= 0 ? derivative[layout.amplifier_slot[axis]] : 0.0;
}

void clamp_published_to_bounds(const ModelParameters& params, double (&reals)[kRealVariableCount]) {
    const RealVariable currents[2] = {vr_i_R1, vr_i_R2}, backlash[2] = {vr_theta_b1, vr_theta_b2};
    for (int axis = 0; axis < 2; ++axis) {
        const double limit = params.motor[axis].current_limit, eta = params.gear[axis].half_backlash;
        reals[currents[axis]] = std::clamp(reals[currents[axis]], -limit, limit);
        reals[backlash[axis]] = std::clamp(reals[backlash[axis]], -eta, eta);
    }
}

}  // namespace gimbal
