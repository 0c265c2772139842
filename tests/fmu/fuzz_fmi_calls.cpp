// Deterministic fuzz test of the FMI 2.0 Co-Simulation C API of the FMU's shared object.
//
//   fuzz_fmi_calls <Gimbal2Axis.so> <modelDescription.xml> [sequences=3000] [seed] [only_sequence]
//
// only_sequence replays one sequence and prints its trace with every logged message; the environment
// variable FUZZ_SKIP="a,b,..." leaves sequences out, to look past a known crash or hang; FUZZ_TIMEOUT sets
// the watchdog of each sequence in seconds (default 10); FUZZ_FP_TRAPS=1 enables trapping floating-point
// exceptions (invalid, divide-by-zero, overflow) in this host around every FMU call, as some hosts do.
//
// Loads the shared object with dlopen and drives random call sequences through every fmi2* function,
// with valid and invalid arguments: value references, values (NaN, +-inf, 1e300, -0.0, huge voltages,
// negative masses, zero gear ratios, ...), NULL arrays with nvr > 0, times and step sizes, states of the
// state machine, log categories, instance names and GUIDs. Never with a dangling component or FMU state
// (undefined behaviour for any FMU); a NULL component is allowed and must give fmi2Error.
//
// Invariants checked on every call:
//   - the process survives (crash handlers print the call trace of the sequence and exit non-zero),
//   - each sequence finishes (alarm() watchdog per sequence),
//   - every fmi2Status returned lies in fmi2OK..fmi2Fatal,
//   - a call on a non-NULL instance that returns fmi2Discard, fmi2Error or fmi2Fatal logged, during that
//     call, at least one message with status >= fmi2Discard, and one with the returned status,
//   - a call with a NULL component returns fmi2Error (and logs nothing),
//   - logger arguments are sane (status in range, non-NULL strings, the instance's environment and name,
//     no printf conversion in the message: this FMU escapes every '%' and passes no arguments),
//   - the FMU writes nothing to stdout/stderr (fds 1 and 2 are redirected to a file during each call),
//   - Real values returned with fmi2OK/fmi2Warning are finite; after every successful fmi2DoStep all Real
//     outputs are read and must be finite, and fmi2LastSuccessfulTime must equal the expected time,
//   - valid fmi2Instantiate calls succeed, invalid ones return NULL (with a logged message when there is
//     a logger), and every instance can be freed at the end of its sequence, whatever happened before.
//
// Each sequence has its own RNG (std::mt19937_64 seeded from the printed seed and the sequence index),
// so a failing sequence can be replayed alone, with its full trace and log, by passing only_sequence.
#include <dlfcn.h>
#include <fcntl.h>
#include <fenv.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "check.hpp"
#include "fmi2FunctionTypes.h"

namespace {

// ------------------------------------------------------------------------------------------ the API

struct Api {
    fmi2GetTypesPlatformTYPE* getTypesPlatform;
    fmi2GetVersionTYPE* getVersion;
    fmi2SetDebugLoggingTYPE* setDebugLogging;
    fmi2InstantiateTYPE* instantiate;
    fmi2FreeInstanceTYPE* freeInstance;
    fmi2SetupExperimentTYPE* setupExperiment;
    fmi2EnterInitializationModeTYPE* enterInitializationMode;
    fmi2ExitInitializationModeTYPE* exitInitializationMode;
    fmi2TerminateTYPE* terminate;
    fmi2ResetTYPE* reset;
    fmi2GetRealTYPE* getReal;
    fmi2GetIntegerTYPE* getInteger;
    fmi2GetBooleanTYPE* getBoolean;
    fmi2GetStringTYPE* getString;
    fmi2SetRealTYPE* setReal;
    fmi2SetIntegerTYPE* setInteger;
    fmi2SetBooleanTYPE* setBoolean;
    fmi2SetStringTYPE* setString;
    fmi2GetFMUstateTYPE* getFMUstate;
    fmi2SetFMUstateTYPE* setFMUstate;
    fmi2FreeFMUstateTYPE* freeFMUstate;
    fmi2SerializedFMUstateSizeTYPE* serializedFMUstateSize;
    fmi2SerializeFMUstateTYPE* serializeFMUstate;
    fmi2DeSerializeFMUstateTYPE* deSerializeFMUstate;
    fmi2GetDirectionalDerivativeTYPE* getDirectionalDerivative;
    fmi2SetRealInputDerivativesTYPE* setRealInputDerivatives;
    fmi2GetRealOutputDerivativesTYPE* getRealOutputDerivatives;
    fmi2DoStepTYPE* doStep;
    fmi2CancelStepTYPE* cancelStep;
    fmi2GetStatusTYPE* getStatus;
    fmi2GetRealStatusTYPE* getRealStatus;
    fmi2GetIntegerStatusTYPE* getIntegerStatus;
    fmi2GetBooleanStatusTYPE* getBooleanStatus;
    fmi2GetStringStatusTYPE* getStringStatus;
};

Api api;

bool load_api(void* handle) {
    bool ok = true;
#define FUZZ_LOAD(field, symbol)                                                        \
    api.field = reinterpret_cast<decltype(api.field)>(dlsym(handle, symbol));          \
    if (api.field == nullptr) {                                                         \
        std::fprintf(stderr, "fuzz_fmi_calls: symbol %s not found: %s\n", symbol, dlerror()); \
        ok = false;                                                                     \
    }
    FUZZ_LOAD(getTypesPlatform, "fmi2GetTypesPlatform")
    FUZZ_LOAD(getVersion, "fmi2GetVersion")
    FUZZ_LOAD(setDebugLogging, "fmi2SetDebugLogging")
    FUZZ_LOAD(instantiate, "fmi2Instantiate")
    FUZZ_LOAD(freeInstance, "fmi2FreeInstance")
    FUZZ_LOAD(setupExperiment, "fmi2SetupExperiment")
    FUZZ_LOAD(enterInitializationMode, "fmi2EnterInitializationMode")
    FUZZ_LOAD(exitInitializationMode, "fmi2ExitInitializationMode")
    FUZZ_LOAD(terminate, "fmi2Terminate")
    FUZZ_LOAD(reset, "fmi2Reset")
    FUZZ_LOAD(getReal, "fmi2GetReal")
    FUZZ_LOAD(getInteger, "fmi2GetInteger")
    FUZZ_LOAD(getBoolean, "fmi2GetBoolean")
    FUZZ_LOAD(getString, "fmi2GetString")
    FUZZ_LOAD(setReal, "fmi2SetReal")
    FUZZ_LOAD(setInteger, "fmi2SetInteger")
    FUZZ_LOAD(setBoolean, "fmi2SetBoolean")
    FUZZ_LOAD(setString, "fmi2SetString")
    FUZZ_LOAD(getFMUstate, "fmi2GetFMUstate")
    FUZZ_LOAD(setFMUstate, "fmi2SetFMUstate")
    FUZZ_LOAD(freeFMUstate, "fmi2FreeFMUstate")
    FUZZ_LOAD(serializedFMUstateSize, "fmi2SerializedFMUstateSize")
    FUZZ_LOAD(serializeFMUstate, "fmi2SerializeFMUstate")
    FUZZ_LOAD(deSerializeFMUstate, "fmi2DeSerializeFMUstate")
    FUZZ_LOAD(getDirectionalDerivative, "fmi2GetDirectionalDerivative")
    FUZZ_LOAD(setRealInputDerivatives, "fmi2SetRealInputDerivatives")
    FUZZ_LOAD(getRealOutputDerivatives, "fmi2GetRealOutputDerivatives")
    FUZZ_LOAD(doStep, "fmi2DoStep")
    FUZZ_LOAD(cancelStep, "fmi2CancelStep")
    FUZZ_LOAD(getStatus, "fmi2GetStatus")
    FUZZ_LOAD(getRealStatus, "fmi2GetRealStatus")
    FUZZ_LOAD(getIntegerStatus, "fmi2GetIntegerStatus")
    FUZZ_LOAD(getBooleanStatus, "fmi2GetBooleanStatus")
    FUZZ_LOAD(getStringStatus, "fmi2GetStringStatus")
#undef FUZZ_LOAD
    return ok;
}

// ------------------------------------------------------------------------- the model description

enum class VarType { Real, Integer, Boolean, String, Other };

struct Variable {
    std::string name;
    unsigned vr = 0;
    VarType type = VarType::Other;
    std::string causality, variability, initial;
    double start = 0.0;
    bool has_start = false;
};

struct Model {
    std::string guid;
    std::vector<Variable> variables;
    std::vector<const Variable*> real_parameters, real_inputs, real_outputs, real_all;
    std::vector<const Variable*> integer_all, boolean_all;
    unsigned max_vr[3] = {0, 0, 0};  // Real, Integer, Boolean: largest valid value reference
    bool model_exchange = false;     // the FMU offers Model Exchange (the small FMUs are Co-Simulation only)
};

// Reads the attributes of the element whose name ends at pos; pos is left after the closing '>'.
// Returns false for a self-closing element.
bool parse_attributes(const std::string& text, size_t& pos, std::map<std::string, std::string>& attributes) {
    while (pos < text.size()) {
        while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
        if (pos >= text.size()) return false;
        if (text[pos] == '>') return ++pos, true;
        if (text[pos] == '/') {
            pos = text.find('>', pos);
            if (pos != std::string::npos) ++pos;
            return false;
        }
        const size_t equals = text.find('=', pos);
        if (equals == std::string::npos) return false;
        std::string name = text.substr(pos, equals - pos);
        while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) name.pop_back();
        size_t quote = equals + 1;
        while (quote < text.size() && text[quote] != '"' && text[quote] != '\'') ++quote;
        if (quote >= text.size()) return false;
        const size_t end = text.find(text[quote], quote + 1);
        if (end == std::string::npos) return false;
        attributes[name] = text.substr(quote + 1, end - quote - 1);
        pos = end + 1;
    }
    return false;
}

