// One simulation instance, split as Pinocchio splits a robot: an InstanceModel, constant through a
// run (the built parameters and what follows from them alone), and a RunData, everything a run
// changes (the variable values, the state, the hybrid system and its integrator, the clocks, the
// continuous-time interface's event memory). The instance holds one of each, and the host's logger.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/hybrid_system/event_handling.hpp"
#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/simulation/instance_outputs.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "gimbal/simulation/linearization.hpp"
#include "gimbal/simulation/step_checks.hpp"
#include "gimbal/model/variable_groups.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

struct SnapshotContent;  // gimbal/simulation/snapshot.hpp

// Which of the 19 continuous states (kContinuousStateCount, the FMU's order) a fidelity integrates,
// and where each lives in the state vector.
struct IntegratedStates {
    int count = 0;
    int state[kContinuousStateCount] = {};  // index among the 19 states
    int slot[kContinuousStateCount] = {};   // its slot in RunData::state
};
IntegratedStates integrated_states_of(const StateLayout& layout);

// What is fixed once the parameters are built: constant during a run. Built whole from the variable
// values at initialization (and a preview before it), or from a snapshot at a restore, and put in
// place whole (ModelSwap, parameter_swap.hpp). The fidelity and the state layout are
// params.fidelity and params.layout.
struct InstanceModel {
    ModelParameters params;
    IntegratedStates integrated;
};
InstanceModel make_instance_model(const ModelParameters& params);

// Everything a run changes, from the host's set values to the integrator's memory.
struct RunData {
    static constexpr int kIndicatorCount = GimbalHybridSystem::kIndicatorCount;

    // The variable values: set by the host (parameters, inputs, start values), published by the
    // model (outputs).
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    bool booleans[kBooleanVariableCount];
    double state[kMaxStateSize];
    // Made at initialization (and restore) with a reference to InstanceModel::params: the current
    // modes, inputs, event counters and dynamics cache, and the integrator working on them.
    std::unique_ptr<GimbalHybridSystem> system;
    std::unique_ptr<HybridIntegrator> integrator;
    bool integrator_running = false;  // false: the next step must restart the integrator
    bool preview_current = false;
    bool at_rest = false;             // exact equilibrium under the running inputs: steps need no integration
    std::string last_integrator_error;
    double voltage_rate[2] = {0.0, 0.0};  // for the next step only
    double time = 0.0;  // the host's time of the current point: epoch + clock
    // The model runs on its own clock, the time since initialization: results do not depend on where
    // the host's clock starts, and event times keep their resolution at large start times. A step
    // advances it by communicationStepSize (never by differences of the host's times, which lose the
    // step's low bits at a large start time); in the continuous-time interface the host owns time and
    // clock is its time less the start.
    double epoch = 0.0;
    double clock = 0.0;
    bool master_tolerance_defined = false;
    double master_tolerance = 0.0;
    bool rtol_set = false;            // solver.rtol set by the user: the master's tolerance does not apply
    StepWorkMonitor step_work;

    // Continuous-time interface state (saved with an FMU state).
    bool continuous_time = false;  // chosen once, before initialization; reset() keeps it
    bool inputs_stale = true;      // an input was set since the hybrid system last took them
    bool outputs_stale = true;     // time, state or inputs changed since outputs were published
    bool decided_here = false;     // update_discrete_states ran at this very point: a repeat changes nothing
    double reference_guards[kIndicatorCount] = {};  // guards as decided at the last update (crossings are
                                                    // measured against them)
    std::int8_t decided_side[kIndicatorCount] = {}; // side a guard exactly on zero was decided for
    ChatteringMemory chattering;      // model times
    GuardSettling guard_settling;
    double preview_states[kContinuousStateCount] = {};      // at the start values, before initialization
    double preview_rotor_start[4] = {};                      // where the rotors start (kRotorStart order)
    double preview_indicators[kIndicatorCount] = {};
    std::int64_t zeno_holds = 0;
};

class GimbalInstance {
public:
    using Logger = std::function<void(GimbalStatus, const char* category, const std::string& message)>;

    using LogFilter = std::function<bool(const char* category)>;

    GimbalInstance(Logger logger, LogFilter filter);
    GimbalInstance(const GimbalInstance&) = delete;
    GimbalInstance& operator=(const GimbalInstance&) = delete;

