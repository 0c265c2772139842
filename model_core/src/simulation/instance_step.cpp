// GimbalInstance's communication step (fmi2DoStep, FMI 3.0's early return): its checks, the inputs
// handed to the hybrid system and the integrator, the integration, the outputs published, and the
// rollback of a step that fails.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/hot_path.hpp"
#include "gimbal/simulation/step_checks.hpp"
#include "gimbal/simulation/step_inputs.hpp"

namespace gimbal {

GimbalStatus GimbalInstance::do_step(double current_time, double step_size) {
    double reached = 0.0;
    return advance_step(current_time, step_size, nullptr, reached);
}

GimbalStatus GimbalInstance::do_step_until_mode_change(double current_time, double step_size, double& reached) {
    return advance_step(current_time, step_size, &reached, reached);
}

GimbalStatus GimbalInstance::do_step_with_early_return(double current_time, double step_size, double& elapsed) {
    const double clock_at_start = run_.clock;
    double end = current_time;
    const GimbalStatus status = do_step_until_mode_change(current_time, step_size, end);
    // The clock moved by step_size itself when the step was not cut short.
    elapsed = run_.clock == clock_at_start + step_size ? step_size : run_.clock - clock_at_start;
    return status;
}

GimbalStatus GimbalInstance::advance_step(double current_time, double step_size, double* early, double& reached) {
    if (!run_.integrator) return refuse(GIMBAL_ERROR, "the instance is not initialized");
    if (run_.continuous_time) return refuse(GIMBAL_ERROR, "the instance serves the continuous-time interface");
    StepStart start;
    std::copy(run_.state, run_.state + kMaxStateSize, start.state);
    start.modes = run_.system->modes();
    start.counters = run_.system->counters();
    start.work = run_.integrator->statistics();
    start.time = run_.time;
    start.clock = run_.clock;
    GimbalStatus status;
    try {
        status = integrate_step(current_time, step_size, start, early);
    } catch (...) {
        // A C++ exception (out of memory while formatting a message, say) must not leave a half-taken step.
        roll_back(start);
        throw;
    }
    reached = run_.time;
    if (status != GIMBAL_OK) return status;
    return report_step_work(step_size, start.work, start.counters);
}

void GimbalInstance::roll_back(const StepStart& start) {
    std::copy(start.state, start.state + kMaxStateSize, run_.state);
    run_.system->restore(start.modes, start.counters);
    if (start.outputs_saved) {
        std::copy(start.reals, start.reals + kRealVariableCount, run_.reals);
        std::copy(start.integers, start.integers + kIntegerVariableCount, run_.integers);
    }
    run_.time = start.time;
    run_.clock = start.clock;
    run_.integrator_running = false;
    run_.at_rest = false;
}

// A step that costs far more than the model usually needs is reported once in a while (StepWorkMonitor).
GimbalStatus GimbalInstance::report_step_work(double step_size, const IntegratorStatistics& before,
                                              const EventCounters& events_before) {
    const IntegratorStatistics after = run_.integrator->statistics();
    if (after.rhs_evaluations - before.rhs_evaluations <= kStepWorkBudget) return GIMBAL_OK;  // every doStep
    const StepWork work{run_.time, step_size, before, after, run_.system->counters().total - events_before.total};
    std::string report;
    if (!run_.step_work.over_budget(work, model_.params, report)) return GIMBAL_OK;
    if (!report.empty()) logger_(GIMBAL_WARNING, "logStatusWarning", report);
    return GIMBAL_WARNING;
}

// Before a step: a fixed base has no motion, and the real-time method's substeps must resolve the
// gears' contact oscillations (simulation/step_checks.hpp).
GIMBAL_HOT_PART GimbalStatus GimbalInstance::check_step(double step_size) {
    const GimbalStatus base_status = check_fixed_base();
    if (base_status != GIMBAL_OK) return base_status;
    if (model_.params.method != static_cast<int>(IntegrationMethod::real_time)) return GIMBAL_OK;
    return check_real_time_resolution(step_size);
}

// Out of line: its message buffer stays out of integrate_step's frame.
GimbalStatus GimbalInstance::check_real_time_resolution(double step_size) {
    std::string why;
    if (real_time_resolution_ok(model_.params, run_.system->dynamics_at(run_.clock, run_.state), step_size, why))
        return GIMBAL_OK;
    return refuse(GIMBAL_ERROR, why);
}

// The inputs of the step from step_start handed to the hybrid system and the integrator. The
// right-hand side is continuous across the step boundary only if the held voltages are the same and
// the base motion continues the running constant-acceleration arc; otherwise the integrator restarts.
// `resting`: an exact equilibrium continues under the same inputs, and the step needs no integration.
GIMBAL_HOT_PART GimbalStatus GimbalInstance::take_step_inputs(double step_start, bool& resting) {
    StepInputs inputs = read_step_inputs(step_start);
    const StepInputs& running = run_.system->inputs();
    const bool continuous = run_.integrator_running && continues_running_inputs(running, inputs, step_start);
    resting = continuous && run_.at_rest && inputs.voltage_rate[0] == 0.0 && inputs.voltage_rate[1] == 0.0;
    if (resting) return GIMBAL_OK;
    run_.at_rest = false;
    if (!continuous) {
        run_.system->set_inputs(inputs);
        // New inputs may cross a switching surface at once (e.g. the voltage reverses while limited).
        run_.system->update_modes(step_start, run_.state, nullptr);
        if (!run_.integrator->restart(step_start, run_.state))
            return refuse(GIMBAL_ERROR, "the integrator could not be restarted");
        return GIMBAL_OK;
    }
    if (!voltages_changed(running, inputs)) return GIMBAL_OK;
    // The right-hand side does not jump: keep the integrator's history, follow the new ramps.
    inputs.base = running.base.advanced(step_start - running.step_start_time);
    run_.system->set_inputs(inputs);
    if (!run_.integrator->inputs_changed(step_start, run_.state))
        return refuse(GIMBAL_ERROR, "the integrator could not take the new inputs (" + run_.last_integrator_error + ")");
    return GIMBAL_OK;
}

// The instance's clock at the end of an integrated step (or where it ended early, at the first mode
// change: the inputs are then left as the step carried them there).
GIMBAL_HOT_PART void GimbalInstance::end_step_at(double step_end, double reached_model_time, bool ended_early) {
    if (ended_early) {
        carry_inputs_to(run_.system->inputs(), reached_model_time, model_.params.fidelity.fixed_base, run_.reals);
        run_.clock = reached_model_time;
        run_.time = run_.epoch + run_.clock;
        run_.at_rest = false;
    } else {
        run_.voltage_rate[0] = run_.voltage_rate[1] = 0.0;  // input derivatives hold for one step
        run_.at_rest = run_.system->at_rest(step_end, run_.state);
        run_.clock = step_end;
        run_.time = run_.epoch + run_.clock;
    }
}

// Finite states can still give non-finite outputs from absurd inputs (a base velocity of 1e300
// makes the kinetic energy overflow): refuse rather than hand out garbage.
GIMBAL_HOT_PART GimbalStatus GimbalInstance::check_published_outputs(double current_time, const StepStart& start) {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(run_.reals[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " = " << run_.reals[vr] << " at t = " << run_.time
          << ": an input or parameter lies beyond what the model can represent; state rolled back to t = "
          << current_time;
        roll_back(start);
        return refuse(GIMBAL_ERROR, s.str());
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::integrate_step(double current_time, double step_size, StepStart& start, double* early) {
    const GimbalStatus ready = check_step(step_size);
    if (ready != GIMBAL_OK) return ready;
    // From the instance's own clock (the host's current_time was checked against its time by the
    // interface): any start time gives the same model times, bit for bit.
    const double step_start = run_.clock;
    const double step_end = run_.clock + step_size;
    bool resting = false;
    const GimbalStatus taken = take_step_inputs(step_start, resting);
    if (taken != GIMBAL_OK) return taken;
    if (resting) {
        run_.clock = step_end;
        run_.time = run_.epoch + run_.clock;  // outputs cannot change either
        return GIMBAL_OK;
    }
    run_.last_integrator_error.clear();
    double reached_model_time = step_end;
    const bool advanced = early != nullptr ? run_.integrator->advance_until_mode_change(step_end, run_.state, reached_model_time)
                                           : run_.integrator->advance(step_end, run_.state);
    if (!advanced) {
        roll_back(start);
        std::ostringstream s;
        s.precision(17);
        s << "integration from t = " << current_time << " over h = " << step_size << " failed ("
          << run_.last_integrator_error << "); state rolled back to t = " << current_time;
        return refuse(GIMBAL_DISCARD, s.str());
    }
    run_.integrator_running = true;
    // Only now is there anything to undo in the published values (a step at rest publishes nothing).
    std::copy(run_.reals, run_.reals + kRealVariableCount, start.reals);
    std::copy(run_.integers, run_.integers + kIntegerVariableCount, start.integers);
    start.outputs_saved = true;
    end_step_at(step_end, reached_model_time, early != nullptr && reached_model_time < step_end);
    publish_outputs();
    return check_published_outputs(current_time, start);
}

}  // namespace gimbal