bool read_model(const char* path, Model& model) {
    std::ifstream file(path);
    if (!file) return false;
    std::stringstream buffer;
    buffer << file.rdbuf();
    const std::string text = buffer.str();

    size_t pos = text.find("<fmiModelDescription");
    if (pos == std::string::npos) return false;
    pos += std::strlen("<fmiModelDescription");
    std::map<std::string, std::string> root;
    parse_attributes(text, pos, root);
    model.guid = root["guid"];
    model.model_exchange = text.find("<ModelExchange") != std::string::npos;

    const std::string tag = "<ScalarVariable";
    while ((pos = text.find(tag, pos)) != std::string::npos) {
        pos += tag.size();
        std::map<std::string, std::string> attributes;
        Variable v;
        const bool has_children = parse_attributes(text, pos, attributes);
        v.name = attributes["name"];
        v.vr = static_cast<unsigned>(std::strtoul(attributes["valueReference"].c_str(), nullptr, 10));
        v.causality = attributes.count("causality") ? attributes["causality"] : "local";
        v.variability = attributes.count("variability") ? attributes["variability"] : "continuous";
        v.initial = attributes["initial"];
        if (has_children) {
            size_t child = text.find('<', pos);
            while (child != std::string::npos && text.compare(child, 4, "<!--") == 0)
                child = text.find('<', text.find("-->", child));
            if (child == std::string::npos) break;
            size_t name_end = child + 1;
            while (name_end < text.size() && std::isalpha(static_cast<unsigned char>(text[name_end]))) ++name_end;
            const std::string element = text.substr(child + 1, name_end - child - 1);
            if (element == "Real") v.type = VarType::Real;
            else if (element == "Integer" || element == "Enumeration") v.type = VarType::Integer;  // fmi2SetInteger both
            else if (element == "Boolean") v.type = VarType::Boolean;
            else if (element == "String") v.type = VarType::String;
            size_t attribute_pos = name_end;
            std::map<std::string, std::string> type_attributes;
            parse_attributes(text, attribute_pos, type_attributes);
            if (type_attributes.count("start")) {
                const std::string& s = type_attributes["start"];
                v.has_start = true;
                v.start = s == "true" ? 1.0 : s == "false" ? 0.0 : std::strtod(s.c_str(), nullptr);
            }
        }
        model.variables.push_back(v);
    }
    for (const Variable& v : model.variables) {
        switch (v.type) {
            case VarType::Real:
                model.real_all.push_back(&v);
                if (v.causality == "parameter") model.real_parameters.push_back(&v);
                if (v.causality == "input") model.real_inputs.push_back(&v);
                if (v.causality == "output") model.real_outputs.push_back(&v);
                model.max_vr[0] = std::max(model.max_vr[0], v.vr);
                break;
            case VarType::Integer:
                model.integer_all.push_back(&v);
                model.max_vr[1] = std::max(model.max_vr[1], v.vr);
                break;
            case VarType::Boolean:
                model.boolean_all.push_back(&v);
                model.max_vr[2] = std::max(model.max_vr[2], v.vr);
                break;
            default: break;
        }
    }
    return !model.guid.empty() && !model.real_all.empty();
}

Model model;

// ----------------------------------------------------------- the trace of the running sequence
// A fixed buffer, so that the crash and watchdog handlers can write it with write(2).

char g_trace[1 << 18];
size_t g_trace_length = 0;
volatile sig_atomic_t g_sequence = -1;
unsigned long long g_seed = 0;
int g_saved_stdout = -1, g_saved_stderr = -1;
int g_capture_fd = -1;

void trace_append(const char* text, size_t length) {
    static const char kTruncated[] = "\n  ... (trace truncated)\n";
    if (g_trace_length + length + sizeof kTruncated >= sizeof g_trace) {
        if (g_trace_length + sizeof kTruncated < sizeof g_trace) {
            std::memcpy(g_trace + g_trace_length, kTruncated, sizeof kTruncated - 1);
            g_trace_length += sizeof kTruncated - 1;
        }
        return;
    }
    std::memcpy(g_trace + g_trace_length, text, length);
    g_trace_length += length;
}

void trace_printf(const char* format, ...) __attribute__((format(printf, 1, 2)));
void trace_printf(const char* format, ...) {
    char text[4096];
    va_list args;
    va_start(args, format);
    const int n = std::vsnprintf(text, sizeof text, format, args);
    va_end(args);
    if (n > 0) trace_append(text, std::min<size_t>(static_cast<size_t>(n), sizeof text - 1));
}

void write_all(int fd, const char* text, size_t length) {
    while (length > 0) {
        const ssize_t n = write(fd, text, length);
        if (n <= 0) return;
        text += n;
        length -= static_cast<size_t>(n);
    }
}

void write_number(int fd, long long value) {
    char digits[32];
    int n = 0;
    const bool negative = value < 0;
    unsigned long long u = negative ? 0ull - static_cast<unsigned long long>(value) : static_cast<unsigned long long>(value);
    do {
        digits[n++] = static_cast<char>('0' + u % 10);
        u /= 10;
    } while (u != 0);
    if (negative) digits[n++] = '-';
    char text[32];
    for (int k = 0; k < n; ++k) text[k] = digits[n - 1 - k];
    write_all(fd, text, static_cast<size_t>(n));
}

void fatal_signal(int signal_number) {
    if (g_saved_stderr >= 0) dup2(g_saved_stderr, 2);  // the FMU call may have had stderr redirected
    if (g_saved_stdout >= 0) dup2(g_saved_stdout, 1);
    const char* what = signal_number == SIGALRM ? "HANG (watchdog expired)" : "CRASH";
    write_all(2, "\nfuzz_fmi_calls: ", 17);
    write_all(2, what, std::strlen(what));
    write_all(2, ": signal ", 9);
    write_number(2, signal_number);
    write_all(2, " in sequence ", 13);
    write_number(2, g_sequence);
    write_all(2, " (seed ", 7);
    write_number(2, static_cast<long long>(g_seed));
    write_all(2, "); the call in progress is the last line of the trace:\n", 55);
    write_all(2, g_trace, g_trace_length);
    write_all(2, "\nfuzz_fmi_calls: FAILED\n", 24);
    _exit(signal_number == SIGALRM ? 3 : 2);
}

void install_signal_handlers() {
    static char alternate_stack[1 << 16];
    stack_t stack{};
    stack.ss_sp = alternate_stack;
    stack.ss_size = sizeof alternate_stack;
    sigaltstack(&stack, nullptr);
    struct sigaction action {};
    action.sa_handler = fatal_signal;
    action.sa_flags = SA_ONSTACK;
    sigemptyset(&action.sa_mask);
    for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM, SIGTRAP}) sigaction(s, &action, nullptr);
}

// ---------------------------------------------------------------- the logger and the call context

const char* status_name(long long status) {
    static const char* const kNames[] = {"fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending"};
    return status >= 0 && status <= 5 ? kNames[status] : "(status out of range)";
}

struct CallContext {
    bool active = false;
    const void* environment = nullptr;  // expected componentEnvironment
    const char* instance_name = nullptr;  // expected instanceName (nullptr: not checked)
    int messages = 0;
    int refusal_messages = 0;  // status >= fmi2Discard
    int by_status[5] = {0, 0, 0, 0, 0};
    int bad_status = 0, null_arguments = 0, wrong_environment = 0, wrong_name = 0, conversions = 0;
    std::string first_refusal;
    std::string first_conversion;
};

CallContext g_call;
long long g_messages_outside_calls = 0;
bool g_verbose = false;
long long g_total_messages = 0;

void logger(fmi2ComponentEnvironment environment, fmi2String instance_name, fmi2Status status, fmi2String category,
            fmi2String message, ...) {
    ++g_total_messages;
    if (!g_call.active) {
        ++g_messages_outside_calls;
        return;
    }
    CallContext& call = g_call;
    ++call.messages;
    const int s = static_cast<int>(status);
    if (s < 0 || s > 4) ++call.bad_status;
    else ++call.by_status[s];
    if (s >= fmi2Discard) ++call.refusal_messages;
    if (instance_name == nullptr || category == nullptr || message == nullptr) ++call.null_arguments;
    if (environment != call.environment) ++call.wrong_environment;
    if (call.instance_name != nullptr && (instance_name == nullptr || std::strcmp(instance_name, call.instance_name) != 0))
        ++call.wrong_name;
    char text[2048] = "(null)";
    if (message != nullptr) {
        // This FMU passes no arguments after the message and escapes every '%': a conversion would
        // make the host read arguments that do not exist. Format only when there is none.
        bool conversion = false;
        for (const char* p = message; *p != '\0'; ++p) {
            if (*p != '%') continue;
            if (p[1] == '%') ++p;
            else conversion = true;
        }
        if (conversion) {
            if (call.conversions++ == 0) call.first_conversion = message;
            std::snprintf(text, sizeof text, "(unformatted) %s", message);
        } else {
            va_list args;
            va_start(args, message);
            std::vsnprintf(text, sizeof text, message, args);
            va_end(args);
        }
    }
    if (s >= fmi2Discard && call.first_refusal.empty()) call.first_refusal = text;
    if (g_verbose)
        trace_printf("      log [%s] %s %s: %s\n", status_name(s), category != nullptr ? category : "(null)",
                     instance_name != nullptr ? instance_name : "(null)", text);
}

void* checked_calloc(size_t count, size_t size) { return std::calloc(count, size); }
void checked_free(void* pointer) { std::free(pointer); }

// ------------------------------------------------------------------------------- failure reports

struct Stats {
    long long sequences = 0, calls = 0, refusals = 0, null_component_calls = 0, instances = 0;
    long long successful_steps = 0, successful_initializations = 0, discarded_steps = 0;
    long long by_status[6] = {0, 0, 0, 0, 0, 0};
    double slowest_call = 0.0;
    long long slow_calls = 0, very_slow_calls = 0;  // > 0.1 s, > 1 s
    std::string slowest_call_description;
    long long slowest_call_sequence = -1;
    int printed_failures = 0, printed_traces = 0;
    std::map<std::string, long long> failure_kinds;
};

Stats stats;
bool g_sequence_failed = false;
int g_call_index = 0;
std::string g_current_call;

bool report_failure(const char* kind, const std::string& detail) {
    ++stats.failure_kinds[kind];
    g_sequence_failed = true;
    trace_printf("    ^^^ FAILED: %s: %s\n", kind, detail.c_str());
    if (stats.printed_failures >= 30) return false;
    ++stats.printed_failures;
    std::fprintf(stderr, "fuzz_fmi_calls: sequence %d, call #%d %s: %s: %s\n", static_cast<int>(g_sequence),
                 g_call_index, g_current_call.c_str(), kind, detail.c_str());
    return true;
}

// The first 30 failures print the CHECK line, later ones only count (the summary gives each kind).
#define FUZZ_CHECK(condition, kind, detail)                  \
    do {                                                     \
        if (!(condition)) {                                  \
            if (report_failure(kind, detail)) CHECK(condition); \
            else ++check::failures;                          \
        }                                                    \
    } while (0)

std::string format(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* f, ...) {
    char text[2048];
    va_list args;
    va_start(args, f);
    std::vsnprintf(text, sizeof text, f, args);
    va_end(args);
    return text;
}

