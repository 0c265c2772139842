// The hybrid integrator on small systems with known event times, independent of the gimbal.
#include <cmath>
#include <cstdlib>
#include <string>

#include "check.hpp"
#include "gimbal/integrators/integrator.hpp"

using namespace gimbal;

namespace {

// A ball dropped from height h0 onto a floor, restitution e: bounce k happens at a known time, and
// the bounces accumulate at t_inf = t1 (1 + e) / (1 - e) (Zeno).
class BouncingBall final : public HybridSystem {
public:
    explicit BouncingBall(double restitution) : restitution_(restitution) {}
    int state_size() const override { return 2; }
    int event_count() const override { return 1; }
    bool derivative(double, const double* x, double* dx) override {
        dx[0] = x[1];
        dx[1] = -9.81;
        return true;
    }
    void event_functions(double, const double* x, double* g) override { g[0] = x[0]; }
    int update_modes(double, double* x, const int* directions) override {
        if (directions == nullptr || directions[0] >= 0 || x[1] >= 0.0) return 0;
        x[0] = 0.0;
        x[1] = -restitution_ * x[1];
        ++bounces;
        return 1;
    }
    int bounces = 0;

private:
    double restitution_;
};

// A switch that chatters: its event function oscillates with the given period, whatever the state.
class Chatter final : public HybridSystem {
public:
    explicit Chatter(double period) : period_(period) {}
    int state_size() const override { return 1; }
    int event_count() const override { return 1; }
    bool derivative(double, const double*, double* dx) override {
        dx[0] = 1.0;
        return true;
    }
    void event_functions(double time, const double*, double* g) override {
        g[0] = std::sin(2.0 * M_PI * time / period_);
    }
    int update_modes(double, double*, const int* directions) override {
        if (directions == nullptr) return 0;
        ++switches;
        return 1;
    }
    long switches = 0;

private:
    double period_;
};

// Two independent decays crossing thresholds at the same instant.
class TwinDecay final : public HybridSystem {
public:
    int state_size() const override { return 2; }
    int event_count() const override { return 2; }
    bool derivative(double, const double* x, double* dx) override {
        dx[0] = -x[0];
        dx[1] = -x[1];
        return true;
    }
    void event_functions(double, const double* x, double* g) override {
        g[0] = x[0] - 0.5;
        g[1] = x[1] - 0.5;
    }
    int update_modes(double time, double*, const int* directions) override {
        if (directions == nullptr) return 0;
        int changes = 0;
        for (int k = 0; k < 2; ++k)
            if (directions[k] != 0) ++changes, crossing_time[k] = time;
        return changes;
    }
    double crossing_time[2] = {-1.0, -1.0};
};

}  // namespace

void check_method(IntegrationMethod method) {
    IntegratorSettings settings;
    settings.method = method;
    settings.relative_tolerance = 1e-10;
    settings.absolute_tolerance = 1e-12;
    auto quiet = [](const std::string& m) { if (std::getenv("DEBUG_INTEGRATOR")) std::fprintf(stderr, "%s\n", m.c_str()); };
    {
        BouncingBall ball(0.5);
        auto integrator_owner = HybridIntegrator::create(ball, settings, quiet, quiet);
        HybridIntegrator& integrator = *integrator_owner;
        double x[2] = {1.0, 0.0};
        CHECK(integrator.restart(0.0, x));
        const double first = std::sqrt(2.0 / 9.81);
        // Before the first bounce, exactly at it (an event on a communication point), then after.
        CHECK(integrator.advance(0.5 * first, x));
        CHECK(ball.bounces == 0);
        CHECK(integrator.advance(first, x));
        CHECK(integrator.advance(first + 0.1, x));
        CHECK(ball.bounces == 1);
        // After the bounce the ball rises with half the impact speed.
        CHECK_NEAR(x[1], 0.5 * 9.81 * first - 9.81 * 0.1, 1e-8);
        // Located bounces are real: after bounce k the next comes (1 + e) v_k / g later; the k-th time is
        // t1 (1 + 2 e (1 - e^(k-1)) / (1 - e)). Re-run and check the third bounce time.
        BouncingBall again(0.5);
        auto second_owner = HybridIntegrator::create(again, settings, quiet, quiet);
        HybridIntegrator& second = *second_owner;
        double y[2] = {1.0, 0.0};
        CHECK(second.restart(0.0, y));
        const double third = first * (1.0 + 2.0 * 0.5 * (1.0 - 0.25) / 0.5);
        CHECK(second.advance(third - 1e-6, y));
        CHECK(again.bounces == 2);
        CHECK(second.advance(third + 1e-6, y));
        CHECK(again.bounces == 3);
    }
    {
        // Chatter at 2e10 switches per second: the guard holds the modes and time goes on.
        Chatter fast(1e-10);
        IntegratorSettings fine = settings;
        fine.max_step = 2e-11;  // so that every sign change is seen
        fine.max_steps = 2000000;
        auto integrator_owner = HybridIntegrator::create(fast, fine, quiet, quiet);
        HybridIntegrator& integrator = *integrator_owner;
        double x[1] = {0.0};
        CHECK(integrator.restart(1e-11, x));
        CHECK(integrator.advance(2e-5, x));
        CHECK_NEAR(x[0], 2e-5 - 1e-11, 1e-12);
        const IntegratorStatistics stats = integrator.statistics();
        CHECK(stats.zeno_holds >= 10);
        CHECK(fast.switches < 20000);  // instead of 400000
    }
    {
        // Switches 2 ns apart are real: every one of them is located.
        Chatter slow(4e-9);
        IntegratorSettings fine = settings;
        fine.max_step = 1e-9;
        auto integrator_owner = HybridIntegrator::create(slow, fine, quiet, quiet);
        HybridIntegrator& integrator = *integrator_owner;
        double x[1] = {0.0};
        CHECK(integrator.restart(1e-10, x));
        CHECK(integrator.advance(1e-6 + 1e-9, x));
        CHECK(integrator.statistics().zeno_holds == 0);
        CHECK(slow.switches == 500);
    }
    {
        TwinDecay twins;
        auto integrator_owner = HybridIntegrator::create(twins, settings, quiet, quiet);
        HybridIntegrator& integrator = *integrator_owner;
        double x[2] = {1.0, 1.0};
        CHECK(integrator.restart(0.0, x));
        CHECK(integrator.advance(1.0, x));
        // Simultaneous events are reported together, both at ln 2.
        CHECK(twins.crossing_time[0] == twins.crossing_time[1]);
        CHECK_NEAR(twins.crossing_time[0], std::log(2.0), 1e-8);
        CHECK(integrator.statistics().events == 2);
    }
}

