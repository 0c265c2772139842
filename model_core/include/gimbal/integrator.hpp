// Integrators under a hybrid system: root finding locates each mode change, the system switches its
// modes, and the integrator restarts from the switching point. The event loop, the chattering guard
// and the statistics are shared; SUNDIALS CVODE (BDF or Adams) and ARKODE (explicit Runge-Kutta)
// are the backends.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nvector.h>

#include "gimbal/hybrid_system.hpp"

namespace gimbal {

struct IntegratorStatistics {
    long steps = 0;
    long rhs_evaluations = 0;
    long jacobian_evaluations = 0;
    long events = 0;       // located mode changes
    long zeno_holds = 0;   // times the chattering guard engaged
};

enum class IntegrationMethod : int {
    bdf_analytic_jacobian = 0,  // CVODE BDF, Newton with the system's Jacobian
    bdf_difference_jacobian = 1,  // CVODE BDF, Newton with a difference-quotient Jacobian
    adams = 2,                  // CVODE Adams-Moulton, Newton with a difference-quotient Jacobian
    explicit_runge_kutta = 3,   // ARKODE ERKStep, Dormand-Prince 5(4), adaptive
};

struct IntegratorSettings {
    IntegrationMethod method = IntegrationMethod::bdf_analytic_jacobian;
    double relative_tolerance = 1e-6;
    double absolute_tolerance = 1e-8;
    long max_steps = 100000;  // internal steps per call of advance
    double max_step = 0.0;  // 0: unlimited. Root finding sees only sign changes between steps.
    // Chattering guard: this many located roots in a row, each within `zeno_window` of the previous
    // one (relative to max(1, |t|)), freeze the event functions for `zeno_dwell` (same scale); modes
    // are then re-selected where the functions come back. Switches further apart than the window
    // (1 ns at t ~ 1 s, i.e. chatter above 1 GHz) are never affected.
    int zeno_event_limit = 50;
    double zeno_window = 1e-9;
    double zeno_dwell = 1e-6;
    // Whether anyone listens to event messages: they are only formatted (and allocated) if so.
    std::function<bool()> events_logged = [] { return true; };
};

class HybridIntegrator {
public:
    using MessageSink = std::function<void(const std::string&)>;

    static std::unique_ptr<HybridIntegrator> create(HybridSystem& system, const IntegratorSettings& settings,
                                                    MessageSink error_sink, MessageSink event_sink);
    virtual ~HybridIntegrator();
    HybridIntegrator(const HybridIntegrator&) = delete;
    HybridIntegrator& operator=(const HybridIntegrator&) = delete;

    // Starts afresh at (time, state): after any discontinuity of the right-hand side.
    bool restart(double time, const double* state);

    // Integrates to exactly end_time, switching modes at every located event. False on failure, with
    // the reason sent to the error sink; the state is then unspecified and the caller must roll back.
    bool advance(double end_time, double* state);

    IntegratorStatistics statistics() const;
    // For restoring a saved instance: counts continue from these.
    void set_statistics(const IntegratorStatistics& totals) { totals_ = totals; }

protected:
    enum class Outcome { reached_end, root, failure };

    HybridIntegrator(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                     MessageSink event_sink);
    bool create_vector();

    // Backend: (re)initialize at (time, y_), integrate towards end_time stopping there exactly, report
    // root directions, and count work since the last (re)initialization.
    virtual bool backend_restart(double time) = 0;
    virtual Outcome backend_advance(double end_time, double& reached) = 0;
    virtual void backend_roots(int* directions) = 0;
    virtual IntegratorStatistics backend_counters() const = 0;

    // Callbacks with SUNDIALS signatures, shared by the backends (user data = this).
    static int right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data);
    static int event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data);
    static void forward_error(int code, const char* module, const char* function, char* message, void* user_data);

    HybridSystem& system_;
    IntegratorSettings settings_;
    MessageSink error_sink_, event_sink_;
    int size_;
    SUNContext context_ = nullptr;
    N_Vector y_ = nullptr;
    bool initialized_ = false;
    std::vector<int> root_directions_;

private:
    IntegratorStatistics totals_;  // of finished backend runs (their counters reset at each restart)
    double last_event_time_ = -1e300;
    int rapid_events_ = 0;
    double dwell_until_ = -1e300;
};

}  // namespace gimbal
