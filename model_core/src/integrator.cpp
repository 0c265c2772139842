#include "gimbal/integrator.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace gimbal {
namespace {

// CVodeGetReturnFlagName hands back memory the caller must free.
std::string flag_name(int flag) {
    char* name = CVodeGetReturnFlagName(flag);
    std::string result = name != nullptr ? name : "unknown flag";
    std::free(name);
    return result;
}

}  // namespace

HybridCvodeIntegrator::HybridCvodeIntegrator(HybridSystem& system, const IntegratorSettings& settings,
                                             MessageSink error_sink, MessageSink event_sink)
    : system_(system),
      settings_(settings),
      error_sink_(std::move(error_sink)),
      event_sink_(std::move(event_sink)),
      size_(system.state_size()),
      root_directions_(system.event_count(), 0) {
    // One context per instance: SUNDIALS keeps no state shared between FMU instances.
    if (SUNContext_Create(nullptr, &context_) != 0) {
        context_ = nullptr;
        return;
    }
    y_ = N_VNew_Serial(size_, context_);
    jacobian_ = SUNDenseMatrix(size_, size_, context_);
    if (y_ != nullptr && jacobian_ != nullptr) linear_solver_ = SUNLinSol_Dense(y_, jacobian_, context_);
    cvode_ = CVodeCreate(CV_BDF, context_);
}

HybridCvodeIntegrator::~HybridCvodeIntegrator() {
    if (cvode_ != nullptr) CVodeFree(&cvode_);
    if (linear_solver_ != nullptr) SUNLinSolFree(linear_solver_);
    if (jacobian_ != nullptr) SUNMatDestroy(jacobian_);
    if (y_ != nullptr) N_VDestroy(y_);
    if (context_ != nullptr) SUNContext_Free(&context_);
}

void HybridCvodeIntegrator::forward_error(int code, const char* module, const char* function, char* message,
                                         void* user_data) {
    auto* self = static_cast<HybridCvodeIntegrator*>(user_data);
    if (code >= 0) return;  // warnings are not failures; the caller reports what matters
    self->error_sink_(std::string(module) + "::" + function + ": " + message);
}

int HybridCvodeIntegrator::right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<HybridCvodeIntegrator*>(user_data);
    // Recoverable failure: CVODE retries with a smaller step.
    return self->system_.derivative(time, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
}

int HybridCvodeIntegrator::event_functions(sunrealtype time, N_Vector y, sunrealtype* values, void* user_data) {
    auto* self = static_cast<HybridCvodeIntegrator*>(user_data);
    if (time < self->dwell_until_) {
        std::fill(values, values + self->root_directions_.size(), 1.0);
        return 0;
    }
    self->system_.event_functions(time, N_VGetArrayPointer(y), values);
    return 0;
}

void HybridCvodeIntegrator::accumulate_statistics() {
    if (!initialized_) return;
    long value = 0;
    CVodeGetNumSteps(cvode_, &value);
    totals_.steps += value;
    CVodeGetNumRhsEvals(cvode_, &value);
    totals_.rhs_evaluations += value;
    CVodeGetNumJacEvals(cvode_, &value);
    totals_.jacobian_evaluations += value;
}

bool HybridCvodeIntegrator::restart(double time, const double* state) {
    if (cvode_ == nullptr || linear_solver_ == nullptr) {
        error_sink_("CVODE could not be created (out of memory)");
        return false;
    }
    std::copy(state, state + size_, N_VGetArrayPointer(y_));
    int flag;
    if (!initialized_) {
        flag = CVodeInit(cvode_, right_hand_side, time, y_);
        if (flag == CV_SUCCESS) flag = CVodeSetUserData(cvode_, this);
        if (flag == CV_SUCCESS) flag = CVodeSetErrHandlerFn(cvode_, forward_error, this);
        if (flag == CV_SUCCESS)
            flag = CVodeSStolerances(cvode_, settings_.relative_tolerance, settings_.absolute_tolerance);
        if (flag == CV_SUCCESS) flag = CVodeSetLinearSolver(cvode_, linear_solver_, jacobian_);
        if (flag == CV_SUCCESS) flag = CVodeSetMaxNumSteps(cvode_, settings_.max_steps);
        if (flag == CV_SUCCESS && settings_.max_step > 0.0) flag = CVodeSetMaxStep(cvode_, settings_.max_step);
        if (flag == CV_SUCCESS && !root_directions_.empty())
            flag = CVodeRootInit(cvode_, static_cast<int>(root_directions_.size()), event_functions);
        // A mode switch can leave an event function at zero: CVODE must not stop there again.
        if (flag == CV_SUCCESS && !root_directions_.empty()) flag = CVodeSetNoInactiveRootWarn(cvode_);
        initialized_ = flag == CV_SUCCESS;
    } else {
        accumulate_statistics();
        flag = CVodeReInit(cvode_, time, y_);
    }
    if (flag != CV_SUCCESS) {
        error_sink_("CVODE set-up failed: " + flag_name(flag));
        return false;
    }
    return true;
}

bool HybridCvodeIntegrator::advance(double end_time, double* state) {
    double* y = N_VGetArrayPointer(y_);
    for (;;) {
        sunrealtype reached = 0.0;
        int flag = CVodeSetStopTime(cvode_, end_time);
        if (flag == CV_SUCCESS) flag = CVode(cvode_, end_time, y_, &reached, CV_NORMAL);
        if (flag < 0) {
            std::ostringstream s;
            s.precision(17);
            s << "CVODE failed at t = " << reached << ": " << flag_name(flag);
            error_sink_(s.str());
            return false;
        }
        std::copy(y, y + size_, state);
        if (flag != CV_ROOT_RETURN) return true;  // reached end_time

        CVodeGetRootInfo(cvode_, root_directions_.data());
        const int changes = system_.update_modes(reached, state, root_directions_.data());
        totals_.events += changes;
        if (changes > 0) {
            std::ostringstream s;
            s.precision(17);
            s << "t = " << reached << ": " << changes << " mode change(s)";
            event_sink_(s.str());
        }
        const double window = settings_.zeno_window * std::max(1.0, std::fabs(reached));
        rapid_events_ = reached - last_event_time_ <= window ? rapid_events_ + 1 : 0;
        last_event_time_ = reached;
        if (rapid_events_ >= settings_.zeno_event_limit) {
            dwell_until_ = reached + settings_.zeno_dwell * std::max(1.0, std::fabs(reached));
            rapid_events_ = 0;
            ++totals_.zeno_holds;
            std::ostringstream s;
            s.precision(17);
            s << "t = " << reached << ": " << settings_.zeno_event_limit
              << " events without progress in time (chattering); modes held until t = " << dwell_until_;
            event_sink_(s.str());
        }
        if (reached >= end_time) {
            if (changes > 0 && !restart(reached, state)) return false;
            return true;
        }
        // New modes change the right-hand side: restart there, from the (possibly projected) state. A
        // root that changed no mode (a grazing touch) needs no restart: CVODE carries on.
        if (changes > 0 && !restart(reached, state)) return false;
    }
}

IntegratorStatistics HybridCvodeIntegrator::statistics() const {
    IntegratorStatistics stats = totals_;
    if (cvode_ == nullptr || !initialized_) return stats;
    long value = 0;
    CVodeGetNumSteps(cvode_, &value);
    stats.steps += value;
    CVodeGetNumRhsEvals(cvode_, &value);
    stats.rhs_evaluations += value;
    CVodeGetNumJacEvals(cvode_, &value);
    stats.jacobian_evaluations += value;
    return stats;
}

}  // namespace gimbal
