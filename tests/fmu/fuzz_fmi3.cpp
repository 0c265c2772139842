// Fuzz test of the FMU's FMI 3.0 binary (loaded with dlopen, as a host does): seeded random sequences
// on Co-Simulation instances (with and without Event Mode and early return) and Model Exchange
// instances, mixing a plausible host (steps, Euler updates, event iterations) with hostile calls
// (every function in every state, NULL pointers, wrong counts, wrong types, NaN/Inf/huge values,
// corrupted FMU states, functions of the other interface, everything the FMU does not offer).
//
// Checked after every call: no crash and no hang, a status in range, every refusal logged with a
// message, nothing written to stdout/stderr, finite values from every successful Float64 getter,
// FMI 3.0's documented answers (discreteStatesNeedUpdate false, a successful step's lastSuccessfulTime
// within it), and with FUZZ_FP_TRAPS=1 the host's trapped exceptions kept.
//
//   fuzz_fmi3 <Gimbal2Axis.so (FMI 3.0)> <modelDescription.xml> <sequences> [seed]
//
// The small FMUs' FMI 3.0 binaries (the ship-motion and controller FMUs: Co-Simulation only, no Event
// Mode), told by a model description without the gimbal's variables, get the same sequences on
// Co-Simulation instances, the roles of the gimbal's variables taken by theirs (the first parameter,
// input, output, Int32 and Boolean) and steps mostly of one size (the ship motion's grid); their
// refusals of Model Exchange, Event Mode and what else they do not offer are part of the hostile calls.
#include <dlfcn.h>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <fenv.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gimbal/gimbal_c_api.h"  // GIMBAL_EVENT_INDICATORS
#include "fmi3FunctionTypes.h"