    void reset();
    GimbalStatus set_real(unsigned vr, double value);
    GimbalStatus get_real(unsigned vr, double& value);
    GimbalStatus set_integer(unsigned vr, int value);
    GimbalStatus get_integer(unsigned vr, int& value);
    GimbalStatus set_boolean(unsigned vr, bool value);
    GimbalStatus get_boolean(unsigned vr, bool& value) const;
    // fmi2SetupExperiment's tolerance: becomes solver.rtol at initialization unless solver.rtol was set.
    void set_master_tolerance(bool defined, double tolerance);
    GimbalStatus initialize(double start_time);
    // fmi2SetRealInputDerivatives: the voltages may ramp over the next step (order 1 only).
    // All or nothing.
    GimbalStatus set_reals(const unsigned* vr, std::size_t count, const double* values);
    GimbalStatus set_input_derivative(unsigned vr, int order, double value);

    // Everything a rollback needs, as plain bytes (fmi2GetFMUstate / serialization). Saving ends the
    // current integration segment: the next step restarts the integrator, so that a rollback to this
    // point replays bit for bit.
    // A snapshot from elsewhere (a deserialized blob) is range-checked field by field: restore()
    // refuses a bad one with the reason and leaves the instance as it was.
    static std::size_t snapshot_size();
    void save(void* buffer);
    GimbalStatus check_snapshot(const void* buffer, bool& initialized) const;
    GimbalStatus restore(const void* buffer);
    GimbalStatus do_step(double current_time, double step_size);
    // A step that may end early, right after the first mode change (FMI 3.0's early return): *reached
    // is the time it ended at. The inputs are then left as the step carried them there (the carrier's
    // arc, a voltage ramp), so that the next step continues the same problem.
    GimbalStatus do_step_until_mode_change(double current_time, double step_size, double& reached);
    // The same step, told how far it went on the model's own clock: `elapsed` is step_size when it did not
    // end early, so that current_time + elapsed is the host's time where it ended (the C interface's and
    // the FMU's early return).
    GimbalStatus do_step_with_early_return(double current_time, double step_size, double& elapsed);
    // Work of one fmi2DoStep, in right-hand-side evaluations, beyond which the step is reported
    // (simulation/step_checks.hpp).
    static constexpr long kStepWorkBudget = gimbal::kStepWorkBudget;
    double time() const { return run_.time; }
    double model_clock() const { return run_.clock; }  // the time since initialization
    bool initialized() const { return run_.system != nullptr && run_.integrator != nullptr; }
    // The continuous model linearized at the current time and state, with the inputs as last set.
    GimbalStatus linearize(LinearModel& model);

