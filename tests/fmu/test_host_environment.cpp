// What a host's process state does to the FMU, and what the FMU leaves of it:
//
//   test_host_environment <Gimbal2Axis.so> <modelDescription.xml>
//
// - a host in another floating-point environment (rounding upward, flush-to-zero and
//   denormals-are-zero as -ffast-math sets them, trapping exceptions) gets the same bits as a host
//   in the default one, no SIGFPE, and its environment back unchanged after every call: rounding
//   mode, enabled traps and its sticky exception flags;
// - loading and unloading the shared object again and again does not leak.
#include <fenv.h>
#include <malloc.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

#include "check.hpp"
#include "fmu_loader.hpp"
#include "gimbal/gimbal_c_api.h"

namespace {

using fmu_loader::Api;
using fmu_loader::Log;
using fmu_loader::ModelDescription;

Api api;
ModelDescription model;
const char* g_fmu_path = nullptr;

const char* const kOutputs[] = {"alpha", "beta", "alpha_dot", "beta_dot", "i_R1", "i_R2", "theta_b1", "theta_b2",
                                "T_E1", "T_E2", "los.omega[1]", "los.omega[2]", "energy.kinetic"};

struct HostEnvironment {
    int rounding;
    int traps;
    unsigned mxcsr;
    int flags;
};

HostEnvironment host_environment() {
    HostEnvironment environment{fegetround(), fegetexcept(), 0u, fetestexcept(FE_ALL_EXCEPT)};
#if defined(__x86_64__) || defined(__i386__)
    environment.mxcsr = _mm_getcsr();
#endif
    return environment;
}

bool same(const HostEnvironment& a, const HostEnvironment& b) {
    return a.rounding == b.rounding && a.traps == b.traps && a.mxcsr == b.mxcsr && a.flags == b.flags;
}

// Times and inputs of the scene, computed once in the default environment: the host's own
// arithmetic in another rounding mode must not be what differs.
struct SceneInputs {
    std::vector<double> times;
    std::vector<std::vector<double>> values;
};

SceneInputs scene_inputs() {
    SceneInputs scene;
    const double h = 1e-3;
    for (int k = 0; k <= 400; ++k) {
        const double t = k * h;
        scene.times.push_back(t);
        scene.values.push_back({3.0 * std::sin(20.0 * t), -2.0 * std::cos(15.0 * t), 0.1 * std::sin(2.0 * t),
                                0.2 * std::cos(2.0 * t), -0.4 * std::sin(2.0 * t)});
    }
    return scene;
}

// A ship scene with a rolling base: every call checks the host's environment is as it was.
std::vector<double> run_scene(const SceneInputs& scene, long& calls_changing_environment) {
    Log log;
    fmi2CallbackFunctions callbacks = fmu_loader::callbacks_for(log);
    const HostEnvironment before = host_environment();
    auto checked = [&](fmi2Status status) {
        const HostEnvironment after = host_environment();
        if (!same(after, before)) {
            if (calls_changing_environment++ == 0)
                std::printf("  first change of the host's environment: rounding %d -> %d, traps %#x -> %#x, MXCSR %#x -> %#x, "
                            "flags %#x -> %#x\n", before.rounding, after.rounding, before.traps, after.traps, before.mxcsr,
                            after.mxcsr, before.flags, after.flags);
        }
        return status;
    };
    fmi2Component c =
        api.instantiate("host", fmi2CoSimulation, model.guid.c_str(), "file:///tmp", &callbacks, fmi2False, fmi2False);
    if (!same(host_environment(), before)) ++calls_changing_environment;
    CHECK(c != nullptr);
    CHECK(checked(api.setupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0)) == fmi2OK);
    CHECK(checked(api.enterInitializationMode(c)) == fmi2OK);
    CHECK(checked(api.exitInitializationMode(c)) == fmi2OK);
    const fmi2ValueReference inputs[] = {model.vr("u_R1"), model.vr("u_R2"), model.vr("base.gamma"),
                                         model.vr("base.gamma_dot"), model.vr("base.gamma_ddot")};
    std::vector<double> trajectory;
    for (int k = 0; k < 400; ++k) {
        const double t = scene.times[k], h = scene.times[k + 1] - scene.times[k];
        CHECK(checked(api.setReal(c, inputs, 5, scene.values[k].data())) == fmi2OK);
        CHECK(checked(api.doStep(c, t, h, fmi2True)) == fmi2OK);
        for (const char* name : kOutputs) {
            const fmi2ValueReference vr = model.vr(name);
            double value = NAN;
            CHECK(checked(api.getReal(c, &vr, 1, &value)) == fmi2OK);
            trajectory.push_back(value);
        }
    }
    // Hostile values that are refused cleanly; with traps enabled they must not become SIGFPE.
    const fmi2ValueReference rate = model.vr("base.gamma_dot");
    const double huge = 1e200;
    CHECK(checked(api.setReal(c, &rate, 1, &huge)) == fmi2OK);
    const fmi2Status hostile = checked(api.doStep(c, scene.times[400], 1e-3, fmi2True));
    CHECK(hostile == fmi2Error || hostile == fmi2Discard);
    CHECK(checked(api.doStep(c, scene.times[400], NAN, fmi2True)) == fmi2Error);
    api.freeInstance(c);
    if (!same(host_environment(), before)) ++calls_changing_environment;
    return trajectory;
}