namespace {

// Value references, read from the FMI 3.0 model description by name.
fmi3ValueReference kBeta, kUR1, kBaseGammaDot, kIR1, kGearModel, kSolverSteps, kDryFriction, kIndicators, kTime, kDerAlphaDot;
constexpr size_t kStates = GIMBAL_CONTINUOUS_STATES, kEventIndicators = GIMBAL_EVENT_INDICATORS;

struct Api {
    fmi3InstantiateModelExchangeTYPE* instantiateModelExchange;
    fmi3InstantiateCoSimulationTYPE* instantiateCoSimulation;
    fmi3InstantiateScheduledExecutionTYPE* instantiateScheduledExecution;
    fmi3FreeInstanceTYPE* freeInstance;
    fmi3EnterInitializationModeTYPE* enterInitializationMode;
    fmi3ExitInitializationModeTYPE* exitInitializationMode;
    fmi3EnterEventModeTYPE* enterEventMode;
    fmi3TerminateTYPE* terminate;
    fmi3ResetTYPE* reset;
    fmi3GetFloat64TYPE* getFloat64;
    fmi3SetFloat64TYPE* setFloat64;
    fmi3GetInt32TYPE* getInt32;
    fmi3GetInt64TYPE* getInt64;
    fmi3SetInt64TYPE* setInt64;
    fmi3GetBooleanTYPE* getBoolean;
    fmi3SetBooleanTYPE* setBoolean;
    fmi3GetFloat32TYPE* getFloat32;
    fmi3GetStringTYPE* getString;
    fmi3GetFMUStateTYPE* getFMUState;
    fmi3SetFMUStateTYPE* setFMUState;
    fmi3FreeFMUStateTYPE* freeFMUState;
    fmi3SerializedFMUStateSizeTYPE* serializedFMUStateSize;
    fmi3SerializeFMUStateTYPE* serializeFMUState;
    fmi3DeserializeFMUStateTYPE* deserializeFMUState;
    fmi3GetDirectionalDerivativeTYPE* getDirectionalDerivative;
    fmi3GetAdjointDerivativeTYPE* getAdjointDerivative;
    fmi3UpdateDiscreteStatesTYPE* updateDiscreteStates;
    fmi3EnterContinuousTimeModeTYPE* enterContinuousTimeMode;
    fmi3CompletedIntegratorStepTYPE* completedIntegratorStep;
    fmi3SetTimeTYPE* setTime;
    fmi3SetContinuousStatesTYPE* setContinuousStates;
    fmi3GetContinuousStateDerivativesTYPE* getContinuousStateDerivatives;
    fmi3GetEventIndicatorsTYPE* getEventIndicators;
    fmi3GetContinuousStatesTYPE* getContinuousStates;
    fmi3GetNominalsOfContinuousStatesTYPE* getNominalsOfContinuousStates;
    fmi3EnterStepModeTYPE* enterStepMode;
    fmi3DoStepTYPE* doStep;
    fmi3GetOutputDerivativesTYPE* getOutputDerivatives;
    fmi3EnterConfigurationModeTYPE* enterConfigurationMode;
} api;

int g_failures = 0, g_saved_stderr = -1, g_capture_fd = -1;
long g_sequence = -1;
char g_last_call[160] = "(none)";
bool g_fp_traps = false;
bool g_small = false;  // a small FMU's binary: Co-Simulation only, without Event Mode
struct Counts {
    long calls = 0, refusals = 0, steps = 0, early_returns = 0, event_updates = 0, restores = 0;
} g_counts;
struct Log {
    int refusals = 0;
    std::string first;
} g_log;

void fatal_signal(int signal_number) {
    if (g_saved_stderr >= 0) dup2(g_saved_stderr, 2);
    char text[400];
    const int n = std::snprintf(text, sizeof text, "\nfuzz_fmi3: %s: signal %d in sequence %ld, in %s\nfuzz_fmi3: FAILED\n",
                                signal_number == SIGALRM ? "HANG" : "CRASH", signal_number, g_sequence, g_last_call);
    if (n > 0) (void)!write(2, text, static_cast<size_t>(n));
    _exit(2);
}

void logger(fmi3InstanceEnvironment, fmi3Status status, fmi3String category, fmi3String message) {
    if (status >= fmi3Discard) {
        ++g_log.refusals;
        if (g_log.first.empty() && message != nullptr) g_log.first = message;
    }
    (void)category;
}

void fail(const std::string& what) {
    if (++g_failures <= 20)
        std::fprintf(stderr, "fuzz_fmi3: sequence %ld, %s: %s (first refusal: \"%s\")\n", g_sequence, g_last_call, what.c_str(),
                     g_log.first.substr(0, 200).c_str());
}

off_t captured() {
    struct stat s {};
    return fstat(g_capture_fd, &s) == 0 ? s.st_size : 0;
}

template <class F>
fmi3Status call(const char* description, F&& function) {
    std::snprintf(g_last_call, sizeof g_last_call, "%s", description);
    g_log = Log{};
    const off_t before = captured();
    std::fflush(stdout);
    std::fflush(stderr);
    const int saved_out = dup(1);
    dup2(g_capture_fd, 1);
    dup2(g_capture_fd, 2);
    if (g_fp_traps) feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
    const fmi3Status status = function();
    if (g_fp_traps) {
        if (fegetexcept() != (FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW)) fail("the host's trapped exceptions were changed");
        fedisableexcept(FE_ALL_EXCEPT);
    }
    std::fflush(stdout);
    std::fflush(stderr);
    dup2(saved_out, 1);
    close(saved_out);
    dup2(g_saved_stderr, 2);
    ++g_counts.calls;
    if (captured() != before) fail("the FMU wrote to stdout/stderr");
    if (status < fmi3OK || status > fmi3Fatal) fail("status out of range");
    if (status >= fmi3Discard) {
        ++g_counts.refusals;
        if (g_log.refusals == 0) fail("refused without a logged message");
    }
    return status;
}

struct Fuzzer {
    std::mt19937_64 random;
    fmi3Instance instance = nullptr;
    bool model_exchange = false, early_allowed = false;
    double time = 0.0;
    std::vector<fmi3FMUState> states;

