// ARKODE's explicit Runge-Kutta stepper under the hybrid layer. A one-step method restarts for free
// at a discontinuity: ERKStepReset keeps the step size, where a multistep method starts over at
// order 1 from a tiny step.
#include <cstdio>  // arkode_butcher.h uses FILE without including it

#include <arkode/arkode_butcher.h>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>

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

// Our own names: ERKStepGetReturnFlagName allocates its answer and writes into it unchecked.
constexpr FlagName kArkodeFlags[] = {
    GIMBAL_FLAG(ARK_SUCCESS),           GIMBAL_FLAG(ARK_TSTOP_RETURN),     GIMBAL_FLAG(ARK_ROOT_RETURN),
    GIMBAL_FLAG(ARK_WARNING),           GIMBAL_FLAG(ARK_TOO_MUCH_WORK),    GIMBAL_FLAG(ARK_TOO_MUCH_ACC),
    GIMBAL_FLAG(ARK_ERR_FAILURE),       GIMBAL_FLAG(ARK_CONV_FAILURE),     GIMBAL_FLAG(ARK_LINIT_FAIL),
    GIMBAL_FLAG(ARK_LSETUP_FAIL),       GIMBAL_FLAG(ARK_LSOLVE_FAIL),      GIMBAL_FLAG(ARK_RHSFUNC_FAIL),
    GIMBAL_FLAG(ARK_FIRST_RHSFUNC_ERR), GIMBAL_FLAG(ARK_REPTD_RHSFUNC_ERR), GIMBAL_FLAG(ARK_UNREC_RHSFUNC_ERR),
    GIMBAL_FLAG(ARK_RTFUNC_FAIL),       GIMBAL_FLAG(ARK_CONSTR_FAIL),      GIMBAL_FLAG(ARK_MEM_FAIL),
    GIMBAL_FLAG(ARK_MEM_NULL),          GIMBAL_FLAG(ARK_ILL_INPUT),        GIMBAL_FLAG(ARK_NO_MALLOC),
    GIMBAL_FLAG(ARK_BAD_K),             GIMBAL_FLAG(ARK_BAD_T),            GIMBAL_FLAG(ARK_BAD_DKY),
    GIMBAL_FLAG(ARK_TOO_CLOSE),         GIMBAL_FLAG(ARK_VECTOROP_ERR),     GIMBAL_FLAG(ARK_INTERP_FAIL),
    GIMBAL_FLAG(ARK_INVALID_TABLE),     GIMBAL_FLAG(ARK_UNRECOGNIZED_ERROR),
};

#undef GIMBAL_FLAG

std::string flag_name(int flag) {
    const char* name = "an unknown flag";
    for (const FlagName& entry : kArkodeFlags)
        if (entry.flag == flag) name = entry.name;
    return std::string(name) + " (" + std::to_string(flag) + ")";
}

// ARKODE_DORMAND_PRINCE_7_4_5, with ARKODE's own expressions (so the same doubles): its loader,
// ERKStepSetTableNum, writes into the table it allocates without checking the allocation.
ARKodeButcherTable dormand_prince_table() {
    sunrealtype c[7] = {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0};
    sunrealtype A[7 * 7] = {};
    auto a = [&A](int row, int column) -> sunrealtype& { return A[7 * row + column]; };
    a(1, 0) = 1.0 / 5.0;
    a(2, 0) = 3.0 / 40.0;
    a(2, 1) = 9.0 / 40.0;
    a(3, 0) = 44.0 / 45.0;
    a(3, 1) = -56.0 / 15.0;
    a(3, 2) = 32.0 / 9.0;
    a(4, 0) = 19372.0 / 6561.0;
    a(4, 1) = -25360.0 / 2187.0;
    a(4, 2) = 64448.0 / 6561.0;
    a(4, 3) = -212.0 / 729.0;
    a(5, 0) = 9017.0 / 3168.0;
    a(5, 1) = -355.0 / 33.0;
    a(5, 2) = 46732.0 / 5247.0;
    a(5, 3) = 49.0 / 176.0;
    a(5, 4) = -5103.0 / 18656.0;
    a(6, 0) = 35.0 / 384.0;
    a(6, 2) = 500.0 / 1113.0;
    a(6, 3) = 125.0 / 192.0;
    a(6, 4) = -2187.0 / 6784.0;
    a(6, 5) = 11.0 / 84.0;
    sunrealtype b[7] = {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0};
    sunrealtype d[7] = {5179.0 / 57600.0,    0.0,           7571.0 / 16695.0, 393.0 / 640.0,
                        -92097.0 / 339200.0, 187.0 / 2100.0, 1.0 / 40.0};
    return ARKodeButcherTable_Create(7, 5, 4, c, A, b, d);
}

class ArkodeBackend final : public SundialsIntegrator {
public:
    ArkodeBackend(HybridSystem& system, const IntegratorSettings& settings, MessageSink error_sink,
                  MessageSink event_sink)
        : SundialsIntegrator(system, settings, std::move(error_sink), std::move(event_sink)) {
        create_vector();
    }

