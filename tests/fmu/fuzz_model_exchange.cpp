// Fuzz test of the FMU's FMI 2.0 Model Exchange interface (the shared object loaded with dlopen, as a
// host does): seeded random sequences that mix a plausible host (time forward, explicit-Euler state
// updates, event mode where an indicator changes sign, the event iteration, back to continuous time)
// with hostile calls: every Model Exchange function in every state, wrong nx/ni, NULL pointers,
// NaN/Inf/huge states and times, time going backwards, inputs in every mode, FMU states saved,
// serialized, corrupted, restored, Co-Simulation functions on the Model Exchange instance.
//
// Checked after every call: no crash and no hang (signal handlers, a watchdog), a status the state
// machine allows (a call its state table allows with valid arguments is not refused; one it does not
// allow is refused, with a message naming the function), every refusal logged, nothing written to
// stdout/stderr, finite values from every successful getter, newDiscreteStatesNeeded false, currents
// and backlash within their bounds after every event update.
//
//   fuzz_model_exchange <Gimbal2Axis.so> <modelDescription.xml> <sequences> [seed]
#include <dlfcn.h>
#include <fenv.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "gimbal/gimbal_c_api.h"  // GIMBAL_EVENT_INDICATORS
#include "fmi2Functions.h"

namespace {

constexpr size_t kStates = GIMBAL_CONTINUOUS_STATES, kIndicators = GIMBAL_EVENT_INDICATORS;

struct Api {
    fmi2InstantiateTYPE* instantiate;
    fmi2FreeInstanceTYPE* freeInstance;
    fmi2SetupExperimentTYPE* setupExperiment;
    fmi2EnterInitializationModeTYPE* enterInitializationMode;
    fmi2ExitInitializationModeTYPE* exitInitializationMode;
    fmi2TerminateTYPE* terminate;
    fmi2ResetTYPE* reset;
    fmi2SetRealTYPE* setReal;
    fmi2GetRealTYPE* getReal;
    fmi2GetFMUstateTYPE* getFMUstate;
    fmi2SetFMUstateTYPE* setFMUstate;
    fmi2FreeFMUstateTYPE* freeFMUstate;
    fmi2SerializedFMUstateSizeTYPE* serializedFMUstateSize;
    fmi2SerializeFMUstateTYPE* serializeFMUstate;
    fmi2DeSerializeFMUstateTYPE* deSerializeFMUstate;
    fmi2GetDirectionalDerivativeTYPE* getDirectionalDerivative;
    fmi2DoStepTYPE* doStep;
    fmi2EnterEventModeTYPE* enterEventMode;
    fmi2NewDiscreteStatesTYPE* newDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE* enterContinuousTimeMode;
    fmi2CompletedIntegratorStepTYPE* completedIntegratorStep;
    fmi2SetTimeTYPE* setTime;
    fmi2SetContinuousStatesTYPE* setContinuousStates;
    fmi2GetDerivativesTYPE* getDerivatives;
    fmi2GetEventIndicatorsTYPE* getEventIndicators;
    fmi2GetContinuousStatesTYPE* getContinuousStates;
    fmi2GetNominalsOfContinuousStatesTYPE* getNominalsOfContinuousStates;
} api;

int g_failures = 0;
struct Counts {
    long calls = 0, refusals = 0, event_updates = 0, state_events = 0, restores = 0, deserializations = 0;
} g_counts;
long g_sequence = -1;
char g_last_call[256] = "(none)";
int g_saved_stderr = -1, g_capture_fd = -1;
// FUZZ_FP_TRAPS=1: the host traps invalid operations, division by zero and overflow during every call
// (the FMU computes in its own environment and must give the host's back).
bool g_fp_traps = false;

void fatal_signal(int signal_number) {
    if (g_saved_stderr >= 0) dup2(g_saved_stderr, 2);
    char text[512];
    const int n = std::snprintf(text, sizeof text, "\nfuzz_model_exchange: %s: signal %d in sequence %ld, in %s\nfuzz_model_exchange: FAILED\n",
                                signal_number == SIGALRM ? "HANG" : "CRASH", signal_number, g_sequence, g_last_call);
    if (n > 0) (void)!write(2, text, static_cast<size_t>(n));
    _exit(2);
}

struct Log {
    int messages = 0, refusals = 0, conversions = 0;
    std::string first;
} g_log;

void logger(fmi2ComponentEnvironment, fmi2String, fmi2Status status, fmi2String category, fmi2String message, ...) {
    ++g_log.messages;
    if (status >= fmi2Discard) ++g_log.refusals;
    if (category == nullptr || message == nullptr) return;
    for (const char* p = message; *p != '\0'; ++p) {
        if (*p != '%') continue;
        if (p[1] == '%') ++p;
        else ++g_log.conversions;
    }
    if (g_log.first.empty() && status >= fmi2Discard) g_log.first = message;
}

void fail(const std::string& what) {
    ++g_failures;
    if (g_failures <= 20)
        std::fprintf(stderr, "fuzz_model_exchange: sequence %ld, %s: %s (first refusal logged: \"%s\")\n", g_sequence,
                     g_last_call, what.c_str(), g_log.first.substr(0, 200).c_str());
}

off_t captured() {
    struct stat s {};
    return fstat(g_capture_fd, &s) == 0 ? s.st_size : 0;
}

// One FMU call: the log context reset, stdout/stderr captured, the status checked against what the
// state table allows (expect: 1 must succeed, 0 must be refused, -1 either).
template <class F>
fmi2Status call(const char* description, int expect, F&& function) {
    std::snprintf(g_last_call, sizeof g_last_call, "%s", description);
    g_log = Log{};
    const off_t before = captured();
    std::fflush(stdout);
    std::fflush(stderr);
    const int saved_out = dup(1);
    dup2(g_capture_fd, 1);
    dup2(g_capture_fd, 2);
    if (g_fp_traps) feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
    const fmi2Status status = function();
    ++g_counts.calls;
    if (status > fmi2Warning) ++g_counts.refusals;
    if (g_fp_traps) {
        if (fegetexcept() != (FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW)) fail("the host's trapped exceptions were changed");
        fedisableexcept(FE_ALL_EXCEPT);
    }
    std::fflush(stdout);
    std::fflush(stderr);
    dup2(saved_out, 1);
    close(saved_out);
    dup2(g_saved_stderr, 2);
    if (captured() != before) fail("the FMU wrote to stdout/stderr");
    if (status < fmi2OK || status > fmi2Pending) fail("status out of range");
    if (status >= fmi2Discard && g_log.refusals == 0) fail("refused without a logged message");
    if (g_log.conversions > 0) fail("a logged message holds an unescaped printf conversion");
    if (expect == 1 && status > fmi2Warning) fail("refused although allowed");
    if (expect == 0 && status <= fmi2Warning) fail("accepted although the state table does not allow it");
    return status;
}

enum class Mode { instantiated, initialization, event, continuous_time, terminated, error };

struct Model {
    std::string guid;
    std::map<std::string, unsigned> real;  // name -> value reference
    std::vector<unsigned> inputs;
};

Model read_model(const char* path) {
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    const std::string xml = text.str();
    Model model;
    std::smatch match;
    if (std::regex_search(xml, match, std::regex("guid=\"([^\"]+)\""))) model.guid = match[1];
    const std::regex variable(
        "<ScalarVariable name=\"([^\"]+)\" valueReference=\"([0-9]+)\" causality=\"([a-z]+)\"[^<]*\\n?[^<]*<Real");
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), variable); it != std::sregex_iterator(); ++it) {
        const unsigned vr = static_cast<unsigned>(std::stoul((*it)[2]));
        model.real[(*it)[1]] = vr;
        if ((*it)[3] == "input") model.inputs.push_back(vr);
    }
    return model;
}

