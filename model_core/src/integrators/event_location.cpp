// Events between accepted steps: a guard's sign change is located on the step's dense output with the
// Illinois method, the system switches its modes at the root (hybrid_system/event_handling.hpp, with
// the chattering guard), and the integration restarts there; a chattering hold that ends re-selects
// the modes.
#include <algorithm>
#include <cmath>

#include "gimbal/hybrid_system/event_handling.hpp"
#include "one_step_integrator.hpp"

namespace gimbal {

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
    const int changes =
        switch_modes(system_, root, y_.data(), directions_.data(), settings_.event_handling, event_sink_, root);
    totals_.events += changes;
    if (changes > 0) reused_lambda_age_ = -1;

    // Roots closer than a few location tolerances cannot be told apart: at large times (1e5 s and more)
    // that spacing exceeds the window itself.
    if (record_mode_change(memory_.chattering, settings_.event_handling, root, 4.0 * tolerance, event_sink_))
        ++totals_.zeno_holds;
    // New modes (or a projection onto a stop) change the right-hand side: one evaluation restarts.
    // A mode that makes the model stiff (a motor's current released from its limit) shows in the
    // explicit method's next steps, which vote for RODAS4 (vote_on_stiffness_explicit). A Jacobian at
    // every mode change to foresee it cost more than it saved (docs/benchmarks.md, 2026-11-26): it
    // judged the new mode by an accuracy step seen under the old one.
    return refresh_at_current_point(directions_.data());
}

bool OneStepIntegrator::reselect_after_dwell() {
    memory_.chattering.dwell_until = -1e300;
    totals_.events += switch_modes(system_, t_, y_.data(), nullptr, settings_.event_handling, event_sink_, t_);
    return refresh_at_current_point();
}

bool OneStepIntegrator::crosses_a_guard() {
    if (event_count_ == 0 || t_new_ <= memory_.chattering.dwell_until || t_ < memory_.chattering.dwell_until) return false;
    return event_values(t_new_, y_new_, g_new_) && any_crossing(g_, g_new_);
}

}  // namespace gimbal
