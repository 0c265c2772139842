// The checks around one communication step (simulation/step_checks.cpp): whether the real-time
// method's substeps resolve the gears' contact oscillations, and the report of a step that cost far
// more than the model usually needs. Both format their messages only when there is something to say.
#pragma once

#include <cstdint>
#include <string>

#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/integrators/integrator.hpp"

namespace gimbal {

// The real-time method's bounds (solver.method = 7, docs/real_time.md): chosen by measurement.
constexpr int kRealTimeEventIterations = 10;        // Illinois iterations per located mode change
constexpr int kRealTimeModeChangesPerSubstep = 8;   // located mode changes per substep, on average
constexpr double kRealTimeContactResolution = 1.0;  // largest omega h of a gear's contact oscillation
constexpr double kRealTimeArmatureResolution = 0.1; // smallest (L/R) / h of an inductive motor

// True when every compliant gear's contact oscillation is resolved by substeps of step_size /
// params.substeps (omega h <= kRealTimeContactResolution) and every inductive motor's armature time
// constant is at least kRealTimeArmatureResolution substeps; otherwise false, with the refusal in `why`.
bool real_time_resolution_ok(const ModelParameters& params, const Dynamics& dynamics, double step_size,
                             std::string& why);

// The work of one step against the budget.
struct StepWork {
    double time;       // where the step ended (the host's time)
    double step_size;
    const IntegratorStatistics& before;
    const IntegratorStatistics& after;
    std::int64_t events;  // mode changes in the step
};

// Work of one fmi2DoStep, in right-hand-side evaluations, beyond which the step is reported (about
// 25 ms of CPU at the measured 230 ns per evaluation: 5,000 times the default scene's).
constexpr long kStepWorkBudget = 100000;

// Counts the steps over budget and reports them once in a while: the first time, then at the 2nd,
// 4th, 8th, ... such step, with what most likely makes them expensive.
class StepWorkMonitor {
public:
    void reset() { over_budget_ = 0; }
    // Whether the step was over budget; `report` is then the message to log, or empty when this one
    // is not reported.
    bool over_budget(const StepWork& work, const ModelParameters& params, std::string& report);

private:
    std::int64_t over_budget_ = 0;
};

}  // namespace gimbal
