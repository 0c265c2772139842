#include "gimbal/switching_elements/element_registry.hpp"

#include <algorithm>

namespace gimbal {

template <ElementKind Kind, class Element>
void SwitchingElementSet::add(std::vector<Element>& kind, int index) {
    constexpr ElementDeclaration declared = kElementDeclarations[static_cast<int>(Kind)];
    static_assert(Element::kGuards == declared.guards, "an element's guards are as many as switching_elements.def declares");
    const int first_indicator = first_indicator_of(Kind) + declared.guards * index;
    kind.emplace_back(index, guard_count_);
    for (int k = 0; k < Element::kGuards; ++k) guard_indicator_.push_back(first_indicator + k);
    guard_count_ += Element::kGuards;
}

SwitchingElementSet::SwitchingElementSet(const ModelParameters& params) : state_size_(params.layout.size) {
    // Each kind in decision order.
    if (params.elevation_stop.present) add<ElementKind::elevation_stop>(stops_, 0);
    for (int axis = 0; axis < 2; ++axis)
        if (params.layout.backlash_slot[axis] >= 0) add<ElementKind::gear_backlash>(backlash_, axis);
    for (int axis = 0; axis < 2; ++axis) add<ElementKind::voltage_clamp>(clamps_, axis);
    // Only a current-driven motor's amplifier acts; in voltage drive its indicators are constants 1.
    for (int axis = 0; axis < 2; ++axis)
        if (current_driven(params, axis)) add<ElementKind::amplifier_saturation>(amplifiers_, axis);
    // A current-driven motor's current is limited by its amplifier, which clamps the command to +-i_L: an
    // ideal limiter at the same level would only meet a current the loop brings onto it tangentially.
    for (int axis = 0; axis < 2; ++axis)
        if (!current_driven(params, axis)) add<ElementKind::current_limiter>(limiters_, axis);
    for (int body = 0; body < 4; ++body)
        if (params.coordinate_friction[body].present()) add<ElementKind::dry_friction>(friction_, body);
    for (const auto& e : stops_) elements_.push_back(&e);
    for (const auto& e : backlash_) elements_.push_back(&e);
    for (const auto& e : clamps_) elements_.push_back(&e);
    for (const auto& e : amplifiers_) elements_.push_back(&e);
    for (const auto& e : limiters_) elements_.push_back(&e);
    for (const auto& e : friction_) elements_.push_back(&e);
}

void SwitchingElementSet::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    for (const SwitchingElement* element : elements_) element->guards(context, modes, values);
}

bool SwitchingElementSet::any_changed(const Modes& before, const Modes& after) const {
    return std::any_of(elements_.begin(), elements_.end(),
                       [&](const SwitchingElement* element) { return element->changed(before, after); });
}

void SwitchingElementSet::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                                 const int* crossings, FunctionRef<void()> refresh) const {
    double state_before[kMaxStateSize];
    std::copy(state, state + state_size_, state_before);
    for (const ElevationStopElement& element : stops_) {
        element.decide(context, previous, modes, state, crossings);
        // An impact moved the rates: the gears' and the rest's decisions read the dynamics after it.
        if (!std::equal(state, state + state_size_, state_before)) refresh();
        element.decide_rest(context, previous, modes, state);
    }
    for (const BacklashElement& element : backlash_) element.decide(context, previous, modes, state, crossings);
    bool clamp_changed = false;
    for (const VoltageClampElement& element : clamps_) {
        element.decide(context, previous, modes, state, crossings);
        clamp_changed = clamp_changed || element.changed(previous, modes);
    }
    for (const AmplifierSaturationElement& element : amplifiers_) {
        element.decide(context, previous, modes, state, crossings);
        clamp_changed = clamp_changed || element.changed(previous, modes);
    }
    // The limiters' steady current depends on the voltage the clamps and the amplifiers now apply.
    if (clamp_changed) refresh();
    for (const CurrentLimiterElement& element : limiters_) element.decide(context, previous, modes, state, crossings);
    for (const DryFrictionElement& element : friction_) element.decide(context, previous, modes, state, crossings);
    // The other torques of the low-speed bodies depend on the modes and the state chosen so far.
    bool any_low_speed = false;
    for (int body = 0; body < 4; ++body) any_low_speed = any_low_speed || low_speed(modes.friction[body]);
    if (any_low_speed && (any_changed(previous, modes) || !std::equal(state, state + state_size_, state_before)))
        refresh();
    for (const DryFrictionElement& element : friction_) element.decide_torque(context, previous, modes, crossings);
}

bool SwitchingElementSet::time_dependent(const StepInputs& inputs, const Modes& modes) const {
    return std::any_of(elements_.begin(), elements_.end(),
                       [&](const SwitchingElement* element) { return element->time_dependent(inputs, modes); });
}

int SwitchingElementSet::count_changes(const Modes& before, const Modes& after, EventCounters& counters) const {
    int changes = 0;
    for (const SwitchingElement* element : elements_) {
        if (!element->changed(before, after)) continue;
        ++changes;
        element->count_change(counters);
    }
    return changes;
}

std::string SwitchingElementSet::describe(const Modes& before, const Modes& after) const {
    std::string text;
    for (const SwitchingElement* element : elements_) {
        const std::string change = element->describe(before, after);
        if (change.empty()) continue;
        if (!text.empty()) text += "; ";
        text += element->name() + ": " + change;
    }
    return text;
}

}  // namespace gimbal