// ---------------------------------------------------------------------------- instances and calls

enum class Phase { instantiated, initialization, step_complete, step_failed, terminated, error };

struct Instance {
    fmi2Component component = nullptr;
    int id = 0;
    std::string name;
    bool has_logger = true;
    Phase phase = Phase::instantiated;
    double time = 0.0;  // the FMU's time as expected from the calls that succeeded
    bool stop_time_defined = false;
    double stop_time = 0.0;
    std::vector<struct SavedState> states;  // FMU states obtained from this instance, not yet freed
};

// What the master knows of an FMU state: the FMU's phase, time and stop time when it was taken.
struct Snapshot {
    Phase phase = Phase::instantiated;
    double time = 0.0;
    bool stop_time_defined = false;
    double stop_time = 0.0;
    bool known = true;  // false for states deserialized from corrupted bytes
};

struct SavedState {
    fmi2FMUstate pointer = nullptr;
    Snapshot snapshot;
};

struct SerializedState {
    std::vector<fmi2Byte> bytes;
    Snapshot snapshot;
};

Snapshot snapshot_of(const Instance& inst) {
    Snapshot s;
    s.phase = inst.phase;
    s.time = inst.time;
    s.stop_time_defined = inst.stop_time_defined;
    s.stop_time = inst.stop_time;
    return s;
}

int g_environment_probe = 0;  // componentEnvironment of instantiations that are expected to fail

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

off_t capture_size() {
    struct stat s {};
    return fstat(g_capture_fd, &s) == 0 ? s.st_size : 0;
}

struct CallScope {
    std::chrono::steady_clock::time_point start;
    off_t captured_before = 0;
};

void begin_call(const Instance* instance, const std::string& description) {
    ++g_call_index;
    ++stats.calls;
    g_current_call = description;
    trace_printf("  #%d %s", g_call_index, description.c_str());
    g_call = CallContext{};
    g_call.active = true;
    g_call.environment = instance != nullptr ? static_cast<const void*>(instance) : &g_environment_probe;
    g_call.instance_name = instance != nullptr ? instance->name.c_str() : nullptr;
    std::fflush(stdout);
    std::fflush(stderr);
    dup2(g_capture_fd, 1);
    dup2(g_capture_fd, 2);
}

void end_call(const CallScope& scope, const char* result) {
    std::fflush(stdout);
    std::fflush(stderr);
    dup2(g_saved_stdout, 1);
    dup2(g_saved_stderr, 2);
    g_call.active = false;
    const double elapsed = seconds_since(scope.start);
    if (elapsed > 0.1) ++stats.slow_calls;
    if (elapsed > 1.0) ++stats.very_slow_calls;
    if (elapsed > stats.slowest_call) {
        stats.slowest_call = elapsed;
        stats.slowest_call_description = g_current_call;
        stats.slowest_call_sequence = g_sequence;
    }
    trace_printf(" -> %s [%d msg]%s%s%s\n", result, g_call.messages, g_call.first_refusal.empty() ? "" : " \"",
                 g_call.first_refusal.substr(0, 160).c_str(), g_call.first_refusal.empty() ? "" : "\"");
    const off_t captured = capture_size();
    if (captured != scope.captured_before) {
        std::string text(static_cast<size_t>(std::min<off_t>(captured - scope.captured_before, 300)), '\0');
        if (pread(g_capture_fd, &text[0], text.size(), scope.captured_before) < 0) text = "?";
        FUZZ_CHECK(captured == scope.captured_before, "FMU wrote to stdout/stderr", text);
    }
    FUZZ_CHECK(g_call.bad_status == 0, "logger called with a status outside fmi2OK..fmi2Fatal", "");
    FUZZ_CHECK(g_call.null_arguments == 0, "logger called with a NULL instanceName, category or message", "");
    FUZZ_CHECK(g_call.wrong_environment == 0, "logger called with a foreign componentEnvironment", "");
    FUZZ_CHECK(g_call.wrong_name == 0, "logger called with a wrong instanceName", "");
    FUZZ_CHECK(g_call.conversions == 0, "logged message contains an unescaped printf conversion", g_call.first_conversion);
}

bool g_fp_traps = false;
constexpr int kHostTraps = FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW;

// Runs one status-returning call and checks the invariants common to all of them.
template <class F>
fmi2Status call(Instance* instance, const std::string& description, F&& function) {
    CallScope scope;
    begin_call(instance, description);
    scope.captured_before = capture_size();
    scope.start = std::chrono::steady_clock::now();
    // FUZZ_FP_TRAPS: the host runs with FP exceptions trapping (SIGFPE) during every FMU call; the FMU
    // must compute in its own environment and give this one back unchanged.
    if (g_fp_traps) {
        feclearexcept(FE_ALL_EXCEPT);
        feenableexcept(kHostTraps);
    }
    const fmi2Status status = function();
    if (g_fp_traps) {
        const int enabled = fegetexcept();
        const int rounding = fegetround();
        fedisableexcept(FE_ALL_EXCEPT);
        FUZZ_CHECK(enabled == kHostTraps, "the call changed the host's enabled FP exceptions", format("%#x", enabled));
        FUZZ_CHECK(rounding == FE_TONEAREST, "the call changed the host's rounding mode", format("%d", rounding));
    }
    const long long raw = static_cast<long long>(status);
    end_call(scope, status_name(raw));

    const bool in_range = raw >= fmi2OK && raw <= fmi2Fatal;
    FUZZ_CHECK(in_range, "returned status outside fmi2OK..fmi2Fatal", format("status = %lld", raw));
    if (raw >= 0 && raw <= 5) ++stats.by_status[raw];
    if (raw >= fmi2Discard) ++stats.refusals;
    if (instance == nullptr) {
        ++stats.null_component_calls;
        FUZZ_CHECK(status == fmi2Error, "a NULL component did not give fmi2Error", status_name(raw));
        FUZZ_CHECK(g_call.messages == 0, "a call with a NULL component logged through some logger", "");
    } else if (instance->has_logger && raw >= fmi2Discard && raw <= fmi2Fatal) {
        FUZZ_CHECK(g_call.refusal_messages >= 1, "refusal without a logged message (status >= fmi2Discard)",
                   status_name(raw));
        FUZZ_CHECK(g_call.by_status[raw] >= 1, "refusal without a logged message of the returned status",
                   format("returned %s, logged OK/Warning/Discard/Error/Fatal = %d/%d/%d/%d/%d", status_name(raw),
                          g_call.by_status[0], g_call.by_status[1], g_call.by_status[2], g_call.by_status[3],
                          g_call.by_status[4]));
    }
    return status;
}

// --------------------------------------------------------------------------------- random values

using Rng = std::mt19937_64;

struct Random {
    Rng rng;
    explicit Random(unsigned long long seed) : rng(seed) {}
    double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
    long long integer(long long a, long long b) { return std::uniform_int_distribution<long long>(a, b)(rng); }
    bool chance(double p) { return uniform(0.0, 1.0) < p; }
    template <class T>
    const T& pick(const std::vector<T>& values) { return values[static_cast<size_t>(integer(0, static_cast<long long>(values.size()) - 1))]; }
};

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

const std::vector<double> kExtremeReals = {
    kNaN, -kNaN, kInf, -kInf, 1e300, -1e300, DBL_MAX, -DBL_MAX, DBL_MIN, 4.9e-324, -0.0, 0.0, 1e9, -1e9, 1e6, -1e6,
    -1.0, 1e-12, -1e-12, 1e12, 1e-300, 2.0, 1.0};

std::string real_text(double x) { return format("%.17g", x); }

// A value a master could plausibly set: a perturbed start value for parameters, a moderate input.
double mild_value(Random& r, const Variable& v) {
    if (v.causality == "input") {
        const std::string& n = v.name;
        if (n.rfind("u_", 0) == 0) return r.uniform(-30.0, 30.0);
        if (n.find("_ddot") != std::string::npos || n.find("a_a") != std::string::npos) return r.uniform(-5.0, 5.0);
        if (n.find("_dot") != std::string::npos) return r.uniform(-1.0, 1.0);
        if (n.find("v_a") != std::string::npos) return r.uniform(-10.0, 10.0);
        return r.uniform(-3.2, 3.2);
    }
    if (v.start == 0.0) return r.chance(0.7) ? 0.0 : r.uniform(0.0, 0.01);
    return v.start * r.uniform(0.7, 1.4);
}

double chaos_value(Random& r, const Variable* v) {
    if (v != nullptr && r.chance(0.3)) return mild_value(r, *v);
    if (v != nullptr && r.chance(0.15)) return v->start * r.pick(std::vector<double>{-1.0, 0.0, 1e3, 1e-3, 1e6, -1e6});
    return r.pick(kExtremeReals);
}

// A value reference: valid of the given kind, or invalid for the type.
unsigned invalid_vr(Random& r, unsigned max_valid) {
    const std::vector<unsigned> candidates = {max_valid + 1, max_valid + 2, max_valid + 100, 1000u, 65536u,
                                              0x7fffffffu, 0xfffffffeu, 0xffffffffu};
    return r.pick(candidates);
}

// ------------------------------------------------------------------------------------ a sequence

struct Sequence {
    Random random;
    std::vector<std::unique_ptr<Instance>> live;
    std::vector<SerializedState> serialized;  // serialized FMU states: portable between the instances
    double chaos = 0.5;
    int next_id = 0;
    explicit Sequence(unsigned long long seed) : random(seed) {}
};

const char* const kCategories[] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard", "logStatusError",
                                   "logAll"};

std::string vr_list_text(const fmi2ValueReference* vr, size_t n) {
    if (vr == nullptr) return n == 0 ? "NULL" : "NULL";
    std::string s = "[";
    for (size_t i = 0; i < n && i < 8; ++i) s += (i ? "," : "") + std::to_string(vr[i]);
    if (n > 8) s += ",...";
    return s + "]";
}

template <class T, class ToText>
std::string values_text(const T* values, size_t n, ToText to_text) {
    if (values == nullptr) return "NULL";
    std::string s = "[";
    for (size_t i = 0; i < n && i < 8; ++i) s += (i ? "," : "") + to_text(values[i]);
    if (n > 8) s += ",...";
    return s + "]";
}

std::string component_text(const Instance* instance) {
    return instance == nullptr ? "NULL" : "c" + std::to_string(instance->id);
}

// ------------------------------------------------------------- verification after a successful step

