// The automatic method's switch between Dormand-Prince and RODAS4: the stiffness votes of each
// accepted (or rejected) step, the power iteration for |lambda_max|, and the rule that compares the two
// methods' predicted work per unit time, as LSODA does (docs/benchmarks.md, "The automatic method off
// the ship scene").
#include <algorithm>
#include <cmath>

#include "one_step_integrator.hpp"
#include "tableaus.hpp"

namespace gimbal {
namespace {

// Automatic method: explicit steps in a row at the stability boundary before the Rosenbrock method
// takes over, and Rosenbrock steps in a row at which the explicit method would be stable before it
// hands back. A few of each: a wrong vote costs one or two steps, a missed switch many.
constexpr int kVotesForStiff = 3, kVotesForNonstiff = 3;
// The explicit method counts as stable at |h lambda| below this (its boundary is ~3.3), with margin.
constexpr double kExplicitStableBound = 2.5;

// Automatic method: the work of one step of each method in right-hand-side equivalents, for the switch
// rule's predicted costs: RODAS4 = fixed + per_state2 n^2 + the Jacobian (the system's analytic one,
// else n right-hand sides by differences). Measured with callgrind when the rule was introduced
// (docs/benchmarks.md, "The switch rule's step costs"; the figures there are historical).
constexpr double kExplicitStepCost = 8.7;
constexpr double kRosenbrockStepCostFixed = 9.6;       // 7 right-hand sides, the event functions, the rest
constexpr double kRosenbrockStepCostPerState2 = 0.063;  // LU and solves, per n^2
constexpr double kAnalyticJacobianCost = 6.2;
// Switch only when the other method is predicted cheaper by this factor: the prediction is rough (the
// stability limit from an estimate of |lambda_max|, the accuracy step from the last one seen) and a
// switch costs a Jacobian and a restarted controller. Of 1.15, 1.3 and 1.5, equally good on the
// random cases, 1.5 switched least (docs/benchmarks.md, "The automatic method off the ship scene").
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

double OneStepIntegrator::rosenbrock_cost_ratio(int state_size, bool analytic_jacobian) {
    const double states = state_size;
    return (kRosenbrockStepCostFixed + kRosenbrockStepCostPerState2 * states * states +
            (analytic_jacobian ? kAnalyticJacobianCost : states)) /
           kExplicitStepCost;
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

}  // namespace gimbal
