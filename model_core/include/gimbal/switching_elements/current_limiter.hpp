// Switching element: the current limiter of one motor (docs/physics.md section 4.1, (2.62)-(2.69)): i held
// at +-i_L while the free circuit would push it further. A quasi-static motor's current is the steady
// current itself and jumps with the voltage. This module owns the motor circuit under the limiter's
// mode (the armature current, its rate, the motor torque), its Jacobian contributions, guards and
// transitions.
//   parameters: ModelParameters::motor[axis] (motor<j>.R, L, k_torque, k_emf, i_L), fidelity.motor[axis]
//   state slot: layout.current_slot[axis] (i_R<j>)        mode: Modes::motor_limited[axis]
//   guards: 2 (indicators 8-11)                            counter: EventCounters::current_limit[axis]
#pragma once

#include "gimbal/switching_elements/amplifier_saturation.hpp"
#include "gimbal/switching_elements/switching_element.hpp"
#include "gimbal/switching_elements/voltage_clamp.hpp"

namespace gimbal {

// The armature current under the limiter's mode, for a layout without fixed slots: held at +-i_L, the
// state's, or (quasi-static) the steady current at the applied voltage.
inline double armature_current(const ModelParameters& params, const Modes& modes, const StepInputs& inputs,
                               double time, int axis, const double* state, double rotor_rate) {
    const MotorParameters& motor = params.motor[axis];
    const int limited = modes.motor_limited[axis];
    if (limited != 0) return limited * motor.current_limit;
    if (params.layout.current_slot[axis] >= 0) return state[params.layout.current_slot[axis]];
    if (current_driven(params, axis)) return quasi_static_driven_current(params, inputs, modes, axis, rotor_rate);
    return unlimited_steady_current(motor, applied_voltage(params, inputs, modes, axis, time), rotor_rate);
}

// Force pass of the dynamics: the applied voltage, the steady current and the current's rate (0 while
// held or quasi-static) written to `out`; returns the motor torque on the rotor.
inline double motor_circuit(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                            int axis, Dynamics& out) {
    const MotorParameters& motor = params.motor[axis];
    const double rotor_rate = out.full.rate[rotor_index(axis)];
    out.amplifier_demand[axis] = 0.0;
    out.amplifier_rate[axis] = 0.0;
    double voltage;
    if (current_driven(params, axis)) {
        // The amplifier's output (amplifier_saturation.hpp) and its integrator, frozen while held.
        const double current = out.full.current[axis];
        const double demand =
            amplifier_demand(params, inputs, axis, current, out.full.amplifier_integrator[axis], rotor_rate);
        out.amplifier_demand[axis] = demand;
        voltage = amplifier_output(params, modes, axis, demand);
        if (params.layout.amplifier_slot[axis] >= 0 && modes.amplifier_saturated[axis] == 0)
            out.amplifier_rate[axis] =
                params.amplifier[axis].integral_gain * (inputs.current_command[axis] - current);
    } else {
        voltage = applied_voltage(params, inputs, modes, axis, time);
    }
    out.voltage[axis] = voltage;
    out.steady_current[axis] = unlimited_steady_current(motor, voltage, rotor_rate);
    out.current_rate[axis] = 0.0;
    if (params.layout.current_slot[axis] >= 0 && modes.motor_limited[axis] == 0)
        out.current_rate[axis] = armature_current_rate(motor, voltage, out.full.current[axis], rotor_rate);
    return electromagnetic_torque(motor, out.full.current[axis]);
}

// Jacobian pass: the motor torque's derivatives on the rotor's row of `force` (through the current
// state, or for a quasi-static motor the back-emf damping); none while the limiter holds i.
inline void add_motor_force_derivatives(const ModelParameters& params, const Modes& modes, int axis, Mat4x12& force) {
    if (modes.motor_limited[axis] != 0) return;
    const MotorParameters& motor = params.motor[axis];
    const int rotor = rotor_index(axis);
    if (params.layout.current_slot[axis] >= 0) {
        force(rotor, kCurrentColumn + axis) += motor.torque_constant;
    } else if (current_driven(params, axis)) {
        // The commanded current does not depend on the state; the bus-limited one falls with the back-emf.
        if (modes.amplifier_saturated[axis] != 0)
            force(rotor, kRateColumn + rotor) -= motor.torque_constant * motor.back_emf_constant / motor.resistance;
    } else {
        force(rotor, kRateColumn + rotor) -= motor.torque_constant * motor.back_emf_constant / motor.resistance;
    }
}

// The row of d(di/dt)/d(state) of a free inductive circuit (q_full = T q_padded); false otherwise. In
// current drive the amplifier's output adds its slopes (amplifier_slopes); d(di/dt)/dx_I is theirs.
bool current_state_row(const ModelParameters& params, const Modes& modes, int axis, const Mat4& T, Row12& row);

class CurrentLimiterElement final : public SwitchingElement {
public:
    CurrentLimiterElement(int axis, int first_guard);
    explicit CurrentLimiterElement(const ElementSlot& slot) : CurrentLimiterElement(slot.instance, slot.first_guard) {}
    // A voltage-driven motor's only: a current-driven motor's current is limited by its amplifier, which
    // clamps the command to +-i_L; an ideal limiter at the same level would only meet a current the loop
    // brings onto it tangentially.
    static bool present(const ModelParameters& params, const ElementSlot& slot) { return !current_driven(params, slot.instance); }
    static constexpr DecisionStage kStage = DecisionStage::current;
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    bool changed(const Modes& before, const Modes& after) const override {
        return before.motor_limited[axis_] != after.motor_limited[axis_];
    }
    void count_change(EventCounters& counters) const override { ++counters.current_limit[axis_]; }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int decide_inductive(const SwitchingContext& context, int current, double& state_current,
                         const int* crossings) const;
    int decide_quasi_static(const SwitchingContext& context, int current, const int* crossings) const;
    int axis_;
};

}  // namespace gimbal
