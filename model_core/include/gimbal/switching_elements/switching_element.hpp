// What every switching element is (docs/physics.md section 5): one unit with its name, its guard
// functions and the rule that re-selects its mode where a guard crosses zero (in the spirit of Drake's
// witness functions with their reset maps). Each element's module (gear_backlash, voltage_clamp,
// current_limiter, dry_friction, axis_stop, amplifier_saturation) derives from SwitchingElement and also
// holds the element's force and Jacobian contributions and the rows of its own states, which the dynamics
// (model/gimbal_model.hpp) call in one pass per element. Which elements a model has, their guards' places
// and their decision order: element_registry.hpp, generated from gimbal/switching_elements.def.
#pragma once

#include <cstdint>
#include <string>

#include "gimbal/model/model_types.hpp"

namespace gimbal {

// The kinds of switching element, as declared once in gimbal/switching_elements.def.
enum class ElementKind : int {
#define ELEMENT(identifier, instances, guards, element_switch, element_class) identifier,
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};

// Each kind's row: instances x guards event indicators, and the parameter that switches it on ("": always).
struct ElementDeclaration {
    const char* identifier;
    int instances;
    int guards;  // per instance
    const char* element_switch;
};

inline constexpr ElementDeclaration kElementDeclarations[] = {
#define ELEMENT(identifier, instances, guards, element_switch, element_class) \
    {#identifier, instances, guards, element_switch},
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};
constexpr int kElementKindCount = static_cast<int>(sizeof(kElementDeclarations) / sizeof(kElementDeclarations[0]));

constexpr const ElementDeclaration& declaration_of(ElementKind kind) {
    return kElementDeclarations[static_cast<int>(kind)];
}

// Where a kind's first instance's guards sit among the event indicators: after every kind declared before.
constexpr int first_indicator_of(ElementKind kind) {
    int first = 0;
    for (int k = 0; k < static_cast<int>(kind); ++k) first += kElementDeclarations[k].instances * kElementDeclarations[k].guards;
    return first;
}

// The guards of every switching element the model can have, in the fixed order of the declaration whatever
// the fidelity (Model Exchange's event indicators, GIMBAL_EVENT_INDICATORS of gimbal_c_api.h, summed from
// the same table). An element this fidelity lacks contributes constants 1.
constexpr int kEventIndicatorCount = first_indicator_of(static_cast<ElementKind>(kElementKindCount));

// When an element's mode is re-selected at an event (SwitchingElementSet::decide), each stage after the
// ones whose results it reads: the end stops first, whose impulse moves the rates every other element
// reads; then the gears; the voltage sources (the clamps and the current amplifiers' bus limits); the
// current limiters, whose steady current depends on the voltage applied; dry friction, whose torques depend
// on everything before. Within a stage, in the declaration's order.
enum class DecisionStage : int { impact, contact, supply, current, friction };
constexpr int kDecisionStageCount = 5;

// Where an element sits: its kind, its instance among the kind's (axis, body, ...), and the first of its
// guards in the model's guard vector. Each element class is made from one (explicit Element(const
// ElementSlot&)) where its static present(params, slot) says the model has it.
struct ElementSlot {
    ElementKind kind;
    int instance;
    int first_guard;
};

// Mode changes so far, by kind (the FMU's event counters).
struct EventCounters {
    std::int64_t total = 0;
    std::int64_t backlash[2] = {0, 0};
    std::int64_t current_limit[2] = {0, 0};
    std::int64_t stick_slip = 0;
    double last_event_time = 0.0;
};

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

    // Why `modes` is impossible for instance `slot.instance` of this kind under `params` (a restored FMU
    // state's check), "" when it is possible: a class whose mode needs the element hides this. Called
    // for every instance, present or not.
    static std::string impossible_mode(const ModelParameters& params, const Modes& modes, const ElementSlot& slot) {
        (void)params, (void)modes, (void)slot;
        return std::string();
    }

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

    // Whether the dynamics under this element's mode move with time alone (a ramped input not yet
    // clamped): the Rosenbrock methods then need the right-hand side's time derivative.
    virtual bool time_dependent(const StepInputs& inputs, const Modes& modes) const {
        (void)inputs, (void)modes;
        return false;
    }

    // Completes a decision with the dynamics re-evaluated under the modes decided so far, where the
    // element's stage asks for it (an impact stop's rest, dry friction's torque); nothing by default.
    virtual void settle(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                        const int* crossings) const {
        (void)context, (void)previous, (void)modes, (void)state, (void)crossings;
    }
    // Whether settle() needs the dynamics re-evaluated first under `modes` (dry friction at low speed).
    virtual bool settles_on_dynamics(const Modes& modes) const {
        (void)modes;
        return false;
    }

    // Whether this element's mode differs between the two; if so, counted in its kind's counter.
    virtual bool changed(const Modes& before, const Modes& after) const = 0;
    virtual void count_change(EventCounters& counters) const { (void)counters; }
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

namespace switching {

inline int sign(double value) { return value > 0.0 ? 1 : (value < 0.0 ? -1 : 0); }

// Contact rule of (2.81) at one side, shared by the limiter: at the stop, and not pulled back.
int select_contact(bool at_plus_stop, bool at_minus_stop, int pull_sign, int current);

// "from -> to".
std::string transition(const char* from, const char* to);

}  // namespace switching
}  // namespace gimbal
