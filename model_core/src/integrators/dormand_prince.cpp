// Dormand-Prince 5(4) (E. Hairer's DOPRI5): one step with the FSAL stage, the PI step size
// controller, the dense output of order 4, and the relaxing states taken exactly
// (HybridSystem::relaxing_states).
#include <algorithm>
#include <cmath>

#include "one_step_integrator.hpp"
#include "tableaus.hpp"

namespace gimbal {

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

}  // namespace gimbal