    explicit Fuzzer(unsigned long long seed) : random(seed) {}
    double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(random); }
    bool chance(double p) { return uniform(0.0, 1.0) < p; }
    int pick(int n) { return static_cast<int>(random() % static_cast<unsigned long long>(n)); }
    double hostile() {
        const double values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e300,
                                 -1e300, 1e-310};
        return values[pick(5)];
    }
    void finite(const double* v, size_t n, const char* what) {
        for (size_t k = 0; k < n; ++k)
            if (!std::isfinite(v[k])) fail(std::string(what) + " handed out a non-finite value");
    }

    bool start() {
        model_exchange = !g_small && chance(0.5);
        early_allowed = chance(0.5);
        const bool event_mode = !g_small && chance(0.5);
        call("fmi3Instantiate", [&] {
            instance = model_exchange
                           ? api.instantiateModelExchange("fuzz", g_token, "", false, chance(0.5), nullptr, logger)
                           : api.instantiateCoSimulation("fuzz", g_token, "", false, chance(0.5), event_mode, early_allowed,
                                                         nullptr, 0, nullptr, logger, nullptr);
            return instance != nullptr ? fmi3OK : fmi3Error;
        });
        if (instance == nullptr) return false;
        const double beta = uniform(-1.0, 1.0);
        call("fmi3SetFloat64(beta)", [&] { return api.setFloat64(instance, &kBeta, 1, &beta, 1); });
        call("fmi3EnterInitializationMode", [&] { return api.enterInitializationMode(instance, false, 0, 0, false, 0); });
        call("fmi3ExitInitializationMode", [&] { return api.exitInitializationMode(instance); });
        time = 0.0;
        if (g_small) return true;  // in step mode already: no Event Mode
        event_update();
        if (model_exchange) call("fmi3EnterContinuousTimeMode", [&] { return api.enterContinuousTimeMode(instance); });
        else call("fmi3EnterStepMode", [&] { return api.enterStepMode(instance); });
        time = 0.0;
        return true;
    }

    void event_update() {
        fmi3Boolean need = true, terminate = true, nominals = true, values = true, defined = true;
        fmi3Float64 next = -1;
        if (call("fmi3UpdateDiscreteStates", [&] {
                return api.updateDiscreteStates(instance, &need, &terminate, &nominals, &values, &defined, &next);
            }) <= fmi3Warning) {
            ++g_counts.event_updates;
            if (need || terminate || nominals) fail("fmi3UpdateDiscreteStates asks for more than one call");
        }
    }

    void host_step() {
        if (model_exchange) {
            double x[kStates], dx[kStates], z[kEventIndicators];
            if (call("fmi3GetContinuousStates", [&] { return api.getContinuousStates(instance, x, kStates); }) > fmi3Warning) return;
            finite(x, kStates, "fmi3GetContinuousStates");
            if (call("fmi3GetContinuousStateDerivatives", [&] { return api.getContinuousStateDerivatives(instance, dx, kStates); }) >
                fmi3Warning)
                return;
            finite(dx, kStates, "fmi3GetContinuousStateDerivatives");
            const double h = std::pow(10.0, uniform(-7.0, -3.5));
            for (size_t k = 0; k < kStates; ++k) x[k] += h * dx[k];
            time += h;
            call("fmi3SetTime", [&] { return api.setTime(instance, time); });
            call("fmi3SetContinuousStates", [&] { return api.setContinuousStates(instance, x, kStates); });
            if (call("fmi3GetEventIndicators", [&] { return api.getEventIndicators(instance, z, kEventIndicators); }) <= fmi3Warning)
                finite(z, kEventIndicators, "fmi3GetEventIndicators");
            if (chance(0.1)) {
                call("fmi3EnterEventMode", [&] { return api.enterEventMode(instance); });
                event_update();
                call("fmi3EnterContinuousTimeMode", [&] { return api.enterContinuousTimeMode(instance); });
            }
        } else {
            const double u = uniform(-30.0, 30.0);
            call("fmi3SetFloat64(u_R1)", [&] { return api.setFloat64(instance, &kUR1, 1, &u, 1); });
            const double h = g_small && chance(0.9) ? 1e-3 : std::pow(10.0, uniform(-5.0, -2.0));
            fmi3Boolean event = false, terminate = false, early = false;
            fmi3Float64 last = -1;
            const fmi3Status status = call("fmi3DoStep", [&] {
                return api.doStep(instance, time, h, true, &event, &terminate, &early, &last);
            });
            if (status <= fmi3Warning) {
                ++g_counts.steps;
                // (a step too small to move a clock as late as a hostile step left it, 1e300 s, ends where it began)
                if (!((last > time || time + h == time) && last <= time + h * (1 + 1e-9)))
                    fail("lastSuccessfulTime " + std::to_string(last) + " lies outside the step from " + std::to_string(time) +
                         " of " + std::to_string(h));
                if (early && !early_allowed) fail("an early return the importer did not allow");
                g_counts.early_returns += early;
                time = last;
            }
        }
    }

    void hostile_call() {
        double values[64];
        switch (pick(14)) {
            case 0: call("fmi3GetFloat64(NULL)", [&] { return api.getFloat64(instance, &kBeta, 1, nullptr, 1); }); break;
            case 1: call("fmi3GetFloat64(wrong count)", [&] { return api.getFloat64(instance, &kBeta, 1, values, 2); }); break;
            case 2: {  // the 36 scalar event indicators (consecutive value references) and time, in one call
                fmi3ValueReference vrs[kEventIndicators + 1];
                for (size_t z = 0; z < kEventIndicators; ++z) vrs[z] = kIndicators + static_cast<fmi3ValueReference>(z);
                vrs[kEventIndicators] = kTime;
                const size_t count = chance(0.5) ? kEventIndicators + 1 : 1 + random() % kEventIndicators;
                if (call("fmi3GetFloat64(indicators/time)", [&] {
                        return api.getFloat64(instance, vrs + kEventIndicators + 1 - count, count, values, count);
                    }) <= fmi3Warning)
                    finite(values, count, "fmi3GetFloat64");
                break;
            }
            case 3: {
                const fmi3ValueReference vr = static_cast<fmi3ValueReference>(random() % 5000);
                call("fmi3GetFloat64(random vr)", [&] { return api.getFloat64(instance, &vr, 1, values, 1); });
                break;
            }
            case 4: {
                const double v = hostile();
                call("fmi3SetFloat64(hostile input)", [&] { return api.setFloat64(instance, &kBaseGammaDot, 1, &v, 1); });
                break;
            }
            case 5: {
                fmi3Int64 v = pick(5) - 1;
                call("fmi3SetInt64(gear1.model)", [&] { return api.setInt64(instance, &kGearModel, 1, &v, 1); });
                fmi3Int32 w = 0;
                call("fmi3GetInt32(enumeration)", [&] { return api.getInt32(instance, &kGearModel, 1, &w, 1); });
                call("fmi3GetInt32(solver.steps)", [&] { return api.getInt32(instance, &kSolverSteps, 1, &w, 1); });
                break;
            }
            case 6: {
                fmi3Boolean b = true;
                call("fmi3SetBoolean(dry_friction)", [&] { return api.setBoolean(instance, &kDryFriction, 1, &b, 1); });
                fmi3Float32 f = 0;
                call("fmi3GetFloat32", [&] { return api.getFloat32(instance, &kBeta, 1, &f, 1); });
                break;
            }
            case 7: {
                fmi3FMUState state = nullptr;
                if (call("fmi3GetFMUState", [&] { return api.getFMUState(instance, &state); }) <= fmi3Warning) states.push_back(state);
                break;
            }
            case 8:
                if (!states.empty()) {
                    fmi3FMUState state = states[pick(static_cast<int>(states.size()))];
                    if (call("fmi3SetFMUState", [&] { return api.setFMUState(instance, state); }) <= fmi3Warning) {
                        ++g_counts.restores;
                        double t = 0;
                        call("fmi3GetFloat64(time)", [&] { return api.getFloat64(instance, &kTime, 1, &t, 1); });
                        time = t;
                    }
                }
                break;
            case 9:
                if (!states.empty()) {
                    fmi3FMUState state = states[pick(static_cast<int>(states.size()))];
                    size_t size = 0;
                    if (call("fmi3SerializedFMUStateSize", [&] { return api.serializedFMUStateSize(instance, state, &size); }) >
                        fmi3Warning)
                        break;
                    std::vector<fmi3Byte> blob(size);
                    if (call("fmi3SerializeFMUState", [&] { return api.serializeFMUState(instance, state, blob.data(), size); }) >
                        fmi3Warning)
                        break;
                    const bool corrupt = chance(0.5);
                    if (corrupt) blob[static_cast<size_t>(pick(static_cast<int>(size)))] ^= static_cast<fmi3Byte>(1 + pick(255));
                    fmi3FMUState copy = nullptr;
                    const fmi3Status s = call("fmi3DeserializeFMUState",
                                              [&] { return api.deserializeFMUState(instance, blob.data(), size, &copy); });
                    if (s <= fmi3Warning) {
                        if (corrupt) fail("a corrupted FMU state was accepted");
                        states.push_back(copy);
                    } else if (!corrupt) {
                        fail("a serialized FMU state was refused");
                    }
                }
                break;
            case 10: {
                const fmi3ValueReference unknown = model_exchange ? kDerAlphaDot : kIR1, known = kUR1;
                const double seed = chance(0.2) ? hostile() : 1.0;
                double result = 0;
                if (call("fmi3GetDirectionalDerivative", [&] {
                        return api.getDirectionalDerivative(instance, &unknown, 1, &known, 1, &seed, 1, &result, 1);
                    }) <= fmi3Warning && !std::isfinite(result))
                    fail("fmi3GetDirectionalDerivative handed out a non-finite value");
                call("fmi3GetAdjointDerivative", [&] {
                    return api.getAdjointDerivative(instance, &unknown, 1, &known, 1, &seed, 1, &result, 1);
                });
                break;
            }
            case 11: {  // the other interface's functions, and what is not offered
                fmi3Boolean event = false, terminate = false, early = false;
                fmi3Float64 last = 0;
                if (model_exchange)
                    call("fmi3DoStep on ME", [&] { return api.doStep(instance, time, 1e-3, true, &event, &terminate, &early, &last); });
                else
                    call("fmi3SetContinuousStates on CS", [&] { return api.setContinuousStates(instance, values, kStates); });
                call("fmi3EnterConfigurationMode", [&] { return api.enterConfigurationMode(instance); });
                const fmi3Int32 order = 1;
                call("fmi3GetOutputDerivatives", [&] { return api.getOutputDerivatives(instance, &kIR1, 1, &order, values, 1); });
                fmi3String text = nullptr;
                call("fmi3GetString", [&] { return api.getString(instance, &kBeta, 1, &text, 1); });
                break;
            }
            case 12: {
                const double t = chance(0.5) ? hostile() : time - uniform(0.0, 1.0);
                call("fmi3SetTime(hostile or backwards)", [&] { return api.setTime(instance, t); });
                double x[kStates];
                for (double& v : x) v = chance(0.1) ? hostile() : uniform(-1, 1);
                call("fmi3SetContinuousStates(hostile)", [&] { return api.setContinuousStates(instance, x, kStates); });
                break;
            }
            default: {
                fmi3Boolean event = false, terminate = false, early = false;
                fmi3Float64 last = 0;
                const double h = chance(0.5) ? hostile() : -1e-3;
                call("fmi3DoStep(hostile h)", [&] { return api.doStep(instance, time, h, true, &event, &terminate, &early, &last); });
                call("fmi3DoStep(NULL outputs)", [&] { return api.doStep(instance, time, 1e-3, true, nullptr, nullptr, nullptr, nullptr); });
            }
        }
    }

    void run(int calls) {
        if (!start()) return;
        for (int k = 0; k < calls; ++k) {
            if (chance(0.7)) host_step();
            else hostile_call();
            if (chance(0.01)) {
                call("fmi3Reset", [&] { return api.reset(instance); });
                for (fmi3FMUState& state : states) call("fmi3FreeFMUState", [&] { return api.freeFMUState(instance, &state); });
                states.clear();
                api.freeInstance(instance);
                if (!start()) return;
            }
        }
        call("fmi3Terminate", [&] { return api.terminate(instance); });
        for (fmi3FMUState& state : states) call("fmi3FreeFMUState", [&] { return api.freeFMUState(instance, &state); });
        call("fmi3FreeInstance", [&] {
            api.freeInstance(instance);
            return fmi3OK;
        });
    }

    static const char* g_token;
};
const char* Fuzzer::g_token = nullptr;