// The same for a Model Exchange host: forward-Euler steps over 0.1 s (the FMU's derivatives,
// indicators, event iterations), every call checked.
std::vector<double> run_model_exchange(long& calls_changing_environment) {
    Log log;
    fmi2CallbackFunctions callbacks = fmu_loader::callbacks_for(log);
    // The host computes between the calls (its Euler step raises its own flags): each call is
    // compared with the environment right before it.
    auto checked = [&](auto&& call) {
        const HostEnvironment before = host_environment();
        const fmi2Status status = call();
        if (!same(host_environment(), before)) ++calls_changing_environment;
        return status;
    };
    fmi2Component c =
        api.instantiate("host", fmi2ModelExchange, model.guid.c_str(), "file:///tmp", &callbacks, fmi2False, fmi2False);
    CHECK(c != nullptr);
    const fmi2ValueReference inputs[] = {model.vr("u_R1"), model.vr("u_R2"), model.vr("base.gamma_dot")};
    const double values[] = {12.0, -8.0, 0.2};
    CHECK(checked([&] { return api.setupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0); }) == fmi2OK);
    CHECK(checked([&] { return api.enterInitializationMode(c); }) == fmi2OK);
    CHECK(checked([&] { return api.setReal(c, inputs, 3, values); }) == fmi2OK);
    CHECK(checked([&] { return api.exitInitializationMode(c); }) == fmi2OK);
    fmi2EventInfo info{};
    CHECK(checked([&] { return api.newDiscreteStates(c, &info); }) == fmi2OK);
    CHECK(checked([&] { return api.enterContinuousTimeMode(c); }) == fmi2OK);
    double x[GIMBAL_CONTINUOUS_STATES], dx[GIMBAL_CONTINUOUS_STATES], z[GIMBAL_EVENT_INDICATORS], z_before[GIMBAL_EVENT_INDICATORS];
    std::vector<double> trajectory;
    long events = 0;
    for (int k = 1; k <= 4000; ++k) {
        CHECK(checked([&] { return api.getEventIndicators(c, z_before, GIMBAL_EVENT_INDICATORS); }) == fmi2OK);
        CHECK(checked([&] { return api.getContinuousStates(c, x, GIMBAL_CONTINUOUS_STATES); }) == fmi2OK);
        CHECK(checked([&] { return api.getDerivatives(c, dx, GIMBAL_CONTINUOUS_STATES); }) == fmi2OK);
        // The first derivatives come before any arithmetic of the host's: the same bits in any host.
        if (k == 1) trajectory.insert(trajectory.end(), dx, dx + GIMBAL_CONTINUOUS_STATES);
        for (int i = 0; i < GIMBAL_CONTINUOUS_STATES; ++i) x[i] += 2.5e-5 * dx[i];
        CHECK(checked([&] { return api.setTime(c, k * 2.5e-5); }) == fmi2OK);
        CHECK(checked([&] { return api.setContinuousStates(c, x, GIMBAL_CONTINUOUS_STATES); }) == fmi2OK);
        CHECK(checked([&] { return api.getEventIndicators(c, z, GIMBAL_EVENT_INDICATORS); }) == fmi2OK);
        bool crossed = false;
        for (int i = 0; i < GIMBAL_EVENT_INDICATORS; ++i) crossed = crossed || ((z[i] > 0.0) != (z_before[i] > 0.0));
        if (crossed) {
            ++events;
            CHECK(checked([&] { return api.enterEventMode(c); }) == fmi2OK);
            CHECK(checked([&] { return api.newDiscreteStates(c, &info); }) == fmi2OK);
            CHECK(checked([&] { return api.enterContinuousTimeMode(c); }) == fmi2OK);
        }
        if (k % 40 == 0) trajectory.insert(trajectory.end(), x, x + GIMBAL_CONTINUOUS_STATES);
    }
    CHECK(events > 0);
    // A non-finite state is refused, not trapped.
    x[0] = NAN;
    CHECK(checked([&] { return api.setContinuousStates(c, x, GIMBAL_CONTINUOUS_STATES); }) == fmi2Error);
    const HostEnvironment before_free = host_environment();
    api.freeInstance(c);
    if (!same(host_environment(), before_free)) ++calls_changing_environment;
    return trajectory;
}

