// Switching element: the clamp of one motor's ramped voltage at +-U_L (docs/physics.md section 4.1,
// (2.142)-(2.145)). A held voltage is clamped once per communication step (clamp_voltage, drive_train.hpp);
// a voltage the master ramps with input derivatives follows its ramp until it reaches +-U_L and is held
// there: that is this element. Its only force contribution is the voltage the motor circuit sees.
//   parameters: ModelParameters::motor[axis].voltage_limit (motor<j>.U_L)
//   state slot: none                                      mode: Modes::voltage_clamped[axis]
//   guards: 2 (indicators 4-7)                            counter: none (counted in the total only)
#pragma once

#include <cmath>

#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

// The ramp a voltage follows before its clamp (constant without input derivatives).
inline double ramped_voltage(const StepInputs& inputs, int axis, double time) {
    return inputs.commanded_voltage[axis] + inputs.voltage_rate[axis] * (time - inputs.step_start_time);
}

// Force pass: the voltage at the motor terminals' input at `time` (after the clamp).
inline double applied_voltage(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, int axis,
                              double time) {
    if (inputs.voltage_rate[axis] == 0.0) return inputs.voltage[axis];
    if (modes.voltage_clamped[axis] != 0) return modes.voltage_clamped[axis] * params.motor[axis].voltage_limit;
    return ramped_voltage(inputs, axis, time);
}

// The linear model's view of a held voltage: at or beyond its clamp (at the limit itself, not only
// beyond: a saturated controller sits exactly there) it does not respond to a small change. The side
// of the limit, or 0 when the voltage passes.
inline int held_clamp_side(const MotorParameters& motor, double commanded_voltage) {
    if (!(std::fabs(commanded_voltage) >= motor.voltage_limit)) return 0;  // NaN passes, as before
    return commanded_voltage > 0.0 ? 1 : -1;
}

class VoltageClampElement final : public SwitchingElement {
public:
    VoltageClampElement(int axis, int first_guard);
    explicit VoltageClampElement(const ElementSlot& slot) : VoltageClampElement(slot.instance, slot.first_guard) {}
    // Every motor's.
    static bool present(const ModelParameters&, const ElementSlot&) { return true; }
    static constexpr DecisionStage kStage = DecisionStage::supply;
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    // A ramp not yet clamped moves the applied voltage with time.
    bool time_dependent(const StepInputs& inputs, const Modes& modes) const override {
        return inputs.voltage_rate[axis_] != 0.0 && modes.voltage_clamped[axis_] == 0;
    }
    bool changed(const Modes& before, const Modes& after) const override {
        return before.voltage_clamped[axis_] != after.voltage_clamped[axis_];
    }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int axis_;
};

}  // namespace gimbal
