#include "sundials_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <nvector/nvector_serial.h>

namespace gimbal {

SundialsIntegrator::SundialsIntegrator(HybridSystem& system, const IntegratorSettings& settings,
                                       MessageSink error_sink, MessageSink event_sink)
    : system_(system),
      settings_(settings),
      error_sink_(std::move(error_sink)),
      event_sink_(std::move(event_sink)),
      size_(system.state_size()),
      root_directions_(system.event_count(), 0) {}

SundialsIntegrator::~SundialsIntegrator() {
    if (y_ != nullptr) N_VDestroy(y_);
    if (context_ != nullptr) SUNContext_Free(&context_);
}

bool SundialsIntegrator::create_vector() {
    // One context per instance: SUNDIALS keeps no state shared between FMU instances.
    if (SUNContext_Create(nullptr, &context_) != 0) {
        context_ = nullptr;
        return false;
    }
    y_ = N_VNew_Serial(size_, context_);
    return y_ != nullptr;
}

void SundialsIntegrator::forward_error(int code, const char* module, const char* function, char* message,
                                     void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    if (code >= 0) return;  // warnings are not failures; the caller reports what matters
    self->error_sink_(std::string(module) + "::" + function + ": " + message);
}

int SundialsIntegrator::right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    // Recoverable failure: the integrator retries with a smaller step.
    return self->system_.derivative(time, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
}

int SundialsIntegrator::event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data) {
    auto* self = static_cast<SundialsIntegrator*>(user_data);
    if (time < self->dwell_until_) {
        std::fill(values, values + self->root_directions_.size(), 1.0);
        return 0;
    }
    self->system_.event_functions(time, N_VGetArrayPointer(y), values);
    return 0;
}

bool SundialsIntegrator::restart(double time, const double* state) {
    if (y_ == nullptr) {
        error_sink_("the integrator could not be created (out of memory)");
        return false;
    }
    if (initialized_) {
        const IntegratorStatistics run = backend_counters();
        totals_.steps += run.steps;
        totals_.rhs_evaluations += run.rhs_evaluations;
        totals_.jacobian_evaluations += run.jacobian_evaluations;
    }
    std::copy(state, state + size_, N_VGetArrayPointer(y_));
    initialized_ = backend_restart(time);
    return initialized_;
}

bool SundialsIntegrator::advance(double end_time, double* state) {
    double* y = N_VGetArrayPointer(y_);
    // One budget of internal steps for the whole call: restarts after mode changes reset the
    // backend's own count, and switches 10-100 ns apart would otherwise run on without bound.
    const long steps_at_start = statistics().steps;
    long events_here = 0;
    for (;;) {
        double reached = 0.0;
        const Outcome outcome = backend_advance(end_time, reached);
        if (outcome == Outcome::failure) return false;
        std::copy(y, y + size_, state);
        if (outcome == Outcome::reached_end) return true;
        if (statistics().steps - steps_at_start > settings_.max_steps) {
            std::ostringstream s;
            s.precision(17);
            s << "more than solver.max_steps = " << settings_.max_steps << " internal steps (" << events_here
              << " mode changes) before t = " << reached << ": the inputs or parameters drive switching faster than "
              << "the model can follow";
            error_sink_(s.str());
            return false;
        }

        backend_roots(root_directions_.data());
        double before[64];
        const bool tracked = size_ <= 64;
        if (tracked) std::copy(state, state + size_, before);
        const int changes = system_.update_modes(reached, state, root_directions_.data());
        // A projection without a mode change (e.g. theta_b clamped back onto a stop) must not be lost.
        const bool projected = tracked && !std::equal(state, state + size_, before);
        totals_.events += changes;
        events_here += changes;
        if (changes > 0 && settings_.events_logged()) {
            std::ostringstream s;
            s.precision(17);
            s << "t = " << reached << ": " << changes << " mode change(s)";
            event_sink_(s.str());
        }
        const double window = settings_.zeno_window;
        rapid_events_ = reached - last_event_time_ <= window ? rapid_events_ + 1 : 0;
        last_event_time_ = reached;
        if (rapid_events_ >= settings_.zeno_event_limit) {
            dwell_until_ = reached + settings_.zeno_dwell;
            rapid_events_ = 0;
            ++totals_.zeno_holds;
            if (settings_.events_logged()) {
                std::ostringstream s;
                s.precision(17);
                s << "t = " << reached << ": " << settings_.zeno_event_limit
                  << " events without progress in time (chattering); modes held until t = " << dwell_until_;
                event_sink_(s.str());
            }
        }
        // New modes change the right-hand side: restart there, from the (possibly projected) state. A
        // root that changed nothing (a grazing touch) needs no restart: the integrator carries on.
        if ((changes > 0 || projected) && !restart(reached, state)) return false;
        if (reached >= end_time) return true;
    }
}

IntegratorStatistics SundialsIntegrator::statistics() const {
    IntegratorStatistics stats = totals_;
    if (!initialized_) return stats;
    const IntegratorStatistics run = backend_counters();
    stats.steps += run.steps;
    stats.rhs_evaluations += run.rhs_evaluations;
    stats.jacobian_evaluations += run.jacobian_evaluations;
    return stats;
}

}  // namespace gimbal
