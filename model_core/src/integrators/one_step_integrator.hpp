// The project's own one-step integrators under the hybrid layer: Dormand-Prince 5(4) (explicit, FSAL,
// dense output of order 4) and RODAS4 (L-stable Rosenbrock, dense output of order 3), alone or
// switched by stiffness. At 4-17 states generic drivers cost more than the physics
// (docs/benchmarks.md), hence these: fixed-capacity storage, no allocation after construction.
//
// Events are found as sign changes of the event functions between accepted steps and located on the
// dense output with the Illinois method; the system switches its modes at the root and the
// integration goes on from there with the same step size. An input jump costs one right-hand side.
//
// One class, its parts in one file each beside this header:
// - one_step_integrator.cpp: the driver (the current point, restarts, the adaptive loop and the
//   real-time method's fixed grid of RODAS4 substeps);
// - dormand_prince.cpp, rodas4.cpp: one step of each method, with its dense output;
// - automatic_method_switch.cpp: the stiffness votes and the predicted-cost rule of method 4;
// - event_location.cpp: the dense output at a time, the Illinois iteration, the switch at the root.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "gimbal/hybrid_system/event_handling.hpp"
#include "gimbal/hot_path.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "iteration_matrix.hpp"

namespace gimbal {

class OneStepIntegrator final : public HybridIntegrator {
public:
    static constexpr int kMaxStates = 24;
    using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxStates, 1>;
    using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxStates, kMaxStates>;

    OneStepIntegrator(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                      MessageSink event_sink);

    bool restart(double time, const double* state) override;
    bool inputs_changed(double time, const double* state) override { return restart(time, state); }
    bool advance(double end_time, double* state) override;
    bool advance_until_mode_change(double end_time, double* state, double& reached) override;
    IntegratorStatistics statistics() const override { return totals_; }
    void set_statistics(const IntegratorStatistics& totals) override { totals_ = totals; }
    bool resumable() const override { return true; }
    IntegratorMemory memory() const override { return memory_; }
    bool resume(double time, const double* state, const IntegratorMemory& memory) override;

    // The continuous extension of the last accepted step, at `time` within it (for tests).
    void dense_output(double time, double* state) const;
    bool stiff() const { return memory_.stiff != 0; }

private:
    enum class StepResult { accepted, rejected, failed };

    static constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
    // Step size control of both methods (E. Hairer's DOPRI5 and RODAS defaults).
    static constexpr double kSafety = 0.9;
    static constexpr double kPiBeta = 0.04;                       // DOPRI5's stabilized (PI) controller
    static constexpr double kMaxGrowth = 10.0, kMaxShrink = 0.2;  // per step, after an accepted / a rejected step

    bool advance_steps(double end_time, double* state);
    // The parts of an adaptive step (advance_steps): its size, the attempt, what follows acceptance
    // (inline: defined with GIMBAL_HOT_PART in one_step_integrator.cpp, the only place they are called;
    // hold_ended and cut_at_hold_end, which the real-time substeps use too, at the end of this header).
    struct StepPlan {
        enum Kind { step, creep, failed } kind = step;  // creep: a few ulp left; failed: reported
        double h = 0.0;
        bool cut_short = false;  // shorter than proposed (the end of the communication step or of a hold)
    };
    inline StepPlan plan_step(double end_time);
    inline bool attempt_step(double h, StepResult& result);
    inline bool accept_step(const StepPlan& plan, double end_time, std::int64_t& events_here, bool& stop);
    inline bool hold_ended() const;
    inline bool cut_at_hold_end(double smallest);
    inline bool fixed_rosenbrock_step(int substeps);
    bool refuse_step_limit(std::int64_t events_here);
    // The real-time method's substep (advance_fixed_substeps) and refusals.
    enum class Substep { taken, grid_reached, stopped, failed };
    inline Substep real_time_substep(double grid_end, double end_time, int substeps, std::int64_t& changes_here);
    bool refuse_failed_substep(int substeps);
    bool refuse_mode_change_bound(double end_time);
    // The real-time method: RODAS4 over a fixed grid of equal substeps, every step accepted.
    bool advance_fixed_substeps(double end_time, double* state);
    bool real_time() const { return settings_.method == IntegrationMethod::real_time; }
    bool creep_to(double end);
    bool move_to_step_end();
    bool start_at(double time, const double* state);
    bool rhs(double time, const Vector& y, Vector& dy);
    bool event_values(double time, const Vector& y, std::vector<double>& values);
    bool guards_at(double time, const double* state, double* values);
    double initial_step(double end_time);
    double error_norm(const Vector& error, const Vector& y_old, const Vector& y_new) const;
    // One attempt from (t_, y_, f_) to t_new; fills y_new_, f_new_ (explicit: the FSAL stage) and the
    // dense output, and sets the controller's next proposal in memory_.
    StepResult dormand_prince_step(double h, double t_new);
    StepResult rosenbrock_step(double h, double t_new);
    bool jacobian_at(double time, const Vector& y);
    // Whether a guard changes sign between (t_, y_) and (t_new_, y_new_) where handle_events would look.
    bool crosses_a_guard();
    // Stops early once the estimate exceeds `enough`.
    double spectral_radius_estimate(double enough = std::numeric_limits<double>::infinity()) const;
    // Automatic method: the work of a RODAS4 step over a Dormand-Prince step at this state size.
    static double rosenbrock_cost_ratio(int state_size, bool analytic_jacobian);
    // Automatic method: RODAS4's predicted work per unit time over the explicit method's.
    double rosenbrock_over_explicit_cost(double accuracy_step, double stable_step) const;
    double explicit_stable_step(double lambda) const;
    void switch_to_rosenbrock();
    double predicted_accuracy_step() const;
    void remember_accuracy_step(double h);
    void vote_on_stiffness_explicit(double h, bool accepted);
    void vote_on_stiffness_rosenbrock(double taken);
    bool time_derivative_at_current_point();
    // Looks for sign changes between g_ (at t_) and g_new_ (at t_new_); if any, locates the first root on
    // the dense output, switches modes there and restarts. False on failure.
    bool handle_events(bool& event_found);
    bool crossed(double before, double after) const { return before != 0.0 && (after == 0.0 || (before > 0.0) != (after > 0.0)); }
    bool any_crossing(const std::vector<double>& before, const std::vector<double>& after) const;
    bool reselect_after_dwell();
    // f_ and g_ at (t_, y_); `decided`: guards whose crossing update_modes has just been told.
    bool refresh_at_current_point(const int* decided = nullptr);

