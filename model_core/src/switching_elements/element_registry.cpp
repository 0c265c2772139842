#include "gimbal/switching_elements/element_registry.hpp"

#include <algorithm>

namespace gimbal {

template <ElementKind Kind, class Element>
void SwitchingElementSet::add(const ModelParameters& params) {
    constexpr ElementDeclaration declared = kElementDeclarations[static_cast<int>(Kind)];
    static_assert(Element::kGuards == declared.guards, "an element's guards are as many as switching_elements.def declares");
    for (int instance = 0; instance < declared.instances; ++instance) {
        const ElementSlot slot{Kind, instance, guard_count_};
        if (!Element::present(params, slot)) continue;
        elements_.push_back(std::make_unique<Element>(slot));
        const int first_indicator = first_indicator_of(Kind) + declared.guards * instance;
        for (int k = 0; k < Element::kGuards; ++k) guard_indicator_.push_back(first_indicator + k);
        guard_count_ += Element::kGuards;
    }
}

// The kinds of one stage, in the declaration's order.
void SwitchingElementSet::add_stage(const ModelParameters& params, DecisionStage stage) {
#define ELEMENT(identifier, instances, guards, element_switch, element_class) \
    if (element_class::kStage == stage) add<ElementKind::identifier, element_class>(params);
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
}

SwitchingElementSet::SwitchingElementSet(const ModelParameters& params) : state_size_(params.layout.size) {
    for (int stage = 0; stage < kDecisionStageCount; ++stage) {
        stage_start_[stage] = static_cast<int>(elements_.size());
        add_stage(params, static_cast<DecisionStage>(stage));
    }
    stage_start_[kDecisionStageCount] = static_cast<int>(elements_.size());
}

std::string impossible_mode(const ModelParameters& params, const Modes& modes) {
    std::string why;
#define ELEMENT(identifier, instances, guards, element_switch, element_class)                                  \
    for (int instance = 0; instance < (instances) && why.empty(); ++instance)                                  \
        why = element_class::impossible_mode(params, modes, ElementSlot{ElementKind::identifier, instance, 0});
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
    return why;
}

void SwitchingElementSet::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    for (const auto& element : elements_) element->guards(context, modes, values);
}

bool SwitchingElementSet::any_changed(const Modes& before, const Modes& after) const {
    return std::any_of(elements_.begin(), elements_.end(),
                       [&](const auto& element) { return element->changed(before, after); });
}

void SwitchingElementSet::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                                 const int* crossings, FunctionRef<void()> refresh) const {
    double state_before[kMaxStateSize];
    std::copy(state, state + state_size_, state_before);
    auto state_moved = [&] { return !std::equal(state, state + state_size_, state_before); };
    using Stage = DecisionStage;
    for (auto e = stage_begin(Stage::impact); e != stage_end(Stage::impact); ++e) {
        (*e)->decide(context, previous, modes, state, crossings);
        // An impact moved the rates: its rest, and every later stage, read the dynamics after it.
        if (state_moved()) refresh();
        (*e)->settle(context, previous, modes, state, crossings);
    }
    for (auto e = stage_begin(Stage::contact); e != stage_end(Stage::contact); ++e)
        (*e)->decide(context, previous, modes, state, crossings);
    bool supply_changed = false;
    for (auto e = stage_begin(Stage::supply); e != stage_end(Stage::supply); ++e) {
        (*e)->decide(context, previous, modes, state, crossings);
        supply_changed = supply_changed || (*e)->changed(previous, modes);
    }
    // The limiters' steady current depends on the voltage the clamps and the amplifiers now apply.
    if (supply_changed) refresh();
    for (auto e = stage_begin(Stage::current); e != stage_end(Stage::current); ++e)
        (*e)->decide(context, previous, modes, state, crossings);
    bool on_dynamics = false;
    for (auto e = stage_begin(Stage::friction); e != stage_end(Stage::friction); ++e)
        (*e)->decide(context, previous, modes, state, crossings);
    for (auto e = stage_begin(Stage::friction); e != stage_end(Stage::friction); ++e)
        on_dynamics = on_dynamics || (*e)->settles_on_dynamics(modes);
    // The other torques of the low-speed bodies depend on the modes and the state chosen so far.
    if (on_dynamics && (any_changed(previous, modes) || state_moved())) refresh();
    for (auto e = stage_begin(Stage::friction); e != stage_end(Stage::friction); ++e)
        (*e)->settle(context, previous, modes, state, crossings);
}

bool SwitchingElementSet::time_dependent(const StepInputs& inputs, const Modes& modes) const {
    return std::any_of(elements_.begin(), elements_.end(),
                       [&](const auto& element) { return element->time_dependent(inputs, modes); });
}

int SwitchingElementSet::count_changes(const Modes& before, const Modes& after, EventCounters& counters) const {
    int changes = 0;
    for (const auto& element : elements_) {
        if (!element->changed(before, after)) continue;
        ++changes;
        element->count_change(counters);
    }
    return changes;
}

std::string SwitchingElementSet::describe(const Modes& before, const Modes& after) const {
    std::string text;
    for (const auto& element : elements_) {
        const std::string change = element->describe(before, after);
        if (change.empty()) continue;
        if (!text.empty()) text += "; ";
        text += element->name() + ": " + change;
    }
    return text;
}

}  // namespace gimbal
