// Switching element: the bus-voltage limit of the servo amplifier of a current-commanded motor
// (docs/physics.md section 4.6). In current drive (motor<j>.drive = current) the FMU's input is the
// current command i_R<j>_cmd, clamped to +-i_L at the step start, and an analog PI current loop makes the
// armature voltage:
//   u_unsat = K_p (i_cmd - i) + x_I (+ k_emf w_rotor with back-emf feed-forward),  u = clamp(u_unsat, +-U_L),
//   dx_I/dt = K_i (i_cmd - i) while the output is free, 0 while it is held at +-U_L (anti-windup by
//   conditional integration).
// A quasi-static motor has no current loop state: the amplifier is an ideal current source limited by the
// bus, i = clamp(i_cmd, (-U_L - k_emf w)/R, (U_L - k_emf w)/R), with u_unsat = R i_cmd + k_emf w the
// voltage the commanded current needs. This element decides which side of the clamp holds. In voltage
// drive it exists but never acts: its guards are constants 1 and its mode stays 0.
//   parameters: ModelParameters::amplifier[axis] (amplifier<j>.f_c, K_p, K_i, back_emf_feedforward),
//               motor[axis].voltage_limit (motor<j>.U_L: the bus voltage in current drive)
//   state slot: layout.amplifier_slot[axis] (amplifier<j>.x_I; inductive motor in current drive only)
//   mode: Modes::amplifier_saturated[axis]                guards: 2 (indicators 38-41)
//   counter: none (counted in the total only)
#pragma once

#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

inline bool current_driven(const ModelParameters& params, int axis) {
    return params.fidelity.drive[axis] == DriveMode::current;
}

// Whether the amplifier has its integrator x_I as a state (StateLayout::amplifier_slot): a current-driven
// inductive motor's only (a quasi-static motor's amplifier is an ideal current source).
inline bool amplifier_integrates(const Fidelity& fidelity, int axis) {
    return fidelity.drive[axis] == DriveMode::current && fidelity.motor[axis] == MotorModel::inductive;
}

// u_unsat of a current-driven motor at the current i, the integrator x_I and the rotor speed w.
inline double amplifier_demand(const ModelParameters& params, const StepInputs& inputs, int axis, double current,
                               double integrator, double rotor_rate) {
    const MotorParameters& motor = params.motor[axis];
    const double command = inputs.current_command[axis];
    if (params.fidelity.motor[axis] != MotorModel::inductive)
        return motor.resistance * command + motor.back_emf_constant * rotor_rate;
    const AmplifierParameters& amplifier = params.amplifier[axis];
    const double feedforward = amplifier.back_emf_feedforward ? motor.back_emf_constant * rotor_rate : 0.0;
    return amplifier.proportional_gain * (command - current) + integrator + feedforward;
}

// The voltage the amplifier applies: its demand, or the bus voltage on the side it is held at.
inline double amplifier_output(const ModelParameters& params, const Modes& modes, int axis, double demand) {
    const int side = modes.amplifier_saturated[axis];
    return side != 0 ? side * params.motor[axis].voltage_limit : demand;
}

// A quasi-static current-driven motor's current (limiter not holding): the command, or what the bus
// voltage can drive against the back-emf on the side the amplifier is held at.
inline double quasi_static_driven_current(const ModelParameters& params, const StepInputs& inputs, const Modes& modes,
                                          int axis, double rotor_rate) {
    const int side = modes.amplifier_saturated[axis];
    const MotorParameters& motor = params.motor[axis];
    if (side == 0) return inputs.current_command[axis];
    return (side * motor.voltage_limit - motor.back_emf_constant * rotor_rate) / motor.resistance;
}

// The derivatives of the applied voltage of a current-driven inductive motor with a free output: d/di,
// d/dw (rotor), d/dx_I. All 0 while held at the bus voltage.
struct AmplifierSlopes {
    double current = 0.0, rotor_rate = 0.0, integrator = 0.0;
};
inline AmplifierSlopes amplifier_slopes(const ModelParameters& params, const Modes& modes, int axis) {
    AmplifierSlopes slopes;
    if (!current_driven(params, axis) || modes.amplifier_saturated[axis] != 0 ||
        params.fidelity.motor[axis] != MotorModel::inductive)
        return slopes;
    const AmplifierParameters& amplifier = params.amplifier[axis];
    slopes.current = -amplifier.proportional_gain;
    slopes.rotor_rate = amplifier.back_emf_feedforward ? params.motor[axis].back_emf_constant : 0.0;
    slopes.integrator = 1.0;
    return slopes;
}

// Jacobian pass of the amplifier's own state x_I (layout.amplifier_slot), into the integrated state's
// Jacobian `jac` (slot by slot): while the output is free, x_I drives the current through 1/L, and
// integrates K_i (i_cmd - i) unless the limiter holds i. No entry without an integrator, or while held.
template <class SlotMatrix>
void add_amplifier_state_entries(const ModelParameters& params, const Modes& modes, int axis, SlotMatrix& jac) {
    const int slot = params.layout.amplifier_slot[axis], current = params.layout.current_slot[axis];
    if (slot < 0 || modes.amplifier_saturated[axis] != 0 || modes.motor_limited[axis] != 0) return;
    jac(current, slot) = amplifier_slopes(params, modes, axis).integrator / params.motor[axis].inductance;
    jac(slot, current) = -params.amplifier[axis].integral_gain;
}

class AmplifierSaturationElement final : public SwitchingElement {
public:
    AmplifierSaturationElement(int axis, int first_guard);
    explicit AmplifierSaturationElement(const ElementSlot& slot) : AmplifierSaturationElement(slot.instance, slot.first_guard) {}
    // A current-driven motor's only; in voltage drive its indicators are constants 1.
    static bool present(const ModelParameters& params, const ElementSlot& slot) { return current_driven(params, slot.instance); }
    static constexpr DecisionStage kStage = DecisionStage::supply;
    static std::string impossible_mode(const ModelParameters& params, const Modes& modes, const ElementSlot& slot) {
        if (current_driven(params, slot.instance) || modes.amplifier_saturated[slot.instance] == 0) return {};
        return "motor " + std::to_string(slot.instance + 1) + " is in voltage drive but has an amplifier saturation mode";
    }
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    bool changed(const Modes& before, const Modes& after) const override {
        return before.amplifier_saturated[axis_] != after.amplifier_saturated[axis_];
    }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int axis_;
};

}  // namespace gimbal
