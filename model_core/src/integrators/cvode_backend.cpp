// CVODE under the hybrid layer: BDF or Adams-Moulton, Newton iteration with a dense linear solver.
#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <sstream>
#include <string>

#include "sundials_integrator.hpp"

namespace gimbal {
namespace {

struct FlagName {
    int flag;
    const char* name;
};

#define GIMBAL_FLAG(name) \
    { name, #name }

// Our own names: CVodeGetReturnFlagName allocates its answer and writes into it unchecked.
constexpr FlagName kCvodeFlags[] = {
    GIMBAL_FLAG(CV_SUCCESS),           GIMBAL_FLAG(CV_TSTOP_RETURN),      GIMBAL_FLAG(CV_ROOT_RETURN),
    GIMBAL_FLAG(CV_WARNING),           GIMBAL_FLAG(CV_TOO_MUCH_WORK),     GIMBAL_FLAG(CV_TOO_MUCH_ACC),
    GIMBAL_FLAG(CV_ERR_FAILURE),       GIMBAL_FLAG(CV_CONV_FAILURE),      GIMBAL_FLAG(CV_LINIT_FAIL),
    GIMBAL_FLAG(CV_LSETUP_FAIL),       GIMBAL_FLAG(CV_LSOLVE_FAIL),       GIMBAL_FLAG(CV_RHSFUNC_FAIL),
    GIMBAL_FLAG(CV_FIRST_RHSFUNC_ERR), GIMBAL_FLAG(CV_REPTD_RHSFUNC_ERR), GIMBAL_FLAG(CV_UNREC_RHSFUNC_ERR),
    GIMBAL_FLAG(CV_RTFUNC_FAIL),       GIMBAL_FLAG(CV_NLS_INIT_FAIL),     GIMBAL_FLAG(CV_NLS_SETUP_FAIL),
    GIMBAL_FLAG(CV_CONSTR_FAIL),       GIMBAL_FLAG(CV_NLS_FAIL),          GIMBAL_FLAG(CV_MEM_FAIL),
    GIMBAL_FLAG(CV_MEM_NULL),          GIMBAL_FLAG(CV_ILL_INPUT),         GIMBAL_FLAG(CV_NO_MALLOC),
    GIMBAL_FLAG(CV_BAD_K),             GIMBAL_FLAG(CV_BAD_T),             GIMBAL_FLAG(CV_BAD_DKY),
    GIMBAL_FLAG(CV_TOO_CLOSE),         GIMBAL_FLAG(CV_VECTOROP_ERR),      GIMBAL_FLAG(CV_UNRECOGNIZED_ERR),
};

// CVodeSetLinearSolver and CVodeSetJacFn answer in the linear solver interface's own numbers.
constexpr FlagName kLinearSolverFlags[] = {
    GIMBAL_FLAG(CVLS_SUCCESS),         GIMBAL_FLAG(CVLS_MEM_NULL),       GIMBAL_FLAG(CVLS_LMEM_NULL),
    GIMBAL_FLAG(CVLS_ILL_INPUT),       GIMBAL_FLAG(CVLS_MEM_FAIL),       GIMBAL_FLAG(CVLS_PMEM_NULL),
    GIMBAL_FLAG(CVLS_JACFUNC_UNRECVR), GIMBAL_FLAG(CVLS_JACFUNC_RECVR),  GIMBAL_FLAG(CVLS_SUNMAT_FAIL),
    GIMBAL_FLAG(CVLS_SUNLS_FAIL),
};

#undef GIMBAL_FLAG

template <size_t N>
std::string flag_name(const FlagName (&table)[N], int flag) {
    const char* name = "an unknown flag";
    for (const FlagName& entry : table)
        if (entry.flag == flag) name = entry.name;
    return std::string(name) + " (" + std::to_string(flag) + ")";
}

class CvodeBackend final : public SundialsIntegrator {
public:
    CvodeBackend(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                 MessageSink event_sink)
        : SundialsIntegrator(system, settings, std::move(error_sink), std::move(event_sink)) {
        if (!create_vector()) return;
        jacobian_ = create_matrix();
        if (jacobian_ != nullptr) linear_solver_ = SUNLinSol_Dense(y_, jacobian_, context_);
    }

    ~CvodeBackend() override {
        release_cvode();
        if (linear_solver_ != nullptr) SUNLinSolFree(linear_solver_);
        if (jacobian_ != nullptr) SUNMatDestroy(jacobian_);
    }

private:
    static int analytic_jacobian(sunrealtype time, N_Vector y, N_Vector, SUNMatrix jacobian, void* user_data,
                                 N_Vector, N_Vector, N_Vector) {
        auto* self = static_cast<CvodeBackend*>(user_data);
        return without_exceptions(-1, [&] {
            return self->system_.jacobian(time, N_VGetArrayPointer(y), SUNDenseMatrix_Data(jacobian)) ? 0 : -1;
        });
    }

    // A failed CVodeInit has freed CVODE's vectors but kept the pointers, which CVodeFree would free
    // again: that CVODE memory is left behind instead (a few kilobytes, only when memory ran out).
    void release_cvode() {
        if (cvode_ != nullptr && cvode_initialized_) CVodeFree(&cvode_);
        cvode_ = nullptr;
        cvode_initialized_ = false;
        created_ = false;
    }

    bool backend_restart(double time) override {
        if (linear_solver_ == nullptr) {
            error_sink_("CVODE could not be created (out of memory)");
            return false;
        }
        if (!created_) return create_cvode(time);
        const int flag = CVodeReInit(cvode_, time, y_);
        if (flag == CV_SUCCESS) return true;
        error_sink_("CVODE restart failed: CVodeReInit returned " + flag_name(kCvodeFlags, flag));
        return false;
    }

    // All or nothing: a failure leaves no CVODE memory, and the next restart starts over.
    bool create_cvode(double time) {
        // CVodeInit clones 7 work vectors and the Nordsieck array (order + 1 columns), the Newton solver
        // 1 vector, the linear solver interface 2 (and the Jacobian once); the rest is margin.
        const int max_order = settings_.method == IntegrationMethod::adams ? 12 : 5;
        if (!reserve_spare_vectors(7 + max_order + 1 + 3 + 4) || !reserve_spare_matrix()) {
            error_sink_("CVODE could not be created (out of memory)");
            return false;
        }
        cvode_ = CVodeCreate(settings_.method == IntegrationMethod::adams ? CV_ADAMS : CV_BDF, context_);
        if (cvode_ == nullptr) {
            error_sink_("CVODE could not be created (out of memory)");
            return false;
        }
        // No exception may leave before release_cvode() has run: the message is built after it.
        const char* failed_call = nullptr;
        int failed_flag = CV_SUCCESS;
        bool linear_solver_failed = false;
        auto succeeded = [&](const char* call, int flag, bool linear_solver_flag = false) {
            if (flag == CV_SUCCESS) return true;
            failed_call = call;
            failed_flag = flag;
            linear_solver_failed = linear_solver_flag;
            return false;
        };
        // The error handler first: CVodeInit's own failures then reach the log.
        bool ok = succeeded("CVodeSetErrHandlerFn", CVodeSetErrHandlerFn(cvode_, forward_error, this)) &&
                  succeeded("CVodeSetUserData", CVodeSetUserData(cvode_, this));
        ok = ok && succeeded("CVodeInit", CVodeInit(cvode_, right_hand_side, time, y_));
        cvode_initialized_ = ok;
        ok = ok && succeeded("CVodeSStolerances",
                             CVodeSStolerances(cvode_, settings_.relative_tolerance, settings_.absolute_tolerance));
        ok = ok && succeeded("CVodeSetLinearSolver", CVodeSetLinearSolver(cvode_, linear_solver_, jacobian_), true);
        if (settings_.method == IntegrationMethod::bdf_analytic_jacobian && system_.has_jacobian())
            ok = ok && succeeded("CVodeSetJacFn", CVodeSetJacFn(cvode_, analytic_jacobian), true);
        ok = ok && succeeded("CVodeSetMaxNumSteps", CVodeSetMaxNumSteps(cvode_, settings_.max_steps));
        if (settings_.max_step > 0.0)
            ok = ok && succeeded("CVodeSetMaxStep", CVodeSetMaxStep(cvode_, settings_.max_step));
        if (!root_directions_.empty()) {
            ok = ok && succeeded("CVodeRootInit", CVodeRootInit(cvode_, static_cast<int>(root_directions_.size()),
                                                                 event_functions));
            // A mode switch can leave an event function at zero: CVODE must not stop there again.
            ok = ok && succeeded("CVodeSetNoInactiveRootWarn", CVodeSetNoInactiveRootWarn(cvode_));
        }
        if (ok) {
            created_ = true;
            return true;
        }
        release_cvode();
        error_sink_(std::string("CVODE set-up failed: ") + failed_call + " returned " +
                    (linear_solver_failed ? flag_name(kLinearSolverFlags, failed_flag)
                                          : flag_name(kCvodeFlags, failed_flag)));
        return false;
    }

    Outcome backend_advance(double end_time, double& reached) override {
        int flag = CVodeSetStopTime(cvode_, end_time);
        if (flag == CV_SUCCESS) flag = CVode(cvode_, end_time, y_, &reached, CV_NORMAL);
        if (flag < 0) {
            std::ostringstream s;
            s.precision(17);
            s << "CVODE failed at t = " << reached << ": " << flag_name(kCvodeFlags, flag);
            error_sink_(s.str());
            return Outcome::failure;
        }
        return flag == CV_ROOT_RETURN ? Outcome::root : Outcome::reached_end;
    }

    void backend_roots(int* directions) override { CVodeGetRootInfo(cvode_, directions); }

    IntegratorStatistics backend_counters() const override {
        IntegratorStatistics run;
        if (cvode_ == nullptr) return run;
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
    bool cvode_initialized_ = false;  // CVodeInit succeeded: CVodeFree is safe
    bool created_ = false;            // set up completely
};

}  // namespace

std::unique_ptr<HybridIntegrator> make_cvode_backend(HybridSystem& system, const IntegratorSettings& settings,
                                                     HybridIntegrator::MessageSink error_sink,
                                                     HybridIntegrator::MessageSink event_sink) {
    return std::make_unique<CvodeBackend>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
