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

struct Options {
    long calls = 200000;
    bool json = false;
    std::string fidelity = "full";
};

// The command line; false when it is not understood.
bool parse(int argc, char** argv, Options& o) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--json") o.json = true;
        else if (a == "--calls" && i + 1 < argc) o.calls = std::atol(argv[++i]);
        else if (a == "--fidelity" && i + 1 < argc) o.fidelity = argv[++i];
        else return false;
    }
    return true;
}

// The parameters from every variable's start value (reduced: rigid gears, quasi-static motors).
bool start_parameters(const std::string& fidelity, ModelParameters& params, std::string& error) {
    static double reals[kRealVariableCount];
    static int integers[kIntegerVariableCount];
    static bool flags[kBooleanVariableCount];
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals[vr] = kRealVariables[vr].start;
    for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) integers[vr] = static_cast<int>(kIntegerVariables[vr].start);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) flags[vr] = kBooleanVariables[vr].start != 0.0;
    if (fidelity == "reduced")
        integers[vi_gear1_model] = integers[vi_gear2_model] = integers[vi_motor1_model] = integers[vi_motor2_model] = 0;
    return build_model_parameters(reals, integers, flags, params, error);
}

// The ship-stabilization operating point: a rolling, pitching, yawing ship, both motors driven.
StepInputs ship_inputs() {
    StepInputs inputs;
    inputs.commanded_voltage[0] = inputs.voltage[0] = 3.0;
    inputs.commanded_voltage[1] = inputs.voltage[1] = -2.0;
    inputs.base.attitude = Vec3(0.02, 0.01, 0.08);
    inputs.base.attitude_rate = Vec3(0.03, 0.01, 0.12);
    inputs.base.attitude_accel = Vec3(-0.02, 0.005, -0.15);
    inputs.base.acceleration_a = Vec3(0.1, -0.2, 0.6);
    return inputs;
}

// A state at the operating point: the bodies turned and turning, the armature currents at 0.5 A.
std::vector<double> operating_state(const ModelParameters& params) {
    const StateLayout& layout = params.layout;
    std::vector<double> state(layout.size, 0.0);
    const double angles[4] = {0.5, 0.5 * params.gear[0].ratio, 0.35, 0.35 * params.gear[1].ratio};
    const double rates[4] = {0.05, 0.05 * params.gear[0].ratio, -0.02, -0.02 * params.gear[1].ratio};
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        state[layout.angle_slot[body]] = angles[body];
        state[layout.rate_slot[body]] = rates[body];
    }
    for (int axis = 0; axis < 2; ++axis)
        if (layout.current_slot[axis] >= 0) state[layout.current_slot[axis]] = 0.5;
    return state;
}

struct Costs {
    double rhs_ns, events_ns, jacobian_ns, outputs_ns;
};

Costs measure(long calls, GimbalHybridSystem& system, const ModelParameters& params, const StepInputs& inputs,
              std::vector<double>& state) {
    const int n = params.layout.size;
    std::vector<double> derivative(n), jacobian(n * n), guards(std::max(1, system.event_count()));
    const int rate_slot = params.layout.rate_slot[0];
    Costs costs;
    // Every call at a new time and a new state, as the stages of an integrator are.
    costs.rhs_ns = nanoseconds_per_call(calls, [&](long i) {
        state[rate_slot] = 0.05 + 1e-12 * static_cast<double>(i & 1023);
        // Within one communication step of the inputs' arc start, as the stages are.
        system.derivative(1e-6 * static_cast<double>(i & 1023), state.data(), derivative.data());
        return derivative[n - 1];
    });
    // The event check after an accepted step: at the point of the last right-hand side.
    const double last_time = 1e-6 * static_cast<double>((calls - 1) & 1023);
    costs.events_ns = nanoseconds_per_call(calls, [&](long) {
        system.event_functions(last_time, state.data(), guards.data());
        return guards[0];
    });
    costs.jacobian_ns = nanoseconds_per_call(calls / 10, [&](long) {
        system.jacobian(last_time, state.data(), jacobian.data());
        return jacobian[0];
    });
    costs.outputs_ns = nanoseconds_per_call(calls / 10, [&](long i) {
        const Dynamics& dynamics = system.dynamics_at(last_time, state.data());
        const ModelOutputs out = outputs_from(params, inputs, system.base_kinematics_at_time(last_time), last_time, dynamics);
        return out.kinetic_energy + static_cast<double>(i & 1);
    });
    return costs;
}

void print_costs(const Options& o, int states, int event_functions, const Costs& c) {
    if (o.json) {
        std::printf("{\"fidelity\": \"%s\", \"states\": %d, \"event_functions\": %d, \"rhs_ns\": %.1f, "
                    "\"event_check_ns\": %.1f, \"jacobian_ns\": %.1f, \"outputs_ns\": %.1f}\n",
                    o.fidelity.c_str(), states, event_functions, c.rhs_ns, c.events_ns, c.jacobian_ns, c.outputs_ns);
        return;
    }
    std::printf("gimbal_bench_core: fidelity %s, %d states, %d event functions, CPU time per call\n", o.fidelity.c_str(),
                states, event_functions);
    std::printf("  right-hand side (new time and state)     %8.1f ns\n", c.rhs_ns);
    std::printf("  event functions (after a right-hand side) %7.1f ns\n", c.events_ns);
    std::printf("  Jacobian                                  %7.1f ns\n", c.jacobian_ns);
    std::printf("  outputs (from the cached dynamics)        %7.1f ns\n", c.outputs_ns);
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    if (!parse(argc, argv, o)) {
        std::fprintf(stderr, "usage: gimbal_bench_core [--json] [--calls N] [--fidelity full|reduced]\n");
        return 2;
    }
    ModelParameters params;
    std::string error;
    if (!start_parameters(o.fidelity, params, error)) {
        std::fprintf(stderr, "gimbal_bench_core: %s\n", error.c_str());
        return 1;
    }
    GimbalHybridSystem system(params);
    const StepInputs inputs = ship_inputs();
    system.set_inputs(inputs);
    std::vector<double> state = operating_state(params);
    system.update_modes(0.0, state.data(), nullptr);
    const Costs costs = measure(o.calls, system, params, inputs, state);
    print_costs(o, params.layout.size, system.event_count(), costs);
    return 0;
}
