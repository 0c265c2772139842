// The switching elements a model has (docs/architecture.md), generated from their one declaration,
// gimbal/switching_elements.def: each ELEMENT row's class, made once per instance its present() accepts, in
// the order their modes are decided (DecisionStage), with each one's guards' place among the FMU's event
// indicators. The registry names no element; the hybrid system (hybrid_system/gimbal_hybrid_system.hpp)
// holds one set.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gimbal/function_ref.hpp"
#include "gimbal/switching_elements/amplifier_saturation.hpp"
#include "gimbal/switching_elements/axis_stop.hpp"
#include "gimbal/switching_elements/current_limiter.hpp"
#include "gimbal/switching_elements/dry_friction.hpp"
#include "gimbal/switching_elements/gear_backlash.hpp"
#include "gimbal/switching_elements/voltage_clamp.hpp"

namespace gimbal {

// Why `modes` is impossible for the elements `params` defines ("" when possible): the first element
// instance, in the declaration's order, whose class refuses it (a restored FMU state's check).
std::string impossible_mode(const ModelParameters& params, const Modes& modes);

class SwitchingElementSet {
public:
    // The registration: one element per switching part the model has.
    explicit SwitchingElementSet(const ModelParameters& params);
    // Owns its elements (each by its own pointer): not copyable.
    SwitchingElementSet(const SwitchingElementSet&) = delete;
    SwitchingElementSet& operator=(const SwitchingElementSet&) = delete;

    int guard_count() const { return guard_count_; }
    int indicator_of_guard(int guard) const { return guard_indicator_[guard]; }

    // Every element's guards under `modes`, each in its slice of `values` (guard_count() of them).
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const;

    // Re-selects every element's mode, stage by stage (DecisionStage): an impact stop's impulse moves the
    // rates, and its rest is settled on the dynamics after it; a change of the voltage sources is seen by
    // the limiters; the low-speed bodies' friction torques are settled on the dynamics under every mode
    // chosen before. `refresh` re-evaluates context.dynamics at (time, state) under the modes chosen so far,
    // where a later decision depends on them.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings, FunctionRef<void()> refresh) const;

    // Whether any element's guards move with time alone (SwitchingElement::time_dependent).
    bool time_dependent(const StepInputs& inputs, const Modes& modes) const;

    // The number of elements whose mode differs between the two, each counted in its kind's counter.
    int count_changes(const Modes& before, const Modes& after, EventCounters& counters) const;
    // "gear1 backlash: gap -> +eta stop; ..." for the elements whose mode differs.
    std::string describe(const Modes& before, const Modes& after) const;

private:
    // Every instance of a kind its class's present() accepts; its guards' indicators follow from the
    // declaration.
    template <ElementKind Kind, class Element>
    void add(const ModelParameters& params);
    void add_stage(const ModelParameters& params, DecisionStage stage);
    bool any_changed(const Modes& before, const Modes& after) const;
    // The elements of one stage, in decision order.
    const std::unique_ptr<SwitchingElement>* stage_begin(DecisionStage stage) const {
        return elements_.data() + stage_start_[static_cast<int>(stage)];
    }
    const std::unique_ptr<SwitchingElement>* stage_end(DecisionStage stage) const {
        return elements_.data() + stage_start_[static_cast<int>(stage) + 1];
    }

    std::vector<std::unique_ptr<SwitchingElement>> elements_;  // all of them, in decision order
    int stage_start_[kDecisionStageCount + 1] = {};
    std::vector<int> guard_indicator_;
    int guard_count_ = 0;
    int state_size_ = 0;
};

}  // namespace gimbal
