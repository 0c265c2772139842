// Integrators under a hybrid system: each locates the mode changes of the system's event functions,
// lets the system switch its modes there, and carries on from the switching point.
//
// Two families share this interface:
// - the project's own one-step methods (one_step_integrator.hpp): Dormand-Prince 5(4) and the
//   Rosenbrock method RODAS4, alone or switched automatically by stiffness. They keep their step size
//   across communication points and restart after an input jump at the cost of one right-hand side;
// - SUNDIALS CVODE (BDF, Adams) and ARKODE (explicit Runge-Kutta), kept as reference methods (in
//   builds with GIMBAL_WITH_SUNDIALS only).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "gimbal/hybrid_system/event_handling.hpp"
#include "gimbal/hybrid_system/hybrid_system.hpp"

namespace gimbal {

// 64-bit on every platform (long is 32-bit on Windows: rhs_evaluations would overflow within a day
// of simulated time at 1 kHz).
struct IntegratorStatistics {
    std::int64_t steps = 0;             // accepted steps
    std::int64_t rhs_evaluations = 0;
    std::int64_t jacobian_evaluations = 0;
    std::int64_t events = 0;            // located mode changes
    std::int64_t zeno_holds = 0;        // times the chattering guard engaged
    std::int64_t method_switches = 0;   // automatic method: explicit <-> Rosenbrock
    std::int64_t rejected_steps = 0;
};

enum class IntegrationMethod : int {
    bdf_analytic_jacobian = 0,    // CVODE BDF, Newton with the system's Jacobian
    bdf_difference_jacobian = 1,  // CVODE BDF, Newton with a difference-quotient Jacobian
    adams = 2,                    // CVODE Adams-Moulton, Newton with a difference-quotient Jacobian
    explicit_runge_kutta = 3,     // ARKODE ERKStep, Dormand-Prince 5(4), adaptive
    automatic = 4,                // own: Dormand-Prince 5(4), RODAS4 while the problem is stiff (default)
    dormand_prince = 5,           // own: Dormand-Prince 5(4) only
    rosenbrock = 6,               // own: RODAS4 only
    real_time = 7,                // own: RODAS4 in a fixed number of equal substeps, bounded event work
};
constexpr int kIntegrationMethodCount = 8;

inline bool is_sundials_method(IntegrationMethod method) { return static_cast<int>(method) <= 3; }

// Whether this build carries SUNDIALS (CMake option GIMBAL_WITH_SUNDIALS, ON for the native build).
// Without it (the FMU's win64 binary, a build from the FMU's sources/) the SUNDIALS methods 0-3 are
// refused with the parameters; the project's own methods 4-6 need nothing else. A compiler invoked
// without the definition (the source FMU's documented build) builds without SUNDIALS.
#ifndef GIMBAL_WITH_SUNDIALS
#define GIMBAL_WITH_SUNDIALS 0
#endif
constexpr bool kSundialsAvailable = GIMBAL_WITH_SUNDIALS != 0;

struct IntegratorSettings {
    IntegrationMethod method = IntegrationMethod::automatic;
    double relative_tolerance = 1e-6;
    double absolute_tolerance = 1e-8;
    long max_steps = 100000;  // internal steps per call of advance
    double max_step = 0.0;    // 0: unlimited. Events are seen as sign changes between steps.
    // Real-time method: equal substeps per communication step, at most `event_iterations` Illinois
    // iterations to locate each mode change, at most `mode_changes_per_step` located mode changes in
    // one communication step (more fail the step: switching late is not safe at a stiff contact).
    int substeps = 1;
    int event_iterations = 100;
    int mode_changes_per_step = 0;  // 0: no limit
    // The chattering guard's limits, and whether anyone listens to event messages (the same whoever
    // integrates: hybrid_system/event_handling.hpp).
    EventHandlingSettings event_handling;
};

// Everything a one-step integrator carries from one communication step to the next besides the state:
// saved with an FMU state, so that a restored copy continues bit for bit.
struct IntegratorMemory {
    double step_size = 0.0;       // the controller's next proposal (0: not yet chosen)
    double previous_error = 1e-4; // for the PI controller
    int stiff = 0;                // 1 while the Rosenbrock method runs
    int stiff_votes = 0;          // consecutive explicit steps at the stability boundary
    int nonstiff_votes = 0;       // consecutive steps that voted the other way
    int last_step_rejected = 0;
    ChatteringMemory chattering;
    // Automatic method, for the switch rule's predicted costs (automatic_method_switch.cpp):
    double accuracy_step = 0.0;    // the last step seen limited by accuracy, not stability (0: none)
    double accuracy_time = 0.0;    // when it was seen
    double explicit_step = 0.0;    // the explicit method's last step at its stability limit (0: none)
    double stable_product = 0.0;   // that step times |lambda_max| when RODAS4 took over (0: RODAS4 not run yet)
    double jump_time = 0.0;        // the last restart (an input jump)
    double jump_step = 0.0;        // the controller's proposal then
    int steps_since_jump = -1;     // RODAS4's steps since, if it has run all along (else -1)
};

class HybridIntegrator {
public:
    using MessageSink = gimbal::MessageSink;  // hybrid_system/event_handling.hpp

    static std::unique_ptr<HybridIntegrator> create(HybridSystem& system, const IntegratorSettings& settings,
                                                    MessageSink error_sink, MessageSink event_sink);
    virtual ~HybridIntegrator() = default;
    HybridIntegrator(const HybridIntegrator&) = delete;
    HybridIntegrator& operator=(const HybridIntegrator&) = delete;

    // Starts again at (time, state) after a discontinuity of the right-hand side (new inputs, new
    // modes). A one-step method keeps its step size; a multistep method starts over.
    virtual bool restart(double time, const double* state) = 0;

    // The inputs changed at (time, state) without a jump of the right-hand side (a voltage ramp that
    // continues from where the last one ended): a one-step method refreshes its first stage, whose
    // value would otherwise be stale; a multistep method keeps its history.
    virtual bool inputs_changed(double time, const double* state) {
        (void)time, (void)state;
        return true;
    }

    // Integrates to exactly end_time, switching modes at every located event. False on failure, with
    // the reason sent to the error sink; the state is then unspecified and the caller must roll back.
    virtual bool advance(double end_time, double* state) = 0;

    // As advance(), but returns right after the first mode change before end_time (for a master that
    // allows an early return); `reached` is where it stopped. Integrators that cannot stop there
    // (the SUNDIALS ones) integrate to end_time.
    virtual bool advance_until_mode_change(double end_time, double* state, double& reached) {
        reached = end_time;
        return advance(end_time, state);
    }

    virtual IntegratorStatistics statistics() const = 0;
    // For restoring a saved instance: counts continue from these.
    virtual void set_statistics(const IntegratorStatistics& totals) = 0;

    // Whether memory() holds all this integrator needs to continue bit for bit after a restore; a
    // multistep method's history does not fit, so a snapshot ends its integration segment instead.
    virtual bool resumable() const { return false; }
    virtual IntegratorMemory memory() const { return {}; }
    // With the state the integrator was at when memory() was taken.
    virtual bool resume(double time, const double* state, const IntegratorMemory& memory) {
        (void)memory;
        return restart(time, state);
    }

protected:
    HybridIntegrator() = default;
};

}  // namespace gimbal