void verify_after_step(Instance& inst) {
    std::vector<fmi2ValueReference> vr;
    for (const Variable* v : model.real_outputs) vr.push_back(v->vr);
    std::vector<fmi2Real> values(vr.size(), kNaN);
    const fmi2Status status = call(&inst, format("[verify] fmi2GetReal(%s, all %zu Real outputs)", component_text(&inst).c_str(), vr.size()),
                                   [&] { return api.getReal(inst.component, vr.data(), vr.size(), values.data()); });
    FUZZ_CHECK(status <= fmi2Warning, "GetReal of the outputs failed after a successful fmi2DoStep", status_name(status));
    if (status <= fmi2Warning) {
        for (size_t i = 0; i < vr.size(); ++i)
            FUZZ_CHECK(std::isfinite(values[i]), "non-finite output after a successful fmi2DoStep",
                       format("%s = %.17g", model.real_outputs[i]->name.c_str(), values[i]));
    }
    fmi2Real last = kNaN;
    const fmi2Status time_status =
        call(&inst, format("[verify] fmi2GetRealStatus(%s, fmi2LastSuccessfulTime)", component_text(&inst).c_str()),
             [&] { return api.getRealStatus(inst.component, fmi2LastSuccessfulTime, &last); });
    FUZZ_CHECK(time_status == fmi2OK, "fmi2GetRealStatus(fmi2LastSuccessfulTime) failed after a successful step",
               status_name(time_status));
    if (time_status == fmi2OK)
        FUZZ_CHECK(last == inst.time, "fmi2LastSuccessfulTime differs from the time reached",
                   format("%.17g, expected %.17g", last, inst.time));
}

// ---------------------------------------------------------------------------------- the functions

enum Function {
    F_GetTypesPlatform, F_GetVersion, F_SetDebugLogging, F_Instantiate, F_FreeInstance, F_SetupExperiment,
    F_EnterInitializationMode, F_ExitInitializationMode, F_Terminate, F_Reset, F_GetReal, F_GetInteger,
    F_GetBoolean, F_GetString, F_SetReal, F_SetInteger, F_SetBoolean, F_SetString, F_GetFMUstate, F_SetFMUstate,
    F_FreeFMUstate, F_SerializedFMUstateSize, F_SerializeFMUstate, F_DeSerializeFMUstate,
    F_GetDirectionalDerivative, F_SetRealInputDerivatives, F_GetRealOutputDerivatives, F_DoStep, F_CancelStep,
    F_GetStatus, F_GetRealStatus, F_GetIntegerStatus, F_GetBooleanStatus, F_GetStringStatus, F_Count
};

// Relative weights of the functions in chaos calls.
const int kWeights[F_Count] = {
    1, 1, 4, 3, 2, 5,   // GetTypesPlatform .. SetupExperiment
    5, 6, 3, 3, 8, 4,   // EnterInitializationMode .. GetInteger
    3, 2, 14, 3, 4, 2,  // GetBoolean .. SetString
    2, 2, 2, 2, 2, 2,   // GetFMUstate .. DeSerializeFMUstate
    1, 1, 1, 12, 2,     // GetDirectionalDerivative .. CancelStep
    2, 2, 1, 1, 1,      // GetStatus .. GetStringStatus
};

// ---- instantiate / free

void do_instantiate(Sequence& s, bool valid) {
    Random& r = s.random;
    static const fmi2CallbackFunctions kFull = {logger, checked_calloc, checked_free, nullptr, nullptr};
    static const fmi2CallbackFunctions kNoMemory = {logger, nullptr, nullptr, nullptr, nullptr};
    static const fmi2CallbackFunctions kNoLogger = {nullptr, checked_calloc, checked_free, nullptr, nullptr};

    auto inst = std::make_unique<Instance>();
    inst->id = s.next_id++;
    std::string name = "fuzz" + std::to_string(inst->id);
    bool null_name = false;
    std::string guid = model.guid;
    const char* guid_pointer = nullptr;
    int type = fmi2CoSimulation;
    const char* resource = "file:///tmp/";
    fmi2CallbackFunctions functions = kFull;
    const fmi2CallbackFunctions* functions_pointer = &functions;
    bool expect_valid = true;  // all arguments valid: an instance is expected
    bool may_succeed = true;   // a valid instance is acceptable

    if (!valid) {
        switch (r.integer(0, 15)) {
            case 0: null_name = true, expect_valid = false, may_succeed = false; break;
            case 1: name = "", expect_valid = false, may_succeed = false; break;
            case 2: name = "%s%n%d%%" + std::to_string(inst->id); break;  // valid, but printf-hostile
            case 3: name = std::string(5000, 'n') + std::to_string(inst->id); break;
            case 4: type = 2, expect_valid = false, may_succeed = false; break;  // neither interface
            case 5:
                type = static_cast<int>(r.integer(-5, 9));
                if (type != fmi2CoSimulation && !(type == fmi2ModelExchange && model.model_exchange))
                    expect_valid = may_succeed = false;
                break;
            case 6: guid = "{00000000-0000-0000-0000-000000000000}", expect_valid = may_succeed = false; break;
            case 7: guid_pointer = nullptr, guid = "(NULL)", expect_valid = may_succeed = false; break;
            case 8: guid = "", expect_valid = may_succeed = false; break;
            case 9: guid = model.guid + "x", expect_valid = may_succeed = false; break;
            case 10: guid = model.guid.substr(1, model.guid.size() - 2), expect_valid = may_succeed = false; break;
            case 11: guid = "%s%s%s%n" + model.guid, expect_valid = may_succeed = false; break;
            case 12: functions_pointer = nullptr, expect_valid = may_succeed = false; break;
            case 13: functions = kNoLogger, expect_valid = false; break;  // nowhere to log: either outcome
            case 14: functions = kNoMemory, expect_valid = false; break;  // canNotUseMemoryManagementFunctions
            default: resource = r.chance(0.5) ? nullptr : "not a uri %s", expect_valid = false; break;
        }
    }
    const char* name_pointer = null_name ? nullptr : name.c_str();
    if (guid != "(NULL)") guid_pointer = guid.c_str();
    inst->name = name_pointer != nullptr ? name : "";
    inst->has_logger = functions_pointer != nullptr && functions_pointer->logger != nullptr;
    functions.componentEnvironment = inst.get();
    const fmi2Boolean visible = static_cast<fmi2Boolean>(r.integer(0, 1));
    const fmi2Boolean logging_on = static_cast<fmi2Boolean>(r.chance(0.3));

    const std::string description =
        format("c%d = fmi2Instantiate(name=%s, type=%d, guid=%s, resource=%s, functions=%s, visible=%d, loggingOn=%d)",
               inst->id, name_pointer != nullptr ? ("\"" + name.substr(0, 40) + (name.size() > 40 ? "...\"" : "\"")).c_str() : "NULL",
               type, guid_pointer != nullptr ? ("\"" + guid + "\"").c_str() : "NULL", resource != nullptr ? resource : "NULL",
               functions_pointer == nullptr ? "NULL" : functions.logger == nullptr ? "{logger=NULL}"
                                                   : functions.allocateMemory == nullptr ? "{logger, no memory functions}"
                                                                                          : "{logger, calloc, free}",
               visible, logging_on);
    CallScope scope;
    begin_call(nullptr, description);
    g_call.environment = inst.get();  // the environment passed in the callbacks
    g_call.instance_name = name_pointer != nullptr ? inst->name.c_str() : nullptr;
    scope.captured_before = capture_size();
    scope.start = std::chrono::steady_clock::now();
    const fmi2Component component = api.instantiate(name_pointer, static_cast<fmi2Type>(type), guid_pointer, resource,
                                                    functions_pointer, visible, logging_on);
    end_call(scope, component != nullptr ? "instance" : "NULL");
    if (expect_valid) FUZZ_CHECK(component != nullptr, "valid fmi2Instantiate returned NULL", g_call.first_refusal);
    if (!may_succeed) FUZZ_CHECK(component == nullptr, "invalid fmi2Instantiate returned an instance", "");
    if (component == nullptr) {
        ++stats.refusals;
        if (inst->has_logger)
            FUZZ_CHECK(g_call.refusal_messages >= 1 && g_call.by_status[fmi2Error] + g_call.by_status[fmi2Fatal] >= 1,
                       "fmi2Instantiate returned NULL without logging an error", "");
        return;
    }
    ++stats.instances;
    inst->component = component;
    if (type == fmi2ModelExchange) {
        // These sequences drive the Co-Simulation interface; a Model Exchange instance is only made
        // and freed here.
        CallScope free_scope;
        begin_call(inst.get(), format("fmi2FreeInstance(c%d)", inst->id));
        free_scope.captured_before = capture_size();
        free_scope.start = std::chrono::steady_clock::now();
        api.freeInstance(component);
        end_call(free_scope, "void");
        return;
    }
    s.live.push_back(std::move(inst));
}

void free_instance(Sequence& s, size_t index) {
    Instance& inst = *s.live[index];
    // Free the FMU states first (with the FMU's own function, while the instance lives).
    for (SavedState& saved : inst.states) {
        fmi2FMUstate copy = saved.pointer;
        call(&inst, format("fmi2FreeFMUstate(%s, &state %p)", component_text(&inst).c_str(), copy),
             [&] { return api.freeFMUstate(inst.component, &copy); });
    }
    inst.states.clear();
    CallScope scope;
    begin_call(&inst, format("fmi2FreeInstance(%s)", component_text(&inst).c_str()));
    scope.captured_before = capture_size();
    scope.start = std::chrono::steady_clock::now();
    api.freeInstance(inst.component);
    end_call(scope, "(void)");
    s.live.erase(s.live.begin() + static_cast<long>(index));  // never used again
}

// ---- the state machine

void after_lifecycle(Instance& inst, Function f, fmi2Status status) {
    if (status > fmi2Warning) return;
    switch (f) {
        case F_EnterInitializationMode: inst.phase = Phase::initialization; break;
        case F_ExitInitializationMode:
            inst.phase = Phase::step_complete;
            ++stats.successful_initializations;
            break;
        case F_Terminate: inst.phase = Phase::terminated; break;
        case F_Reset:
            inst.phase = Phase::instantiated;
            inst.time = 0.0;
            inst.stop_time_defined = false;
            break;
        default: break;
    }
}

void do_lifecycle(Instance* inst, Function f) {
    const std::string c = component_text(inst);
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    fmi2Status status = fmi2OK;
    switch (f) {
        case F_EnterInitializationMode:
            status = call(inst, "fmi2EnterInitializationMode(" + c + ")", [&] { return api.enterInitializationMode(component); });
            break;
        case F_ExitInitializationMode:
            status = call(inst, "fmi2ExitInitializationMode(" + c + ")", [&] { return api.exitInitializationMode(component); });
            break;
        case F_Terminate: status = call(inst, "fmi2Terminate(" + c + ")", [&] { return api.terminate(component); }); break;
        case F_Reset: status = call(inst, "fmi2Reset(" + c + ")", [&] { return api.reset(component); }); break;
        case F_CancelStep: status = call(inst, "fmi2CancelStep(" + c + ")", [&] { return api.cancelStep(component); }); break;
        default: return;
    }
    if (inst != nullptr) after_lifecycle(*inst, f, status);
}

