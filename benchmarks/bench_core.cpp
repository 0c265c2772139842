// Micro-benchmark of the core's pieces at the ship-stabilization operating point, without FMI or an
// integrator: the right-hand side (base kinematics at a new time included, as every integrator stage
// has), the event functions at the point of the last right-hand side (what the integrator checks after
// every step), the Jacobian, and the outputs. CPU time per call, best of several repetitions.
//
//   build/benchmarks/gimbal_bench_core [--json] [--calls N] [--fidelity full|reduced]
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/simulation/parameter_building.hpp"

using namespace gimbal;

namespace {

double cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

volatile double g_sink = 0.0;  // keeps the measured work alive

template <class Work>
double nanoseconds_per_call(long calls, Work&& work) {
    double best = 1e300;
    for (int repeat = 0; repeat < 5; ++repeat) {
        const double start = cpu_seconds();
        double accumulated = 0.0;
        for (long i = 0; i < calls; ++i) accumulated += work(i);
        const double elapsed = cpu_seconds() - start;
        g_sink = g_sink + accumulated;
        best = std::min(best, elapsed);
    }
    return 1e9 * best / static_cast<double>(calls);
}

}  // namespace

int main(int argc, char** argv) {
    long calls = 200000;
    bool json = false;
    std::string fidelity = "full";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--json") json = true;
        else if (a == "--calls" && i + 1 < argc) calls = std::atol(argv[++i]);
        else if (a == "--fidelity" && i + 1 < argc) fidelity = argv[++i];
        else {
            std::fprintf(stderr, "usage: gimbal_bench_core [--json] [--calls N] [--fidelity full|reduced]\n");
            return 2;
        }
    }
    static double reals[kRealVariableCount];
    static int integers[kIntegerVariableCount];
    static bool flags[kBooleanVariableCount];
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals[vr] = kRealVariables[vr].start;
    for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) integers[vr] = static_cast<int>(kIntegerVariables[vr].start);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) flags[vr] = kBooleanVariables[vr].start != 0.0;
    if (fidelity == "reduced")
        integers[vi_gear1_model] = integers[vi_gear2_model] = integers[vi_motor1_model] = integers[vi_motor2_model] = 0;
    ModelParameters params;
    std::string error;
    if (!build_model_parameters(reals, integers, flags, params, error)) {
        std::fprintf(stderr, "gimbal_bench_core: %s\n", error.c_str());
        return 1;
    }
    GimbalHybridSystem system(params);
    StepInputs inputs;
    inputs.commanded_voltage[0] = inputs.voltage[0] = 3.0;
    inputs.commanded_voltage[1] = inputs.voltage[1] = -2.0;
    inputs.base.attitude = Vec3(0.02, 0.01, 0.08);  // a rolling, pitching, yawing ship
    inputs.base.attitude_rate = Vec3(0.03, 0.01, 0.12);
    inputs.base.attitude_accel = Vec3(-0.02, 0.005, -0.15);
    inputs.base.acceleration_a = Vec3(0.1, -0.2, 0.6);
    system.set_inputs(inputs);
    const StateLayout& layout = params.layout;
    const int n = layout.size;
    std::vector<double> state(n, 0.0), derivative(n), jacobian(n * n), guards(std::max(1, system.event_count()));
    const double angles[4] = {0.5, 0.5 * params.gear[0].ratio, 0.35, 0.35 * params.gear[1].ratio};
    const double rates[4] = {0.05, 0.05 * params.gear[0].ratio, -0.02, -0.02 * params.gear[1].ratio};
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        state[layout.angle_slot[body]] = angles[body];
        state[layout.rate_slot[body]] = rates[body];
    }
    for (int axis = 0; axis < 2; ++axis)
        if (layout.current_slot[axis] >= 0) state[layout.current_slot[axis]] = 0.5;
    system.update_modes(0.0, state.data(), nullptr);
    const int rate_slot = layout.rate_slot[0];

    // Every call at a new time and a new state, as the stages of an integrator are.
    const double rhs_ns = nanoseconds_per_call(calls, [&](long i) {
        state[rate_slot] = 0.05 + 1e-12 * static_cast<double>(i & 1023);
        // Within one communication step of the inputs' arc start, as the stages are.
        system.derivative(1e-6 * static_cast<double>(i & 1023), state.data(), derivative.data());
        return derivative[n - 1];
    });
    // The event check after an accepted step: at the point of the last right-hand side.
    const double events_ns = nanoseconds_per_call(calls, [&](long i) {
        (void)i;
        system.event_functions(1e-6 * static_cast<double>((calls - 1) & 1023), state.data(), guards.data());
        return guards[0];
    });
    const double jacobian_ns = nanoseconds_per_call(calls / 10, [&](long i) {
        (void)i;
        system.jacobian(1e-6 * static_cast<double>((calls - 1) & 1023), state.data(), jacobian.data());
        return jacobian[0];
    });
    const double outputs_ns = nanoseconds_per_call(calls / 10, [&](long i) {
        const double time = 1e-6 * static_cast<double>((calls - 1) & 1023);
        const Dynamics& dynamics = system.dynamics_at(time, state.data());
        const ModelOutputs out = outputs_from(params, inputs, system.base_kinematics_at_time(time), time, dynamics);
        return out.kinetic_energy + static_cast<double>(i & 1);
    });
    if (json) {
        std::printf("{\"fidelity\": \"%s\", \"states\": %d, \"event_functions\": %d, \"rhs_ns\": %.1f, "
                    "\"event_check_ns\": %.1f, \"jacobian_ns\": %.1f, \"outputs_ns\": %.1f}\n",
                    fidelity.c_str(), n, system.event_count(), rhs_ns, events_ns, jacobian_ns, outputs_ns);
    } else {
        std::printf("gimbal_bench_core: fidelity %s, %d states, %d event functions, CPU time per call\n", fidelity.c_str(),
                    n, system.event_count());
        std::printf("  right-hand side (new time and state)     %8.1f ns\n", rhs_ns);
        std::printf("  event functions (after a right-hand side) %7.1f ns\n", events_ns);
        std::printf("  Jacobian                                  %7.1f ns\n", jacobian_ns);
        std::printf("  outputs (from the cached dynamics)        %7.1f ns\n", outputs_ns);
    }
    return 0;
}
