// gimbal_bench_me: what a Model Exchange host pays per evaluation, against the core's own right-hand
// side, in one run and at one operating point (that of gimbal_bench_core: a rolling, pitching,
// yawing carrier, motors at 3 V and -2 V, both axes moving).
//
// Loads the FMU's shared object with dlopen (as a host does) and times, in CPU time per call, best of
// five repetitions:
// - fmi2SetTime + fmi2SetContinuousStates + fmi2GetDerivatives at a new time and state (one host RHS);
// - fmi2GetEventIndicators at the point of the last derivatives (the host's root check);
// and, linked into this executable, the core's GimbalHybridSystem::derivative at a new state with the
// carrier's motion held as Model Exchange holds it (the same work without the interface), and with the
// carrier moved to a new time as a Co-Simulation integrator stage has it.
//
//   build/benchmarks/gimbal_bench_me --fmu build/fmu_staging/binaries/linux64/Gimbal2Axis.so
//                                    --model-description build/fmu_staging/modelDescription.xml [--json]
#include <dlfcn.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "fmi2Functions.h"
#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/simulation/parameter_building.hpp"
#include "gimbal/model/variable_groups.hpp"

using namespace gimbal;

namespace {

double cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

volatile double g_sink = 0.0;

template <class Work>
double nanoseconds_per_call(long calls, Work&& work) {
    double best = 1e300;
    for (int repeat = 0; repeat < 5; ++repeat) {
        const double start = cpu_seconds();
        double accumulated = 0.0;
        for (long i = 0; i < calls; ++i) accumulated += work(i);
        best = std::min(best, cpu_seconds() - start);
        g_sink = g_sink + accumulated;
    }
    return 1e9 * best / static_cast<double>(calls);
}

[[noreturn]] void die(const std::string& message) {
    std::fprintf(stderr, "gimbal_bench_me: %s\n", message.c_str());
    std::exit(2);
}

void quiet_logger(fmi2ComponentEnvironment, fmi2String, fmi2Status status, fmi2String category, fmi2String message, ...) {
    if (status >= fmi2Error) std::fprintf(stderr, "[%s] %s\n", category, message);
}

// name -> (value reference, type) of <ModelVariables>, read with a regular expression: enough for the
// generator's one-attribute-per-line layout.
std::map<std::string, unsigned> real_references(const std::string& path, std::string& guid) {
    std::ifstream file(path);
    if (!file) die("cannot read " + path);
    std::stringstream text;
    text << file.rdbuf();
    const std::string xml = text.str();
    std::smatch match;
    if (std::regex_search(xml, match, std::regex("guid=\"([^\"]+)\""))) guid = match[1];
    std::map<std::string, unsigned> references;
    const std::regex variable("<ScalarVariable name=\"([^\"]+)\" valueReference=\"([0-9]+)\"[^<]*<Real");
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), variable); it != std::sregex_iterator(); ++it)
        references[(*it)[1]] = static_cast<unsigned>(std::stoul((*it)[2]));
    return references;
}

template <class F>
F load(void* library, const char* name) {
    void* symbol = dlsym(library, name);
    if (symbol == nullptr) die(std::string("the FMU lacks ") + name);
    return reinterpret_cast<F>(symbol);
}

}  // namespace

