// The hybrid integrator's bounds on event work, independent of the gimbal. What every method shares
// (orders, event location, the chattering guard, the contract) is in test_every_integrator.cpp.
#include <cmath>
#include <cstdlib>
#include <string>

#include "check.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "hybrid_test_systems.hpp"

using namespace gimbal;
using hybrid_test_systems::BouncingBall;

namespace {

// The real-time method: RODAS4 on a fixed grid of substeps, bounded event work.
void check_real_time() {
    auto quiet = [](const std::string&) {};
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
        const double first = ball.bounce_time(1);
        const double third = ball.bounce_time(3);
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
    check_real_time();
    return check_report("hybrid_integrator");
}