void do_setup_experiment(Sequence& s, Instance* inst, bool valid) {
    Random& r = s.random;
    fmi2Boolean tolerance_defined = static_cast<fmi2Boolean>(r.integer(0, 1));
    double tolerance = r.pick(std::vector<double>{1e-6, 1e-4, 0.0, -1.0, kNaN, kInf});
    double start = 0.0, stop = 0.0;
    fmi2Boolean stop_defined = static_cast<fmi2Boolean>(r.chance(0.5));
    if (valid) {
        start = r.pick(std::vector<double>{0.0, 0.0, 0.0, -0.0, 1.0, -5.0, r.uniform(0.0, 100.0)});
        stop = start + r.pick(std::vector<double>{0.05, 0.5, 10.0, 1e-3});
    } else {
        start = r.pick(std::vector<double>{0.0, -0.0, kNaN, kInf, -kInf, 1e300, -1e300, 1e12, 1e15, 1e-300, -5.0,
                                           r.uniform(0.0, 100.0), DBL_MAX});
        stop = r.pick(std::vector<double>{kNaN, kInf, start - 1.0, start, start + 1e-6, start + 0.05, start + 10.0, 1e300,
                                          -kInf});
        if (r.chance(0.1)) stop_defined = static_cast<fmi2Boolean>(r.pick(std::vector<double>{2.0, 255.0, -1.0}));
    }
    const std::string d = format("fmi2SetupExperiment(%s, tolDefined=%d, tol=%s, start=%s, stopDefined=%d, stop=%s)",
                                 component_text(inst).c_str(), tolerance_defined, real_text(tolerance).c_str(),
                                 real_text(start).c_str(), stop_defined, real_text(stop).c_str());
    const fmi2Status status = call(inst, d, [&] {
        return api.setupExperiment(inst != nullptr ? inst->component : nullptr, tolerance_defined, tolerance, start,
                                   stop_defined, stop);
    });
    if (inst != nullptr && status <= fmi2Warning) {
        inst->time = start;
        inst->stop_time_defined = stop_defined != fmi2False;
        inst->stop_time = stop;
    }
}

void do_step(Sequence& s, Instance* inst, bool valid) {
    Random& r = s.random;
    const double t = inst != nullptr ? inst->time : 0.0;
    double point = t, h = 1e-3;
    if (valid) {
        h = r.pick(std::vector<double>{1e-3, 1e-3, 1e-4, 5e-3, 0.01, r.uniform(1e-6, 0.01), 1e-9});
    } else {
        switch (r.integer(0, 11)) {
            case 0: case 1: case 2: case 3: case 4: point = t; break;
            case 5: point = t + 1e-13 * std::max(1.0, std::fabs(t)); break;  // near the tolerance of communication_point.h
            case 6: point = t + 1e-3; break;
            case 7: point = t - 0.5; break;
            case 8: point = r.pick(std::vector<double>{kNaN, kInf, -kInf}); break;
            case 9: point = r.uniform(-10.0, 10.0); break;
            case 10: point = -0.0; break;
            default: point = t * (1.0 + 1e-9); break;
        }
        switch (r.integer(0, 15)) {
            case 0: case 1: case 2: case 3: case 4: h = r.uniform(0.0, 0.01); break;
            case 5: h = 1e-3; break;
            case 6: h = 1e-15; break;
            case 7: h = 1e-300; break;
            case 8: h = 4.9e-324; break;
            case 9: h = 0.0; break;
            case 10: h = -0.0; break;
            case 11: h = -1e-3; break;
            case 12: h = r.pick(std::vector<double>{kNaN, kInf, -kInf}); break;
            case 13: h = 1e-9; break;
            case 14: h = 0.01; break;
            default:
                // Long steps only where a stop time refuses them: runs stay short.
                h = inst != nullptr && inst->stop_time_defined && std::isfinite(inst->stop_time) &&
                            t + 1.0 > inst->stop_time + 1e-6 * std::max(1.0, std::fabs(inst->stop_time))
                        ? r.pick(std::vector<double>{1.0, 1e3, 1e300})
                        : 0.005;
                break;
        }
    }
    const fmi2Boolean no_prior = static_cast<fmi2Boolean>(r.integer(0, 1));
    const std::string d = format("fmi2DoStep(%s, t=%s, h=%s, noSetFMUStatePriorToCurrentPoint=%d)",
                                 component_text(inst).c_str(), real_text(point).c_str(), real_text(h).c_str(), no_prior);
    const fmi2Status status =
        call(inst, d, [&] { return api.doStep(inst != nullptr ? inst->component : nullptr, point, h, no_prior); });
    if (inst == nullptr) return;
    if (status <= fmi2Warning) {
        inst->time = point + h;  // the master's point becomes the FMU's time (communication_point.h)
        inst->phase = Phase::step_complete;
        ++stats.successful_steps;
        verify_after_step(*inst);
    } else if (status == fmi2Discard) {
        inst->phase = Phase::step_failed;
        ++stats.discarded_steps;
    }
}

// ---- values

// One of `variables`, or nullptr when the FMU has none of them (the ship-motion FMU has no inputs).
const Variable* pick_variable(Random& r, const std::vector<const Variable*>& variables) {
    return variables.empty() ? nullptr : r.pick(variables);
}

std::vector<fmi2ValueReference> real_vrs(Random& r, size_t n, bool settable_only, std::vector<const Variable*>& vars) {
    std::vector<fmi2ValueReference> vr;
    for (size_t i = 0; i < n; ++i) {
        const double u = r.uniform(0.0, 1.0);
        const Variable* v = nullptr;
        if (u < 0.45) v = pick_variable(r, model.real_parameters);
        else if (u < 0.78) v = pick_variable(r, model.real_inputs);
        else if (u < (settable_only ? 0.85 : 0.92)) v = pick_variable(r, model.real_outputs);
        else if (u < 0.93) v = pick_variable(r, model.real_all);
        if (v != nullptr) {
            vr.push_back(v->vr);
            vars.push_back(v);
        } else {
            vr.push_back(invalid_vr(r, model.max_vr[0]));
            vars.push_back(nullptr);
        }
    }
    return vr;
}

// NULL-array variants: 0 = arrays, 1 = vr NULL, 2 = value NULL, 3 = both NULL (with nvr = 0 mostly).
int null_mode(Random& r) {
    const double u = r.uniform(0.0, 1.0);
    return u < 0.88 ? 0 : u < 0.93 ? 1 : u < 0.97 ? 2 : 3;
}

void do_set_real(Sequence& s, Instance* inst, bool valid) {
    Random& r = s.random;
    std::vector<const Variable*> vars;
    size_t n = static_cast<size_t>(valid ? r.integer(1, 4) : r.integer(0, 6));
    std::vector<fmi2ValueReference> vr;
    std::vector<fmi2Real> value;
    if (valid) {
        // What a well-behaved master sets in this phase: parameters before initialization, inputs after.
        const bool before_initialized =
            inst != nullptr && (inst->phase == Phase::instantiated || inst->phase == Phase::initialization);
        const bool parameters = before_initialized && (r.chance(0.5) || model.real_inputs.empty());
        const std::vector<const Variable*>& settable = parameters ? model.real_parameters : model.real_inputs;
        if (settable.empty()) n = 0;  // nothing this master could set now: an empty call
        for (size_t i = 0; i < n; ++i) {
            const Variable* v = r.pick(settable);
            vr.push_back(v->vr);
            value.push_back(mild_value(r, *v));
        }
    } else {
        vr = real_vrs(r, n, true, vars);
        for (size_t i = 0; i < n; ++i) value.push_back(chaos_value(r, vars[i]));
    }
    const int mode = valid ? 0 : null_mode(r);
    if (mode == 3 && r.chance(0.5)) n = 0;
    const fmi2ValueReference* vr_pointer = mode == 1 || mode == 3 ? nullptr : vr.data();
    const fmi2Real* value_pointer = mode == 2 || mode == 3 ? nullptr : value.data();
    const std::string d = format("fmi2SetReal(%s, vr=%s, nvr=%zu, value=%s)", component_text(inst).c_str(),
                                 vr_list_text(vr_pointer, n).c_str(), n, values_text(value_pointer, n, real_text).c_str());
    call(inst, d, [&] { return api.setReal(inst != nullptr ? inst->component : nullptr, vr_pointer, n, value_pointer); });
}

void do_get_real(Sequence& s, Instance* inst) {
    Random& r = s.random;
    std::vector<const Variable*> vars;
    size_t n = static_cast<size_t>(r.integer(0, 8));
    std::vector<fmi2ValueReference> vr = real_vrs(r, n, false, vars);
    std::vector<fmi2Real> value(n + 1, -12345.0);
    const int mode = null_mode(r);
    if (mode == 3 && r.chance(0.5)) n = 0;
    const fmi2ValueReference* vr_pointer = mode == 1 || mode == 3 ? nullptr : vr.data();
    fmi2Real* value_pointer = mode == 2 || mode == 3 ? nullptr : value.data();
    const std::string d = format("fmi2GetReal(%s, vr=%s, nvr=%zu, value=%s)", component_text(inst).c_str(),
                                 vr_list_text(vr_pointer, n).c_str(), n, value_pointer == nullptr ? "NULL" : "buffer");
    const fmi2Status status =
        call(inst, d, [&] { return api.getReal(inst != nullptr ? inst->component : nullptr, vr_pointer, n, value_pointer); });
    if (status <= fmi2Warning && value_pointer != nullptr) {
        for (size_t i = 0; i < n; ++i)
            FUZZ_CHECK(std::isfinite(value[i]), "fmi2GetReal returned a non-finite value with fmi2OK/fmi2Warning",
                       format("vr %u = %.17g", vr[i], value[i]));
    }
}

// A value a master could plausibly give an Integer or Boolean parameter: a small choice (structural
// variants), a scaled step budget, or a flag.
long long mild_discrete(Random& r, const Variable& v, bool integer) {
    if (!integer) return r.integer(0, 1);
    if (v.start >= 0.0 && v.start <= 3.0) return r.integer(0, 3);
    return std::max(1LL, static_cast<long long>(v.start * r.pick(std::vector<double>{1e-5, 1e-4, 1e-3, 1e-2, 1.0, 1.0})));
}