int main(int argc, char** argv) {
    std::string fmu_path, model_description;
    long calls = 200000;
    bool json = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--fmu" && i + 1 < argc) fmu_path = argv[++i];
        else if (a == "--model-description" && i + 1 < argc) model_description = argv[++i];
        else if (a == "--calls" && i + 1 < argc) calls = std::atol(argv[++i]);
        else if (a == "--json") json = true;
        else die("usage: gimbal_bench_me --fmu <Gimbal2Axis.so> --model-description <modelDescription.xml> [--calls N] [--json]");
    }
    if (fmu_path.empty() || model_description.empty()) die("--fmu and --model-description are required");

    // ---- the core alone, at the operating point of gimbal_bench_core
    static double reals[kRealVariableCount];
    static int integers[kIntegerVariableCount];
    static bool flags[kBooleanVariableCount];
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals[vr] = kRealVariables[vr].start;
    for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) integers[vr] = static_cast<int>(kIntegerVariables[vr].start);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) flags[vr] = kBooleanVariables[vr].start != 0.0;
    ModelParameters params;
    std::string error;
    if (!build_model_parameters(reals, integers, flags, params, error)) die(error);
    StepInputs inputs;
    inputs.commanded_voltage[0] = inputs.voltage[0] = 3.0;
    inputs.commanded_voltage[1] = inputs.voltage[1] = -2.0;
    inputs.base.attitude = Vec3(0.02, 0.01, 0.08);
    inputs.base.attitude_rate = Vec3(0.03, 0.01, 0.12);
    inputs.base.attitude_accel = Vec3(-0.02, 0.005, -0.15);
    inputs.base.acceleration_a = Vec3(0.1, -0.2, 0.6);
    const double angles[4] = {0.5, 0.5 * params.gear[0].ratio, 0.35, 0.35 * params.gear[1].ratio};
    const double rates[4] = {0.05, 0.05 * params.gear[0].ratio, -0.02, -0.02 * params.gear[1].ratio};
    std::vector<double> state(kMaxStateSize, 0.0), derivative(kMaxStateSize);
    const StateLayout& layout = params.layout;
    for (int body = 0; body < 4; ++body) {
        state[layout.angle_slot[body]] = angles[body];
        state[layout.rate_slot[body]] = rates[body];
    }
    for (int axis = 0; axis < 2; ++axis) state[layout.current_slot[axis]] = 0.5;
    const int rate_slot = layout.rate_slot[0];
    auto core_rhs = [&](bool held) {
        GimbalHybridSystem system(params);
        system.hold_inputs_at_any_time(held);
        system.set_inputs(inputs);
        system.update_modes(0.0, state.data(), nullptr);
        return nanoseconds_per_call(calls, [&](long i) {
            state[rate_slot] = 0.05 + 1e-12 * static_cast<double>(i & 1023);
            system.derivative(1e-6 * static_cast<double>(i & 1023), state.data(), derivative.data());
            return derivative[0];
        });
    };
    const double core_held_ns = core_rhs(true);
    const double core_moving_ns = core_rhs(false);

    // ---- the FMU as a Model Exchange host calls it
    std::string guid;
    const std::map<std::string, unsigned> vr = real_references(model_description, guid);
    void* library = dlopen(fmu_path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) die(std::string("dlopen: ") + dlerror());
    auto instantiate = load<fmi2InstantiateTYPE*>(library, "fmi2Instantiate");
    auto setup = load<fmi2SetupExperimentTYPE*>(library, "fmi2SetupExperiment");
    auto enter_init = load<fmi2EnterInitializationModeTYPE*>(library, "fmi2EnterInitializationMode");
    auto exit_init = load<fmi2ExitInitializationModeTYPE*>(library, "fmi2ExitInitializationMode");
    auto set_real = load<fmi2SetRealTYPE*>(library, "fmi2SetReal");
    auto new_discrete_states = load<fmi2NewDiscreteStatesTYPE*>(library, "fmi2NewDiscreteStates");
    auto enter_ct = load<fmi2EnterContinuousTimeModeTYPE*>(library, "fmi2EnterContinuousTimeMode");
    auto set_time = load<fmi2SetTimeTYPE*>(library, "fmi2SetTime");
    auto set_states = load<fmi2SetContinuousStatesTYPE*>(library, "fmi2SetContinuousStates");
    auto get_states = load<fmi2GetContinuousStatesTYPE*>(library, "fmi2GetContinuousStates");
    auto get_derivatives = load<fmi2GetDerivativesTYPE*>(library, "fmi2GetDerivatives");
    auto get_indicators = load<fmi2GetEventIndicatorsTYPE*>(library, "fmi2GetEventIndicators");
    auto free_instance = load<fmi2FreeInstanceTYPE*>(library, "fmi2FreeInstance");

    fmi2CallbackFunctions callbacks{quiet_logger, nullptr, nullptr, nullptr, nullptr};
    fmi2Component me = instantiate("bench", fmi2ModelExchange, guid.c_str(), "", &callbacks, fmi2False, fmi2False);
    if (me == nullptr) die("fmi2Instantiate failed");
    auto set = [&](const char* name, double value) {
        const auto it = vr.find(name);
        if (it == vr.end()) die(std::string("no Real variable ") + name);
        const fmi2ValueReference reference = it->second;
        if (set_real(me, &reference, 1, &value) > fmi2Warning) die(std::string("fmi2SetReal ") + name);
    };
    const char* body_angles[4] = {"alpha", "alpha_m", "beta", "beta_m"};
    const char* body_rates[4] = {"alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot"};
    setup(me, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    for (int body = 0; body < 4; ++body) set(body_angles[body], angles[body]), set(body_rates[body], rates[body]);
    set("i_R1", 0.5), set("i_R2", 0.5);
    enter_init(me);
    set("u_R1", 3.0), set("u_R2", -2.0);
    const char* attitude[3] = {"base.delta", "base.psi", "base.gamma"};
    for (int k = 0; k < 3; ++k) {
        set(attitude[k], inputs.base.attitude[k]);
        set((std::string(attitude[k]) + "_dot").c_str(), inputs.base.attitude_rate[k]);
        set((std::string(attitude[k]) + "_ddot").c_str(), inputs.base.attitude_accel[k]);
        set(("base.a_a[" + std::to_string(k + 1) + "]").c_str(), inputs.base.acceleration_a[k]);
    }
    if (exit_init(me) > fmi2Warning) die("fmi2ExitInitializationMode failed");
    fmi2EventInfo info{};
    new_discrete_states(me, &info);
    enter_ct(me);
    const int nx = kContinuousStateCount, nz = GimbalHybridSystem::kIndicatorCount;
    std::vector<double> x(nx), dx(nx), z(nz);
    get_states(me, x.data(), nx);
    const double host_rhs_ns = nanoseconds_per_call(calls, [&](long i) {
        x[4] = 0.05 + 1e-12 * static_cast<double>(i & 1023);
        set_time(me, 1e-6 * static_cast<double>(i & 1023));
        set_states(me, x.data(), nx);
        get_derivatives(me, dx.data(), nx);
        return dx[0];
    });
    // Its parts: the interface calls alone (the derivatives then come from the cached dynamics).
    const double set_time_ns = nanoseconds_per_call(calls, [&](long i) {
        set_time(me, 1e-6 * static_cast<double>(i & 1023));
        return 0.0;
    });
    const double set_states_ns = nanoseconds_per_call(calls, [&](long i) {
        x[4] = 0.05 + 1e-12 * static_cast<double>(i & 1023);
        set_states(me, x.data(), nx);
        return 0.0;
    });
    const double cached_derivatives_ns = nanoseconds_per_call(calls, [&](long) {
        get_derivatives(me, dx.data(), nx);
        return dx[0];
    });
    const double indicators_ns = nanoseconds_per_call(calls, [&](long) {
        get_indicators(me, z.data(), nz);
        return z[0];
    });
    free_instance(me);

    if (json) {
        std::printf("{\"core_rhs_held_ns\": %.1f, \"core_rhs_moving_ns\": %.1f, \"me_derivatives_ns\": %.1f, "
                    "\"me_event_indicators_ns\": %.1f, \"ratio_derivatives_to_core\": %.3f, \"set_time_ns\": %.1f, "
                    "\"set_states_ns\": %.1f, \"cached_derivatives_ns\": %.1f}\n",
                    core_held_ns, core_moving_ns, host_rhs_ns, indicators_ns, host_rhs_ns / core_held_ns, set_time_ns,
                    set_states_ns, cached_derivatives_ns);
    } else {
        std::printf("gimbal_bench_me: CPU time per call, best of 5 x %ld calls\n", calls);
        std::printf("  core right-hand side, carrier held (as Model Exchange)      %8.1f ns\n", core_held_ns);
        std::printf("  core right-hand side, carrier at a new time (a CS stage)    %8.1f ns\n", core_moving_ns);
        std::printf("  fmi2SetTime + fmi2SetContinuousStates + fmi2GetDerivatives  %8.1f ns  (%.2fx the held core RHS)\n",
                    host_rhs_ns, host_rhs_ns / core_held_ns);
        std::printf("  fmi2GetEventIndicators (after the derivatives)              %8.1f ns\n", indicators_ns);
        std::printf("  parts: fmi2SetTime %.1f ns, fmi2SetContinuousStates %.1f ns, fmi2GetDerivatives at the same point %.1f ns\n",
                    set_time_ns, set_states_ns, cached_derivatives_ns);
    }
    return 0;
}