void test_host_floating_point_environment_is_held() {
    const SceneInputs scene = scene_inputs();
    long changed = 0;
    feclearexcept(FE_ALL_EXCEPT);
    const std::vector<double> reference = run_scene(scene, changed);
    CHECK(changed == 0);
    long changed_me = 0;
    const std::vector<double> me_reference = run_model_exchange(changed_me);
    CHECK(changed_me == 0);

    // Rounding upward, FTZ and DAZ, trapping exceptions, sticky flags raised before the calls.
    fesetround(FE_UPWARD);
#if defined(__x86_64__) || defined(__i386__)
    _mm_setcsr(_mm_getcsr() | 0x8040u);
#endif
    feraiseexcept(FE_INEXACT | FE_UNDERFLOW);
    feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
    long changed_in_hostile_host = 0;
    const std::vector<double> hostile_host = run_scene(scene, changed_in_hostile_host);
    long changed_in_hostile_me_host = 0;
    const std::vector<double> hostile_me_host = run_model_exchange(changed_in_hostile_me_host);
    fedisableexcept(FE_ALL_EXCEPT);
    fesetenv(FE_DFL_ENV);
    CHECK(changed_in_hostile_host == 0);
    CHECK(hostile_host.size() == reference.size());
    long differing = 0;
    for (size_t k = 0; k < reference.size() && k < hostile_host.size(); ++k)
        differing += std::memcmp(&reference[k], &hostile_host[k], sizeof(double)) != 0;
    CHECK(differing == 0);
    CHECK(changed_in_hostile_me_host == 0);
    CHECK(hostile_me_host.size() == me_reference.size());
    long differing_me = 0;
    for (size_t k = 0; k < me_reference.size() && k < hostile_me_host.size(); ++k)
        differing_me += std::memcmp(&me_reference[k], &hostile_me_host[k], sizeof(double)) != 0;
    CHECK(hostile_me_host.size() >= GIMBAL_CONTINUOUS_STATES &&
          std::memcmp(me_reference.data(), hostile_me_host.data(), GIMBAL_CONTINUOUS_STATES * sizeof(double)) == 0);
    // The host's own Euler arithmetic runs in its environment here: only the FMU's part is the same.
    std::printf("  Model Exchange host: %zu states recorded, %ld differ (the host's own arithmetic rounds upward); "
                "calls that changed the host's environment: %ld and %ld\n",
                me_reference.size(), differing_me, changed_me, changed_in_hostile_me_host);
    std::printf("  %zu outputs in a host rounding upward with FTZ/DAZ and traps: %ld differ from the default host's; "
                "calls that changed the host's environment: %ld and %ld\n",
                reference.size(), differing, changed, changed_in_hostile_host);
}

void test_repeated_loading_does_not_leak() {
#if defined(__SANITIZE_ADDRESS__)
    std::printf("  repeated loading: not measured under AddressSanitizer (its allocator is not malloc's)\n");
#else
    auto cycle = [] {
        void* handle = dlopen(g_fmu_path, RTLD_NOW | RTLD_LOCAL);
        CHECK(dlopen(g_fmu_path, RTLD_NOW | RTLD_NOLOAD) == handle);  // loaded by this call, once
        CHECK(handle != nullptr);
        if (handle == nullptr) return;
        auto instantiate = reinterpret_cast<fmi2InstantiateTYPE*>(dlsym(handle, "fmi2Instantiate"));
        auto free_instance = reinterpret_cast<fmi2FreeInstanceTYPE*>(dlsym(handle, "fmi2FreeInstance"));
        Log log;
        fmi2CallbackFunctions callbacks = fmu_loader::callbacks_for(log);
        fmi2Component c =
            instantiate("cycle", fmi2CoSimulation, model.guid.c_str(), "file:///tmp", &callbacks, fmi2False, fmi2False);
        free_instance(c);
        dlclose(handle);
        dlclose(handle);
    };
    for (int k = 0; k < 3; ++k) cycle();  // the loader's own one-time allocations
    const size_t before = mallinfo2().uordblks;
    const int cycles = 40;
    for (int k = 0; k < cycles; ++k) cycle();
    const long growth = static_cast<long>(mallinfo2().uordblks) - static_cast<long>(before);
    // The static C++ runtime's emergency pool alone was 72,704 bytes per cycle.
    CHECK(growth < 16384);
    std::printf("  %d dlopen/dlclose cycles: heap in use grew by %ld bytes\n", cycles, growth);
#endif
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s <fmu.so> <modelDescription.xml>\n", argv[0]);
        return 2;
    }
    g_fmu_path = argv[1];
    if (!model.read(argv[2])) return 2;
    test_repeated_loading_does_not_leak();  // first: no other handle may keep the object loaded
    if (!api.load(argv[1])) return 2;
    test_host_floating_point_environment_is_held();
    return check_report("host_environment");
}