    ~ArkodeBackend() override {
        if (arkode_ != nullptr) ERKStepFree(&arkode_);
    }

private:
    bool backend_restart(double time) override {
        if (arkode_ == nullptr && !create_arkode(time)) return false;
        if (!fresh_) {
            const int flag = ERKStepReset(arkode_, time, y_);
            if (flag != ARK_SUCCESS) {
                error_sink_("ARKODE restart failed: ERKStepReset returned " + flag_name(flag));
                return false;
            }
        }
        fresh_ = false;
        baseline_ = cumulative();  // whether or not a reset zeroes ARKODE's counters
        return true;
    }

    // All or nothing: a failure leaves no ARKODE memory, and the next restart starts over.
    bool create_arkode(double time) {
        // ERKStepCreate clones 6 work vectors, the Hermite interpolation 4, the first step 7 stages; the
        // rest is margin.
        if (!reserve_spare_vectors(6 + 4 + 7 + 5)) {
            error_sink_("ARKODE could not be created (out of memory)");
            return false;
        }
        arkode_ = ERKStepCreate(right_hand_side, time, y_, context_);
        if (arkode_ == nullptr) {
            error_sink_("ARKODE could not be created (out of memory)");
            return false;
        }
        // No exception may leave before ERKStepFree has run: the message is built after it.
        const char* failed_call = nullptr;
        int failed_flag = ARK_SUCCESS;
        auto succeeded = [&](const char* call, int flag) {
            if (flag == ARK_SUCCESS) return true;
            failed_call = call;
            failed_flag = flag;
            return false;
        };
        bool ok = succeeded("ERKStepSetErrHandlerFn", ERKStepSetErrHandlerFn(arkode_, forward_error, this)) &&
                  succeeded("ERKStepSetUserData", ERKStepSetUserData(arkode_, this));
        if (ok) {
            ARKodeButcherTable table = dormand_prince_table();
            ok = table != nullptr ? succeeded("ERKStepSetTable", ERKStepSetTable(arkode_, table))
                                  : succeeded("ARKodeButcherTable_Create", ARK_MEM_FAIL);
            if (table != nullptr) ARKodeButcherTable_Free(table);
        }
        ok = ok && succeeded("ERKStepSStolerances",
                             ERKStepSStolerances(arkode_, settings_.relative_tolerance, settings_.absolute_tolerance));
        ok = ok && succeeded("ERKStepSetMaxNumSteps", ERKStepSetMaxNumSteps(arkode_, settings_.max_steps));
        if (settings_.max_step > 0.0)
            ok = ok && succeeded("ERKStepSetMaxStep", ERKStepSetMaxStep(arkode_, settings_.max_step));
        if (!root_directions_.empty()) {
            ok = ok && succeeded("ERKStepRootInit", ERKStepRootInit(arkode_, static_cast<int>(root_directions_.size()),
                                                                     event_functions));
            ok = ok && succeeded("ERKStepSetNoInactiveRootWarn", ERKStepSetNoInactiveRootWarn(arkode_));
        }
        if (ok) {
            fresh_ = true;  // created at (time, y_): no reset needed
            return true;
        }
        ERKStepFree(&arkode_);
        arkode_ = nullptr;
        error_sink_(std::string("ARKODE set-up failed: ") + failed_call + " returned " + flag_name(failed_flag));
        return false;
    }

    Outcome backend_advance(double end_time, double& reached) override {
        int flag = ERKStepSetStopTime(arkode_, end_time);
        if (flag == ARK_SUCCESS) flag = ERKStepEvolve(arkode_, end_time, y_, &reached, ARK_NORMAL);
        if (flag < 0) {
            std::ostringstream s;
            s.precision(17);
            s << "ARKODE failed at t = " << reached << ": " << flag_name(flag);
            error_sink_(s.str());
            return Outcome::failure;
        }
        return flag == ARK_ROOT_RETURN ? Outcome::root : Outcome::reached_end;
    }

    void backend_roots(int* directions) override { ERKStepGetRootInfo(arkode_, directions); }

    IntegratorStatistics backend_counters() const override {
        const IntegratorStatistics now = cumulative();
        IntegratorStatistics run;
        run.steps = now.steps - baseline_.steps;
        run.rhs_evaluations = now.rhs_evaluations - baseline_.rhs_evaluations;
        return run;
    }

    IntegratorStatistics cumulative() const {
        IntegratorStatistics run;
        if (arkode_ == nullptr) return run;
        long value = 0;
        ERKStepGetNumSteps(arkode_, &value);
        run.steps = value;
        ERKStepGetNumRhsEvals(arkode_, &value);
        run.rhs_evaluations = value;
        return run;
    }

    void* arkode_ = nullptr;
    bool fresh_ = false;
    IntegratorStatistics baseline_;
};

}  // namespace

std::unique_ptr<HybridIntegrator> make_arkode_backend(HybridSystem& system, const IntegratorSettings& settings,
                                                      HybridIntegrator::MessageSink error_sink,
                                                      HybridIntegrator::MessageSink event_sink) {
    return std::make_unique<ArkodeBackend>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
