// The SUNDIALS reference methods under the hybrid layer: the backend (CVODE or ARKODE) finds roots of
// the event functions itself; this class runs the event loop, the chattering guard and the statistics.
#pragma once

#include <vector>

#include <sundials/sundials_context.h>
#include <sundials/sundials_nvector.h>

#include "gimbal/integrator.hpp"

namespace gimbal {

class SundialsIntegrator : public HybridIntegrator {
public:
    ~SundialsIntegrator() override;
    bool restart(double time, const double* state) override;
    bool advance(double end_time, double* state) override;
    IntegratorStatistics statistics() const override;
    void set_statistics(const IntegratorStatistics& totals) override { totals_ = totals; }

protected:
    enum class Outcome { reached_end, root, failure };

    SundialsIntegrator(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
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

std::unique_ptr<HybridIntegrator> make_cvode_backend(HybridSystem&, const IntegratorSettings&,
                                                     HybridIntegrator::MessageSink, HybridIntegrator::MessageSink);
std::unique_ptr<HybridIntegrator> make_arkode_backend(HybridSystem&, const IntegratorSettings&,
                                                      HybridIntegrator::MessageSink, HybridIntegrator::MessageSink);

}  // namespace gimbal
