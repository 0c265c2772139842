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

GimbalStatus GimbalInstance::advance_step(double current_time, double step_size, double* early, double& reached) {
    if (!integrator_) return refuse(GIMBAL_ERROR, "the instance is not initialized");
    if (continuous_time_) return refuse(GIMBAL_ERROR, "the instance serves the continuous-time interface");
    StepStart start;
    std::copy(state_, state_ + kMaxStateSize, start.state);
    start.modes = system_->modes();
    start.counters = system_->counters();
    start.work = integrator_->statistics();
    start.time = time_;
    start.clock = clock_;
    GimbalStatus status;
    try {
        status = integrate_step(current_time, step_size, start, early);
    } catch (...) {
        // A C++ exception (out of memory while formatting a message, say) must not leave a half-taken step.
        roll_back(start);
        throw;
    }
    reached = time_;
    if (status != GIMBAL_OK) return status;
    return report_step_work(step_size, start.work, start.counters);
}

void GimbalInstance::roll_back(const StepStart& start) {
    std::copy(start.state, start.state + kMaxStateSize, state_);
    system_->restore(start.modes, start.counters);
    if (start.outputs_saved) {
        std::copy(start.reals, start.reals + kRealVariableCount, reals_);
        std::copy(start.integers, start.integers + kIntegerVariableCount, integers_);
    }
    time_ = start.time;
    clock_ = start.clock;
    integrator_running_ = false;
    at_rest_ = false;
}

// A step that costs far more than the model usually needs is reported once in a while (StepWorkMonitor).
GimbalStatus GimbalInstance::report_step_work(double step_size, const IntegratorStatistics& before,
                                              const EventCounters& events_before) {
    const IntegratorStatistics after = integrator_->statistics();
    if (after.rhs_evaluations - before.rhs_evaluations <= kStepWorkBudget) return GIMBAL_OK;  // every doStep
    const StepWork work{time_, step_size, before, after, system_->counters().total - events_before.total};
    std::string report;
    if (!step_work_.over_budget(work, params_, report)) return GIMBAL_OK;
    if (!report.empty()) logger_(GIMBAL_WARNING, "logStatusWarning", report);
    return GIMBAL_WARNING;
}

// Before a step: a fixed base has no motion, and the real-time method's substeps must resolve the
// gears' contact oscillations (simulation/step_checks.hpp).
GIMBAL_HOT_PART GimbalStatus GimbalInstance::check_step(double step_size) {
    const GimbalStatus base_status = check_fixed_base();
    if (base_status != GIMBAL_OK) return base_status;
    if (params_.method != static_cast<int>(IntegrationMethod::real_time)) return GIMBAL_OK;
    return check_real_time_resolution(step_size);
}

// Out of line: its message buffer stays out of integrate_step's frame.
GimbalStatus GimbalInstance::check_real_time_resolution(double step_size) {
    std::string why;
    if (real_time_resolution_ok(params_, system_->dynamics_at(clock_, state_), step_size, why)) return GIMBAL_OK;
    return refuse(GIMBAL_ERROR, why);
}

// The inputs of the step from step_start handed to the hybrid system and the integrator. The
// right-hand side is continuous across the step boundary only if the held voltages are the same and
// the base motion continues the running constant-acceleration arc; otherwise the integrator restarts.
// `resting`: an exact equilibrium continues under the same inputs, and the step needs no integration.
GIMBAL_HOT_PART GimbalStatus GimbalInstance::take_step_inputs(double step_start, bool& resting) {
    StepInputs inputs = read_step_inputs(step_start);
    const StepInputs& running = system_->inputs();
    const bool continuous = integrator_running_ && continues_running_inputs(running, inputs, step_start);
    resting = continuous && at_rest_ && inputs.voltage_rate[0] == 0.0 && inputs.voltage_rate[1] == 0.0;
    if (resting) return GIMBAL_OK;
    at_rest_ = false;
    if (!continuous) {
        system_->set_inputs(inputs);
        // New inputs may cross a switching surface at once (e.g. the voltage reverses while limited).
        system_->update_modes(step_start, state_, nullptr);
        if (!integrator_->restart(step_start, state_)) return refuse(GIMBAL_ERROR, "the integrator could not be restarted");
        return GIMBAL_OK;
    }
    if (!voltages_changed(running, inputs)) return GIMBAL_OK;
    // The right-hand side does not jump: keep the integrator's history, follow the new ramps.
    inputs.base = running.base.advanced(step_start - running.step_start_time);
    system_->set_inputs(inputs);
    if (!integrator_->inputs_changed(step_start, state_))
        return refuse(GIMBAL_ERROR, "the integrator could not take the new inputs (" + last_integrator_error_ + ")");
    return GIMBAL_OK;
}

// The instance's clock at the end of an integrated step (or where it ended early, at the first mode
// change: the inputs are then left as the step carried them there).
GIMBAL_HOT_PART void GimbalInstance::end_step_at(double step_end, double reached_model_time, bool ended_early) {
    if (ended_early) {
        carry_inputs_to(system_->inputs(), reached_model_time, params_.fidelity.fixed_base, reals_);
        clock_ = reached_model_time;
        time_ = epoch_ + clock_;
        at_rest_ = false;
    } else {
        voltage_rate_[0] = voltage_rate_[1] = 0.0;  // input derivatives hold for one step
        at_rest_ = system_->at_rest(step_end, state_);
        clock_ = step_end;
        time_ = epoch_ + clock_;
    }
}

// Finite states can still give non-finite outputs from absurd inputs (a base velocity of 1e300
// makes the kinetic energy overflow): refuse rather than hand out garbage.
GIMBAL_HOT_PART GimbalStatus GimbalInstance::check_published_outputs(double current_time, const StepStart& start) {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(reals_[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " = " << reals_[vr] << " at t = " << time_
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
    const double step_start = clock_;
    const double step_end = clock_ + step_size;
    bool resting = false;
    const GimbalStatus taken = take_step_inputs(step_start, resting);
    if (taken != GIMBAL_OK) return taken;
    if (resting) {
        clock_ = step_end;
        time_ = epoch_ + clock_;  // outputs cannot change either
        return GIMBAL_OK;
    }
    last_integrator_error_.clear();
    double reached_model_time = step_end;
    const bool advanced = early != nullptr ? integrator_->advance_until_mode_change(step_end, state_, reached_model_time)
                                           : integrator_->advance(step_end, state_);
    if (!advanced) {
        roll_back(start);
        std::ostringstream s;
        s.precision(17);
        s << "integration from t = " << current_time << " over h = " << step_size << " failed ("
          << last_integrator_error_ << "); state rolled back to t = " << current_time;
        return refuse(GIMBAL_DISCARD, s.str());
    }
    integrator_running_ = true;
    // Only now is there anything to undo in the published values (a step at rest publishes nothing).
    std::copy(reals_, reals_ + kRealVariableCount, start.reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, start.integers);
    start.outputs_saved = true;
    end_step_at(step_end, reached_model_time, early != nullptr && reached_model_time < step_end);
    publish_outputs();
    return check_published_outputs(current_time, start);
}

}  // namespace gimbal