template <class T>
void load(void* library, T& field, const char* name) {
    field = reinterpret_cast<T>(dlsym(library, name));
    if (field == nullptr) {
        std::fprintf(stderr, "fuzz_fmi3: the FMU lacks %s\n", name);
        std::exit(2);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: fuzz_fmi3 <Gimbal2Axis.so> <modelDescription.xml (FMI 3.0)> <sequences> [seed]\n");
        return 2;
    }
    void* library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
        std::fprintf(stderr, "fuzz_fmi3: %s\n", dlerror());
        return 2;
    }
    std::ifstream file(argv[2]);
    std::stringstream text;
    text << file.rdbuf();
    const std::string xml = text.str();
    static std::string token;
    std::smatch match;
    if (std::regex_search(xml, match, std::regex("instantiationToken=\"([^\"]+)\""))) token = match[1];
    std::map<std::string, fmi3ValueReference> vr;
    const std::regex variable("<(Float64|Int32|Enumeration|Boolean) name=\"([^\"]+)\" valueReference=\"([0-9]+)\"");
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), variable); it != std::sregex_iterator(); ++it)
        vr[(*it)[2]] = static_cast<fmi3ValueReference>(std::stoul((*it)[3]));
    g_small = vr.count("event_indicators[1]") == 0;
    if (g_small) {  // the roles of the gimbal's variables, by causality and type
        std::map<std::string, fmi3ValueReference> first;
        const std::regex described("<(Float64|Int32|Boolean) name=\"[^\"]+\" valueReference=\"([0-9]+)\" causality=\"([a-z]+)\"");
        for (auto it = std::sregex_iterator(xml.begin(), xml.end(), described); it != std::sregex_iterator(); ++it)
            first.emplace(std::string((*it)[1]) + " " + std::string((*it)[3]), static_cast<fmi3ValueReference>(std::stoul((*it)[2])));
        const auto role = [&](const char* gimbal_name, std::initializer_list<const char*> kinds, fmi3ValueReference none) {
            vr[gimbal_name] = none;
            for (const char* kind : kinds)
                if (first.count(kind)) {
                    vr[gimbal_name] = first[kind];
                    break;
                }
        };
        role("beta", {"Float64 parameter", "Float64 input"}, 0);
        role("u_R1", {"Float64 input", "Float64 parameter"}, 0);
        vr["base.gamma_dot"] = vr["u_R1"];
        role("i_R1", {"Float64 output"}, 0);
        vr["der(alpha_dot)"] = vr["i_R1"];
        role("gear1.model", {"Int32 parameter"}, 1000);
        vr["solver.steps"] = vr["gear1.model"];
        role("dry_friction", {"Boolean parameter"}, 2000);
        vr["event_indicators[1]"] = vr["i_R1"];
    }
    const char* needed[] = {"beta", "u_R1", "base.gamma_dot", "i_R1", "gear1.model", "solver.steps", "dry_friction",
                            "event_indicators[1]", "time", "der(alpha_dot)"};
    for (const char* name : needed)
        if (vr.count(name) == 0 || token.empty()) {
            std::fprintf(stderr, "fuzz_fmi3: %s is not the FMI 3.0 model description of an FMU of this project (%s)\n",
                         argv[2], name);
            return 2;
        }
    kBeta = vr["beta"], kUR1 = vr["u_R1"], kBaseGammaDot = vr["base.gamma_dot"], kIR1 = vr["i_R1"];
    kGearModel = vr["gear1.model"], kSolverSteps = vr["solver.steps"], kDryFriction = vr["dry_friction"];
    kIndicators = vr["event_indicators[1]"], kTime = vr["time"], kDerAlphaDot = vr["der(alpha_dot)"];
    Fuzzer::g_token = token.c_str();
