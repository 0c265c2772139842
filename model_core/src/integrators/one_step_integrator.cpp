#include <cstdint>
#include "one_step_integrator.hpp"

#include "gimbal/hybrid_system/event_handling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tableaus.hpp"

namespace gimbal {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Step size control (E. Hairer's DOPRI5 and RODAS defaults).
constexpr double kSafety = 0.9;
constexpr double kPiBeta = 0.04;                   // DOPRI5's stabilized (PI) controller
// A step may be stretched by this fraction of itself to end on a communication point.
constexpr double kStretch = 0.1;
constexpr double kMaxGrowth = 10.0, kMaxShrink = 0.2;  // per step, after an accepted / a rejected step
// Automatic method: explicit steps in a row at the stability boundary before the Rosenbrock method
// takes over, and Rosenbrock steps in a row at which the explicit method would be stable before it
// hands back. A few of each: a wrong vote costs one or two steps, a missed switch many.
constexpr int kVotesForStiff = 3, kVotesForNonstiff = 3;
// The explicit method counts as stable at |h lambda| below this (its boundary is ~3.3), with margin.
constexpr double kExplicitStableBound = 2.5;

// Automatic method: the work of one step of each method in right-hand-side equivalents, for the switch
// rule's predicted costs. Measured with callgrind (valgrind 3.19, g++ 12.2 -O3, gimbal_bench on 0.2 s
// of the ship scene with methods 5 and 6; instructions inclusive, per accepted step, over those of one
// GimbalHybridSystem::derivative: 1,745 at full fidelity, 1,558 reduced):
// - Dormand-Prince: dormand_prince_step + handle_events = 8.9 RHS at full fidelity (12 states), 8.4
//   reduced (4 states): 6 right-hand sides, the stage arithmetic, the error norm, the event functions.
// - RODAS4: rosenbrock_step + jacobian_at + time_derivative_at_current_point + handle_events = 24.9 RHS
//   at full fidelity, 16.8 reduced: 6 + 1 right-hand sides, the analytic Jacobian (6.4 and 5.9: mostly
//   the rigid body's, which does not shrink with the fidelity), the event functions, and the LU with 7
//   solves, which grow with the state size: 17,900 instructions besides the right-hand sides at 12
//   states, 4,500 at 4, i.e. 1.6 + 0.063 n^2 RHS. Fitted: 9.6 + 0.063 n^2 + the Jacobian.
// So RODAS4 costs 2.8 Dormand-Prince steps at full fidelity and 2.0 reduced: the ratio depends on the
// state size, and on the Jacobian (by differences it costs n right-hand sides; 6.2 is this model's
// analytic one).
constexpr double kExplicitStepCost = 8.7;
constexpr double kRosenbrockStepCostFixed = 9.6;       // 7 right-hand sides, the event functions, the rest
constexpr double kRosenbrockStepCostPerState2 = 0.063;  // LU and solves, per n^2
constexpr double kAnalyticJacobianCost = 6.2;
// Switch only when the other method is predicted cheaper by this factor: the prediction is rough (the
// stability limit from an estimate of |lambda_max|, the accuracy step from the last one seen) and a
// switch costs a Jacobian and a restarted controller. Measured (docs/benchmarks.md): 1.15, 1.3 and 1.5
// did equally well on the 25 random cases of scripts/random_cases.py (worst 1.009-1.012 times the
// better single method's work, in all 0.957-0.958 times), 1.5 with the fewest switches (539 against
// 551 and 587) and on the k_s = 1e8 variant the least work (1.3: 1.8 % more).
constexpr double kSwitchMargin = 1.5;
// While the explicit method runs at its stability limit it cannot see RODAS4's accuracy step: the last
// one seen is assumed to grow by this much per unit time (1 ms per second), so that an outdated short
// one cannot keep the explicit method forever; RODAS4 is then tried again and measures it. (0.01 made
// the explicit method hand over too early where its stable step is close to RODAS4's: a round trip
// every few milliseconds on the random cases.)
constexpr double kAccuracyStepGrowth = 0.001;
// An explicit step this far inside the stability region (h |lambda|, Hairer's estimate) was limited by
// accuracy: its proposal is the accuracy step.
constexpr double kAccuracyLimited = 0.5 * kExplicitStableBound;
// Bound on the explicit method's step at its stability limit times the estimate of |lambda_max|.
constexpr double kMaxStableProduct = 10.0;
// After an input jump both methods take short steps through the transient, growing them over tens of
// steps; until RODAS4's step is back to this fraction of the step before the jump, it neither votes
// nor is remembered: at such a step any method is stable, but the explicit method would meet its
// stability limit a few steps later, with only the transient's short steps to compare with.
constexpr double kSettledFraction = 0.5;
// Nor while its steps still grow by more than this per step (from the first step of a run, or after a
// switch, which restarts the step size controller).
constexpr double kSettledGrowth = 1.5;

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
    const double states = size_;
    cost_ratio_ = (kRosenbrockStepCostFixed + kRosenbrockStepCostPerState2 * states * states +
                   (system.has_jacobian() ? kAnalyticJacobianCost : states)) /
                  kExplicitStepCost;
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
        [this](const int* directions) { return switch_modes(system_, t_, y_.data(), directions, settings_, event_sink_, t_); });
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

OneStepIntegrator::StepResult OneStepIntegrator::dormand_prince_step(double h, double t_new) {
    using namespace tableau::dopri5;
    const int n = size_;
    Vector* k = stage_;
    k[0] = f_;
    // A relaxing state is not integrated: each stage and the step's end take its exact value, so neither
    // its rate (up to 1e10 1/s) nor its error limits the step.
    relaxing_count_ = system_.relaxing_states(relaxing_);
    for (int r = 0; r < relaxing_count_; ++r) relaxing_distance_[r] = relaxing_[r].source(y_.data()) - y_[relaxing_[r].index];
    auto stage = [&](int index, double c, auto&& combine) {
        for (int i = 0; i < n; ++i) stage_state_[i] = y_[i] + h * combine(i);
        place_relaxing_states(c - t_, stage_state_.data());
        return rhs(c, stage_state_, k[index]);
    };
    bool ok = stage(1, t_ + c2 * h, [&](int i) { return a21 * k[0][i]; }) &&
              stage(2, t_ + c3 * h, [&](int i) { return a31 * k[0][i] + a32 * k[1][i]; }) &&
              stage(3, t_ + c4 * h, [&](int i) { return a41 * k[0][i] + a42 * k[1][i] + a43 * k[2][i]; }) &&
              stage(4, t_ + c5 * h,
                    [&](int i) { return a51 * k[0][i] + a52 * k[1][i] + a53 * k[2][i] + a54 * k[3][i]; }) &&
              stage(5, t_new, [&](int i) {
                  return a61 * k[0][i] + a62 * k[1][i] + a63 * k[2][i] + a64 * k[3][i] + a65 * k[4][i];
              });
    // stage_state_ now holds the argument of the sixth stage, which the stiffness test needs.
    if (ok) {
        for (int i = 0; i < n; ++i)
            y_new_[i] = y_[i] + h * (b1 * k[0][i] + b3 * k[2][i] + b4 * k[3][i] + b5 * k[4][i] + b6 * k[5][i]);
        place_relaxing_states(t_new - t_, y_new_.data());
        ok = rhs(t_new, y_new_, f_new_);
    }
    if (!ok) {  // a non-finite right-hand side: try a much smaller step
        memory_.step_size = 0.25 * h;
        memory_.last_step_rejected = 1;
        stiffness_estimate_ = 0.0;
        return StepResult::rejected;
    }
    for (int i = 0; i < n; ++i)
        error_[i] = h * (e1 * k[0][i] + e3 * k[2][i] + e4 * k[3][i] + e5 * k[4][i] + e6 * k[5][i] + e7 * f_new_[i]);
    for (int r = 0; r < relaxing_count_; ++r) error_[relaxing_[r].index] = 0.0;  // exact
    const double err = error_norm(error_, y_, y_new_);
    // Hairer's stiffness test: h |lambda| estimated from the last two stages, both at t_new. Taken on
    // rejected steps too: a step rejected for instability is the clearest sign of stiffness.
    // The relaxing states' own rate is no limit on this method's stability: left out.
    double numerator = 0.0, denominator = 0.0;
    for (int i = 0; i < n; ++i) {
        if (relaxing_count_ > 0 && relaxing(i)) continue;
        numerator += (f_new_[i] - k[5][i]) * (f_new_[i] - k[5][i]);
        denominator += (y_new_[i] - stage_state_[i]) * (y_new_[i] - stage_state_[i]);
    }
    stiffness_estimate_ = denominator > 0.0 ? h * std::sqrt(numerator / denominator) : 0.0;
    const double exponent = 0.2 - kPiBeta * 0.75;
    const double raw = std::pow(err, exponent);
    if (!(err <= 1.0)) {
        memory_.step_size = h / std::min(1.0 / kMaxShrink, raw / kSafety);
        memory_.last_step_rejected = 1;
        return StepResult::rejected;
    }
    double factor = raw / std::pow(memory_.previous_error, kPiBeta) / kSafety;
    proposal_limited_ = factor < 1.0 / kMaxGrowth || memory_.last_step_rejected;
    factor = std::clamp(factor, 1.0 / kMaxGrowth, 1.0 / kMaxShrink);
    double next = h / factor;
    if (memory_.last_step_rejected) next = std::min(next, h);
    memory_.previous_error = std::max(err, 1e-4);
    memory_.last_step_rejected = 0;

    dense_rosenbrock_ = false;
    dense_t0_ = t_, dense_h_ = h;
    for (int i = 0; i < n; ++i) {
        const double difference = y_new_[i] - y_[i];
        const double slope_start = h * k[0][i] - difference;
        dense_[0][i] = y_[i];
        dense_[1][i] = difference;
        dense_[2][i] = slope_start;
        dense_[3][i] = difference - h * f_new_[i] - slope_start;
        dense_[4][i] = h * (d1 * k[0][i] + d3 * k[2][i] + d4 * k[3][i] + d5 * k[4][i] + d6 * k[5][i] + d7 * f_new_[i]);
    }
    dense_relaxing_count_ = relaxing_count_;
    for (int r = 0; r < relaxing_count_; ++r) {
        dense_relaxing_[r] = relaxing_[r];
        dense_relaxing_distance_[r] = relaxing_distance_[r];
    }
    proposal_ = next;
    return StepResult::accepted;
}

bool OneStepIntegrator::jacobian_at(double time, const Vector& y) {
    ++totals_.jacobian_evaluations;
    const int n = size_;
    if (system_.has_jacobian() && system_.jacobian(time, y.data(), jacobian_.data())) return jacobian_.allFinite();
    // Forward differences, one right-hand side per column (f_ holds f(time, y)).
    perturbed_ = y;
    for (int j = 0; j < n; ++j) {
        const double delta = std::sqrt(kEpsilon * std::max(1e-5, std::fabs(y[j])));  // as in Hairer's codes
        perturbed_[j] = y[j] + delta;
        if (!rhs(time, perturbed_, stage_state_)) return false;
        jacobian_.col(j) = (stage_state_ - f_) / delta;
        perturbed_[j] = y[j];
    }
    return jacobian_.allFinite();
}

OneStepIntegrator::StepResult OneStepIntegrator::rosenbrock_step(double h, double t_new) {
    using namespace tableau::rodas4;
    Vector* k = stage_;
    auto reject = [&] {
        memory_.step_size = 0.25 * h;
        memory_.last_step_rejected = 1;
        return StepResult::rejected;
    };
    if (!iteration_matrix_.factorize(jacobian_.data(), 1.0 / (h * gamma))) return reject();
    // Stage i solves (I/(h gamma) - J) k_i = rhs in place.
    auto solve = [&](Vector& stage, const auto& rhs) {
        stage = rhs;
        iteration_matrix_.solve(stage.data());
    };
    const double hd1 = h * d1, hd2 = h * d2, hd3 = h * d3, hd4 = h * d4;
    const double hc21 = c21 / h, hc31 = c31 / h, hc32 = c32 / h, hc41 = c41 / h, hc42 = c42 / h, hc43 = c43 / h;
    const double hc51 = c51 / h, hc52 = c52 / h, hc53 = c53 / h, hc54 = c54 / h;
    const double hc61 = c61 / h, hc62 = c62 / h, hc63 = c63 / h, hc64 = c64 / h, hc65 = c65 / h;
    Vector& dy = f_new_;  // stage derivative (f_new_ is written last)
    solve(k[0], f_ + hd1 * time_derivative_);

    stage_state_ = y_ + a21 * k[0];
    if (!rhs(t_ + c2 * h, stage_state_, dy)) return reject();
    solve(k[1], dy + hd2 * time_derivative_ + hc21 * k[0]);

    stage_state_ = y_ + a31 * k[0] + a32 * k[1];
    if (!rhs(t_ + c3 * h, stage_state_, dy)) return reject();
    solve(k[2], dy + hd3 * time_derivative_ + hc31 * k[0] + hc32 * k[1]);

    stage_state_ = y_ + a41 * k[0] + a42 * k[1] + a43 * k[2];
    if (!rhs(t_ + c4 * h, stage_state_, dy)) return reject();
    solve(k[3], dy + hd4 * time_derivative_ + hc41 * k[0] + hc42 * k[1] + hc43 * k[2]);

    stage_state_ = y_ + a51 * k[0] + a52 * k[1] + a53 * k[2] + a54 * k[3];
    if (!rhs(t_new, stage_state_, dy)) return reject();
    solve(k[4], dy + hc51 * k[0] + hc52 * k[1] + hc53 * k[2] + hc54 * k[3]);

    // Stiffly accurate: the embedded solution is the fifth stage's argument plus k5.
    stage_state_ += k[4];
    if (!rhs(t_new, stage_state_, dy)) return reject();
    solve(k[5], dy + hc61 * k[0] + hc62 * k[1] + hc63 * k[2] + hc64 * k[3] + hc65 * k[4]);
    y_new_ = stage_state_ + k[5];
    if (!y_new_.allFinite()) return reject();

    // The embedded estimate k6, filtered through (I - h gamma J)^-1 as RADAU5 filters its own (Hairer &
    // Wanner, section IV.8): components with |h lambda| >> 1 follow the slow ones within the step, and
    // their raw estimate (the distance still to go in a boundary layer after an input jump) would force
    // steps of the fast time scale although the solution does not need them.
    solve(error_, k[5] / (h * gamma));
    const double err = error_norm(error_, y_, y_new_);
    // The filter vouches for the step's end, not for its inside: the continuous extension through a
    // boundary layer the step did not resolve is no place to locate an event (attempt_step).
    unresolved_layer_ = err <= 1.0 ? error_norm(k[5], y_, y_new_) : 0.0;
    const double raw = std::pow(err, 0.25) / kSafety;
    // The real-time method takes every step: its grid is fixed.
    if (!(err <= 1.0) && !real_time()) {
        memory_.step_size = h / std::min(1.0 / kMaxShrink, raw);
        memory_.last_step_rejected = 1;
        return StepResult::rejected;
    }
    proposal_limited_ = raw < 1.0 / 6.0 || memory_.last_step_rejected;
    double next = h / std::clamp(raw, 1.0 / 6.0, 1.0 / kMaxShrink);
    if (memory_.last_step_rejected) next = std::min(next, h);
    memory_.last_step_rejected = 0;
    memory_.previous_error = std::max(err, 1e-4);

    dense_rosenbrock_ = true;
    dense_t0_ = t_, dense_h_ = h;
    dense_[0] = y_;
    dense_[1] = y_new_;
    dense_[2] = d21 * k[0] + d22 * k[1] + d23 * k[2] + d24 * k[3] + d25 * k[4];
    dense_[3] = d31 * k[0] + d32 * k[1] + d33 * k[2] + d34 * k[3] + d35 * k[4];
    // The next step's first stage needs f(t_new, y_new) anyway: it also feeds the event check.
    if (!rhs(t_new, y_new_, f_new_)) return reject();
    proposal_ = next;
    return StepResult::accepted;
}

void OneStepIntegrator::dense_output(double time, double* state) const {
    const double s = dense_h_ > 0.0 ? (time - dense_t0_) / dense_h_ : 1.0;
    const double r = 1.0 - s;
    for (int i = 0; i < size_; ++i) {
        if (dense_rosenbrock_) {
            state[i] = r * dense_[0][i] + s * (dense_[1][i] + r * (dense_[2][i] + s * dense_[3][i]));
        } else {
            state[i] = dense_[0][i] + s * (dense_[1][i] + r * (dense_[2][i] + s * (dense_[3][i] + r * dense_[4][i])));
        }
    }
    if (dense_rosenbrock_) return;
    for (int k = 0; k < dense_relaxing_count_; ++k) {
        const RelaxingState& relaxing = dense_relaxing_[k];
        state[relaxing.index] =
            relaxing.source(state) - dense_relaxing_distance_[k] * std::exp(-relaxing.rate * (time - dense_t0_));
    }
}

// Magnitude of the Jacobian's dominant eigenvalue by power iteration: (|J^m v| / |v|)^(1/m). A
// complex pair or a multiple eigenvalue does not converge to a single ratio, but the m-th root of the
// growth tends to |lambda_max|; for a non-normal Jacobian (the motor and gear rows couple states of
// very different scales) it overshoots over the first iterations, which is why it takes eight (with
// four, a scene that is not stiff was judged stiff after mode changes). Enough for a choice between
// two methods.
double OneStepIntegrator::spectral_radius_estimate(double enough) const {
    constexpr int kIterations = 8;
    const int n = size_;
    double v[kMaxStates], w[kMaxStates];
    for (int i = 0; i < n; ++i) v[i] = power_iteration_start_[i];
    // The relaxing states act on no other state (their column is zero but for the diagonal), so J is
    // block-triangular: without their rows and columns it has the eigenvalues the explicit method must
    // be stable for, as it takes them exactly.
    RelaxingState relaxing[HybridSystem::kMaxRelaxingStates];
    const int relaxing_count = system_.relaxing_states(relaxing);
    for (int r = 0; r < relaxing_count; ++r) v[relaxing[r].index] = 0.0;
    double growth = 1.0;  // |J^m v| / |v|: at most (1e38)^8 before it counts as infinite
    for (int iteration = 0; iteration < kIterations; ++iteration) {
        double norm = 0.0;
        for (int i = 0; i < n; ++i) w[i] = 0.0;
        for (int j = 0; j < n; ++j) {
            const double* column = jacobian_.data() + j * n;  // n x n, column-major
            for (int i = 0; i < n; ++i) w[i] += column[i] * v[j];
        }
        for (int r = 0; r < relaxing_count; ++r) w[relaxing[r].index] = 0.0;
        for (int i = 0; i < n; ++i) norm += w[i] * w[i];
        norm = std::sqrt(norm);
        if (!std::isfinite(norm)) return std::numeric_limits<double>::infinity();
        if (!(norm > 0.0)) {
            // Still in a null space: fall back on Gershgorin's bound, max_i sum_j |J_ij|.
            double bound = 0.0;
            for (int i = 0; i < n; ++i) {
                double row = 0.0;
                bool left_out = false;
                for (int r = 0; r < relaxing_count; ++r) left_out = left_out || relaxing[r].index == i;
                if (left_out) continue;
                for (int j = 0; j < n; ++j) row += std::fabs(jacobian_.data()[i + j * n]);
                bound = std::max(bound, row);
            }
            return bound;
        }
        growth *= norm;
        for (int i = 0; i < n; ++i) v[i] = w[i] / norm;
        if (iteration >= 1 && enough < std::numeric_limits<double>::infinity()) {
            const double estimate = std::pow(growth, 1.0 / (iteration + 1));
            if (estimate > enough) return estimate;
        }
    }
    return std::pow(growth, 1.0 / kIterations);
}

// The switch rule of the automatic method, as LSODA's: predicted work per unit time, explicit = its
// cost per step / min(its accuracy step, its stable step), RODAS4 = its cost per step / its accuracy
// step. Both accuracy steps are taken as the same (Dormand-Prince's order 5 against RODAS4's 4 and its
// order-3 error estimate: on the random cases of scripts/random_cases.py RODAS4's steps were 0.7-1.5
// times Dormand-Prince's where neither is stiff), so RODAS4 over explicit is
// cost_ratio_ * min(1, stable_step / accuracy_step).
double OneStepIntegrator::rosenbrock_over_explicit_cost(double accuracy_step, double stable_step) const {
    return cost_ratio_ * std::min(1.0, stable_step / accuracy_step);
}

// The explicit method's stable step at |lambda_max| = lambda: kExplicitStableBound / lambda, or what it
// was seen to reach. The power iteration's |lambda_max| is rough for the model's non-normal Jacobian
// (a complex pair, an overshoot): the explicit method has been seen at 1.3-2.7 times 2.5 / lambda.
double OneStepIntegrator::explicit_stable_step(double lambda) const {
    return std::max(kExplicitStableBound, memory_.stable_product) / lambda;
}

// The accuracy step last seen, grown by what the time since may have allowed; 0 if none was seen.
double OneStepIntegrator::predicted_accuracy_step() const {
    if (!(memory_.accuracy_step > 0.0)) return 0.0;
    return memory_.accuracy_step + kAccuracyStepGrowth * std::max(0.0, t_ - memory_.accuracy_time);
}

void OneStepIntegrator::remember_accuracy_step(double h) {
    memory_.accuracy_step = h;
    memory_.accuracy_time = t_;
}

void OneStepIntegrator::switch_to_rosenbrock() {
    memory_.stiff = 1;
    memory_.stiff_votes = memory_.nonstiff_votes = 0;
    memory_.previous_error = 1e-4;
    ++totals_.method_switches;
}

void OneStepIntegrator::vote_on_stiffness_explicit(double h, bool accepted) {
    // stiffness_estimate_ is already h |lambda| of the step just taken.
    if (settings_.method != IntegrationMethod::automatic) return;
    // The step this one proposes next (h may have been cut short to end on a communication point).
    const double next = std::max(h, memory_.step_size);
    memory_.steps_since_jump = -1;
    if (accepted) memory_.explicit_step = stiffness_estimate_ > kAccuracyLimited ? next : 0.0;
    if (stiffness_estimate_ > tableau::dopri5::stiffness_threshold) {
        memory_.nonstiff_votes = 0;
        if (++memory_.stiff_votes >= kVotesForStiff) {
            // At the stability boundary: RODAS4 takes over if it is predicted cheaper, at the accuracy
            // step last seen, than the explicit method at the step it now takes (Hairer's |lambda| is
            // too rough for this: up to 4 times the power iteration's after a rejected step). Until
            // RODAS4 has run once (no accuracy step of its own seen) it is tried, and measures it.
            // Declined, every further accepted step at the boundary asks again, as the remembered
            // accuracy step ages.
            memory_.stiff_votes = kVotesForStiff;
            const double accuracy_step = predicted_accuracy_step();
            if (memory_.stable_product > 0.0 && accuracy_step > 0.0 &&
                (!accepted || rosenbrock_over_explicit_cost(accuracy_step, next) * kSwitchMargin >= 1.0))
                return;
            if (!accepted) memory_.explicit_step = memory_.step_size;
            switch_to_rosenbrock();
        }
    } else {
        // The explicit method's accuracy step only raises the one remembered: after an input jump it
        // runs through the transient at short steps, below its stability limit, while the step RODAS4
        // took (and will take again) once the transient has passed is the one to compare with.
        if (accepted && stiffness_estimate_ <= kAccuracyLimited && proposal_ <= kSettledGrowth * h &&
            !proposal_limited_ && next > predicted_accuracy_step())
            remember_accuracy_step(next);
        if (++memory_.nonstiff_votes >= 6) memory_.stiff_votes = 0;
    }
}

void OneStepIntegrator::vote_on_stiffness_rosenbrock(double taken) {
    if (settings_.method != IntegrationMethod::automatic) return;
    // Judged at the step RODAS4 proposes next, not the one just taken (which may have been cut short
    // to end on a communication point).
    const double h = std::max(taken, memory_.step_size);
    // h: the step RODAS4 takes for accuracy, also taken as the explicit method's (see above). The
    // explicit method takes over if it is predicted cheaper by the margin: at most at
    // |lambda_max| < max(kExplicitStableBound, stable_product) * cost_ratio_ / (kSwitchMargin h).
    const double limit =
        std::max(kExplicitStableBound, memory_.stable_product) * cost_ratio_ / (kSwitchMargin * h);
    double lambda;
    if (memory_.explicit_step > 0.0 || !(memory_.stable_product > 0.0)) {
        // The first step after the explicit method handed over (or RODAS4's first step at all): how far
        // the explicit method got at its stability limit, in units of 1 / |lambda_max| (bounded: it may
        // have been taken under other modes).
        lambda = spectral_radius_estimate();
        memory_.stable_product = std::clamp(memory_.explicit_step * lambda, kExplicitStableBound, kMaxStableProduct);
        memory_.explicit_step = 0.0;
    } else if (reused_lambda_age_ >= 0 && reused_lambda_age_ < kLambdaReuseSteps) {
        // Within a mode the dominant eigenvalue moves slowly; its power iteration was 12 % of a stiff
        // scene's work when taken at every step.
        lambda = reused_lambda_;
        ++reused_lambda_age_;
    } else {
        // A growth far beyond the limit after two iterations settles it without the rest.
        lambda = spectral_radius_estimate(20.0 * limit);
        reused_lambda_ = lambda;
        reused_lambda_age_ = 0;
    }
    bool explicit_cheaper = rosenbrock_over_explicit_cost(h, explicit_stable_step(lambda)) > kSwitchMargin;
    if (memory_.steps_since_jump >= 0) ++memory_.steps_since_jump;
    if (memory_.steps_since_jump >= 0 && memory_.accuracy_time == memory_.jump_time && memory_.accuracy_step > 0.0) {
        // RODAS4 ran through the whole last interval between input jumps: judged by its mean step there.
        explicit_cheaper =
            rosenbrock_over_explicit_cost(memory_.accuracy_step, explicit_stable_step(lambda)) > kSwitchMargin;
    } else if (h >= kSettledFraction * memory_.jump_step && proposal_ <= kSettledGrowth * taken && !proposal_limited_) {
        remember_accuracy_step(h);
    } else if (explicit_cheaper) {
        // In the transient after an input jump every method is stable at the short steps: the explicit
        // method takes over only if it would keep running once the steps have grown back, i.e. if at
        // the step RODAS4 took before the jump it would not be predicted dearer by the margin.
        const double accuracy_step = predicted_accuracy_step();
        explicit_cheaper = accuracy_step > 0.0 &&
                           rosenbrock_over_explicit_cost(accuracy_step, explicit_stable_step(lambda)) * kSwitchMargin >= 1.0;
    }
    if (explicit_cheaper) {
        if (++memory_.nonstiff_votes >= kVotesForNonstiff) {
            memory_.stiff = 0;
            memory_.nonstiff_votes = 0;
            memory_.stiff_votes = 0;
            memory_.previous_error = 1e-4;
            ++totals_.method_switches;
        }
    } else {
        memory_.nonstiff_votes = 0;
    }
}

bool OneStepIntegrator::any_crossing(const std::vector<double>& before, const std::vector<double>& after) const {
    for (int k = 0; k < event_count_; ++k)
        if (crossed(before[k], after[k])) return true;
    return false;
}

bool OneStepIntegrator::handle_events(bool& event_found) {
    event_found = false;
    if (event_count_ == 0 || t_new_ <= memory_.chattering.dwell_until) return true;
    if (!event_values(t_new_, y_new_, g_new_)) return false;
    if (t_ < memory_.chattering.dwell_until) {
        // The chattering guard held the modes until inside this step: re-select them here.
        return true;
    }
    if (!any_crossing(g_, g_new_)) return true;
    event_found = true;

    // Illinois iteration on the first root in (t_, t_new_], with every function watched at once.
    double low = t_, high = t_new_;
    g_low_ = g_, g_high_ = g_new_;
    const double tolerance = 100.0 * kEpsilon * (std::fabs(t_) + (t_new_ - t_));
    double weight = 1.0;
    int previous_side = 0;
    for (int iteration = 0; iteration < settings_.event_iterations && high - low > tolerance; ++iteration) {
        double estimate = high;
        for (int k = 0; k < event_count_; ++k) {
            if (!crossed(g_low_[k], g_high_[k])) continue;
            const double denominator = g_high_[k] - weight * g_low_[k];
            const double candidate = denominator != 0.0 ? high - (high - low) * g_high_[k] / denominator : high;
            estimate = std::min(estimate, candidate);
        }
        const double margin = 0.5 * tolerance;
        double middle = std::clamp(estimate, low + margin, high - margin);
        if (iteration % 8 == 7) middle = 0.5 * (low + high);  // a bisection now and then bounds the count
        dense_output(middle, stage_state_.data());
        if (!event_values(middle, stage_state_, g_mid_)) return false;
        int side;
        if (any_crossing(g_low_, g_mid_)) {
            high = middle, g_high_ = g_mid_, side = 1;
        } else {
            low = middle, g_low_ = g_mid_, side = 2;
        }
        if (side == previous_side) weight = side == 2 ? 2.0 * weight : 0.5 * weight;
        else weight = 1.0;
        previous_side = side;
    }

    // Switch at the right end of the bracket: every function that crossed has its new sign there.
    const double root = high;
    if (root != t_new_) dense_output(root, y_new_.data());
    if (!event_values(root, y_new_, g_high_)) return false;
    for (int k = 0; k < event_count_; ++k)
        directions_[k] = crossed(g_[k], g_high_[k]) ? (g_high_[k] > g_[k] ? 1 : -1) : 0;
    t_ = root;
    y_ = y_new_;
    const int changes = switch_modes(system_, root, y_.data(), directions_.data(), settings_, event_sink_, root);
    totals_.events += changes;
    if (changes > 0) reused_lambda_age_ = -1;

    // Roots closer than a few location tolerances cannot be told apart: at large times (1e5 s and more)
    // that spacing exceeds the window itself.
    if (record_mode_change(memory_.chattering, settings_, root, 4.0 * tolerance, event_sink_)) ++totals_.zeno_holds;
    // New modes (or a projection onto a stop) change the right-hand side: one evaluation restarts.
    // A mode that makes the model stiff (a motor's current released from its limit) shows in the
    // explicit method's next steps, which vote for RODAS4 (vote_on_stiffness_explicit). A Jacobian at
    // every mode change to foresee it cost more than it saved (docs/benchmarks.md, 2026-11-26): it
    // judged the new mode by an accuracy step seen under the old one.
    return refresh_at_current_point(directions_.data());
}

bool OneStepIntegrator::time_derivative_at_current_point() {
    if (!system_.time_dependent()) {
        time_derivative_.setZero(size_);
        return true;
    }
    const double delta = std::sqrt(kEpsilon) * std::max(1.0, std::fabs(t_));
    if (!rhs(t_ + delta, y_, time_derivative_)) return false;
    time_derivative_ = (time_derivative_ - f_) / delta;
    return true;
}

bool OneStepIntegrator::reselect_after_dwell() {
    memory_.chattering.dwell_until = -1e300;
    totals_.events += switch_modes(system_, t_, y_.data(), nullptr, settings_, event_sink_, t_);
    return refresh_at_current_point();
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

// The chattering guard's hold ends at a step end, so that the modes are re-selected on time: t_new_
// is moved back to it if it lies within the step (and not within `smallest` of its start).
GIMBAL_HOT_PART bool OneStepIntegrator::cut_at_hold_end(double smallest) {
    const double hold_end = memory_.chattering.dwell_until;
    if (!(t_ < hold_end && hold_end < t_new_ && hold_end - t_ > smallest)) return false;
    t_new_ = hold_end;
    return true;
}

// Whether a chattering hold ended at the current point (the modes are then re-selected).
GIMBAL_HOT_PART bool OneStepIntegrator::hold_ended() const {
    return memory_.chattering.dwell_until > -1e300 && t_ >= memory_.chattering.dwell_until;
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

bool OneStepIntegrator::crosses_a_guard() {
    if (event_count_ == 0 || t_new_ <= memory_.chattering.dwell_until || t_ < memory_.chattering.dwell_until) return false;
    return event_values(t_new_, y_new_, g_new_) && any_crossing(g_, g_new_);
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
