// The one-step integrators' driver: construction, the current point (its derivative, its guards,
// their settling after a mode change), restarts, and the two loops that advance to a communication
// point: advance_steps (adaptive step size, the method in force per step) and advance_fixed_substeps
// (the real-time method's fixed grid). The methods' steps, the automatic switch between them and the
// location of events have their own files beside this one (see one_step_integrator.hpp).
#include "one_step_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

namespace gimbal {
namespace {

// A step may be stretched by this fraction of itself to end on a communication point.
constexpr double kStretch = 0.1;

}  // namespace

OneStepIntegrator::OneStepIntegrator(HybridSystem& system, const IntegratorSettings& settings,
                                     MessageSink error_sink, MessageSink event_sink)
    : system_(system),
      settings_(settings),
      error_sink_(std::move(error_sink)),
      event_sink_(std::move(event_sink)),
      size_(system.state_size()),
      event_count_(system.event_count()),
      g_(event_count_, 0.0),
      g_new_(event_count_, 0.0),
      g_low_(event_count_, 0.0),
      g_high_(event_count_, 0.0),
      g_mid_(event_count_, 0.0),
      directions_(event_count_, 0) {
    const int n = std::min(size_, kMaxStates);
    for (Vector* v : {&y_, &f_, &y_new_, &f_new_, &stage_state_, &error_, &time_derivative_, &perturbed_})
        v->setZero(n);
    for (Vector& v : stage_) v.setZero(n);
    for (Vector& v : dense_) v.setZero(n);
    jacobian_.setZero(n, n);
    int position[kMaxStates], velocity[kMaxStates];
    const int pairs = system.kinematic_pairs(position, velocity);
    iteration_matrix_.set_structure(n, position, velocity, pairs);
    // The power iteration's start: uneven, as a uniform vector lies in the null space of, e.g., a
    // spring between two equal coordinates (J 1 = 0 there), and the estimate would read 0.
    double start_norm = 0.0;
    for (int i = 0; i < n; ++i) {
        power_iteration_start_[i] = 1.0 + std::fmod(0.6180339887 * (i + 1), 1.0);
        start_norm += power_iteration_start_[i] * power_iteration_start_[i];
    }
    for (int i = 0; i < n; ++i) power_iteration_start_[i] /= std::sqrt(start_norm);
    if (settings_.method == IntegrationMethod::rosenbrock || real_time()) memory_.stiff = 1;
    cost_ratio_ = rosenbrock_cost_ratio(size_, system.has_jacobian());
}

bool OneStepIntegrator::rhs(double time, const Vector& y, Vector& dy) {
    ++totals_.rhs_evaluations;
    return system_.derivative(time, y.data(), dy.data());
}

bool OneStepIntegrator::event_values(double time, const Vector& y, std::vector<double>& values) {
    return guards_at(time, y.data(), values.data());
}

bool OneStepIntegrator::guards_at(double time, const double* state, double* values) {
    if (event_count_ == 0) return true;
    system_.event_functions(time, state, values);
    for (int k = 0; k < event_count_; ++k) {
        if (std::isfinite(values[k])) continue;
        std::ostringstream s;
        s.precision(17);
        s << "event function " << k << " is not finite at t = " << time;
        error_sink_(s.str());
        return false;
    }
    return true;
}

bool OneStepIntegrator::refresh_at_current_point(const int* decided) {
    jacobian_current_ = false;
    const double lookahead = 1e-6 * (memory_.step_size > 0.0 ? memory_.step_size : 1e-6);
    int changes = 0;
    const bool settled = guard_settling_.settle(
        t_, y_.data(), size_, event_count_, lookahead, decided, f_.data(), g_.data(), changes,
        [this](double time, const double* state, double* derivative) {
            ++totals_.rhs_evaluations;
            if (system_.derivative(time, state, derivative)) return true;
            std::ostringstream s;
            s.precision(17);
            s << "the right-hand side is not finite at t = " << time;
            error_sink_(s.str());
            return false;
        },
        [this](double time, const double* state, double* values) { return guards_at(time, state, values); },
        [this](const int* directions) {
            return switch_modes(system_, t_, y_.data(), directions, settings_.event_handling, event_sink_, t_);
        });
    totals_.events += changes;
    return settled;
}

bool OneStepIntegrator::restart(double time, const double* state) {
    if (settings_.method == IntegrationMethod::automatic) {
        // An input jump. If RODAS4 ran all the way from the previous one, its mean step over the
        // interval, transient included, is the accuracy step it is remembered by: with inputs that jump
        // at every communication point, the transients can take most of its steps.
        if (memory_.steps_since_jump > 0 && time > memory_.jump_time) {
            memory_.accuracy_step = (time - memory_.jump_time) / memory_.steps_since_jump;
            memory_.accuracy_time = time;
        }
        memory_.jump_time = time;
        memory_.jump_step = memory_.step_size;
        memory_.steps_since_jump = memory_.stiff ? 0 : -1;
    }
    return start_at(time, state);
}

bool OneStepIntegrator::start_at(double time, const double* state) {
    if (size_ > kMaxStates) {
        error_sink_("the one-step integrators hold at most " + std::to_string(kMaxStates) + " states");
        return false;
    }
    t_ = time;
    for (int k = 0; k < size_; ++k) y_[k] = state[k];
    reused_lambda_age_ = -1;
    initialized_ = refresh_at_current_point();
    return initialized_;
}

bool OneStepIntegrator::resume(double time, const double* state, const IntegratorMemory& memory) {
    memory_ = memory;
    if (settings_.method == IntegrationMethod::rosenbrock || real_time()) memory_.stiff = 1;
    if (settings_.method == IntegrationMethod::dormand_prince) memory_.stiff = 0;
    return start_at(time, state);
}

double OneStepIntegrator::error_norm(const Vector& error, const Vector& y_old, const Vector& y_new) const {
    double sum = 0.0;
    for (int k = 0; k < size_; ++k) {
        const double scale = settings_.absolute_tolerance +
                             settings_.relative_tolerance * std::max(std::fabs(y_old[k]), std::fabs(y_new[k]));
        const double ratio = error[k] / scale;
        sum += ratio * ratio;
    }
    return std::sqrt(sum / size_);
}

// E. Hairer's starting step (HINIT of DOPRI5): from the sizes of y, f and an estimate of f'.
double OneStepIntegrator::initial_step(double end_time) {
    double limit = end_time - t_;
    if (settings_.max_step > 0.0) limit = std::min(limit, settings_.max_step);
    // The relaxing states' rates say nothing of the step (Dormand-Prince takes them exactly).
    relaxing_count_ = memory_.stiff ? 0 : system_.relaxing_states(relaxing_);
    double norm_y = 0.0, norm_f = 0.0;
    for (int k = 0; k < size_; ++k) {
        if (relaxing_count_ > 0 && relaxing(k)) continue;
        const double scale = settings_.absolute_tolerance + settings_.relative_tolerance * std::fabs(y_[k]);
        norm_y += (y_[k] / scale) * (y_[k] / scale);
        norm_f += (f_[k] / scale) * (f_[k] / scale);
    }
    norm_y = std::sqrt(norm_y / size_), norm_f = std::sqrt(norm_f / size_);
    double h = (norm_f <= 1e-5 || norm_y <= 1e-5) ? 1e-6 : 0.01 * norm_y / norm_f;
    h = std::min(h, limit);
    for (int k = 0; k < size_; ++k) stage_state_[k] = y_[k] + h * f_[k];
    if (!rhs(t_ + h, stage_state_, stage_[1])) return std::min(1e-6, limit);
    double second = 0.0;
    for (int k = 0; k < size_; ++k) {
        if (relaxing_count_ > 0 && relaxing(k)) continue;
        const double scale = settings_.absolute_tolerance + settings_.relative_tolerance * std::fabs(y_[k]);
        const double d = (stage_[1][k] - f_[k]) / scale;
        second += d * d;
    }
    second = std::sqrt(second / size_) / h;
    const double larger = std::max(second, norm_f);
    const double h1 = larger <= 1e-15 ? std::max(1e-6, h * 1e-3) : std::pow(0.01 / larger, 0.2);
    return std::min({100.0 * h, h1, limit});
}

bool OneStepIntegrator::advance(double end_time, double* state) {
    if (!initialized_) {
        error_sink_("the integrator was not started");
        return false;
    }
    // A failed advance leaves the controller where it was (the caller rolls the state back): a step
    // size shrunk to nothing on the way must not fail the next attempt from a healthy point.
    const IntegratorMemory at_start = memory_;
    // Not carried across communication points: a copy restored from an FMU state decides the same.
    reused_lambda_age_ = -1;
    if (real_time() ? advance_fixed_substeps(end_time, state) : advance_steps(end_time, state)) return true;
    memory_ = at_start;
    return false;
}

bool OneStepIntegrator::advance_until_mode_change(double end_time, double* state, double& reached) {
    stop_at_mode_change_ = true;
    const bool advanced = advance(end_time, state);
    stop_at_mode_change_ = false;
    reached = t_;
    return advanced;
}

// A few ulp left (an event located just short of the end): no step can be that short; move there with
// the derivative, which is exact to rounding over such a span.
bool OneStepIntegrator::creep_to(double end) {
    const double remaining = end - t_;
    for (int i = 0; i < size_; ++i) y_[i] += remaining * f_[i];
    t_ = end;
    return refresh_at_current_point();
}

// The accepted step's end becomes the current point; a chattering hold that ended there is lifted.
bool OneStepIntegrator::move_to_step_end() {
    t_ = t_new_;
    std::swap(y_, y_new_);
    std::swap(f_, f_new_);
    std::swap(g_, g_new_);
    return !(event_count_ > 0 && t_ >= memory_.chattering.dwell_until && memory_.chattering.dwell_until > -1e300) ||
           reselect_after_dwell();
}

bool OneStepIntegrator::refuse_failed_substep(int substeps) {
    std::ostringstream s;
    s.precision(17);
    s << "the real-time method's step from t = " << t_ << " to " << t_new_
      << " failed (a state or right-hand side not finite, or a singular iteration matrix): "
      << "solver.substeps = " << substeps << " is too few for this model";
    error_sink_(s.str());
    return false;
}

bool OneStepIntegrator::refuse_mode_change_bound(double end_time) {
    std::ostringstream s;
    s.precision(17);
    s << "more than " << settings_.mode_changes_per_step << " mode changes in the communication step "
      << "ending at t = " << end_time << " (the real-time method's bound: its work per step is "
      << "fixed, and switching later is not safe at a stiff contact); raise solver.substeps, or "
      << "model the gear without backlash if the scene does not need it";
    error_sink_(s.str());
    return false;
}

// RODAS4 over [t_, t_new_] with a fresh Jacobian, accepted whatever its error estimate; false (reported)
// when it cannot be taken.
GIMBAL_HOT_PART bool OneStepIntegrator::fixed_rosenbrock_step(int substeps) {
    if (!jacobian_at(t_, y_) || !time_derivative_at_current_point()) {
        error_sink_("the Jacobian or the right-hand side is not finite at t = " + std::to_string(t_));
        return false;
    }
    if (rosenbrock_step(t_new_ - t_, t_new_) != StepResult::accepted) return refuse_failed_substep(substeps);
    ++totals_.steps;
    return true;
}

// One substep of the real-time method toward grid_end: shorter where a chattering hold ends, or where
// a mode change is located inside it (a shorter one then finishes it).
GIMBAL_HOT_PART OneStepIntegrator::Substep OneStepIntegrator::real_time_substep(double grid_end, double end_time, int substeps,
                                                                std::int64_t& changes_here) {
    if (hold_ended() && !reselect_after_dwell()) return Substep::failed;
    const double smallest = 16.0 * kEpsilon * std::max(1.0, std::fabs(t_));
    const double remaining = grid_end - t_;
    if (remaining <= smallest) return creep_to(grid_end) ? Substep::grid_reached : Substep::failed;
    t_new_ = grid_end;
    cut_at_hold_end(smallest);
    if (!fixed_rosenbrock_step(substeps)) return Substep::failed;
    bool event_found = false;
    const std::int64_t events_before = totals_.events;
    if (!handle_events(event_found)) return Substep::failed;
    changes_here += totals_.events - events_before;
    if (settings_.mode_changes_per_step > 0 && changes_here > settings_.mode_changes_per_step) {
        refuse_mode_change_bound(end_time);
        return Substep::failed;
    }
    if (event_found)
        return stop_at_mode_change_ && totals_.events > events_before && t_ < end_time ? Substep::stopped
                                                                                       : Substep::taken;
    return move_to_step_end() ? Substep::taken : Substep::failed;
}

bool OneStepIntegrator::advance_fixed_substeps(double end_time, double* state) {
    // The grid is fixed by the communication step alone: a mode change located inside a substep ends
    // that step early, and a shorter one finishes it, so the work per communication step is bounded by
    // the substeps plus, per located mode change, its iterations and one step.
    const double start = t_;
    const int substeps = std::max(1, settings_.substeps);
    const double grid_step = (end_time - start) / substeps;
    std::int64_t changes_here = 0;
    bool stopped = false;
    for (int k = 1; k <= substeps && !stopped; ++k) {
        const double grid_end = k == substeps ? end_time : start + k * grid_step;
        while (t_ < grid_end) {
            const Substep outcome = real_time_substep(grid_end, end_time, substeps, changes_here);
            if (outcome == Substep::failed) return false;
            stopped = outcome == Substep::stopped;
            if (stopped || outcome == Substep::grid_reached) break;
        }
    }
    for (int i = 0; i < size_; ++i) state[i] = y_[i];
    return true;
}

bool OneStepIntegrator::refuse_step_limit(std::int64_t events_here) {
    std::ostringstream s;
    s.precision(17);
    s << "more than solver.max_steps = " << settings_.max_steps << " internal steps (" << events_here
      << " mode changes) before t = " << t_ << ": the inputs or parameters drive switching faster than "
      << "the model can follow";
    error_sink_(s.str());
    return false;
}

// The next step toward end_time from the controller's proposal; sets t_new_.
GIMBAL_HOT_PART OneStepIntegrator::StepPlan OneStepIntegrator::plan_step(double end_time) {
    StepPlan plan;
    if (memory_.step_size <= 0.0) memory_.step_size = initial_step(end_time);
    double h = memory_.step_size;
    if (settings_.max_step > 0.0) h = std::min(h, settings_.max_step);
    const double remaining = end_time - t_;
    // Equal steps to the end of the communication step, each at most 10 % longer than proposed (the
    // controller's safety factor absorbs that): a proposal just short of a divisor of the
    // communication step would otherwise cost a whole extra step.
    const double steps_left = std::max(1.0, std::ceil(remaining / h - kStretch));
    bool last = false;
    if (steps_left <= 1.0) {
        h = remaining, last = true;
    } else {
        h = remaining / steps_left;
    }
    const double smallest = 16.0 * kEpsilon * std::max(1.0, std::fabs(t_));
    if (remaining <= smallest) {
        plan.kind = StepPlan::creep;
        return plan;
    }
    if (h <= smallest) {
        std::ostringstream s;
        s.precision(17);
        s << "the step size fell to " << h << " at t = " << t_ << " (a right-hand side that is not finite, or "
          << "an accuracy the tolerances cannot reach)";
        error_sink_(s.str());
        plan.kind = StepPlan::failed;
        return plan;
    }
    t_new_ = last ? end_time : t_ + h;
    plan.cut_short = cut_at_hold_end(smallest) || last;
    plan.h = t_new_ - t_;
    return plan;
}

// One attempt over h to t_new_ by the method in force (RODAS4 with a current Jacobian while stiff).
// False when the Jacobian or the time derivative cannot be had.
GIMBAL_HOT_PART bool OneStepIntegrator::attempt_step(double h, StepResult& result) {
    if (memory_.stiff && !jacobian_current_) {
        if (!jacobian_at(t_, y_)) {
            error_sink_("the Jacobian is not finite");
            return false;
        }
        if (!time_derivative_at_current_point()) {
            error_sink_("the right-hand side is not finite just after t");
            return false;
        }
        jacobian_current_ = true;  // until the point or the modes change (a rejected step keeps it)
    }
    unresolved_layer_ = 0.0;
    result = memory_.stiff ? rosenbrock_step(h, t_new_) : dormand_prince_step(h, t_new_);
    if (result == StepResult::accepted && unresolved_layer_ > 1.0 && !real_time() && crosses_a_guard()) {
        // An event inside a boundary layer that only the filtered estimate let the step pass over (a
        // current limit reached within microseconds of a voltage jump): its time, and what the fast
        // state did before it, come from an interpolant the estimate did not check. The step is taken
        // again at the size the unfiltered estimate asks for, until the layer is resolved or the event
        // lies beyond the step.
        memory_.step_size = h * std::max(kMaxShrink, kSafety * std::pow(unresolved_layer_, -0.25));
        memory_.last_step_rejected = 1;
        result = StepResult::rejected;
    }
    return true;
}

// An accepted step: the controller's next proposal, the mode changes within it, and its end as the
// current point. `stop`: the integration stops at the mode change found (early return).
GIMBAL_HOT_PART bool OneStepIntegrator::accept_step(const StepPlan& plan, double end_time, std::int64_t& events_here, bool& stop) {
    ++totals_.steps;
    jacobian_current_ = false;
    // A step cut short to land on end_time or on the end of a hold says nothing against the longer
    // step proposed before it.
    memory_.step_size =
        plan.cut_short ? std::max(proposal_, std::min(memory_.step_size, proposal_ * kMaxGrowth)) : proposal_;
    bool event_found = false;
    const std::int64_t events_before = totals_.events;
    if (!handle_events(event_found)) return false;
    events_here += totals_.events - events_before;
    if (event_found) {
        stop = stop_at_mode_change_ && totals_.events > events_before && t_ < end_time;
        return true;
    }
    if (!move_to_step_end()) return false;
    // Judged at the step the Rosenbrock method proposes next, not the one just taken: right after an
    // input jump it takes a few short steps, at which any method would be stable.
    if (memory_.stiff) vote_on_stiffness_rosenbrock(plan.h);
    else vote_on_stiffness_explicit(plan.h, true);
    return true;
}

bool OneStepIntegrator::advance_steps(double end_time, double* state) {
    long attempts = 0;
    std::int64_t events_here = 0;
    while (t_ < end_time) {
        if (hold_ended() && !reselect_after_dwell()) return false;
        if (++attempts > settings_.max_steps) return refuse_step_limit(events_here);
        const StepPlan plan = plan_step(end_time);
        if (plan.kind == StepPlan::failed) return false;
        if (plan.kind == StepPlan::creep) {
            if (!creep_to(end_time)) return false;
            break;
        }
        StepResult result;
        if (!attempt_step(plan.h, result)) return false;
        if (result == StepResult::rejected) {
            ++totals_.rejected_steps;
            if (!memory_.stiff && std::isfinite(stiffness_estimate_)) vote_on_stiffness_explicit(plan.h, false);
            continue;
        }
        bool stop = false;
        if (!accept_step(plan, end_time, events_here, stop)) return false;
        if (stop) break;
    }
    for (int k = 0; k < size_; ++k) state[k] = y_[k];
    return true;
}

}  // namespace gimbal