struct Fuzzer {
    const Model& model;
    std::mt19937_64 random;
    fmi2CallbackFunctions callbacks{logger, nullptr, nullptr, nullptr, nullptr};
    fmi2Component me = nullptr;
    Mode mode = Mode::instantiated;
    double time = 0.0;
    std::vector<fmi2FMUstate> states;
    std::vector<std::vector<char>> blobs;
    double limits[4] = {4.0, 3.0, 2e-4, 2e-4};  // i_L 1/2, eta 1/2 (the defaults; not changed here)

    Fuzzer(const Model& m, unsigned long long seed) : model(m), random(seed) {}

    double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(random); }
    bool chance(double p) { return uniform(0.0, 1.0) < p; }
    int pick(int n) { return static_cast<int>(random() % static_cast<unsigned long long>(n)); }
    double hostile() {
        const double values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                 -std::numeric_limits<double>::infinity(), 1e300, -1e300, 1e-310, 0.0};
        return values[pick(7)];
    }
    bool evaluable() const {
        return mode == Mode::event || mode == Mode::continuous_time || mode == Mode::terminated || mode == Mode::error;
    }

    void check_finite(const double* values, size_t n, const char* what) {
        for (size_t k = 0; k < n; ++k)
            if (!std::isfinite(values[k])) fail(std::string(what) + " handed out a non-finite value");
    }

    void check_bounds() {
        const char* names[4] = {"i_R1", "i_R2", "theta_b1", "theta_b2"};
        for (int k = 0; k < 4; ++k) {
            const fmi2ValueReference vr = model.real.at(names[k]);
            double value = 0.0;
            if (call("fmi2GetReal(bounded output)", -1, [&] { return api.getReal(me, &vr, 1, &value); }) <= fmi2Warning &&
                std::fabs(value) > limits[k])
                fail(std::string(names[k]) + " = " + std::to_string(value) + " lies beyond its bound after an event update");
        }
    }

    void start() {
        me = nullptr;
        call("fmi2Instantiate(ME)", 1, [&] {
            me = api.instantiate("fuzz", fmi2ModelExchange, model.guid.c_str(), "", &callbacks, fmi2False, fmi2True);
            return me != nullptr ? fmi2OK : fmi2Error;
        });
        mode = Mode::instantiated;
        time = 0.0;
    }

    void initialize() {
        call("fmi2SetupExperiment", mode == Mode::instantiated, [&] { return api.setupExperiment(me, fmi2False, 0, 0, fmi2False, 0); });
        const fmi2ValueReference beta = model.real.at("beta");
        const double start = uniform(-1.0, 1.0);
        call("fmi2SetReal(beta)", mode == Mode::instantiated || mode == Mode::initialization ? 1 : -1,
             [&] { return api.setReal(me, &beta, 1, &start); });
        if (call("fmi2EnterInitializationMode", mode == Mode::instantiated ? 1 : 0,
                 [&] { return api.enterInitializationMode(me); }) <= fmi2Warning)
            mode = Mode::initialization;
        if (call("fmi2ExitInitializationMode", mode == Mode::initialization ? 1 : 0,
                 [&] { return api.exitInitializationMode(me); }) <= fmi2Warning)
            mode = Mode::event;
    }

    void event_iteration() {
        fmi2EventInfo info{};
        const fmi2Status status = call("fmi2NewDiscreteStates", mode == Mode::event ? 1 : 0,
                                       [&] { return api.newDiscreteStates(me, &info); });
        if (status <= fmi2Warning) {
            ++g_counts.event_updates;
            if (info.newDiscreteStatesNeeded) fail("newDiscreteStatesNeeded after one call");
            check_bounds();
        }
    }

    void host_step() {
        double x[kStates], dx[kStates], z[kIndicators], z_after[kIndicators];
        const bool ct = mode == Mode::continuous_time;
        if (call("fmi2GetContinuousStates", evaluable() ? 1 : 0, [&] { return api.getContinuousStates(me, x, kStates); }) > fmi2Warning) return;
        check_finite(x, kStates, "fmi2GetContinuousStates");
        if (call("fmi2GetEventIndicators", -1, [&] { return api.getEventIndicators(me, z, kIndicators); }) > fmi2Warning) return;
        if (call("fmi2GetDerivatives", -1, [&] { return api.getDerivatives(me, dx, kStates); }) > fmi2Warning) return;
        check_finite(dx, kStates, "fmi2GetDerivatives");
        const double h = std::pow(10.0, uniform(-7.0, -3.0));
        for (size_t k = 0; k < kStates; ++k) x[k] += h * dx[k];
        time += h;
        call("fmi2SetTime", ct ? 1 : -1, [&] { return api.setTime(me, time); });
        if (call("fmi2SetContinuousStates", ct ? 1 : 0, [&] { return api.setContinuousStates(me, x, kStates); }) > fmi2Warning) return;
        // After hostile states or inputs the model may not be representable: a refusal is right then.
        if (call("fmi2GetEventIndicators", -1, [&] { return api.getEventIndicators(me, z_after, kIndicators); }) > fmi2Warning) return;
        check_finite(z_after, kIndicators, "fmi2GetEventIndicators");
        fmi2Boolean enter = fmi2False, terminate = fmi2False;
        call("fmi2CompletedIntegratorStep", ct ? 1 : 0, [&] { return api.completedIntegratorStep(me, fmi2True, &enter, &terminate); });
        bool crossed = false;
        for (size_t k = 0; k < kIndicators; ++k) crossed = crossed || ((z[k] > 0) != (z_after[k] > 0));
        if (crossed && ct) {
            ++g_counts.state_events;
            if (call("fmi2EnterEventMode", 1, [&] { return api.enterEventMode(me); }) <= fmi2Warning) mode = Mode::event;
            event_iteration();
            if (call("fmi2EnterContinuousTimeMode", 1, [&] { return api.enterContinuousTimeMode(me); }) <= fmi2Warning)
                mode = Mode::continuous_time;
        }
    }

    void hostile_call() {
        double x[kStates + 4], z[kIndicators + 4];
        const size_t sizes[] = {0, kStates - 1, kStates + 1, static_cast<size_t>(-1), kIndicators - 1, kIndicators + 1};
        switch (pick(16)) {
            case 0: call("fmi2GetDerivatives(wrong nx)", 0, [&] { return api.getDerivatives(me, x, sizes[pick(6)]); }); break;
            case 1: call("fmi2GetEventIndicators(wrong ni)", 0, [&] { return api.getEventIndicators(me, z, sizes[pick(4)]); }); break;
            case 2: call("fmi2GetDerivatives(NULL)", 0, [&] { return api.getDerivatives(me, nullptr, kStates); }); break;
            case 3: call("fmi2SetContinuousStates(NULL)", 0, [&] { return api.setContinuousStates(me, nullptr, kStates); }); break;
            case 4: {
                if (call("fmi2GetContinuousStates", evaluable() ? 1 : 0, [&] { return api.getContinuousStates(me, x, kStates); }) > fmi2Warning) break;
                x[pick(kStates)] = hostile();
                const bool finite = std::isfinite(x[0]) && [&] { for (size_t k = 0; k < kStates; ++k) if (!std::isfinite(x[k])) return false; return true; }();
                call("fmi2SetContinuousStates(hostile)", mode == Mode::continuous_time && finite ? -1 : 0,
                     [&] { return api.setContinuousStates(me, x, kStates); });
                break;
            }
            case 5: {
                const double t = chance(0.5) ? hostile() : time - uniform(0.0, 1.0);
                call("fmi2SetTime(hostile or backwards)", (mode == Mode::event || mode == Mode::continuous_time) && std::isfinite(t) && t >= 0.0 ? 1 : 0,
                     [&] { return api.setTime(me, t); });
                break;
            }
            case 6: {
                const fmi2ValueReference vr = model.inputs[pick(static_cast<int>(model.inputs.size()))];
                const double value = chance(0.3) ? hostile() : uniform(-30.0, 30.0);
                call("fmi2SetReal(input)", std::isfinite(value) && mode != Mode::terminated && mode != Mode::error ? -1 : 0,
                     [&] { return api.setReal(me, &vr, 1, &value); });
                break;
            }
            case 7: call("fmi2EnterEventMode", mode == Mode::continuous_time ? 1 : 0, [&] {
                    const fmi2Status s = api.enterEventMode(me);
                    if (s <= fmi2Warning) mode = Mode::event;
                    return s;
                });
                break;
            case 8: event_iteration(); break;
            case 9: call("fmi2EnterContinuousTimeMode", mode == Mode::event ? 1 : 0, [&] {
                    const fmi2Status s = api.enterContinuousTimeMode(me);
                    if (s <= fmi2Warning) mode = Mode::continuous_time;
                    return s;
                });
                break;
            case 10: call("fmi2DoStep on Model Exchange", 0, [&] { return api.doStep(me, time, 1e-3, fmi2True); }); break;
            case 11: {
                fmi2FMUstate state = nullptr;
                if (call("fmi2GetFMUstate", mode == Mode::error ? 0 : -1, [&] { return api.getFMUstate(me, &state); }) <= fmi2Warning)
                    states.push_back(state);
                break;
            }
            case 12:
                if (!states.empty()) {
                    fmi2FMUstate state = states[pick(static_cast<int>(states.size()))];
                    if (call("fmi2SetFMUstate", -1, [&] { return api.setFMUstate(me, state); }) <= fmi2Warning) ++g_counts.restores;
                    // The wrapper's state after a restore is the saved one: read it back by trying.
                    mode = Mode::continuous_time;
                    fmi2Boolean a, b;
                    if (api.completedIntegratorStep(me, fmi2True, &a, &b) > fmi2Warning) {
                        fmi2EventInfo info{};
                        mode = api.newDiscreteStates(me, &info) <= fmi2Warning ? Mode::event : Mode::initialization;
                        if (mode == Mode::initialization) {
                            double probe[kStates];
                            mode = api.getDerivatives(me, probe, kStates) <= fmi2Warning ? Mode::terminated : Mode::instantiated;
                        }
                    }
                }
                break;
            case 13:
                if (!states.empty()) {
                    size_t size = 0;
                    fmi2FMUstate state = states[pick(static_cast<int>(states.size()))];
                    if (call("fmi2SerializedFMUstateSize", 1, [&] { return api.serializedFMUstateSize(me, state, &size); }) > fmi2Warning) break;
                    std::vector<char> blob(size);
                    if (call("fmi2SerializeFMUstate", 1, [&] { return api.serializeFMUstate(me, state, blob.data(), size); }) > fmi2Warning) break;
                    const bool corrupt = chance(0.5);
                    if (corrupt) blob[static_cast<size_t>(pick(static_cast<int>(size)))] ^= static_cast<char>(1 + pick(255));
                    fmi2FMUstate copy = nullptr;
                    if (call("fmi2DeSerializeFMUstate", corrupt ? 0 : 1,
                             [&] { return api.deSerializeFMUstate(me, blob.data(), size, &copy); }) <= fmi2Warning) {
                        states.push_back(copy);
                        ++g_counts.deserializations;
                    }
                }
                break;
            case 14: {
                const fmi2ValueReference unknown = model.real.at("der(beta_dot)"), known = model.real.at("beta");
                const double seed = chance(0.2) ? hostile() : 1.0;
                double result = 0.0;
                if (call("fmi2GetDirectionalDerivative", evaluable() && std::isfinite(seed) ? -1 : 0,
                         [&] { return api.getDirectionalDerivative(me, &unknown, 1, &known, 1, &seed, &result); }) <= fmi2Warning &&
                    !std::isfinite(result))
                    fail("fmi2GetDirectionalDerivative handed out a non-finite value");
                break;
            }
            default: {
                double nominals[kStates];
                if (call("fmi2GetNominalsOfContinuousStates", mode != Mode::initialization ? 1 : 0,
                         [&] { return api.getNominalsOfContinuousStates(me, nominals, kStates); }) <= fmi2Warning) {
                    for (double n : nominals)
                        if (!(n > 0.0) || !std::isfinite(n)) fail("a nominal value is not positive and finite");
                }
            }
        }
    }

    void run(int calls) {
        start();
        if (me == nullptr) return;
        initialize();
        event_iteration();
        if (call("fmi2EnterContinuousTimeMode", mode == Mode::event ? 1 : 0, [&] { return api.enterContinuousTimeMode(me); }) <= fmi2Warning)
            mode = Mode::continuous_time;
        for (int k = 0; k < calls; ++k) {
            if (chance(0.7)) host_step();
            else hostile_call();
            if (chance(0.01)) {
                call("fmi2Reset", 1, [&] { return api.reset(me); });
                mode = Mode::instantiated;
                time = 0.0;
                initialize();
                event_iteration();
                if (call("fmi2EnterContinuousTimeMode", mode == Mode::event ? 1 : 0, [&] { return api.enterContinuousTimeMode(me); }) <= fmi2Warning)
                    mode = Mode::continuous_time;
            }
        }
        for (fmi2FMUstate& state : states) call("fmi2FreeFMUstate", 1, [&] { return api.freeFMUstate(me, &state); });
        call("fmi2FreeInstance", -1, [&] {
            api.freeInstance(me);
            return fmi2OK;
        });
    }
};