void do_set_get_discrete(Sequence& s, Instance* inst, bool set, bool integer, bool valid) {
    Random& r = s.random;
    const std::vector<const Variable*>& all = integer ? model.integer_all : model.boolean_all;
    std::vector<const Variable*> parameters;
    for (const Variable* v : all)
        if (v->causality == "parameter") parameters.push_back(v);
    const unsigned max_vr = model.max_vr[integer ? 1 : 2];
    if (valid && parameters.empty()) valid = false;
    size_t n = static_cast<size_t>(valid ? r.integer(1, 3) : r.integer(0, 5));
    std::vector<fmi2ValueReference> vr;
    std::vector<fmi2Integer> value(n + 1, -7);
    for (size_t i = 0; i < n; ++i) {
        if (valid) {
            const Variable* v = r.pick(parameters);
            vr.push_back(v->vr);
            value[i] = static_cast<fmi2Integer>(mild_discrete(r, *v, integer));
            continue;
        }
        const Variable* v = !all.empty() && r.chance(0.75) ? (r.chance(0.5) && !parameters.empty() ? r.pick(parameters) : r.pick(all)) : nullptr;
        vr.push_back(v != nullptr ? v->vr : invalid_vr(r, max_vr));
        if (set) {
            value[i] = v != nullptr && r.chance(0.4)
                           ? static_cast<fmi2Integer>(mild_discrete(r, *v, integer))
                       : integer ? static_cast<fmi2Integer>(r.pick(std::vector<long long>{0, 1, -1, 2, 3, 4, INT_MAX, INT_MIN, 100000, r.integer(-1000, 1000)}))
                                 : static_cast<fmi2Integer>(r.pick(std::vector<long long>{fmi2True, fmi2False, 2, -1, 255}));
        }
    }
    using T = fmi2Integer;  // fmi2Boolean is int as well
    const int mode = valid ? 0 : null_mode(r);
    if (mode == 3 && r.chance(0.5)) n = 0;
    const fmi2ValueReference* vr_pointer = mode == 1 || mode == 3 ? nullptr : vr.data();
    T* value_pointer = mode == 2 || mode == 3 ? nullptr : value.data();
    const char* function = set ? (integer ? "fmi2SetInteger" : "fmi2SetBoolean") : (integer ? "fmi2GetInteger" : "fmi2GetBoolean");
    const std::string values =
        set ? values_text(value_pointer, n, [](T x) { return std::to_string(x); }) : (value_pointer ? "buffer" : "NULL");
    const std::string d = format("%s(%s, vr=%s, nvr=%zu, value=%s)", function, component_text(inst).c_str(),
                                 vr_list_text(vr_pointer, n).c_str(), n, values.c_str());
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    // fmi2Integer and fmi2Boolean are both int: choose the function by the flag, not by the type.
    call(inst, d, [&] {
        if (integer)
            return set ? api.setInteger(component, vr_pointer, n, value_pointer)
                       : api.getInteger(component, vr_pointer, n, value_pointer);
        return set ? api.setBoolean(component, vr_pointer, n, value_pointer)
                   : api.getBoolean(component, vr_pointer, n, value_pointer);
    });
}

void do_string(Sequence& s, Instance* inst, bool set) {
    Random& r = s.random;
    size_t n = static_cast<size_t>(r.integer(0, 3));
    std::vector<fmi2ValueReference> vr;
    std::vector<fmi2String> value(n + 1, nullptr);
    static const char* const kStrings[] = {"", "text", "%s%n%x", nullptr, "a very long string ..........................................."};
    for (size_t i = 0; i < n; ++i) {
        vr.push_back(r.chance(0.5) ? static_cast<unsigned>(r.integer(0, 5)) : invalid_vr(r, 10));
        if (set) value[i] = kStrings[r.integer(0, 4)];
    }
    const int mode = null_mode(r);
    if (mode == 3 && r.chance(0.5)) n = 0;
    const fmi2ValueReference* vr_pointer = mode == 1 || mode == 3 ? nullptr : vr.data();
    fmi2String* value_pointer = mode == 2 || mode == 3 ? nullptr : value.data();
    const std::string d = format("%s(%s, vr=%s, nvr=%zu, value=%s)", set ? "fmi2SetString" : "fmi2GetString",
                                 component_text(inst).c_str(), vr_list_text(vr_pointer, n).c_str(), n,
                                 value_pointer == nullptr ? "NULL" : set ? "strings" : "buffer");
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    const fmi2Status status = call(inst, d, [&] {
        return set ? api.setString(component, vr_pointer, n, value_pointer) : api.getString(component, vr_pointer, n, value_pointer);
    });
    if (!set && status <= fmi2Warning && value_pointer != nullptr)
        for (size_t i = 0; i < n; ++i) FUZZ_CHECK(value[i] != nullptr, "fmi2GetString returned a NULL string with fmi2OK", "");
}

void do_set_debug_logging(Sequence& s, Instance* inst) {
    Random& r = s.random;
    const fmi2Boolean on = static_cast<fmi2Boolean>(r.integer(0, 1));
    size_t n = static_cast<size_t>(r.integer(0, 4));
    std::vector<fmi2String> categories;
    std::string names;
    for (size_t i = 0; i < n; ++i) {
        const long long k = r.integer(0, 9);
        const char* c = k < 6 ? kCategories[k] : k == 6 ? "noSuchCategory" : k == 7 ? "%s%n%p" : k == 8 ? "" : nullptr;
        categories.push_back(c);
        names += (i ? "," : "") + (c != nullptr ? "\"" + std::string(c) + "\"" : std::string("NULL"));
    }
    const bool null_array = n > 0 && r.chance(0.05);
    const fmi2String* pointer = null_array || n == 0 ? (r.chance(0.5) ? nullptr : categories.data()) : categories.data();
    if (null_array) pointer = nullptr;
    const std::string d = format("fmi2SetDebugLogging(%s, loggingOn=%d, n=%zu, categories=%s)", component_text(inst).c_str(),
                                 on, n, pointer == nullptr ? "NULL" : ("[" + names + "]").c_str());
    call(inst, d, [&] { return api.setDebugLogging(inst != nullptr ? inst->component : nullptr, on, n, pointer); });
}

// After a successful fmi2SetFMUstate the FMU is where the state was taken.
void restored(Instance& inst, const Snapshot& snapshot) {
    if (snapshot.known) {
        inst.phase = snapshot.phase;
        inst.time = snapshot.time;
        inst.stop_time_defined = snapshot.stop_time_defined;
        inst.stop_time = snapshot.stop_time;
        return;
    }
    // Unknown (deserialized from altered bytes): ask the FMU where it is.
    fmi2Real last = kNaN;
    const fmi2Status status = call(&inst, format("[resync] fmi2GetRealStatus(%s, fmi2LastSuccessfulTime)", component_text(&inst).c_str()),
                                   [&] { return api.getRealStatus(inst.component, fmi2LastSuccessfulTime, &last); });
    if (status == fmi2OK) inst.time = last, inst.phase = Phase::step_complete;
}

