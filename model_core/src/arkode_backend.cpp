// ARKODE's explicit Runge-Kutta stepper under the hybrid layer. A one-step method restarts for free
// at a discontinuity: ERKStepReset keeps the step size, where a multistep method starts over at
// order 1 from a tiny step.
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>

#include <cstdlib>
#include <sstream>

#include "sundials_integrator.hpp"

namespace gimbal {
namespace {

std::string flag_name(int flag) {
    char* name = ERKStepGetReturnFlagName(flag);
    std::string result = name != nullptr ? name : "unknown flag";
    std::free(name);
    return result;
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
        int flag;
        if (arkode_ == nullptr) {
            arkode_ = ERKStepCreate(right_hand_side, time, y_, context_);
            if (arkode_ == nullptr) {
                error_sink_("ARKODE could not be created (out of memory)");
                return false;
            }
            flag = ERKStepSetUserData(arkode_, this);
            if (flag == ARK_SUCCESS) flag = ERKStepSetErrHandlerFn(arkode_, forward_error, this);
            if (flag == ARK_SUCCESS) flag = ERKStepSetTableNum(arkode_, ARKODE_DORMAND_PRINCE_7_4_5);
            if (flag == ARK_SUCCESS)
                flag = ERKStepSStolerances(arkode_, settings_.relative_tolerance, settings_.absolute_tolerance);
            if (flag == ARK_SUCCESS) flag = ERKStepSetMaxNumSteps(arkode_, settings_.max_steps);
            if (flag == ARK_SUCCESS && settings_.max_step > 0.0) flag = ERKStepSetMaxStep(arkode_, settings_.max_step);
            if (flag == ARK_SUCCESS && !root_directions_.empty())
                flag = ERKStepRootInit(arkode_, static_cast<int>(root_directions_.size()), event_functions);
            if (flag == ARK_SUCCESS && !root_directions_.empty()) flag = ERKStepSetNoInactiveRootWarn(arkode_);
        } else {
            flag = ERKStepReset(arkode_, time, y_);
        }
        if (flag != ARK_SUCCESS) {
            error_sink_("ARKODE set-up failed: " + flag_name(flag));
            return false;
        }
        baseline_ = cumulative();  // whether or not a reset zeroes ARKODE's counters
        return true;
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
    IntegratorStatistics baseline_;
};

}  // namespace

std::unique_ptr<HybridIntegrator> make_arkode_backend(HybridSystem& system, const IntegratorSettings& settings,
                                                      HybridIntegrator::MessageSink error_sink,
                                                      HybridIntegrator::MessageSink event_sink) {
    return std::make_unique<ArkodeBackend>(system, settings, std::move(error_sink), std::move(event_sink));
}

}  // namespace gimbal
