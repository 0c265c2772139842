// SUNDIALS CVODE (BDF, Newton, dense linear solver) under a hybrid system: root finding locates each
// mode change, the system switches its modes, and the integrator restarts from the switching point.
#pragma once

#include <functional>
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

struct IntegratorSettings {
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
};

class HybridCvodeIntegrator {
public:
    using MessageSink = std::function<void(const std::string&)>;

    HybridCvodeIntegrator(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                          MessageSink event_sink);
    ~HybridCvodeIntegrator();
    HybridCvodeIntegrator(const HybridCvodeIntegrator&) = delete;
    HybridCvodeIntegrator& operator=(const HybridCvodeIntegrator&) = delete;

    // Starts afresh at (time, state): after any discontinuity of the right-hand side.
    bool restart(double time, const double* state);

    // Integrates to exactly end_time, switching modes at every located event. False on failure, with
    // the reason sent to the error sink; the state is then unspecified and the caller must roll back.
    bool advance(double end_time, double* state);

    IntegratorStatistics statistics() const;
    // For restoring a saved instance: counts continue from these.
    void set_statistics(const IntegratorStatistics& totals) { totals_ = totals; }

private:
    static int right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data);
    static int event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data);
    static void forward_error(int code, const char* module, const char* function, char* message, void* user_data);
    void accumulate_statistics();

    HybridSystem& system_;
    IntegratorSettings settings_;
    MessageSink error_sink_, event_sink_;
    int size_;
    SUNContext context_ = nullptr;
    N_Vector y_ = nullptr;
    SUNMatrix jacobian_ = nullptr;
    SUNLinearSolver linear_solver_ = nullptr;
    void* cvode_ = nullptr;
    bool initialized_ = false;
    std::vector<int> root_directions_;
    IntegratorStatistics totals_;     // of finished CVODE runs (counters reset at each restart)
    double last_event_time_ = -1e300;
    int rapid_events_ = 0;
    double dwell_until_ = -1e300;
};

}  // namespace gimbal
