// RODAS4 (Hairer and Wanner's L-stable Rosenbrock method of order 4 with an order-3 error estimate):
// the Jacobian (the system's analytic one, else forward differences), the time derivative of a
// time-dependent right-hand side, and one step with its dense output of order 3.
#include <algorithm>
#include <cmath>

#include "one_step_integrator.hpp"
#include "tableaus.hpp"

namespace gimbal {

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

}  // namespace gimbal