    HybridSystem& system_;
    IntegratorSettings settings_;
    MessageSink error_sink_, event_sink_;
    int size_;
    int event_count_;
    bool initialized_ = false;

    double t_ = 0.0;
    Vector y_, f_;              // state and its derivative under the current modes
    std::vector<double> g_;     // event functions at (t_, y_)
    IntegratorMemory memory_;
    IntegratorStatistics totals_;

    // Work space of one step.
    double t_new_ = 0.0;
    Vector y_new_, f_new_, stage_[7], stage_state_, error_;
    std::vector<double> g_new_, g_low_, g_high_, g_mid_;
    std::vector<int> directions_;
    GuardSettling guard_settling_;
    // Continuous extension of the last accepted step over [dense_t0_, dense_t0_ + dense_h_].
    bool dense_rosenbrock_ = false;
    double dense_t0_ = 0.0, dense_h_ = 0.0;
    Vector dense_[5];
    // The relaxing states (HybridSystem::relaxing_states) that Dormand-Prince takes exactly: those of the
    // step being attempted, and their distance from their source at its start, s - state[index]; the
    // dense output's copy belongs to the last accepted step.
    RelaxingState relaxing_[HybridSystem::kMaxRelaxingStates];
    double relaxing_distance_[HybridSystem::kMaxRelaxingStates] = {};
    int relaxing_count_ = 0;
    RelaxingState dense_relaxing_[HybridSystem::kMaxRelaxingStates];
    double dense_relaxing_distance_[HybridSystem::kMaxRelaxingStates] = {};
    int dense_relaxing_count_ = 0;
    // Sets the relaxing states of `state` to their exact values a time `elapsed` after the step start.
    void place_relaxing_states(double elapsed, double* state) const {
        for (int r = 0; r < relaxing_count_; ++r) {
            const RelaxingState& relaxing = relaxing_[r];
            state[relaxing.index] = relaxing.source(state) - relaxing_distance_[r] * std::exp(-relaxing.rate * elapsed);
        }
    }
    bool relaxing(int index) const {
        for (int r = 0; r < relaxing_count_; ++r)
            if (relaxing_[r].index == index) return true;
        return false;
    }
    // Rosenbrock: Jacobian, df/dt and the factorized iteration matrix.
    Matrix jacobian_;
    IterationMatrix<kMaxStates> iteration_matrix_;
    Vector time_derivative_, perturbed_;
    double stiffness_estimate_ = 0.0;  // h |lambda| of the last explicit step
    // RODAS4's unfiltered error norm of an accepted step (0 when the filtered one rejected it, or the
    // step was explicit): above 1, the step passed over a boundary layer it did not resolve.
    double unresolved_layer_ = 0.0;
    double power_iteration_start_[kMaxStates] = {};  // spectral_radius_estimate's start vector, unit length
    // The switch rule's |lambda_max|, reused for kLambdaReuseSteps Rosenbrock steps within a mode and a
    // communication step (-1: none).
    static constexpr int kLambdaReuseSteps = 4;
    double reused_lambda_ = 0.0;
    int reused_lambda_age_ = -1;
    double cost_ratio_ = 1.0;          // work of a RODAS4 step over a Dormand-Prince step
    bool jacobian_current_ = false;    // jacobian_ and time_derivative_ belong to (t_, y_) and the modes
    double proposal_ = 0.0;            // the controller's next step size after the last accepted step
    bool proposal_limited_ = false;    // ... held back by the growth bound or a rejection just before
    bool stop_at_mode_change_ = false; // advance_until_mode_change: return after the first one
};

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

}  // namespace gimbal