namespace {

// x' = -x + sin t, x(0) = 1: x = (sin t - cos t) / 2 + 1.5 e^-t. No events.
class ForcedDecay final : public HybridSystem {
public:
    int state_size() const override { return 1; }
    int event_count() const override { return 0; }
    bool derivative(double time, const double* x, double* dx) override {
        dx[0] = -x[0] + std::sin(time);
        return true;
    }
    bool has_jacobian() const override { return true; }
    bool jacobian(double, const double*, double* column_major) override {
        column_major[0] = -1.0;
        return true;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
    static double exact(double t) { return 0.5 * (std::sin(t) - std::cos(t)) + 1.5 * std::exp(-t); }
};

// The real-time method: RODAS4 on a fixed grid of substeps, bounded event work.
void check_real_time() {
    auto quiet = [](const std::string&) {};
    {
        // Order 4 in the substeps on a problem with a known solution (communication steps of 0.1 s).
        double errors[3];
        for (int k = 0; k < 3; ++k) {
            ForcedDecay decay;
            IntegratorSettings settings;
            settings.method = IntegrationMethod::real_time;
            settings.substeps = 1 << k;
            auto integrator = HybridIntegrator::create(decay, settings, quiet, quiet);
            double x[1] = {1.0};
            CHECK(integrator->restart(0.0, x));
            for (int step = 1; step <= 20; ++step) CHECK(integrator->advance(0.1 * step, x));
            errors[k] = std::fabs(x[0] - ForcedDecay::exact(2.0));
            // Every step is taken, none rejected: substeps per communication step exactly.
            CHECK(integrator->statistics().steps == 20 * (1 << k));
            CHECK(integrator->statistics().rejected_steps == 0);
        }
        CHECK(errors[0] < 1e-5);
        CHECK(errors[0] / errors[1] > 12.0 && errors[0] / errors[1] < 22.0);
        CHECK(errors[1] / errors[2] > 12.0 && errors[1] / errors[2] < 22.0);
    }
    {
        // A bouncing ball: each bounce located within the iteration bound, at its known time, until
        // the bounces crowd towards their accumulation point and one step holds more than the bound.
        BouncingBall ball(0.5);
        IntegratorSettings settings;
        settings.method = IntegrationMethod::real_time;
        settings.substeps = 2;
        settings.event_iterations = 10;
        settings.mode_changes_per_step = 3;
        std::string error;
        auto integrator = HybridIntegrator::create(ball, settings, [&](const std::string& m) { error = m; }, quiet);
        double x[2] = {1.0, 0.0};
        CHECK(integrator->restart(0.0, x));
        const double first = std::sqrt(2.0 / 9.81);
        const double third = first * (1.0 + 2.0 * 0.5 * (1.0 - 0.25) / 0.5);
        double time = 0.0;
        while (time + 0.01 < third - 1e-3) CHECK(integrator->advance(time += 0.01, x));
        CHECK(ball.bounces == 2);
        CHECK(integrator->advance(time += 0.01, x));
        CHECK(ball.bounces == 3);
        // After the third bounce at `third` the ball rises with 1/8 of the first impact speed.
        CHECK_NEAR(x[1], 0.125 * 9.81 * first - 9.81 * (time - third), 1e-6);
        const double accumulation = first * 3.0;
        bool failed = false;
        while (!failed && time < accumulation + 0.1) failed = !integrator->advance(time += 0.01, x);
        CHECK(failed);
        CHECK(time <= accumulation + 0.01);
        CHECK(error.find("more than 3 mode changes in the communication step") != std::string::npos);
    }
}

}  // namespace

int main() {
    // The same hybrid layer over every backend.
    check_real_time();
    for (IntegrationMethod method : {IntegrationMethod::bdf_difference_jacobian, IntegrationMethod::adams,
                                     IntegrationMethod::explicit_runge_kutta, IntegrationMethod::automatic,
                                     IntegrationMethod::dormand_prince, IntegrationMethod::rosenbrock}) {
        const int before = check::failures;
        check_method(method);
        if (check::failures != before) std::fprintf(stderr, "  (method %d)\n", static_cast<int>(method));
    }
    return check_report("hybrid_integrator");
}
