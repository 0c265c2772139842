// One simulation instance: the variable values, the constant model built from them, the state, the
// hybrid system and its integrator (Pinocchio-style split: ModelParameters is constant during a run,
// the rest is per-run data).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "gimbal/gimbal_c_api.h"
#include "gimbal/gimbal_hybrid_system.hpp"
#include "gimbal/integrator.hpp"
#include "gimbal/linearization.hpp"
#include "gimbal/variables.hpp"

namespace gimbal {

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
    GimbalStatus set_input_derivative(unsigned vr, int order, double value);

    // Everything a rollback needs, as plain bytes (fmi2GetFMUstate / serialization). Saving ends the
    // current integration segment: the next step restarts the integrator, so that a rollback to this
    // point replays bit for bit.
    // A snapshot from elsewhere (a deserialized blob) is range-checked field by field: restore()
    // refuses a bad one with the reason and leaves the instance as it was.
    static std::size_t snapshot_size();
    void save(void* buffer);
    GimbalStatus check_snapshot(const char* function, const void* buffer, bool& initialized) const;
    GimbalStatus restore(const void* buffer);
    GimbalStatus do_step(double current_time, double step_size);
    // Work of one fmi2DoStep, in right-hand-side evaluations, beyond which the step is reported
    // (about 25 ms of CPU at the measured 230 ns per evaluation: 5,000 times the default scene's).
    static constexpr long kStepWorkBudget = 100000;
    double time() const { return time_; }
    // The continuous model linearized at the current time and state, with the inputs as last set.
    GimbalStatus linearize(LinearModel& model);

private:
    StepInputs read_step_inputs(double step_start) const;
    bool build_parameters(ModelParameters& params, std::string& error) const;
    void load_start_state();
    GimbalStatus check_fixed_base(const char* function) const;
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
    };
    GimbalStatus integrate_step(double current_time, double step_size, StepStart& start);
    void roll_back(const StepStart& start);
    GimbalStatus report_step_work(double step_size, const IntegratorStatistics& before, const EventCounters& events_before);
    void apply_master_tolerance();
    // Before initialization ends, calculated outputs follow from the start values on request.
    GimbalStatus preview_outputs(const char* function, const char* name);
    void publish_outputs();
    GimbalStatus refuse(GimbalStatus status, const std::string& message) const;

    Logger logger_;
    LogFilter log_filter_;
    double reals_[kRealVariableCount];
    int integers_[kIntegerVariableCount];
    bool booleans_[kBooleanVariableCount];
    ModelParameters params_;
    double state_[kMaxStateSize];
    std::unique_ptr<GimbalHybridSystem> system_;
    std::unique_ptr<HybridIntegrator> integrator_;
    bool integrator_running_ = false;  // false: the next step must restart the integrator
    bool preview_current_ = false;
    bool at_rest_ = false;             // exact equilibrium under the running inputs: steps need no integration
    std::string last_integrator_error_;
    double voltage_rate_[2] = {0.0, 0.0};  // for the next step only
    double time_ = 0.0;
    // The model runs on time since initialization: results do not depend on where the master's clock
    // starts, and event times keep their resolution at large start times.
    double epoch_ = 0.0;
    double model_time(double time) const { return time - epoch_; }
    bool master_tolerance_defined_ = false;
    double master_tolerance_ = 0.0;
    bool rtol_set_ = false;            // solver.rtol set by the user: the master's tolerance does not apply
    std::int64_t steps_over_budget_ = 0;
};

}  // namespace gimbal
