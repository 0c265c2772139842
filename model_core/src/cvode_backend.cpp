// CVODE under the hybrid layer: BDF or Adams-Moulton, Newton iteration with a dense linear solver.
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cstdlib>
#include <sstream>

#include "sundials_integrator.hpp"

namespace gimbal {
namespace {

// CVodeGetReturnFlagName hands back memory the caller must free.
std::string flag_name(int flag) {
    char* name = CVodeGetReturnFlagName(flag);
    std::string result = name != nullptr ? name : "unknown flag";
    std::free(name);
    return result;
}

class CvodeBackend final : public SundialsIntegrator {
public:
    CvodeBackend(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                 MessageSink event_sink)
        : SundialsIntegrator(system, settings, std::move(error_sink), std::move(event_sink)) {
        if (!create_vector()) return;
        jacobian_ = SUNDenseMatrix(size_, size_, context_);
        if (jacobian_ != nullptr) linear_solver_ = SUNLinSol_Dense(y_, jacobian_, context_);
        cvode_ = CVodeCreate(settings.method == IntegrationMethod::adams ? CV_ADAMS : CV_BDF, context_);
    }

    ~CvodeBackend() override {
        if (cvode_ != nullptr) CVodeFree(&cvode_);
        if (linear_solver_ != nullptr) SUNLinSolFree(linear_solver_);
        if (jacobian_ != nullptr) SUNMatDestroy(jacobian_);
    }

private:
    static int analytic_jacobian(sunrealtype time, N_Vector y, N_Vector, SUNMatrix jacobian, void* user_data,
                                 N_Vector, N_Vector, N_Vector) {
        auto* self = static_cast<CvodeBackend*>(user_data);
        return self->system_.jacobian(time, N_VGetArrayPointer(y), SUNDenseMatrix_Data(jacobian)) ? 0 : -1;
    }

    bool backend_restart(double time) override {
        if (cvode_ == nullptr || linear_solver_ == nullptr) {
            error_sink_("CVODE could not be created (out of memory)");
            return false;
        }
        int flag;
        if (!created_) {
            flag = CVodeInit(cvode_, right_hand_side, time, y_);
            if (flag == CV_SUCCESS) flag = CVodeSetUserData(cvode_, this);
            if (flag == CV_SUCCESS) flag = CVodeSetErrHandlerFn(cvode_, forward_error, this);
            if (flag == CV_SUCCESS)
                flag = CVodeSStolerances(cvode_, settings_.relative_tolerance, settings_.absolute_tolerance);
            if (flag == CV_SUCCESS) flag = CVodeSetLinearSolver(cvode_, linear_solver_, jacobian_);
            if (flag == CV_SUCCESS && settings_.method == IntegrationMethod::bdf_analytic_jacobian && system_.has_jacobian())
                flag = CVodeSetJacFn(cvode_, analytic_jacobian);
            if (flag == CV_SUCCESS) flag = CVodeSetMaxNumSteps(cvode_, settings_.max_steps);
            if (flag == CV_SUCCESS && settings_.max_step > 0.0) flag = CVodeSetMaxStep(cvode_, settings_.max_step);
            if (flag == CV_SUCCESS && !root_directions_.empty())
                flag = CVodeRootInit(cvode_, static_cast<int>(root_directions_.size()), event_functions);
            // A mode switch can leave an event function at zero: CVODE must not stop there again.
            if (flag == CV_SUCCESS && !root_directions_.empty()) flag = CVodeSetNoInactiveRootWarn(cvode_);
            created_ = flag == CV_SUCCESS;
        } else {
            flag = CVodeReInit(cvode_, time, y_);
        }
        if (flag != CV_SUCCESS) {
            error_sink_("CVODE set-up failed: " + flag_name(flag));
            return false;
        }
        return true;
    }

    Outcome backend_advance(double end_time, double& reached) override {
        int flag = CVodeSetStopTime(cvode_, end_time);
        if (flag == CV_SUCCESS) flag = CVode(cvode_, end_time, y_, &reached, CV_NORMAL);
        if (flag < 0) {
            std::ostringstream s;
            s.precision(17);
            s << "CVODE failed at t = " << reached << ": " << flag_name(flag);
            error_sink_(s.str());
            return Outcome::failure;
        }
        return flag == CV_ROOT_RETURN ? Outcome::root : Outcome::reached_end;
    }

    void backend_roots(int* directions) override { CVodeGetRootInfo(cvode_, directions); }

    IntegratorStatistics backend_counters() const override {
        IntegratorStatistics run;
        long value = 0;
        CVodeGetNumSteps(cvode_, &value);
        run.steps = value;
        CVodeGetNumRhsEvals(cvode_, &value);
        run.rhs_evaluations = value;
        // Difference quotients cost one right-hand side per state column: count them as such.
        long jacobian_rhs = 0;
        CVodeGetNumLinRhsEvals(cvode_, &jacobian_rhs);
        run.rhs_evaluations += jacobian_rhs;
        CVodeGetNumJacEvals(cvode_, &value);
        run.jacobian_evaluations = value;
        return run;
    }

    SUNMatrix jacobian_ = nullptr;
    SUNLinearSolver linear_solver_ = nullptr;
    void* cvode_ = nullptr;
    bool created_ = false;
};

}  // namespace

std::unique_ptr<HybridIntegrator> make_cvode_backend(HybridSystem& system, const IntegratorSettings& settings,
                                                     HybridIntegrator::MessageSink error_sink,
                                                     HybridIntegrator::MessageSink event_sink) {
    return std::make_unique<CvodeBackend>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
