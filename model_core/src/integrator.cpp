#include "gimbal/integrator.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cstdlib>
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

CvodeIntegrator::CvodeIntegrator(const ModelParameters& params, ErrorSink error_sink)
    : params_(params), error_sink_(std::move(error_sink)) {
    // One context per instance: SUNDIALS keeps no state shared between FMU instances.
    if (SUNContext_Create(nullptr, &context_) != 0) {
        context_ = nullptr;
        return;
    }
    y_ = N_VNew_Serial(kStateSize, context_);
    jacobian_ = SUNDenseMatrix(kStateSize, kStateSize, context_);
    if (y_ != nullptr && jacobian_ != nullptr) linear_solver_ = SUNLinSol_Dense(y_, jacobian_, context_);
    cvode_ = CVodeCreate(CV_BDF, context_);
}

CvodeIntegrator::~CvodeIntegrator() {
    if (cvode_ != nullptr) CVodeFree(&cvode_);
    if (linear_solver_ != nullptr) SUNLinSolFree(linear_solver_);
    if (jacobian_ != nullptr) SUNMatDestroy(jacobian_);
    if (y_ != nullptr) N_VDestroy(y_);
    if (context_ != nullptr) SUNContext_Free(&context_);
}

void CvodeIntegrator::forward_error(int code, const char* module, const char* function, char* message,
                                   void* user_data) {
    auto* self = static_cast<CvodeIntegrator*>(user_data);
    if (code >= 0) return;  // warnings are not failures; the caller reports what matters
    self->error_sink_(std::string(module) + "::" + function + ": " + message);
}

int CvodeIntegrator::right_hand_side(sunrealtype time, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodeIntegrator*>(user_data);
    const Eigen::Map<const StateVector> state(N_VGetArrayPointer(y));
    Eigen::Map<StateVector> derivative(N_VGetArrayPointer(ydot));
    StateVector result;
    evaluate_state_derivative(self->params_, self->inputs_, time, state, result);
    if (!result.allFinite()) return 1;  // recoverable: CVODE retries with a smaller step
    derivative = result;
    return 0;
}

bool CvodeIntegrator::restart(double time, const StateVector& state) {
    if (cvode_ == nullptr || linear_solver_ == nullptr) {
        error_sink_("CVODE could not be created (out of memory)");
        return false;
    }
    Eigen::Map<StateVector>(N_VGetArrayPointer(y_)) = state;
    int flag;
    if (!initialized_) {
        flag = CVodeInit(cvode_, right_hand_side, time, y_);
        if (flag == CV_SUCCESS) flag = CVodeSetUserData(cvode_, this);
        if (flag == CV_SUCCESS) flag = CVodeSetErrHandlerFn(cvode_, forward_error, this);
        if (flag == CV_SUCCESS) flag = CVodeSStolerances(cvode_, params_.relative_tolerance, params_.absolute_tolerance);
        if (flag == CV_SUCCESS) flag = CVodeSetLinearSolver(cvode_, linear_solver_, jacobian_);
        if (flag == CV_SUCCESS) flag = CVodeSetMaxNumSteps(cvode_, 100000);
        initialized_ = flag == CV_SUCCESS;
    } else {
        flag = CVodeReInit(cvode_, time, y_);
    }
    if (flag != CV_SUCCESS) {
        error_sink_("CVODE set-up failed: " + flag_name(flag));
        return false;
    }
    return true;
}

bool CvodeIntegrator::advance(const StepInputs& inputs, double end_time, StateVector& state) {
    inputs_ = inputs;
    sunrealtype reached = 0.0;
    int flag = CVodeSetStopTime(cvode_, end_time);
    if (flag == CV_SUCCESS) flag = CVode(cvode_, end_time, y_, &reached, CV_NORMAL);
    if (flag < 0) {
        error_sink_("CVODE failed at t = " + std::to_string(reached) + ": " + flag_name(flag));
        return false;
    }
    state = Eigen::Map<const StateVector>(N_VGetArrayPointer(y_));
    return true;
}

IntegratorStatistics CvodeIntegrator::statistics() const {
    IntegratorStatistics stats;
    if (cvode_ == nullptr || !initialized_) return stats;
    long value = 0;
    CVodeGetNumSteps(cvode_, &value);
    stats.steps = value;
    CVodeGetNumRhsEvals(cvode_, &value);
    stats.rhs_evaluations = value;
    CVodeGetNumJacEvals(cvode_, &value);
    stats.jacobian_evaluations = value;
    return stats;
}

}  // namespace gimbal
