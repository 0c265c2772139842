// One suite over every integration method the core offers (IntegrationMethod), each through the
// HybridIntegrator interface a simulation uses: its order of convergence on a problem with a known
// solution, event location at known times, and the contract every method keeps (the end time reached,
// max_step and max_steps honoured, failures said and not sticky, statistics, early return, resuming).
// A method added to IntegrationMethod without its MethodTraits here does not compile.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>

#include "check.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "hybrid_test_systems.hpp"

using namespace gimbal;
using namespace hybrid_test_systems;

namespace {

// How a method's error goes to zero: with the step size it is given (order p), with the number of
// fixed substeps per communication step (order p), or with the tolerance (variable-order multistep
// methods, whose order is their own choice).
enum class Convergence { step_size, substeps, tolerance };

template <IntegrationMethod M>
struct MethodTraits;  // undefined: every method needs its own

template <>
struct MethodTraits<IntegrationMethod::bdf_analytic_jacobian> {
    static constexpr const char* name = "CVODE BDF";
    static constexpr Convergence convergence = Convergence::tolerance;
    static constexpr double order = 0.0;
    static constexpr bool one_step = false;
};
template <>
struct MethodTraits<IntegrationMethod::bdf_difference_jacobian> {
    static constexpr const char* name = "CVODE BDF (difference Jacobian)";
    static constexpr Convergence convergence = Convergence::tolerance;
    static constexpr double order = 0.0;
    static constexpr bool one_step = false;
};
template <>
struct MethodTraits<IntegrationMethod::adams> {
    static constexpr const char* name = "CVODE Adams";
    static constexpr Convergence convergence = Convergence::tolerance;
    static constexpr double order = 0.0;
    static constexpr bool one_step = false;
};
template <>
struct MethodTraits<IntegrationMethod::explicit_runge_kutta> {
    static constexpr const char* name = "ARKODE ERK (Dormand-Prince 5(4))";
    static constexpr Convergence convergence = Convergence::step_size;
    static constexpr double order = 5.0;
    static constexpr bool one_step = false;
};
template <>
struct MethodTraits<IntegrationMethod::automatic> {
    static constexpr const char* name = "automatic";
    static constexpr Convergence convergence = Convergence::step_size;
    static constexpr double order = 5.0;  // the problem is not stiff: Dormand-Prince throughout
    static constexpr bool one_step = true;
};
template <>
struct MethodTraits<IntegrationMethod::dormand_prince> {
    static constexpr const char* name = "Dormand-Prince 5(4)";
    static constexpr Convergence convergence = Convergence::step_size;
    static constexpr double order = 5.0;
    static constexpr bool one_step = true;
};
template <>
struct MethodTraits<IntegrationMethod::rosenbrock> {
    static constexpr const char* name = "RODAS4";
    static constexpr Convergence convergence = Convergence::step_size;
    static constexpr double order = 4.0;
    static constexpr bool one_step = true;
};
template <>
struct MethodTraits<IntegrationMethod::real_time> {
    static constexpr const char* name = "real time (RODAS4, fixed substeps)";
    static constexpr Convergence convergence = Convergence::substeps;
    static constexpr double order = 4.0;
    static constexpr bool one_step = true;
};

auto quiet = [](const std::string& message) {
    if (std::getenv("DEBUG_INTEGRATOR") != nullptr) std::fprintf(stderr, "%s\n", message.c_str());
};

template <IntegrationMethod M>
IntegratorSettings tight() {
    IntegratorSettings settings;
    settings.method = M;
    settings.relative_tolerance = 1e-10;
    settings.absolute_tolerance = 1e-12;
    if (M == IntegrationMethod::real_time) settings.substeps = 4;
    return settings;
}

// The forced decay over [0, 1] in `intervals` communication steps; the error at t = 1.
template <IntegrationMethod M>
double forced_decay_error(IntegratorSettings settings, int intervals, IntegratorStatistics* statistics = nullptr) {
    ForcedDecay decay;
    auto integrator = HybridIntegrator::create(decay, settings, quiet, quiet);
    double x[1] = {1.0};
    IntegratorMemory memory;
    memory.step_size = 1.0 / intervals;  // a one-step method's first step: the one imposed
    CHECK(integrator->resume(0.0, x, memory));
    for (int k = 1; k <= intervals; ++k) CHECK(integrator->advance(k == intervals ? 1.0 : double(k) / intervals, x));
    if (statistics != nullptr) *statistics = integrator->statistics();
    return std::fabs(x[0] - ForcedDecay::exact(1.0));
}

// Order of convergence on the forced decay.
template <IntegrationMethod M>
void check_convergence() {
    using Traits = MethodTraits<M>;
    IntegratorSettings settings;
    settings.method = M;
    if constexpr (Traits::convergence == Convergence::step_size) {
        // Steps imposed: a tolerance every step meets, no step beyond the communication step.
        settings.relative_tolerance = settings.absolute_tolerance = 1e3;
        double errors[2];
        for (int k = 0; k < 2; ++k) {
            const int intervals = 10 << k;
            settings.max_step = 1.0 / intervals;
            IntegratorStatistics statistics;
            errors[k] = forced_decay_error<M>(settings, intervals, &statistics);
            // ARKODE picks its first steps itself (a few smaller ones, 6 here), then takes the one imposed.
            if constexpr (Traits::one_step) {
                CHECK(statistics.steps == intervals);
            } else {
                CHECK(statistics.steps >= intervals && statistics.steps <= intervals + 10);
            }
            CHECK(statistics.rejected_steps == 0);
        }
        const double observed = std::log2(errors[0] / errors[1]);
        std::printf("%s: error %.3g -> %.3g with half the step, order %.2f\n", Traits::name, errors[0], errors[1],
                    observed);
        CHECK(std::fabs(observed - Traits::order) < 0.3);
    } else if constexpr (Traits::convergence == Convergence::substeps) {
        double errors[3];
        for (int k = 0; k < 3; ++k) {
            settings.substeps = 1 << k;
            IntegratorStatistics statistics;
            errors[k] = forced_decay_error<M>(settings, 10, &statistics);
            CHECK(statistics.steps == 10 * (1 << k));  // every substep taken, none rejected
            CHECK(statistics.rejected_steps == 0);
        }
        std::printf("%s: error %.3g -> %.3g -> %.3g with twice the substeps, order %.2f, %.2f\n", Traits::name,
                    errors[0], errors[1], errors[2], std::log2(errors[0] / errors[1]), std::log2(errors[1] / errors[2]));
        CHECK(errors[0] < 1e-5);
        CHECK(std::fabs(std::log2(errors[0] / errors[1]) - Traits::order) < 0.3);
        CHECK(std::fabs(std::log2(errors[1] / errors[2]) - Traits::order) < 0.3);
    } else {
        // The error follows the tolerance: within a modest factor of it, and 1000 times smaller for a
        // tolerance 1000 times smaller (to within a factor 10: the method picks its order).
        double errors[2];
        const double tolerances[2] = {1e-6, 1e-9};
        for (int k = 0; k < 2; ++k) {
            settings.relative_tolerance = settings.absolute_tolerance = tolerances[k];
            errors[k] = forced_decay_error<M>(settings, 10);
        }
        std::printf("%s: error %.3g at tolerance 1e-6, %.3g at 1e-9\n", Traits::name, errors[0], errors[1]);
        CHECK(errors[0] < 100.0 * tolerances[0]);
        CHECK(errors[1] < 100.0 * tolerances[1]);
        CHECK(errors[0] / errors[1] > 100.0);
    }
}

// Events at known times: the bounces of a ball, an event on a communication point and one a few ulp
// before it, two simultaneous events reported together.
template <IntegrationMethod M>
void check_event_location() {
    const IntegratorSettings settings = tight<M>();
    {
        BouncingBall ball(0.5);
        auto integrator = HybridIntegrator::create(ball, settings, quiet, quiet);
        double x[2] = {1.0, 0.0};
        CHECK(integrator->restart(0.0, x));
        const double first = ball.bounce_time(1);
        // Before the first bounce, exactly at it (an event on a communication point), then after.
        CHECK(integrator->advance(0.5 * first, x));
        CHECK(ball.bounces == 0);
        CHECK(integrator->advance(first, x));
        CHECK(integrator->advance(first + 0.1, x));
        CHECK(ball.bounces == 1);
        // After the bounce the ball rises with half the impact speed.
        CHECK_NEAR(x[1], 0.5 * kGravity * first - kGravity * 0.1, 1e-8);
        // On a master's grid of 10 ms: the next two bounces, each at its time.
        double time = first + 0.1;
        while (time < ball.bounce_time(3) + 0.005) CHECK(integrator->advance(time += 0.01, x));
        CHECK(ball.bounces == 3);
        for (int k = 1; k <= ball.bounces && k <= 3; ++k) CHECK_NEAR(ball.times[k - 1], ball.bounce_time(k), 1e-8);
        CHECK(integrator->statistics().events == 3);
    }
    {
        // An event 2e-15 s before the end of a 0.01 s step: located, and the step completes.
        Ramp ramp(0.01 - 2e-15);
        auto integrator = HybridIntegrator::create(ramp, settings, quiet, quiet);
        double y[1] = {0.0};
        CHECK(integrator->restart(0.0, y));
        CHECK(integrator->advance(0.01, y));
        CHECK(ramp.crossings == 1);
        CHECK_NEAR(y[0], 0.01, 1e-15);
    }
    {
        TwinDecay twins;
        auto integrator = HybridIntegrator::create(twins, settings, quiet, quiet);
        double x[2] = {1.0, 1.0};
        CHECK(integrator->restart(0.0, x));
        for (int k = 1; k <= 100; ++k) CHECK(integrator->advance(0.01 * k, x));
        CHECK(twins.crossing_time[0] == twins.crossing_time[1]);
        CHECK_NEAR(twins.crossing_time[0], std::log(2.0), 1e-8);
        CHECK(integrator->statistics().events == 2);
    }
}

// The chattering guard (hybrid_system/event_handling.hpp) under every method: switches faster than it
// allows are held, slower ones all located.
template <IntegrationMethod M>
void check_chattering_guard() {
    IntegratorSettings settings = tight<M>();
    {
        // 2e10 switches per second: the guard holds the modes and time goes on.
        Chatter fast(1e-10);
        settings.max_step = 2e-11;  // so that every sign change is seen
        settings.max_steps = 2000000;
        settings.substeps = 1000;   // the real-time method: substeps of 2e-11 s over 2e-8 s
        auto integrator = HybridIntegrator::create(fast, settings, quiet, quiet);
        double x[1] = {0.0};
        CHECK(integrator->restart(1e-11, x));
        // The real-time method in one communication step of 1000 substeps.
        const double end = M == IntegrationMethod::real_time ? 2e-8 : 2e-5;
        CHECK(integrator->advance(end, x));
        CHECK_NEAR(x[0], end - 1e-11, 1e-12);
        CHECK(integrator->statistics().zeno_holds >= 1);
        CHECK(fast.switches < end / 1e-10 / 2.0);  // fewer than the 2 per period it would otherwise take
    }
    {
        // Switches 2 ns apart are real: every one of them is located.
        Chatter slow(4e-9);
        settings = tight<M>();
        settings.max_step = 1e-9;
        settings.substeps = 1000;
        auto integrator = HybridIntegrator::create(slow, settings, quiet, quiet);
        double x[1] = {0.0};
        CHECK(integrator->restart(1e-10, x));
        CHECK(integrator->advance(1e-6 + 1e-9, x));
        CHECK(integrator->statistics().zeno_holds == 0);
        CHECK(slow.switches == 500);
    }
}

// What every method promises its caller.
template <IntegrationMethod M>
void check_contract() {
    using Traits = MethodTraits<M>;
    {
        // max_step bounds every step; the statistics count them and the right-hand sides, and continue
        // from totals set after a restore.
        IntegratorSettings settings = tight<M>();
        settings.max_step = 1e-3;
        ForcedDecay decay;
        auto integrator = HybridIntegrator::create(decay, settings, quiet, quiet);
        double x[1] = {1.0};
        CHECK(integrator->restart(0.0, x));
        CHECK(integrator->advance(0.1, x));
        const IntegratorStatistics first = integrator->statistics();
        if (M != IntegrationMethod::real_time) CHECK(first.steps >= 100);
        CHECK(first.rhs_evaluations >= first.steps);
        IntegratorStatistics totals;
        totals.steps = 1000000, totals.rhs_evaluations = 5000000;
        integrator->set_statistics(totals);
        CHECK(integrator->advance(0.2, x));
        CHECK(integrator->statistics().steps > totals.steps);
        CHECK(integrator->statistics().rhs_evaluations > totals.rhs_evaluations);
        CHECK_NEAR(x[0], ForcedDecay::exact(0.2), 1e-8);
    }
    {
        // A right-hand side that cannot be evaluated fails the step with a message; the failure does not
        // stick: started again, the integrator integrates as if it never happened.
        Cliff cliff;
        std::string error;
        auto integrator = HybridIntegrator::create(cliff, tight<M>(), [&](const std::string& m) { error = m; }, quiet);
        double y[1] = {1.0};
        CHECK(integrator->restart(0.0, y));
        CHECK(!integrator->advance(2.0, y));
        CHECK(!error.empty());
        double fresh[1] = {1.0};
        CHECK(integrator->restart(0.0, fresh));
        CHECK(integrator->advance(0.5, fresh));
        CHECK_NEAR(fresh[0], std::exp(-0.5), 1e-6);
    }
    if constexpr (M != IntegrationMethod::real_time) {
        // More internal steps than max_steps in one call fail it, and say so.
        IntegratorSettings settings = tight<M>();
        settings.max_step = 1e-4;
        settings.max_steps = 50;
        ForcedDecay decay;
        std::string error;
        auto integrator = HybridIntegrator::create(decay, settings, [&](const std::string& m) { error = m; }, quiet);
        double x[1] = {1.0};
        CHECK(integrator->restart(0.0, x));
        CHECK(!integrator->advance(0.1, x));
        CHECK(!error.empty());
    }
    {
        // An early return at the first mode change for a one-step method; the others reach the end,
        // before the second bounce.
        BouncingBall ball(0.5);
        auto integrator = HybridIntegrator::create(ball, tight<M>(), quiet, quiet);
        double x[2] = {1.0, 0.0};
        CHECK(integrator->restart(0.0, x));
        double reached = 0.0;
        CHECK(integrator->advance_until_mode_change(0.8, x, reached));
        CHECK(ball.bounces == 1);
        if constexpr (Traits::one_step) {
            CHECK_NEAR(reached, ball.bounce_time(1), 1e-8);
        } else {
            CHECK(reached == 0.8);
        }
    }
    {
        // A one-step method resumes from its memory bit for bit; a multistep method says it cannot.
        ForcedDecay decay;
        auto integrator = HybridIntegrator::create(decay, tight<M>(), quiet, quiet);
        CHECK(integrator->resumable() == Traits::one_step);
        if constexpr (Traits::one_step) {
            double x[1] = {1.0};
            CHECK(integrator->restart(0.0, x));
            CHECK(integrator->advance(0.5, x));
            const IntegratorMemory memory = integrator->memory();
            double copy[1] = {x[0]};
            CHECK(integrator->advance(1.0, x));
            ForcedDecay again;
            auto resumed = HybridIntegrator::create(again, tight<M>(), quiet, quiet);
            CHECK(resumed->resume(0.5, copy, memory));
            CHECK(resumed->advance(1.0, copy));
            CHECK(std::memcmp(x, copy, sizeof x) == 0);
        }
    }
}

template <IntegrationMethod M>
void check_method() {
    if (is_sundials_method(M) && !kSundialsAvailable) {
        std::printf("%s: not in this build (GIMBAL_WITH_SUNDIALS off)\n", MethodTraits<M>::name);
        return;
    }
    const int before = check::failures;
    check_convergence<M>();
    check_event_location<M>();
    check_chattering_guard<M>();
    check_contract<M>();
    if (check::failures != before) std::fprintf(stderr, "  (%s, method %d)\n", MethodTraits<M>::name, static_cast<int>(M));
}

template <int... Methods>
void check_every_method(std::integer_sequence<int, Methods...>) {
    (check_method<static_cast<IntegrationMethod>(Methods)>(), ...);
}

}  // namespace

int main() {
    check_every_method(std::make_integer_sequence<int, kIntegrationMethodCount>{});
    return check_report("every_integrator");
}