void do_fmu_state(Sequence& s, Instance* inst, Function f) {
    Random& r = s.random;
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    const std::string c = component_text(inst);
    // Only states this instance handed out, or NULL: never a dangling pointer.
    const bool have_state = inst != nullptr && !inst->states.empty() && r.chance(0.85);
    const size_t state_index = have_state ? static_cast<size_t>(r.integer(0, static_cast<long long>(inst->states.size()) - 1)) : 0;
    fmi2FMUstate state = have_state ? inst->states[state_index].pointer : nullptr;
    switch (f) {
        case F_GetFMUstate: {
            // The standard lets the master hand back one of its states to be overwritten.
            const bool reuse = have_state && r.chance(0.3);
            fmi2FMUstate fresh = reuse ? state : nullptr;
            const bool null_pointer = r.chance(0.08);
            const fmi2Status status =
                call(inst, format("fmi2GetFMUstate(%s, %s)", c.c_str(), null_pointer ? "NULL" : reuse ? "&own state (reuse)" : "&NULL"),
                     [&] { return api.getFMUstate(component, null_pointer ? nullptr : &fresh); });
            if (inst == nullptr || null_pointer) break;
            if (status <= fmi2Warning) {
                FUZZ_CHECK(fresh != nullptr, "fmi2GetFMUstate succeeded without a state", "");
                if (reuse) inst->states[state_index] = SavedState{fresh, snapshot_of(*inst)};
                else if (fresh != nullptr) inst->states.push_back(SavedState{fresh, snapshot_of(*inst)});
            } else if (reuse) {
                FUZZ_CHECK(fresh == state, "a refused fmi2GetFMUstate changed the state pointer handed in", "");
            }
            break;
        }
        case F_SetFMUstate: {
            const fmi2Status status = call(inst, format("fmi2SetFMUstate(%s, %s)", c.c_str(), have_state ? "own state" : "NULL"),
                                           [&] { return api.setFMUstate(component, state); });
            if (inst != nullptr && have_state && status <= fmi2Warning) restored(*inst, inst->states[state_index].snapshot);
            if (inst != nullptr && have_state && status == fmi2Error) inst->phase = Phase::error;
            break;
        }
        case F_FreeFMUstate: {
            fmi2FMUstate copy = state;
            const bool null_pointer = r.chance(0.1);
            const fmi2Status status =
                call(inst, format("fmi2FreeFMUstate(%s, %s)", c.c_str(), null_pointer ? "NULL" : have_state ? "&own state" : "&NULL"),
                     [&] { return api.freeFMUstate(component, null_pointer ? nullptr : &copy); });
            if (have_state && !null_pointer && status <= fmi2Warning) {
                FUZZ_CHECK(copy == nullptr, "fmi2FreeFMUstate succeeded but did not set the state to NULL", "");
                inst->states.erase(inst->states.begin() + static_cast<long>(state_index));
            }
            break;
        }
        case F_SerializedFMUstateSize: {
            size_t size = 12345;
            const bool null_size = r.chance(0.1);
            call(inst, format("fmi2SerializedFMUstateSize(%s, %s, %s)", c.c_str(), have_state ? "own state" : "NULL",
                              null_size ? "NULL" : "&size"),
                 [&] { return api.serializedFMUstateSize(component, state, null_size ? nullptr : &size); });
            break;
        }
        case F_SerializeFMUstate: {
            size_t needed = 0;
            if (have_state) {
                const fmi2Status status = call(inst, format("fmi2SerializedFMUstateSize(%s, own state, &size)", c.c_str()),
                                               [&] { return api.serializedFMUstateSize(component, state, &needed); });
                if (status > fmi2Warning) needed = 16;
            } else {
                needed = static_cast<size_t>(r.integer(0, 64));
            }
            if (needed > (1u << 24)) needed = 1u << 24;  // a sane buffer; the FMU is told its true length
            size_t size = needed;
            const double u = r.uniform(0.0, 1.0);
            if (u < 0.1) size = needed > 0 ? needed - 1 : 0;
            else if (u < 0.15) size = 0;
            else if (u < 0.25) size = needed + static_cast<size_t>(r.integer(1, 100));
            // 64 guard bytes after the size passed: the FMU must not write past it.
            std::vector<fmi2Byte> buffer(size + 64, static_cast<fmi2Byte>(0xA5));
            const bool null_buffer = r.chance(0.08);
            const fmi2Status status =
                call(inst, format("fmi2SerializeFMUstate(%s, %s, %s, size=%zu of %zu needed)", c.c_str(), have_state ? "own state" : "NULL",
                                  null_buffer ? "NULL" : "buffer", size, needed),
                     [&] { return api.serializeFMUstate(component, state, null_buffer ? nullptr : buffer.data(), size); });
            bool guard_intact = true;
            for (size_t k = size; k < buffer.size(); ++k) guard_intact = guard_intact && buffer[k] == static_cast<fmi2Byte>(0xA5);
            FUZZ_CHECK(guard_intact, "fmi2SerializeFMUstate wrote past the size it was given", format("size %zu", size));
            if (inst != nullptr && status <= fmi2Warning && have_state && !null_buffer) {
                FUZZ_CHECK(size >= needed, "fmi2SerializeFMUstate accepted a buffer below fmi2SerializedFMUstateSize",
                           format("%zu < %zu", size, needed));
                buffer.resize(needed);
                s.serialized.push_back(SerializedState{buffer, inst->states[state_index].snapshot});
            }
            break;
        }
        case F_DeSerializeFMUstate: {
            std::vector<fmi2Byte> bytes;
            std::string what;
            Snapshot snapshot;
            snapshot.known = false;
            if (!s.serialized.empty() && r.chance(0.7)) {
                const SerializedState& source = r.pick(s.serialized);
                bytes = source.bytes;
                snapshot = source.snapshot;
                what = "serialized state";
                const double u = r.uniform(0.0, 1.0);
                if (u < 0.1 && !bytes.empty()) {
                    // Altered bytes: the standard does not promise detection, but the FMU must not crash.
                    const size_t k = static_cast<size_t>(r.integer(0, static_cast<long long>(bytes.size()) - 1));
                    bytes[k] = static_cast<fmi2Byte>(bytes[k] ^ (1 << r.integer(0, 7)));
                    what = format("serialized state with bit flipped in byte %zu", k);
                    snapshot.known = false;
                } else if (u < 0.2 && !bytes.empty()) {
                    bytes.pop_back();
                    what = "truncated serialized state";
                } else if (u < 0.25) {
                    bytes.push_back(0);
                    what = "serialized state with an extra byte";
                }
            } else {
                bytes.resize(static_cast<size_t>(r.integer(0, 256)));
                for (fmi2Byte& b : bytes) b = static_cast<fmi2Byte>(r.integer(0, 255));
                what = "random bytes";
            }
            const bool null_bytes = r.chance(0.08);
            const size_t size = null_bytes ? static_cast<size_t>(r.integer(0, 1)) * 8 : bytes.size();
            const bool null_state = r.chance(0.08);
            fmi2FMUstate result = nullptr;
            const fmi2Status status = call(
                inst, format("fmi2DeSerializeFMUstate(%s, %s, size=%zu, %s)", c.c_str(), null_bytes ? "NULL" : what.c_str(), size,
                             null_state ? "NULL" : "&state"),
                [&] { return api.deSerializeFMUstate(component, null_bytes ? nullptr : bytes.data(), size, null_state ? nullptr : &result); });
            if (inst != nullptr && status <= fmi2Warning && !null_state && result != nullptr)
                inst->states.push_back(SavedState{result, snapshot});
            break;
        }
        default: break;
    }
}

void do_derivatives(Sequence& s, Instance* inst, Function f) {
    Random& r = s.random;
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    const std::string c = component_text(inst);
    const size_t n = static_cast<size_t>(r.integer(0, 3));
    std::vector<fmi2ValueReference> vr(n + 1), vr2(n + 1);
    std::vector<fmi2Real> a(n + 1, 1.0), b(n + 1, 0.0);
    std::vector<fmi2Integer> order(n + 1, 1);
    for (size_t i = 0; i < n; ++i) {
        const Variable* unknown = pick_variable(r, r.chance(0.5) ? model.real_outputs : model.real_inputs);
        const Variable* known = r.chance(0.8) ? pick_variable(r, model.real_inputs) : nullptr;
        vr[i] = unknown != nullptr ? unknown->vr : invalid_vr(r, model.max_vr[0]);
        vr2[i] = known != nullptr ? known->vr : invalid_vr(r, model.max_vr[0]);
        a[i] = chaos_value(r, nullptr);
        order[i] = static_cast<fmi2Integer>(r.pick(std::vector<long long>{0, 1, 2, -1, INT_MAX}));
    }
    const bool nulls = r.chance(0.2);
    switch (f) {
        case F_GetDirectionalDerivative:
            call(inst, format("fmi2GetDirectionalDerivative(%s, nUnknown=%zu, nKnown=%zu, arrays=%s)", c.c_str(), n, n, nulls ? "NULL" : "valid"),
                 [&] {
                     return nulls ? api.getDirectionalDerivative(component, nullptr, n, nullptr, n, nullptr, nullptr)
                                  : api.getDirectionalDerivative(component, vr.data(), n, vr2.data(), n, a.data(), b.data());
                 });
            break;
        case F_SetRealInputDerivatives:
            call(inst, format("fmi2SetRealInputDerivatives(%s, vr=%s, n=%zu, arrays=%s)", c.c_str(), vr_list_text(vr2.data(), n).c_str(), n,
                              nulls ? "NULL" : "valid"),
                 [&] {
                     return nulls ? api.setRealInputDerivatives(component, nullptr, n, nullptr, nullptr)
                                  : api.setRealInputDerivatives(component, vr2.data(), n, order.data(), a.data());
                 });
            break;
        case F_GetRealOutputDerivatives:
            call(inst, format("fmi2GetRealOutputDerivatives(%s, vr=%s, n=%zu, arrays=%s)", c.c_str(), vr_list_text(vr.data(), n).c_str(), n,
                              nulls ? "NULL" : "valid"),
                 [&] {
                     return nulls ? api.getRealOutputDerivatives(component, nullptr, n, nullptr, nullptr)
                                  : api.getRealOutputDerivatives(component, vr.data(), n, order.data(), b.data());
                 });
            break;
        default: break;
    }
}

void do_status(Sequence& s, Instance* inst, Function f) {
    Random& r = s.random;
    fmi2Component component = inst != nullptr ? inst->component : nullptr;
    const std::string c = component_text(inst);
    const int kind = static_cast<int>(r.chance(0.85) ? r.integer(0, 3) : r.pick(std::vector<long long>{-1, 4, 99, INT_MIN}));
    const bool null_value = r.chance(0.1);
    const char* v = null_value ? "NULL" : "&value";
    switch (f) {
        case F_GetStatus: {
            fmi2Status value = static_cast<fmi2Status>(77);
            const fmi2Status st = call(inst, format("fmi2GetStatus(%s, kind=%d, %s)", c.c_str(), kind, v),
                                       [&] { return api.getStatus(component, static_cast<fmi2StatusKind>(kind), null_value ? nullptr : &value); });
            if (st == fmi2OK && !null_value)
                FUZZ_CHECK(value >= fmi2OK && value <= fmi2Pending, "fmi2GetStatus returned a value outside fmi2Status",
                           format("%d", static_cast<int>(value)));
            break;
        }
        case F_GetRealStatus: {
            fmi2Real value = kNaN;
            const fmi2Status st = call(inst, format("fmi2GetRealStatus(%s, kind=%d, %s)", c.c_str(), kind, v),
                                       [&] { return api.getRealStatus(component, static_cast<fmi2StatusKind>(kind), null_value ? nullptr : &value); });
            if (st == fmi2OK && !null_value)
                FUZZ_CHECK(std::isfinite(value), "fmi2GetRealStatus returned a non-finite time", real_text(value));
            break;
        }
        case F_GetIntegerStatus: {
            fmi2Integer value = 0;
            call(inst, format("fmi2GetIntegerStatus(%s, kind=%d, %s)", c.c_str(), kind, v),
                 [&] { return api.getIntegerStatus(component, static_cast<fmi2StatusKind>(kind), null_value ? nullptr : &value); });
            break;
        }
        case F_GetBooleanStatus: {
            fmi2Boolean value = 0;
            call(inst, format("fmi2GetBooleanStatus(%s, kind=%d, %s)", c.c_str(), kind, v),
                 [&] { return api.getBooleanStatus(component, static_cast<fmi2StatusKind>(kind), null_value ? nullptr : &value); });
            break;
        }
        case F_GetStringStatus: {
            fmi2String value = nullptr;
            const fmi2Status st = call(inst, format("fmi2GetStringStatus(%s, kind=%d, %s)", c.c_str(), kind, v),
                                       [&] { return api.getStringStatus(component, static_cast<fmi2StatusKind>(kind), null_value ? nullptr : &value); });
            if (st == fmi2OK && !null_value) FUZZ_CHECK(value != nullptr, "fmi2GetStringStatus returned a NULL string", "");
            break;
        }
        default: break;
    }
}

void do_inquiry(Function f) {
    CallScope scope;
    begin_call(nullptr, f == F_GetVersion ? "fmi2GetVersion()" : "fmi2GetTypesPlatform()");
    scope.captured_before = capture_size();
    scope.start = std::chrono::steady_clock::now();
    const char* text = f == F_GetVersion ? api.getVersion() : api.getTypesPlatform();
    end_call(scope, text != nullptr ? text : "NULL");
    const char* expected = f == F_GetVersion ? "2.0" : fmi2TypesPlatform;
    FUZZ_CHECK(text != nullptr && std::strcmp(text, expected) == 0, "fmi2GetVersion/fmi2GetTypesPlatform value",
               text != nullptr ? text : "NULL");
}

// ---- one call of a sequence

Function pick_chaos_function(Random& r) {
    int total = 0;
    for (int w : kWeights) total += w;
    long long x = r.integer(0, total - 1);
    for (int f = 0; f < F_Count; ++f) {
        if (x < kWeights[f]) return static_cast<Function>(f);
        x -= kWeights[f];
    }
    return F_GetReal;
}