template <class T>
void load(void* library, T& field, const char* name) {
    field = reinterpret_cast<T>(dlsym(library, name));
    if (field == nullptr) {
        std::fprintf(stderr, "fuzz_model_exchange: the FMU lacks %s\n", name);
        std::exit(2);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: fuzz_model_exchange <Gimbal2Axis.so> <modelDescription.xml> <sequences> [seed]\n");
        return 2;
    }
    void* library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
        std::fprintf(stderr, "fuzz_model_exchange: %s\n", dlerror());
        return 2;
    }
    load(library, api.instantiate, "fmi2Instantiate");
    load(library, api.freeInstance, "fmi2FreeInstance");
    load(library, api.setupExperiment, "fmi2SetupExperiment");
    load(library, api.enterInitializationMode, "fmi2EnterInitializationMode");
    load(library, api.exitInitializationMode, "fmi2ExitInitializationMode");
    load(library, api.terminate, "fmi2Terminate");
    load(library, api.reset, "fmi2Reset");
    load(library, api.setReal, "fmi2SetReal");
    load(library, api.getReal, "fmi2GetReal");
    load(library, api.getFMUstate, "fmi2GetFMUstate");
    load(library, api.setFMUstate, "fmi2SetFMUstate");
    load(library, api.freeFMUstate, "fmi2FreeFMUstate");
    load(library, api.serializedFMUstateSize, "fmi2SerializedFMUstateSize");
    load(library, api.serializeFMUstate, "fmi2SerializeFMUstate");
    load(library, api.deSerializeFMUstate, "fmi2DeSerializeFMUstate");
    load(library, api.getDirectionalDerivative, "fmi2GetDirectionalDerivative");
    load(library, api.doStep, "fmi2DoStep");
    load(library, api.enterEventMode, "fmi2EnterEventMode");
    load(library, api.newDiscreteStates, "fmi2NewDiscreteStates");
    load(library, api.enterContinuousTimeMode, "fmi2EnterContinuousTimeMode");
    load(library, api.completedIntegratorStep, "fmi2CompletedIntegratorStep");
    load(library, api.setTime, "fmi2SetTime");
    load(library, api.setContinuousStates, "fmi2SetContinuousStates");
    load(library, api.getDerivatives, "fmi2GetDerivatives");
    load(library, api.getEventIndicators, "fmi2GetEventIndicators");
    load(library, api.getContinuousStates, "fmi2GetContinuousStates");
    load(library, api.getNominalsOfContinuousStates, "fmi2GetNominalsOfContinuousStates");
    const Model model = read_model(argv[2]);
    if (model.guid.empty() || model.inputs.empty() || model.real.count("der(beta_dot)") == 0) {
        std::fprintf(stderr, "fuzz_model_exchange: %s is not this FMU's model description\n", argv[2]);
        return 2;
    }
    const long sequences = std::atol(argv[3]);
    g_fp_traps = std::getenv("FUZZ_FP_TRAPS") != nullptr && std::string(std::getenv("FUZZ_FP_TRAPS")) == "1";
    const unsigned long long seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1;
    char capture_path[] = "/tmp/fuzz_model_exchange_XXXXXX";
    g_capture_fd = mkstemp(capture_path);
    unlink(capture_path);
    g_saved_stderr = dup(2);
    struct sigaction action {};
    action.sa_handler = fatal_signal;
    for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM}) sigaction(s, &action, nullptr);
    for (g_sequence = 0; g_sequence < sequences; ++g_sequence) {
        alarm(60);
        Fuzzer fuzzer(model, seed * 1000003ULL + static_cast<unsigned long long>(g_sequence));
        fuzzer.run(200);
        alarm(0);
    }
    // A run that never reached what it is meant to exercise proves nothing.
    if (g_counts.state_events == 0 || g_counts.restores == 0 || g_counts.deserializations == 0) {
        ++g_failures;
        std::fprintf(stderr, "fuzz_model_exchange: the sequences never reached a state event, a restore or a deserialization\n");
    }
    std::printf("fuzz_model_exchange: %ld calls, %ld refused, %ld event updates (%ld after state events), %ld restores, "
                "%ld deserializations\n", g_counts.calls, g_counts.refusals, g_counts.event_updates, g_counts.state_events,
                g_counts.restores, g_counts.deserializations);
    std::printf("fuzz_model_exchange: %ld sequences%s: %s (%d failed checks)\n", sequences,
                g_fp_traps ? " with the host trapping FP exceptions" : "", g_failures == 0 ? "passed" : "FAILED", g_failures);
    return g_failures == 0 ? 0 : 1;
}
