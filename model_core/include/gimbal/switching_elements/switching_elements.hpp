// The gimbal's switching elements, each one unit with its name, its guard functions and the rule that
// re-selects its mode where a guard crosses zero (in the spirit of Drake's witness functions with
// their reset maps). The hybrid system owns one per backlash gear, voltage clamp, current limiter and
// dry-friction body present, hands each a contiguous slice of the event vector, and calls them in
// dependency order: contacts first, then the voltage clamps, the limiters (whose steady current
// depends on the clamped voltage), then friction (whose torques depend on everything before).
#pragma once

#include <string>

#include "gimbal/model/gimbal_model.hpp"

namespace gimbal {

// What guards and rules see at one instant: the constant model, the step inputs, and the dynamics
// evaluated at (time, state) under the modes being decided.
struct SwitchingContext {
    const ModelParameters& params;
    const StepInputs& inputs;
    const Dynamics& dynamics;
    double time;
};

class SwitchingElement {
public:
    SwitchingElement(std::string name, int first_guard) : name_(std::move(name)), first_guard_(first_guard) {}
    virtual ~SwitchingElement() = default;

    const std::string& name() const { return name_; }
    int first_guard() const { return first_guard_; }
    virtual int guard_count() const = 0;

    // The guard functions under the current modes, written to values[first_guard() ...]; slots the
    // current mode does not use hold 1 (they never cross).
    virtual void guards(const SwitchingContext& context, const Modes& modes, double* values) const = 0;

    // Re-selects this element's mode in `modes` (holding the previous modes' values on entry).
    // `crossings[first_guard() + k]` is +1 / -1 when guard k has just crossed zero upward / downward, 0
    // otherwise; nullptr after an input change. May project the state onto the new mode's constraint.
    virtual void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                        const int* crossings) const = 0;

    // "gap -> +eta stop" when this element's mode differs between the two, else empty.
    virtual std::string describe(const Modes& before, const Modes& after) const = 0;

protected:
    // The sign of guard k at a decision: right after a located crossing the guard may sit exactly on
    // zero or a rounding error short of it, and the crossing's direction decides.
    int side(double value, const int* crossings, int guard) const;
    int crossing(const int* crossings, int guard) const {
        return crossings != nullptr && guard >= 0 ? crossings[first_guard_ + guard] : 0;
    }

private:
    std::string name_;
    int first_guard_;
};

// Backlash of one gear (2.81): in the gap, or held at a stop while the free backlash rate X pushes
// into it. A gear with c_s = 0 is the pure dead zone: theta_b = clamp(theta_d, +-eta).
class BacklashElement final : public SwitchingElement {
public:
    BacklashElement(int axis, int first_guard);
    int guard_count() const override { return 2; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int axis_;
};

// The clamp of a ramped voltage at +-U_L (2.142-2.145), with input derivatives only.
class VoltageClampElement final : public SwitchingElement {
public:
    VoltageClampElement(int axis, int first_guard);
    int guard_count() const override { return 2; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int axis_;
};

// The current limiter of one motor (2.63-2.69): i held at +-i_L while the free circuit would push it
// further. A quasi-static motor's current is the steady current itself and jumps with the voltage.
class CurrentLimiterElement final : public SwitchingElement {
public:
    CurrentLimiterElement(int axis, int first_guard);
    int guard_count() const override { return 2; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int axis_;
};

// Dry friction with stick-slip on one coordinate (2.98-2.106). Decided in two passes: the speed regime
// (slipping, or a stick candidate below w_min) for all bodies first, because the other torques of
// (2.106) depend on which bodies are at low speed; then, at low speed, stuck or breaking away.
class DryFrictionElement final : public SwitchingElement {
public:
    DryFrictionElement(int body, int first_guard);
    int guard_count() const override { return 6; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    // The speed regime; decide_torque completes the decision with the dynamics of the new regimes.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    void decide_torque(const SwitchingContext& context, const Modes& previous, Modes& modes,
                       const int* crossings) const;
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int body_;
};

}  // namespace gimbal