void dispatch(Sequence& s, Function f, Instance* inst, bool valid) {
    switch (f) {
        case F_GetTypesPlatform:
        case F_GetVersion: do_inquiry(f); break;
        case F_SetDebugLogging: do_set_debug_logging(s, inst); break;
        case F_Instantiate: do_instantiate(s, valid); break;
        case F_FreeInstance: break;  // handled by the caller
        case F_SetupExperiment: do_setup_experiment(s, inst, valid); break;
        case F_EnterInitializationMode:
        case F_ExitInitializationMode:
        case F_Terminate:
        case F_Reset:
        case F_CancelStep: do_lifecycle(inst, f); break;
        case F_GetReal: do_get_real(s, inst); break;
        case F_GetInteger: do_set_get_discrete(s, inst, false, true, false); break;
        case F_GetBoolean: do_set_get_discrete(s, inst, false, false, false); break;
        case F_SetInteger: do_set_get_discrete(s, inst, true, true, valid); break;
        case F_SetBoolean: do_set_get_discrete(s, inst, true, false, valid); break;
        case F_GetString: do_string(s, inst, false); break;
        case F_SetString: do_string(s, inst, true); break;
        case F_SetReal: do_set_real(s, inst, valid); break;
        case F_GetFMUstate:
        case F_SetFMUstate:
        case F_FreeFMUstate:
        case F_SerializedFMUstateSize:
        case F_SerializeFMUstate:
        case F_DeSerializeFMUstate: do_fmu_state(s, inst, f); break;
        case F_GetDirectionalDerivative:
        case F_SetRealInputDerivatives:
        case F_GetRealOutputDerivatives: do_derivatives(s, inst, f); break;
        case F_DoStep: do_step(s, inst, valid); break;
        case F_GetStatus:
        case F_GetRealStatus:
        case F_GetIntegerStatus:
        case F_GetBooleanStatus:
        case F_GetStringStatus: do_status(s, inst, f); break;
        default: break;
    }
}

// The next call of a well-behaved master in the instance's phase.
Function progress_function(Random& r, const Instance& inst) {
    switch (inst.phase) {
        case Phase::instantiated: {
            const double u = r.uniform(0.0, 1.0);
            return u < 0.2 ? F_SetupExperiment : u < 0.4 ? F_SetReal : u < 0.5 ? F_SetInteger : u < 0.55 ? F_SetBoolean
                                                                                                 : F_EnterInitializationMode;
        }
        case Phase::initialization: {
            const double u = r.uniform(0.0, 1.0);
            return u < 0.25 ? F_SetReal : u < 0.35 ? F_SetInteger : u < 0.4 ? F_SetBoolean : F_ExitInitializationMode;
        }
        case Phase::step_complete: {
            const double u = r.uniform(0.0, 1.0);
            return u < 0.2 ? F_SetReal : u < 0.8 ? F_DoStep : u < 0.84 ? F_GetReal : u < 0.89 ? F_GetFMUstate
                   : u < 0.94 ? F_SetFMUstate : u < 0.96 ? F_SerializeFMUstate : u < 0.98 ? F_DeSerializeFMUstate : F_Terminate;
        }
        case Phase::step_failed:
        case Phase::terminated:
        case Phase::error:
        default: return r.chance(0.7) ? F_Reset : F_GetStatus;
    }
}

void free_null() {
    CallScope scope;
    begin_call(nullptr, "fmi2FreeInstance(NULL)");
    scope.captured_before = capture_size();
    scope.start = std::chrono::steady_clock::now();
    api.freeInstance(nullptr);
    end_call(scope, "(void)");
    FUZZ_CHECK(g_call.messages == 0, "a call with a NULL component logged through some logger", "");
}

void one_call(Sequence& s) {
    Random& r = s.random;
    if (s.live.empty()) {
        // Nothing to call on: instantiate (mostly validly), or call something with a NULL component.
        if (r.chance(0.85)) do_instantiate(s, r.chance(0.8));
        else {
            const Function f = pick_chaos_function(r);
            if (f == F_Instantiate) do_instantiate(s, false);
            else if (f == F_FreeInstance) free_null();
            else dispatch(s, f, nullptr, false);
        }
        return;
    }
    Instance* inst = s.live[static_cast<size_t>(r.integer(0, static_cast<long long>(s.live.size()) - 1))].get();
    if (!r.chance(s.chaos)) {
        dispatch(s, progress_function(r, *inst), inst, true);
        return;
    }
    const Function f = pick_chaos_function(r);
    if (f == F_Instantiate) {
        if (s.live.size() < 3) do_instantiate(s, r.chance(0.5));
        return;
    }
    if (f == F_FreeInstance) {
        if (r.chance(0.3)) {
            free_null();
        } else {
            for (size_t k = 0; k < s.live.size(); ++k)
                if (s.live[k].get() == inst) free_instance(s, k);
        }
        return;
    }
    dispatch(s, f, r.chance(0.06) ? nullptr : inst, false);
}

void run_sequence(int index, unsigned long long seed, unsigned timeout_seconds, bool print_trace) {
    g_sequence = index;
    g_trace_length = 0;
    g_call_index = 0;
    g_sequence_failed = false;
    const unsigned long long sequence_seed = seed ^ (0x9E3779B97F4A7C15ull * static_cast<unsigned long long>(index + 1));
    Sequence s(sequence_seed);
    s.chaos = s.random.pick(std::vector<double>{0.05, 0.15, 0.3, 0.6, 1.0});
    const int length = static_cast<int>(s.random.integer(4, 50));
    trace_printf("sequence %d (seed %llu, chaos %.2f, %d calls):\n", index, seed, s.chaos, length);
    alarm(timeout_seconds);
    for (int k = 0; k < length; ++k) one_call(s);
    while (!s.live.empty()) free_instance(s, s.live.size() - 1);  // whatever happened, each instance can be freed
    alarm(0);
    ++stats.sequences;
    if (print_trace || (g_sequence_failed && stats.printed_traces < 5)) {
        if (!print_trace) ++stats.printed_traces;
        std::fwrite(g_trace, 1, g_trace_length, print_trace ? stdout : stderr);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s <fmu.so> <modelDescription.xml> [sequences=3000] [seed] [only_sequence]\n", argv[0]);
        return 2;
    }
    const long sequences = argc > 3 ? std::strtol(argv[3], nullptr, 0) : 3000;
    g_seed = argc > 4 ? std::strtoull(argv[4], nullptr, 0) : 20261122ull;
    const long only = argc > 5 ? std::strtol(argv[5], nullptr, 0) : -1;
    // Seconds per sequence (FUZZ_TIMEOUT overrides): a sequence normally takes milliseconds.
    const unsigned timeout = std::getenv("FUZZ_TIMEOUT") ? static_cast<unsigned>(std::atoi(std::getenv("FUZZ_TIMEOUT"))) : 10u;
    g_verbose = only >= 0;
    g_fp_traps = std::getenv("FUZZ_FP_TRAPS") != nullptr && std::string(std::getenv("FUZZ_FP_TRAPS")) == "1";

    if (!read_model(argv[2], model)) {
        std::fprintf(stderr, "fuzz_fmi_calls: cannot read the GUID and variables from %s\n", argv[2]);
        return 2;
    }
    void* handle = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
        std::fprintf(stderr, "fuzz_fmi_calls: dlopen(%s) failed: %s\n", argv[1], dlerror());
        return 2;
    }
    if (!load_api(handle)) return 2;

    // fds 1 and 2 go to this file during every FMU call: anything in it is output of the FMU.
    std::FILE* capture = std::tmpfile();
    g_capture_fd = capture != nullptr ? fileno(capture) : -1;
    g_saved_stdout = dup(1);
    g_saved_stderr = dup(2);
    if (g_capture_fd < 0 || g_saved_stdout < 0 || g_saved_stderr < 0) {
        std::fprintf(stderr, "fuzz_fmi_calls: cannot set up the stdout/stderr capture\n");
        return 2;
    }
    install_signal_handlers();

    std::printf("fuzz_fmi_calls: seed %llu, %ld sequences, %zu Real (%zu parameters, %zu inputs, %zu outputs), %zu Integer, %zu Boolean variables\n",
                g_seed, sequences, model.real_all.size(), model.real_parameters.size(), model.real_inputs.size(),
                model.real_outputs.size(), model.integer_all.size(), model.boolean_all.size());
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    // FUZZ_SKIP="969,1234": sequences not to run, to look past a known crash or hang (reported in the summary).
    std::vector<long> skip;
    if (const char* list = std::getenv("FUZZ_SKIP")) {
        for (const char* p = list; *p != '\0';) {
            char* end = nullptr;
            const long k = std::strtol(p, &end, 10);
            if (end == p) break;
            skip.push_back(k);
            p = *end == ',' ? end + 1 : end;
        }
    }
    for (long index = 0; index < sequences; ++index) {
        if (only >= 0 && index != only) continue;
        if (std::find(skip.begin(), skip.end(), index) != skip.end()) {
            std::printf("fuzz_fmi_calls: sequence %ld skipped (FUZZ_SKIP)\n", index);
            continue;
        }
        run_sequence(static_cast<int>(index), g_seed, timeout, only >= 0);
    }
    const double elapsed = seconds_since(start);
    g_sequence = -1;
    CHECK(g_messages_outside_calls == 0);

    std::printf("fuzz_fmi_calls: %.2f s; statuses OK/Warning/Discard/Error/Fatal = %lld/%lld/%lld/%lld/%lld; %lld instances, "
                "%lld initializations, %lld successful steps, %lld discarded steps, %lld NULL-component calls, %lld log messages; "
                "%lld calls > 0.1 s, %lld > 1 s, slowest %.3f s (sequence %lld: %s)\n",
                elapsed, stats.by_status[0], stats.by_status[1], stats.by_status[2], stats.by_status[3], stats.by_status[4],
                stats.instances, stats.successful_initializations, stats.successful_steps, stats.discarded_steps,
                stats.null_component_calls, g_total_messages, stats.slow_calls, stats.very_slow_calls, stats.slowest_call, stats.slowest_call_sequence,
                stats.slowest_call_description.c_str());
    for (const auto& kind : stats.failure_kinds)
        std::fprintf(stderr, "fuzz_fmi_calls: %lld x %s\n", kind.second, kind.first.c_str());
    dlclose(handle);
    const std::string suite = format("fuzz_fmi_calls: %lld sequences, %lld calls, %lld refusals", stats.sequences, stats.calls,
                                     stats.refusals);
    return check_report(suite.c_str());
}
