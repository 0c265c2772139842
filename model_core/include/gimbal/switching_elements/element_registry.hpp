// The one place where the switching elements are registered (docs/architecture.md): which elements a
// model has, in the order their modes are decided, and where each one's guards sit among the FMU's
// event indicators. The hybrid system (hybrid_system/gimbal_hybrid_system.hpp) holds one set and
// knows no element by name.
#pragma once

#include <string>
#include <vector>

#include "gimbal/function_ref.hpp"
#include "gimbal/switching_elements/amplifier_saturation.hpp"
#include "gimbal/switching_elements/current_limiter.hpp"
#include "gimbal/switching_elements/dry_friction.hpp"
#include "gimbal/switching_elements/elevation_stop.hpp"
#include "gimbal/switching_elements/gear_backlash.hpp"
#include "gimbal/switching_elements/voltage_clamp.hpp"

namespace gimbal {

// The kinds of switching element, as declared once in gimbal/switching_elements.def.
enum class ElementKind : int {
#define ELEMENT(identifier, instances, guards, element_switch) identifier,
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};

struct ElementDeclaration {
    int instances;
    int guards;  // per instance
};

inline constexpr ElementDeclaration kElementDeclarations[] = {
#define ELEMENT(identifier, instances, guards, element_switch) {instances, guards},
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};

// Where a kind's first instance's guards sit among the event indicators: after every kind declared before.
constexpr int first_indicator_of(ElementKind kind) {
    int first = 0;
    for (int k = 0; k < static_cast<int>(kind); ++k) first += kElementDeclarations[k].instances * kElementDeclarations[k].guards;
    return first;
}

// The guards of every switching element the model can have, in the fixed order of the declaration whatever
// the fidelity (Model Exchange's event indicators, GIMBAL_EVENT_INDICATORS of gimbal_c_api.h, summed from
// the same table). An element this fidelity lacks contributes constants 1.
constexpr int kEventIndicatorCount =
    first_indicator_of(static_cast<ElementKind>(sizeof(kElementDeclarations) / sizeof(kElementDeclarations[0])));

class SwitchingElementSet {
public:
    // The registration: one element per switching part the model has.
    explicit SwitchingElementSet(const ModelParameters& params);
    // The element list points into the element vectors: not copyable.
    SwitchingElementSet(const SwitchingElementSet&) = delete;
    SwitchingElementSet& operator=(const SwitchingElementSet&) = delete;

    int guard_count() const { return guard_count_; }
    int indicator_of_guard(int guard) const { return guard_indicator_[guard]; }

    // Every element's guards under `modes`, each in its slice of `values` (guard_count() of them).
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const;

    // Re-selects every element's mode, in dependency order: the contacts first (the end stop, whose
    // impulse moves the rates every other element reads, before the gears), then the voltage
    // clamps and the current amplifiers' bus limits, the limiters (whose steady current depends on the clamped voltage), then friction
    // (whose torques depend on everything before). `refresh` re-evaluates context.dynamics at
    // (time, state) under the modes chosen so far, where a later decision depends on them.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings, FunctionRef<void()> refresh) const;

    // Whether any element's guards move with time alone (SwitchingElement::time_dependent).
    bool time_dependent(const StepInputs& inputs, const Modes& modes) const;

    // The number of elements whose mode differs between the two, each counted in its kind's counter.
    int count_changes(const Modes& before, const Modes& after, EventCounters& counters) const;
    // "gear1 backlash: gap -> +eta stop; ..." for the elements whose mode differs.
    std::string describe(const Modes& before, const Modes& after) const;

private:
    // Instance `index` of a kind; its guards' indicators follow from the declaration.
    template <ElementKind Kind, class Element>
    void add(std::vector<Element>& kind, int index);
    bool any_changed(const Modes& before, const Modes& after) const;

    std::vector<ElevationStopElement> stops_;
    std::vector<BacklashElement> backlash_;
    std::vector<VoltageClampElement> clamps_;
    std::vector<AmplifierSaturationElement> amplifiers_;
    std::vector<CurrentLimiterElement> limiters_;
    std::vector<DryFrictionElement> friction_;
    std::vector<const SwitchingElement*> elements_;  // all of them, in decision order
    std::vector<int> guard_indicator_;
    int guard_count_ = 0;
    int state_size_ = 0;
};

}  // namespace gimbal
