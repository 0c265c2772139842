// The gimbal as a hybrid system: modes of docs/physics.md sections 4-5 (backlash contact side, current
// limiter, stick/slip), their event functions and their switching rules.
#pragma once

#include "gimbal/hybrid_system/hybrid_system.hpp"
#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/switching_elements/element_registry.hpp"

namespace gimbal {

class GimbalHybridSystem final : public HybridSystem {
public:
    explicit GimbalHybridSystem(const ModelParameters& params);
    // The element list points into the element vectors: not copyable.
    GimbalHybridSystem(const GimbalHybridSystem&) = delete;
    GimbalHybridSystem& operator=(const GimbalHybridSystem&) = delete;

    int state_size() const override { return params_.state_size(); }
    int event_count() const override { return elements_.guard_count(); }
    bool derivative(double time, const double* state, double* derivative) override;
    int kinematic_pairs(int* position, int* velocity) const override;
    bool has_jacobian() const override { return true; }
    bool jacobian(double time, const double* state, double* column_major) override;
    // The backlash states of the gears in their gap (docs/physics.md section 4.2): there
    // d(theta_d - theta_b)/dt = -(k_s / c_s)(theta_d - theta_b) and T_E = 0 exactly. Not offered with
    // energy accounting, whose damper dissipation would then need the relaxation resolved.
    int relaxing_states(RelaxingState* out) const override;
    void event_functions(double time, const double* state, double* values) override;
    int update_modes(double time, double* state, const int* directions) override;

    bool time_dependent() const override;
    std::string describe_last_changes() const override;

    void set_inputs(const StepInputs& inputs);
    // Model Exchange: the host sets the inputs at every instant it evaluates, so the carrier's motion is
    // taken as set, not extrapolated from where it was set (the Co-Simulation step's arc).
    void hold_inputs_at_any_time(bool held) {
        inputs_held_ = held;
        base_cached_ = false;
        cache_valid_ = false;
    }

    // The guards of every switching element the model can have, in one fixed order whatever the
    // fidelity (Model Exchange's event indicators; element_registry.hpp).
    static constexpr int kIndicatorCount = kEventIndicatorCount;
    void event_indicators(double time, const double* state, double* values);
    // Where guard k of event_functions() sits among the indicators.
    int indicator_of_guard(int guard) const { return elements_.indicator_of_guard(guard); }
    // The dynamics at (time, state) under the current modes: those of the last right-hand side when it
    // was evaluated there (the usual case at the end of a step), else evaluated now.
    const Dynamics& dynamics_at(double time, const double* state);
    const BaseKinematics& base_kinematics_at_time(double time) { return base_at(time); }
    // At an exact equilibrium under constant inputs the solution stays put (it is unique): a step
    // needs no integration. True if the base does not move and every state derivative is exactly 0.
    bool at_rest(double time, const double* state);
    const StepInputs& inputs() const { return inputs_; }
    const Modes& modes() const { return modes_; }
    const EventCounters& counters() const { return counters_; }
    // For rolling a failed step back.
    void restore(const Modes& modes, const EventCounters& counters) {
        modes_ = modes, counters_ = counters;
        cache_valid_ = false;
    }

private:
    const BaseKinematics& base_at(double time);

    const ModelParameters& params_;
    // The switching elements present (registered in element_registry.cpp).
    SwitchingElementSet elements_;
    bool inputs_held_ = false;
    StepInputs inputs_;
    BaseKinematics base_;
    double base_time_ = 0.0;
    bool base_cached_ = false;
    bool base_constant_ = false;
    AttitudeTrig arc_start_trig_;  // of the attitude where the inputs' constant-acceleration arc starts
    Modes modes_;
    Modes previous_modes_;  // before the last update_modes, for the event log
    EventCounters counters_;
    // The last evaluated dynamics and where: the event functions and outputs at the end of a step reuse
    // the right-hand side's work instead of evaluating the dynamics again.
    Dynamics cache_;
    double cache_time_ = 0.0;
    double cache_state_[kMaxStateSize];
    bool cache_valid_ = false;
};

}  // namespace gimbal