#define LOAD(field, name) load(library, api.field, name)
    LOAD(instantiateModelExchange, "fmi3InstantiateModelExchange");
    LOAD(instantiateCoSimulation, "fmi3InstantiateCoSimulation");
    LOAD(instantiateScheduledExecution, "fmi3InstantiateScheduledExecution");
    LOAD(freeInstance, "fmi3FreeInstance");
    LOAD(enterInitializationMode, "fmi3EnterInitializationMode");
    LOAD(exitInitializationMode, "fmi3ExitInitializationMode");
    LOAD(enterEventMode, "fmi3EnterEventMode");
    LOAD(terminate, "fmi3Terminate");
    LOAD(reset, "fmi3Reset");
    LOAD(getFloat64, "fmi3GetFloat64");
    LOAD(setFloat64, "fmi3SetFloat64");
    LOAD(getInt32, "fmi3GetInt32");
    LOAD(getInt64, "fmi3GetInt64");
    LOAD(setInt64, "fmi3SetInt64");
    LOAD(getBoolean, "fmi3GetBoolean");
    LOAD(setBoolean, "fmi3SetBoolean");
    LOAD(getFloat32, "fmi3GetFloat32");
    LOAD(getString, "fmi3GetString");
    LOAD(getFMUState, "fmi3GetFMUState");
    LOAD(setFMUState, "fmi3SetFMUState");
    LOAD(freeFMUState, "fmi3FreeFMUState");
    LOAD(serializedFMUStateSize, "fmi3SerializedFMUStateSize");
    LOAD(serializeFMUState, "fmi3SerializeFMUState");
    LOAD(deserializeFMUState, "fmi3DeserializeFMUState");
    LOAD(getDirectionalDerivative, "fmi3GetDirectionalDerivative");
    LOAD(getAdjointDerivative, "fmi3GetAdjointDerivative");
    LOAD(updateDiscreteStates, "fmi3UpdateDiscreteStates");
    LOAD(enterContinuousTimeMode, "fmi3EnterContinuousTimeMode");
    LOAD(completedIntegratorStep, "fmi3CompletedIntegratorStep");
    LOAD(setTime, "fmi3SetTime");
    LOAD(setContinuousStates, "fmi3SetContinuousStates");
    LOAD(getContinuousStateDerivatives, "fmi3GetContinuousStateDerivatives");
    LOAD(getEventIndicators, "fmi3GetEventIndicators");
    LOAD(getContinuousStates, "fmi3GetContinuousStates");
    LOAD(getNominalsOfContinuousStates, "fmi3GetNominalsOfContinuousStates");
    LOAD(enterStepMode, "fmi3EnterStepMode");
    LOAD(doStep, "fmi3DoStep");
    LOAD(getOutputDerivatives, "fmi3GetOutputDerivatives");
    LOAD(enterConfigurationMode, "fmi3EnterConfigurationMode");
    const long sequences = std::atol(argv[3]);
    const unsigned long long seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1;
    g_fp_traps = std::getenv("FUZZ_FP_TRAPS") != nullptr && std::string(std::getenv("FUZZ_FP_TRAPS")) == "1";
    char capture_path[] = "/tmp/fuzz_fmi3_XXXXXX";
    g_capture_fd = mkstemp(capture_path);
    unlink(capture_path);
    g_saved_stderr = dup(2);
    struct sigaction action {};
    action.sa_handler = fatal_signal;
    for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM}) sigaction(s, &action, nullptr);
    // Instantiation refusals: a wrong token, no logger, Scheduled Execution.
    if (api.instantiateCoSimulation("x", "{wrong}", "", false, false, false, false, nullptr, 0, nullptr, logger, nullptr) != nullptr ||
        api.instantiateModelExchange("x", token.c_str(), "", false, false, nullptr, nullptr) != nullptr ||
        api.instantiateScheduledExecution("x", token.c_str(), "", false, false, nullptr, logger, nullptr, nullptr, nullptr) != nullptr)
        fail("an instantiation that must be refused returned an instance");
    for (g_sequence = 0; g_sequence < sequences; ++g_sequence) {
        alarm(60);
        Fuzzer fuzzer(seed * 1000003ULL + static_cast<unsigned long long>(g_sequence));
        fuzzer.run(150);
        alarm(0);
    }
    if (g_counts.steps == 0 || g_counts.restores == 0 ||
        (!g_small && (g_counts.event_updates == 0 || g_counts.early_returns == 0))) {
        ++g_failures;
        std::fprintf(stderr, "fuzz_fmi3: the sequences never reached a step, an event update, a restore or an early return\n");
    }
    std::printf("fuzz_fmi3: %ld calls, %ld refused, %ld steps (%ld early returns), %ld event updates, %ld restores\n",
                g_counts.calls, g_counts.refusals, g_counts.steps, g_counts.early_returns, g_counts.event_updates,
                g_counts.restores);
    std::printf("fuzz_fmi3: %ld sequences%s: %s (%d failed checks)\n", sequences,
                g_fp_traps ? " with the host trapping FP exceptions" : "", g_failures == 0 ? "passed" : "FAILED", g_failures);
    return g_failures == 0 ? 0 : 1;
}
