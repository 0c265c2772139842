// Edge cases of the one-step integrators' hybrid layer, each once a silent wrong answer: a hold of the
// chattering guard that outlived its dwell, the guard blind at large times, and a Jacobian whose null
// space hid its stiffness. An event a few ulp before the end of a step and a failure that stuck to the
// next attempt are checked for every method in test_every_integrator.cpp.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "check.hpp"
#include "integrators/one_step_integrator.hpp"

using namespace gimbal;

namespace {

auto quiet = [](const std::string& message) {
    if (std::getenv("DEBUG_INTEGRATOR") != nullptr) std::fprintf(stderr, "%s\n", message.c_str());
};

// y' = -s with s = sign(y) chosen at each crossing: a sliding mode, whose exact solution from y(0) > 0
// reaches 0 and stays there. Every step after that chatters.
class SlidingMode final : public HybridSystem {
public:
    int state_size() const override { return 1; }
    int event_count() const override { return 1; }
    bool derivative(double, const double*, double* dy) override {
        dy[0] = -side;
        return true;
    }
    void event_functions(double, const double* y, double* g) override { g[0] = y[0]; }
    int update_modes(double, double* y, const int* directions) override {
        const int chosen = directions != nullptr && directions[0] != 0 ? directions[0] : (y[0] >= 0.0 ? 1 : -1);
        const int changes = chosen != side ? 1 : 0;
        side = chosen;
        return changes;
    }
    int side = 1;
};

// Two bodies of equal inertia joined by a stiff damped spring (k = 1e8, c = 1e5): J times the uniform
// vector is 0, which a power iteration started there reads as "not stiff".
class StiffCoupling final : public HybridSystem {
public:
    int state_size() const override { return 4; }
    int event_count() const override { return 0; }
    bool derivative(double t, const double* x, double* dx) override {
        const double spring = 1e8 * (x[0] - x[1]) + 1e5 * (x[2] - x[3]);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = -spring + std::sin(10.0 * t);
        dx[3] = spring;
        return true;
    }
    bool has_jacobian() const override { return true; }
    bool jacobian(double, const double*, double* j) override {
        for (int k = 0; k < 16; ++k) j[k] = 0.0;
        auto at = [&](int row, int column) -> double& { return j[row + 4 * column]; };
        at(0, 2) = at(1, 3) = 1.0;
        at(2, 0) = -1e8, at(2, 1) = 1e8, at(2, 2) = -1e5, at(2, 3) = 1e5;
        at(3, 0) = 1e8, at(3, 1) = -1e8, at(3, 2) = 1e5, at(3, 3) = -1e5;
        return true;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
};

IntegratorSettings with(IntegrationMethod method) {
    IntegratorSettings settings;
    settings.method = method;
    return settings;
}

}  // namespace

int main() {
    for (IntegrationMethod method :
         {IntegrationMethod::automatic, IntegrationMethod::dormand_prince, IntegrationMethod::rosenbrock}) {
        const int before = check::failures;
        for (double start : {0.0, 1e6}) {
            // The sliding mode: the guard holds the modes for its 1 us dwell and no longer, so |y| stays
            // within a dwell's drift (1e-6) of 0, at any start time (at 1e6 s roots closer than the
            // location tolerance count as chattering too).
            SlidingMode sliding;
            OneStepIntegrator integrator(sliding, with(method), quiet, quiet);
            double y[1] = {1e-3};
            sliding.update_modes(start, y, nullptr);
            CHECK(integrator.restart(start, y));
            double worst = 0.0;
            for (int k = 1; k <= 10; ++k) {
                CHECK(integrator.advance(start + 1e-3 * k, y));
                if (k > 1) worst = std::max(worst, std::fabs(y[0]));
            }
            CHECK(worst <= 2e-6);
            CHECK(integrator.statistics().zeno_holds >= 1);
        }
        if (check::failures != before) std::fprintf(stderr, "  (method %d)\n", static_cast<int>(method));
    }
    {
        // The stiff coupling: the automatic method settles on RODAS4 instead of switching back and forth.
        StiffCoupling coupling;
        OneStepIntegrator integrator(coupling, with(IntegrationMethod::automatic), quiet, quiet);
        double x[4] = {0.0, 0.0, 0.0, 0.0};
        CHECK(integrator.restart(0.0, x));
        for (int k = 1; k <= 100; ++k) CHECK(integrator.advance(1e-3 * k, x));
        const IntegratorStatistics stats = integrator.statistics();
        std::printf("stiff coupling: %ld steps, %ld method switches, %ld right-hand sides\n", stats.steps,
                    stats.method_switches, stats.rhs_evaluations);
        CHECK(stats.method_switches <= 2);
        CHECK(integrator.stiff());
    }
    return check_report("integrator_edge_cases");
}