    // ---- The continuous-time interface (Model Exchange; gimbal_instance_continuous.cpp) ----
    // The host integrates: it sets the time, the states and the inputs, reads derivatives and event
    // indicators, and calls update_discrete_states() where an indicator crossed zero (or an input
    // jumped, or the time event it was given came). Chosen once, before initialization.
    void use_continuous_time_interface() { run_.continuous_time = true; }
    bool continuous_time_interface() const { return run_.continuous_time; }
    static constexpr int kStateCount = kContinuousStateCount;
    static constexpr int kIndicatorCount = GimbalHybridSystem::kIndicatorCount;
    struct DiscreteUpdate {
        bool states_changed = false;      // a transition moved the state (onto a stop, a limit)
        bool next_time_defined = false;   // the chattering guard holds the modes until next_time
        double next_time = 0.0;
        int mode_changes = 0;
    };
    GimbalStatus set_time(double time);
    GimbalStatus set_continuous_states(const double* states);
    void get_continuous_states(double* states);
    void get_nominal_states(double* nominals) const;
    GimbalStatus get_derivatives(double* derivatives);
    GimbalStatus get_event_indicators(double* indicators);
    // Before initialization ends: the states and indicators at the start values (the FMU's part of
    // initialization mode), computed as the outputs are previewed then.
    GimbalStatus preview_continuous(double* states, double* indicators);
    GimbalStatus update_discrete_states(DiscreteUpdate& update);
    // d(unknowns)/d(knowns) . seed at the current point, within the modes in force: unknowns are state
    // derivatives or outputs, knowns continuous states or inputs (Real value references). The
    // derivatives' dependence on the integrated states comes from the analytic Jacobian, the rest from
    // central differences.
    GimbalStatus directional_derivative(const unsigned* unknowns, std::size_t unknown_count, const unsigned* knowns,
                                        std::size_t known_count, const double* seed, double* result);

private:
    // The snapshot (gimbal/simulation/snapshot.hpp walks its table of fields): what only an initialized instance
    // saves, a snapshot decoded and checked, and the run it describes rebuilt aside.
    void save_run(SnapshotContent& snap);
    GimbalStatus read_snapshot(const void* buffer, SnapshotContent& snap) const;
    GimbalStatus rebuild_run(const SnapshotContent& snap, std::unique_ptr<GimbalHybridSystem>& system,
                             std::unique_ptr<HybridIntegrator>& integrator);
    StepInputs read_step_inputs(double step_start) const;
    bool build_parameters(ModelParameters& params, std::string& error) const;
    void load_start_state();
    void rotor_in_mesh(int axis, double& angle, double& rate) const;
    void report_gear_starts() const;
    GimbalStatus check_fixed_base() const;
    std::unique_ptr<HybridIntegrator> make_integrator(GimbalHybridSystem& system, const ModelParameters& params);
    void create_integrator();
    // What a failed or interrupted step returns to.
    struct StepStart {
        double state[kMaxStateSize];
        Modes modes;
        EventCounters counters;
        IntegratorStatistics work;
        double reals[kRealVariableCount];  // the published values, once the step is about to change them
        int integers[kIntegerVariableCount];
        bool outputs_saved = false;
        double time;
        double clock;
    };
    GimbalStatus integrate_step(double current_time, double step_size, StepStart& start, double* early = nullptr);
    // The parts of a step: its checks, its inputs, its end, its outputs' check (inline, defined in
    // simulation/instance_step.cpp, the only place they are called).
    inline GimbalStatus check_step(double step_size);
    GimbalStatus check_real_time_resolution(double step_size);
    inline GimbalStatus take_step_inputs(double step_start, bool& resting);
    inline void end_step_at(double step_end, double reached_model_time, bool ended_early);
    inline GimbalStatus check_published_outputs(double current_time, const StepStart& start);
    GimbalStatus check_initial_outputs();
    GimbalStatus advance_step(double current_time, double step_size, double* early, double& reached);
    void roll_back(const StepStart& start);
    GimbalStatus report_step_work(double step_size, const IntegratorStatistics& before, const EventCounters& events_before);
    void apply_master_tolerance();
    // Before initialization ends, calculated outputs follow from the start values on request.
    GimbalStatus preview_outputs(const char* name);
    void publish_outputs() {
        gimbal::publish_outputs(OutputPoint{model_.params, *run_.system, *run_.integrator, run_.state, run_.clock,
                                            run_.epoch, run_.zeno_holds},
                                run_.reals, run_.integers);
    }
    GimbalStatus refuse(GimbalStatus status, const std::string& message) const;
    // Pushes inputs set since the last evaluation into the hybrid system.
    void refresh_held_inputs();
    void log_event(const std::string& message) const { logger_(GIMBAL_OK, "logEvents", message); }
    // The outputs at the point the host set; refused (and the last good ones kept) where the states or
    // inputs set make one of them non-finite.
    GimbalStatus publish_continuous_time_outputs();
    // update_discrete_states' settling of the guards left exactly on zero; the mode changes it made.
    int settle_guards(double now, int n, const int* directions, const HybridIntegrator::MessageSink& sink);
    // The parts of directional_derivative: the knowns' seeds, the unknowns' Jacobian rows, the part the
    // Jacobian answers.
    GimbalStatus seed_knowns(const unsigned* knowns, std::size_t known_count, const double* seed, double* state_seed,
                             std::vector<std::pair<unsigned, double>>& input_seed) const;
    GimbalStatus jacobian_rows(const unsigned* unknowns, std::size_t unknown_count, std::vector<int>& jacobian_row,
                               bool& all_rows_analytic) const;
    GimbalStatus jacobian_part(const std::vector<int>& jacobian_row, const double* state_seed, double* result,
                               bool& used);
    bool difference_step(const double* state_seed, const std::vector<std::pair<unsigned, double>>& input_seed,
                         double& step);
    // d(unknowns)/d(states, inputs) . seed by one central difference (two evaluations), the point restored.
    GimbalStatus central_difference(const unsigned* unknowns, std::size_t unknown_count, const double* state_seed,
                                    const std::vector<std::pair<unsigned, double>>& input_seed, double* result);

    // The host's connection, fixed for the instance's life: where messages go, which are wanted, and
    // the chattering guard's limits with the filter of event messages.
    Logger logger_;
    LogFilter log_filter_;
    EventHandlingSettings event_settings_;
    InstanceModel model_;
    RunData run_;
};

}  // namespace gimbal
