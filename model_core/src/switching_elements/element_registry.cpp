#include "gimbal/switching_elements/element_registry.hpp"

#include <algorithm>

namespace gimbal {

template <class Element>
void SwitchingElementSet::add(std::vector<Element>& kind, int index, int first_indicator) {
    kind.emplace_back(index, guard_count_);
    for (int k = 0; k < kind.back().guard_count(); ++k) guard_indicator_.push_back(first_indicator + k);
    guard_count_ += kind.back().guard_count();
}

SwitchingElementSet::SwitchingElementSet(const ModelParameters& params) : state_size_(params.layout.size) {
    // Each kind in decision order, with the first indicator of its first instance.
    for (int axis = 0; axis < 2; ++axis)
        if (params.layout.backlash_slot[axis] >= 0) add(backlash_, axis, 2 * axis);
    for (int axis = 0; axis < 2; ++axis) add(clamps_, axis, 4 + 2 * axis);
    for (int axis = 0; axis < 2; ++axis) add(limiters_, axis, 8 + 2 * axis);
    for (int body = 0; body < 4; ++body)
        if (params.coordinate_friction[body].present()) add(friction_, body, 12 + 6 * body);
    for (const auto& e : backlash_) elements_.push_back(&e);
    for (const auto& e : clamps_) elements_.push_back(&e);
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
    for (const BacklashElement& element : backlash_) element.decide(context, previous, modes, state, crossings);
    bool clamp_changed = false;
    for (const VoltageClampElement& element : clamps_) {
        element.decide(context, previous, modes, state, crossings);
        clamp_changed = clamp_changed || element.changed(previous, modes);
    }
    // The limiters' steady current depends on the voltage the clamps now apply.
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
