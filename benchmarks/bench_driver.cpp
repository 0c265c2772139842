// gimbal_bench: native benchmark driver for the Gimbal2Axis FMU (issue 6).
//
// Loads the FMU's shared object with dlopen and runs a ship-stabilization master loop without
// Python: a sea-state base motion (analytic sums of sinusoids, exact rates and accelerations), a
// PD line-of-sight controller with payload-gyro rate feedback and the seed's one-step delay, and a
// fixed communication step. Reports wall and CPU time, doStep calls, the real-time factor, the
// FMU's solver counters, and the heap allocations made inside fmi2DoStep (malloc & co. are
// interposed by this executable: the FMU resolves them dynamically, so the definitions below win).
//
// Mode --fmi-overhead: doStep of a model at rest (fixed base, g = 0, zero voltage) with a tiny step,
// many calls: nanoseconds per doStep and the instance's heap memory.
//
// Run `gimbal_bench --help` for the options.
#include <dlfcn.h>
#include <execinfo.h>
#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fmi2Functions.h"
#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/set_points.h"
#include "gimbal_kernel/sum_of_sines.h"

// ------------------------------------------------------------------------------------------------
// Heap allocation counting (interposition of the C allocator)
// ------------------------------------------------------------------------------------------------
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void __libc_free(void*);
void* __libc_memalign(size_t, size_t);
}

namespace {

struct AllocCounters {
    uint64_t allocations = 0;  // malloc, calloc, realloc (to a new or grown block), memalign family
    uint64_t frees = 0;
    uint64_t bytes = 0;        // requested bytes
    int64_t live = 0;          // usable bytes currently held (malloc_usable_size)
};

AllocCounters g_alloc;
bool g_trace = false;      // capture call sites of allocations (only inside the measured doStep calls)
bool g_in_trace = false;   // re-entrancy guard while backtrace() runs

constexpr int kMaxFrames = 24;
constexpr int kMaxSites = 16;
struct Site {
    void* frames[kMaxFrames];
    int depth = 0;
    uint64_t count = 0;
    uint64_t bytes = 0;
    double first_time = 0.0;  // communication point of the first occurrence
};
Site g_sites[kMaxSites];
int g_site_count = 0;
uint64_t g_sites_dropped = 0;
uint64_t g_traced = 0;                 // allocations whose call site was recorded
constexpr uint64_t kMaxTraced = 256;   // then only count: backtrace() would distort the timing
double g_current_time = 0.0;

void record_site(size_t n) {
    if (g_in_trace) return;
    if (g_traced >= kMaxTraced) {
        g_sites_dropped++;
        return;
    }
    g_traced++;
    g_in_trace = true;
    void* frames[kMaxFrames];
    const int depth = backtrace(frames, kMaxFrames);
    // frames[0] is record_site, frames[1] the interposed allocator: skip them.
    const int skip = 2;
    int found = -1;
    for (int s = 0; s < g_site_count && found < 0; ++s) {
        if (g_sites[s].depth != depth - skip) continue;
        if (std::memcmp(g_sites[s].frames, frames + skip, sizeof(void*) * (depth - skip)) == 0) found = s;
    }
    if (found < 0 && g_site_count < kMaxSites) {
        found = g_site_count++;
        Site& site = g_sites[found];
        site.depth = std::max(0, depth - skip);
        std::memcpy(site.frames, frames + skip, sizeof(void*) * site.depth);
        site.first_time = g_current_time;
    }
    if (found >= 0) {
        g_sites[found].count++;
        g_sites[found].bytes += n;
    } else {
        g_sites_dropped++;
    }
    g_in_trace = false;
}

inline void note_alloc(void* p, size_t n) {
    if (p == nullptr) return;
    g_alloc.allocations++;
    g_alloc.bytes += n;
    g_alloc.live += static_cast<int64_t>(malloc_usable_size(p));
    if (g_trace) record_site(n);
}

inline void note_free(void* p) {
    if (p == nullptr) return;
    g_alloc.frees++;
    g_alloc.live -= static_cast<int64_t>(malloc_usable_size(p));
}

}  // namespace

extern "C" {
void* malloc(size_t n) {
    void* p = __libc_malloc(n);
    note_alloc(p, n);
    return p;
}
void* calloc(size_t count, size_t n) {
    void* p = __libc_calloc(count, n);
    note_alloc(p, count * n);
    return p;
}
void* realloc(void* old, size_t n) {
    if (old == nullptr) return malloc(n);
    if (n == 0) {
        free(old);
        return nullptr;
    }
    const int64_t old_size = static_cast<int64_t>(malloc_usable_size(old));
    void* p = __libc_realloc(old, n);
    if (p != nullptr) {
        g_alloc.live += static_cast<int64_t>(malloc_usable_size(p)) - old_size;
        g_alloc.allocations++;  // a realloc counts as an allocation (it may move the block)
        g_alloc.bytes += n;
        if (g_trace) record_site(n);
    }
    return p;
}
void free(void* p) {
    note_free(p);
    __libc_free(p);
}
void* memalign(size_t alignment, size_t n) {
    void* p = __libc_memalign(alignment, n);
    note_alloc(p, n);
    return p;
}
void* aligned_alloc(size_t alignment, size_t n) { return memalign(alignment, n); }
int posix_memalign(void** out, size_t alignment, size_t n) {
    void* p = memalign(alignment, n);
    if (p == nullptr) return ENOMEM;
    *out = p;
    return 0;
}
void* valloc(size_t n) { return memalign(4096, n); }
}

// ------------------------------------------------------------------------------------------------
// Utilities
// ------------------------------------------------------------------------------------------------
namespace {

[[noreturn]] void die(const std::string& message) {
    std::fprintf(stderr, "gimbal_bench: %s\n", message.c_str());
    std::exit(2);
}

double clock_seconds(clockid_t id) {
    timespec ts;
    clock_gettime(id, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// splitmix64: a portable, seeded generator (the same phases on every platform and compiler).
struct Random {
    uint64_t state;
    explicit Random(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    double uniform() { return (next() >> 11) * 0x1.0p-53; }
};

// ------------------------------------------------------------------------------------------------
// modelDescription.xml: GUID and name -> (type, value reference)
// ------------------------------------------------------------------------------------------------
struct VariableRef {
    char type = '?';  // 'R', 'I', 'B', 'S'
    fmi2ValueReference vr = 0;
};

struct ModelDescription {
    std::string guid;
    std::string model_identifier;
    std::map<std::string, VariableRef> variables;

    static std::string attribute(const std::string& text, size_t from, size_t to, const char* name) {
        const std::string key = std::string(" ") + name + "=\"";
        size_t p = text.find(key, from);
        if (p == std::string::npos || p > to) {
            const std::string key2 = std::string("\n") + name + "=\"";
            p = text.find(key2, from);
            if (p == std::string::npos || p > to) return "";
        }
        p = text.find('"', p) + 1;
        const size_t q = text.find('"', p);
        return text.substr(p, q - p);
    }

    void load(const std::string& path) {
        std::ifstream in(path);
        if (!in) die("cannot read " + path + " (give --model-description)");
        std::stringstream buffer;
        buffer << in.rdbuf();
        const std::string text = buffer.str();
        const size_t root = text.find("<fmiModelDescription");
        if (root == std::string::npos) die(path + " is not an FMI model description");
        guid = attribute(text, root, text.find('>', root), "guid");
        const size_t cs = text.find("<CoSimulation");
        if (cs != std::string::npos) model_identifier = attribute(text, cs, text.find('>', cs), "modelIdentifier");
        size_t pos = 0;
        while ((pos = text.find("<ScalarVariable", pos)) != std::string::npos) {
            const size_t end_tag = text.find('>', pos);
            const size_t close = text.find("</ScalarVariable>", pos);
            const std::string name = attribute(text, pos, end_tag, "name");
            const std::string vr = attribute(text, pos, end_tag, "valueReference");
            VariableRef ref;
            ref.vr = static_cast<fmi2ValueReference>(std::strtoul(vr.c_str(), nullptr, 10));
            const std::string body = text.substr(end_tag, close - end_tag);
            if (body.find("<Real") != std::string::npos) ref.type = 'R';
            else if (body.find("<Integer") != std::string::npos || body.find("<Enumeration") != std::string::npos)
                ref.type = 'I';  // an FMI 2.0 Enumeration is set and read with fmi2SetInteger/fmi2GetInteger
            else if (body.find("<Boolean") != std::string::npos) ref.type = 'B';
            else if (body.find("<String") != std::string::npos) ref.type = 'S';
            variables[name] = ref;
            pos = close == std::string::npos ? end_tag : close;
        }
        if (guid.empty() || variables.empty()) die(path + ": no guid or no variables found");
    }

    bool has(const std::string& name) const { return variables.count(name) != 0; }
    fmi2ValueReference vr(const std::string& name, char type) const {
        const auto it = variables.find(name);
        if (it == variables.end()) die("the FMU has no variable '" + name + "'");
        if (it->second.type != type)
            die("variable '" + name + "' is of type " + it->second.type + ", expected " + type);
        return it->second.vr;
    }
};

// ------------------------------------------------------------------------------------------------
// The FMU's functions
// ------------------------------------------------------------------------------------------------
struct Fmi2 {
    void* handle = nullptr;
    fmi2InstantiateTYPE* instantiate;
    fmi2FreeInstanceTYPE* free_instance;
    fmi2SetupExperimentTYPE* setup_experiment;
    fmi2EnterInitializationModeTYPE* enter_initialization_mode;
    fmi2ExitInitializationModeTYPE* exit_initialization_mode;
    fmi2TerminateTYPE* terminate;
    fmi2SetRealTYPE* set_real;
    fmi2GetRealTYPE* get_real;
    fmi2SetIntegerTYPE* set_integer;
    fmi2GetIntegerTYPE* get_integer;
    fmi2SetBooleanTYPE* set_boolean;
    fmi2DoStepTYPE* do_step;

    template <typename T>
    void bind(T*& function, const char* name) {
        function = reinterpret_cast<T*>(dlsym(handle, name));
        if (function == nullptr) die(std::string("the FMU does not export ") + name);
    }

    void load(const std::string& path) {
        handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (handle == nullptr) die(std::string("dlopen failed: ") + dlerror());
        bind(instantiate, "fmi2Instantiate");
        bind(free_instance, "fmi2FreeInstance");
        bind(setup_experiment, "fmi2SetupExperiment");
        bind(enter_initialization_mode, "fmi2EnterInitializationMode");
        bind(exit_initialization_mode, "fmi2ExitInitializationMode");
        bind(terminate, "fmi2Terminate");
        bind(set_real, "fmi2SetReal");
        bind(get_real, "fmi2GetReal");
        bind(set_integer, "fmi2SetInteger");
        bind(get_integer, "fmi2GetInteger");
        bind(set_boolean, "fmi2SetBoolean");
        bind(do_step, "fmi2DoStep");
    }
};

int g_log_count = 0;
void fmu_logger(fmi2ComponentEnvironment, fmi2String instance, fmi2Status status, fmi2String category,
                fmi2String message, ...) {
    if (++g_log_count > 20) return;  // a flood of warnings would distort the timing
    std::fprintf(stderr, "[%s] %s (status %d): %s\n", instance ? instance : "?", category ? category : "?",
                 static_cast<int>(status), message ? message : "");
}

void check(fmi2Status status, const char* what) {
    if (status > fmi2Warning) die(std::string(what) + " failed with status " + std::to_string(status));
}

// ------------------------------------------------------------------------------------------------
// Sea-state base motion: per axis q(t) = sum_i A_i sin(w_i t + phi_i), rates and accelerations
// exact. The sums are the C kernel's (c_kernel/include/gimbal_kernel/sum_of_sines.h), the scene runner's: rows
// are evaluated a block at a time, when the step reaches the next block.
// ------------------------------------------------------------------------------------------------
struct SeaState {
    static constexpr int kTerms = 10;
    static constexpr int kAxes = 4;  // pitch delta, yaw psi, roll gamma, heave z
    static constexpr long kBlock = GIMBAL_SUM_OF_SINES_BLOCK;
    double amplitude[kAxes][kTerms], omega[kAxes][kTerms], phase[kAxes][kTerms];
    double weights[kAxes][3 * kTerms];
    double rotation[kAxes][2 * kBlock * kTerms];
    double value[kAxes][kBlock], rate[kAxes][kBlock], acceleration[kAxes][kBlock];
    double h = 1e-3;
    long k = 0;
    long block_first = -1;  // the first row of the block in value, rate, acceleration (-1: none yet)

    // Significant amplitudes (2 sigma) [rad, rad, rad, m] and a JONSWAP-like spectrum about the
    // peak period: a moderate sea, the ship heading into it.
    void setup(uint64_t seed, double step) {
        h = step;
        Random rng(seed);
        const double significant[kAxes] = {3.0 * M_PI / 180.0, 1.5 * M_PI / 180.0, 8.0 * M_PI / 180.0, 1.0};
        const double peak_period[kAxes] = {7.0, 12.0, 9.0, 8.0};
        for (int a = 0; a < kAxes; ++a) {
            const double wp = 2.0 * M_PI / peak_period[a];
            const double lo = 0.5 * wp, hi = 3.0 * wp, dw = (hi - lo) / kTerms;
            double total = 0.0;
            for (int i = 0; i < kTerms; ++i) {
                const double w = omega[a][i] = lo + (i + rng.uniform()) * dw;
                phase[a][i] = 2.0 * M_PI * rng.uniform();
                const double r = wp / w;
                const double shape = std::pow(w, -5.0) * std::exp(-1.25 * r * r * r * r) *
                                     std::pow(3.3, std::exp(-std::pow(w - wp, 2) / (2.0 * 0.08 * 0.08 * wp * wp)));
                amplitude[a][i] = shape * dw;  // variance share, normalized below
                total += amplitude[a][i];
            }
            const double sigma = significant[a] / 2.0;
            for (int i = 0; i < kTerms; ++i) amplitude[a][i] = std::sqrt(2.0 * amplitude[a][i] / total) * sigma;
            gimbal_sum_of_sines_weights(kTerms, amplitude[a], omega[a], weights[a]);
            gimbal_sum_of_sines_rotation(h, kTerms, omega[a], rotation[a]);
        }
        reset(0);
    }

    void reset(long step_index) { k = step_index; }
    void advance() { ++k; }

    // The 15 base inputs at t_k in the order delta, psi, gamma, *_dot, *_ddot, v_a[1..3], a_a[1..3].
    void inputs(double out[15]) {
        const long first = k - k % kBlock;
        if (first != block_first) {
            for (int a = 0; a < kAxes; ++a)
                gimbal_sum_of_sines_rows(first, kBlock, 0.0, h, kTerms, omega[a], phase[a], weights[a], rotation[a],
                                         value[a], rate[a], acceleration[a]);
            block_first = first;
        }
        const long m = k - first;
        for (int a = 0; a < 3; ++a) {
            out[a] = value[a][m];
            out[3 + a] = rate[a][m];
            out[6 + a] = acceleration[a][m];
        }
        out[9] = 0.0;
        out[10] = 0.0;
        out[11] = rate[3][m];  // heave velocity of point a
        out[12] = 0.0;
        out[13] = 0.0;
        out[14] = acceleration[3][m];
    }
};

// ------------------------------------------------------------------------------------------------
// Line of sight: inverse kinematics of a fixed inertial target, the kernel's (set_points.h, which
// the scene runner and the controller FMU use), alpha in the turn nearest alpha_near.
// ------------------------------------------------------------------------------------------------
void gimbal_angles_for(const double target[3], double delta, double psi, double gamma, double alpha_near,
                       double& alpha, double& beta) {
    const double attitude[3] = {delta, psi, gamma};
    double angles[2];
    gimbal_target_angles(target, attitude, angles);
    alpha = gimbal_angle_nearest_turn(angles[0], alpha_near);
    beta = angles[1];
}

// PD on each axis about the IK set points, with the payload gyro as the rate signal: the kernel's
// PID (c_kernel/include/gimbal_kernel/controllers.h, the scene runner's) with kp and k_gyro only. Its rates:
// elevation = los.omega[1], azimuth = los.omega[3] / cos(beta) (secant correction).
struct Controller {
    static constexpr double kp[2] = {300.0, 640.0};  // V/rad
    static constexpr double kd[2] = {6.0, 12.0};     // V.s/rad, on the gyro rates
    double target[3];
    GimbalController pid;

    // Gains, the voltage limits (the motors' U_L: the output saturates there) and a state at rest.
    void setup(const double u_limit[2]) {
        std::memset(&pid, 0, sizeof pid);
        pid.kind = gimbal_controller_kind("pid");
        for (int i = 0; i < 2; ++i) {
            pid.u_limit[i] = u_limit[i];
            GimbalAxisPid& axis = pid.axis[i];
            axis.kp = kp[i];
            axis.k_gyro = kd[i];
            axis.u_limit = axis.i_limit = u_limit[i];
        }
    }

    void compute(long k, double h, double alpha, double beta, const double gyro[3], const double base[15], double u[2]) {
        double set_point[4] = {0.0, 0.0, 0.0, 0.0}, reference[2];
        gimbal_angles_for(target, base[0], base[1], base[2], alpha, set_point[0], set_point[1]);
        const double measured[5] = {alpha, beta, gyro[0], gyro[1], gyro[2]};
        gimbal_controller_step(&pid, k, h, measured, set_point, u, reference);
    }
};

// ------------------------------------------------------------------------------------------------
// Options
// ------------------------------------------------------------------------------------------------
struct Options {
    std::string fmu;
    std::string model_description;
    double duration = 10.0;
    double step = 1e-3;
    double rtol = NAN;
    double atol = NAN;
    int method = -1;  // -1: the FMU's default (solver.method not set)
    std::string fidelity = "full";
    std::string trajectory;
    bool json = false;
    bool fmi_overhead = false;
    long overhead_steps = 1000000;
    double overhead_step = 1e-6;
    uint64_t seed = 1;
    bool trace_allocations = true;
    bool time_dostep = false;

    double target_azimuth_deg = 30.0;
    double target_elevation_deg = 20.0;
    std::vector<std::pair<std::string, double>> real_parameters;  // --set NAME=VALUE
};

void usage() {
    std::puts(
        "usage: gimbal_bench --fmu PATH/Gimbal2Axis.so [options]\n"
        "  --fmu PATH               the FMU's shared object (binaries/linux64/Gimbal2Axis.so of an unpacked FMU)\n"
        "  --model-description P    modelDescription.xml (default: ../../modelDescription.xml from the .so)\n"
        "  --duration T             simulated time [s] (default 10)\n"
        "  --step H                 communication step [s] (default 1e-3)\n"
        "  --rtol R, --atol A       solver.rtol, solver.atol (default: the FMU's)\n"
        "  --method M               solver.method (an Enumeration, set as an integer): 4 automatic (the FMU's\n"
        "                           default), 5 Dormand-Prince, 6 RODAS4; SUNDIALS: 0 CVODE BDF analytic Jacobian,\n"
        "                           1 CVODE BDF finite-difference Jacobian, 2 CVODE Adams, 3 ARKODE explicit RK\n"
        "  --fidelity full|reduced  reduced: rigid gears (gear*.model = 0), quasi-static motors (motor*.model = 0)\n"
        "  --set NAME=VALUE         a Real parameter, e.g. --set motor1.L=1e-7 (repeatable): the stiff variants\n"
        "  --trajectory FILE        write t, alpha, beta, los.omega[1..3] at every communication point\n"
        "                           (FILE.csv: CSV with a header; otherwise raw little-endian float64, 6 per row)\n"
        "  --seed N                 seed of the sea-state phases and frequencies (default 1)\n"
        "  --json                   print one JSON line instead of the text report\n"
        "  --fmi-overhead           doStep of a model at rest (fixed base, g = 0, 0 V): ns per doStep, memory\n"
        "  --overhead-steps N       doStep calls in --fmi-overhead (default 1000000)\n"
        "  --overhead-step H        step of --fmi-overhead [s] (default 1e-6)\n"
        "  --no-trace               do not record the call sites of allocations inside doStep\n"
        "  --time-dostep            also time each doStep (CLOCK_MONOTONIC and the thread's CPU clock): total, and\n"
        "                           the median, 99th, 99.9th percentile and maximum of single doSteps");
}

// The options by the kind of value they take: a text, a number, an integer, or none (a flag's value).
const std::map<std::string, std::string Options::*> kTextOptions = {
    {"--fmu", &Options::fmu}, {"--model-description", &Options::model_description},
    {"--fidelity", &Options::fidelity}, {"--trajectory", &Options::trajectory}};
const std::map<std::string, double Options::*> kNumberOptions = {
    {"--duration", &Options::duration}, {"--step", &Options::step}, {"--rtol", &Options::rtol},
    {"--atol", &Options::atol}, {"--overhead-step", &Options::overhead_step}};
const std::map<std::string, void (*)(Options&, double)> kIntegerOptions = {
    {"--method", [](Options& o, double v) { o.method = static_cast<int>(v); }},
    {"--seed", [](Options& o, double v) { o.seed = static_cast<uint64_t>(v); }},
    {"--overhead-steps", [](Options& o, double v) { o.overhead_steps = static_cast<long>(v); }}};
const std::map<std::string, std::pair<bool Options::*, bool>> kFlags = {
    {"--json", {&Options::json, true}}, {"--fmi-overhead", {&Options::fmi_overhead, true}},
    {"--no-trace", {&Options::trace_allocations, false}}, {"--time-dostep", {&Options::time_dostep, true}}};

// --set NAME=VALUE: a Real parameter.
void add_real_parameter(Options& o, const std::string& assignment) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0) die("--set expects NAME=VALUE, got " + assignment);
    const std::string text = assignment.substr(equals + 1);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0') die("--set " + assignment + ": not a number");
    o.real_parameters.emplace_back(assignment.substr(0, equals), v);
}

// The checks across options, and the model description's default place beside the shared object.
void complete(Options& o) {
    if (o.fmu.empty()) die("--fmu is required (see --help)");
    if (o.fidelity != "full" && o.fidelity != "reduced") die("--fidelity must be 'full' or 'reduced'");
    if (!(o.step > 0.0) || !(o.duration > 0.0)) die("--step and --duration must be > 0");
    if (o.model_description.empty()) {
        std::string dir = o.fmu.substr(0, o.fmu.find_last_of('/') == std::string::npos ? 0 : o.fmu.find_last_of('/'));
        if (dir.empty()) dir = ".";
        o.model_description = dir + "/../../modelDescription.xml";
    }
}

Options parse(int argc, char** argv) {
    Options o;
    auto value = [&](int& i) -> std::string {
        if (i + 1 >= argc) die(std::string("option ") + argv[i] + " needs a value");
        return argv[++i];
    };
    auto number = [&](int& i) -> double {
        const std::string text = value(i);
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') die(std::string("option ") + argv[i - 1] + ": not a number: " + text);
        return v;
    };
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (const auto text = kTextOptions.find(a); text != kTextOptions.end()) o.*(text->second) = value(i);
        else if (const auto real = kNumberOptions.find(a); real != kNumberOptions.end()) o.*(real->second) = number(i);
        else if (const auto integer = kIntegerOptions.find(a); integer != kIntegerOptions.end()) integer->second(o, number(i));
        else if (const auto flag = kFlags.find(a); flag != kFlags.end()) o.*(flag->second.first) = flag->second.second;
        else if (a == "--set") add_real_parameter(o, value(i));
        else if (a == "--help" || a == "-h") {
            usage();
            std::exit(0);
        } else die("unknown option " + a + " (see --help)");
    }
    complete(o);
    return o;
}

// ------------------------------------------------------------------------------------------------
// Allocation call sites: resolve frames to object + offset, then to function names with addr2line.
// ------------------------------------------------------------------------------------------------
std::string resolve_frame(void* address) {
    Dl_info info;
    if (dladdr(address, &info) == 0 || info.dli_fname == nullptr) {
        char text[64];
        std::snprintf(text, sizeof text, "%p", address);
        return text;
    }
    const uintptr_t offset = reinterpret_cast<uintptr_t>(address) - reinterpret_cast<uintptr_t>(info.dli_fbase);
    // Return addresses point after the call: look up offset - 1.
    char command[4096];
    std::snprintf(command, sizeof command, "addr2line -f -C -e '%s' 0x%lx 2>/dev/null", info.dli_fname,
                  static_cast<unsigned long>(offset - 1));
    std::string function;
    if (FILE* pipe = popen(command, "r")) {
        char line[2048];
        if (std::fgets(line, sizeof line, pipe)) function = line;
        pclose(pipe);
    }
    while (!function.empty() && (function.back() == '\n' || function.back() == '\r')) function.pop_back();
    if (function.empty() || function == "??") function = info.dli_sname ? info.dli_sname : "??";
    const char* base = std::strrchr(info.dli_fname, '/');
    char text[4096];
    std::snprintf(text, sizeof text, "%s+0x%lx %s", base ? base + 1 : info.dli_fname,
                  static_cast<unsigned long>(offset), function.c_str());
    return text;
}

std::string json_escape(const std::string& s) {
    std::string out;
    for (char ch : s) {
        if (ch == '"' || ch == '\\') {
            out += '\\';
            out += ch;
        } else if (ch == '\n') {
            out += "\\n";
        } else if (static_cast<unsigned char>(ch) < 0x20) {
            out += ' ';
        } else {
            out += ch;
        }
    }
    return out;
}

struct Report {
    std::string mode;
    double simulated = 0, wall = 0, cpu = 0, dostep_wall = NAN, master_cpu = NAN;
    // --time-dostep: single doSteps' wall times [s], median, 99th and 99.9th percentile, maximum.
    double dostep_p50 = NAN, dostep_p99 = NAN, dostep_p999 = NAN, dostep_max = NAN;
    // The same in the thread's CPU time (CLOCK_THREAD_CPUTIME_ID): time the thread was descheduled does
    // not count, so what remains of the tail is the FMU's work, interrupts and the caches.
    double dostep_cpu_p50 = NAN, dostep_cpu_p99 = NAN, dostep_cpu_p999 = NAN, dostep_cpu_max = NAN;
    // The median doStep by the mode changes located in it (none, one, more), their counts, and the
    // share of the slowest 0.1 % of doSteps that located at least one.
    double dostep_median_by_events[3] = {NAN, NAN, NAN};
    long dostep_count_by_events[3] = {0, 0, 0};
    double slowest_with_events = NAN;
    // Right-hand sides per doStep: the median, the 99.9th percentile and the maximum (the work, free of
    // the machine's noise), and the median over the slowest 0.1 % of doSteps in wall time.
    double rhs_per_dostep_median = NAN, rhs_per_dostep_p999 = NAN, rhs_per_dostep_max = NAN, rhs_per_slowest_median = NAN;
    long dostep_calls = 0;
    long counters[5] = {-1, -1, -1, -1, -1};  // rhs, jacobian, steps, events, method switches
    uint64_t instance_allocations = 0;
    int64_t instance_bytes = 0;
    uint64_t first_step_allocations = 0;
    uint64_t dostep_allocations = 0;
    uint64_t dostep_alloc_bytes = 0;
    long states = -1;
    std::vector<std::string> sites;  // text per site
    std::string failure;
};

const char* kCounterNames[5] = {"solver.rhs_evaluations", "solver.jacobian_evaluations", "solver.steps", "events.total",
                                "solver.method_switches"};
const char* kCounterKeys[5] = {"rhs_evaluations", "jacobian_evaluations", "solver_steps", "events", "method_switches"};

void collect_sites(Report& report) {
    for (int s = 0; s < g_site_count; ++s) {
        const Site& site = g_sites[s];
        std::ostringstream text;
        text << site.count << " allocations (" << site.bytes << " bytes), first at t = " << site.first_time << ":";
        for (int f = 0; f < site.depth; ++f) {
            const std::string frame = resolve_frame(site.frames[f]);
            text << "\n      #" << f << " " << frame;
            if (frame.find("fmi2DoStep") != std::string::npos) break;  // the rest is the driver
        }
        report.sites.push_back(text.str());
    }
    if (g_sites_dropped > 0)
        report.sites.push_back(std::to_string(g_sites_dropped) + " further allocations not traced (the first " +
                               std::to_string(kMaxTraced) + " were; counts per site above are among those)");
}

// The report as one JSON line (scripts/benchmark.py reads it).
void print_json(const Options& o, const Report& r) {
    const double rtf = r.cpu > 0 ? r.simulated / r.cpu : 0.0;
    auto num = [](double v) {
        char text[32];
        if (std::isnan(v)) return std::string("null");
        std::snprintf(text, sizeof text, "%.6g", v);
        return std::string(text);
    };
    std::printf("{\"mode\": \"%s\", \"fidelity\": \"%s\", \"method\": %s, \"rtol\": %s, \"atol\": %s, "
                "\"step\": %.9g, \"duration\": %.9g, \"simulated\": %.9g, \"wall_s\": %.6g, \"cpu_s\": %.6g, "
                "\"dostep_wall_s\": %s, \"master_cpu_s\": %s, \"dostep_calls\": %ld, \"rtf\": %.6g, "
                "\"cpu_us_per_step\": %.6g, \"states\": %ld",
                r.mode.c_str(), o.fidelity.c_str(), o.method < 0 ? "null" : std::to_string(o.method).c_str(),
                num(o.rtol).c_str(), num(o.atol).c_str(),
                r.mode == "overhead" ? o.overhead_step : o.step, r.simulated, r.simulated, r.wall, r.cpu,
                num(r.dostep_wall).c_str(), num(r.master_cpu).c_str(), r.dostep_calls, rtf, r.dostep_calls ? 1e6 * r.cpu / r.dostep_calls : 0.0, r.states);
    std::printf(", \"dostep_p50_s\": %s, \"dostep_p99_s\": %s, \"dostep_p999_s\": %s, "
                "\"dostep_max_s\": %s", num(r.dostep_p50).c_str(), num(r.dostep_p99).c_str(),
                num(r.dostep_p999).c_str(), num(r.dostep_max).c_str());
    std::printf(", \"dostep_cpu_p50_s\": %s, \"dostep_cpu_p99_s\": %s, \"dostep_cpu_p999_s\": %s, "
                "\"dostep_cpu_max_s\": %s", num(r.dostep_cpu_p50).c_str(), num(r.dostep_cpu_p99).c_str(),
                num(r.dostep_cpu_p999).c_str(), num(r.dostep_cpu_max).c_str());
    std::printf(", \"rhs_per_dostep_median\": %s, \"rhs_per_dostep_p999\": %s, \"rhs_per_dostep_max\": %s",
                num(r.rhs_per_dostep_median).c_str(), num(r.rhs_per_dostep_p999).c_str(),
                num(r.rhs_per_dostep_max).c_str());
    for (int c = 0; c < 5; ++c) std::printf(", \"%s\": %ld", kCounterKeys[c], r.counters[c]);
    std::printf(", \"instance_allocations\": %llu, \"instance_bytes\": %lld, \"first_step_allocations\": %llu, "
                "\"dostep_allocations\": %llu, \"dostep_alloc_bytes\": %llu",
                (unsigned long long)r.instance_allocations, (long long)r.instance_bytes,
                (unsigned long long)r.first_step_allocations, (unsigned long long)r.dostep_allocations,
                (unsigned long long)r.dostep_alloc_bytes);
    if (r.mode == "overhead")
        std::printf(", \"ns_per_dostep\": %.6g, \"wall_ns_per_dostep\": %.6g", 1e9 * r.cpu / r.dostep_calls,
                    1e9 * r.wall / r.dostep_calls);
    std::printf(", \"allocation_sites\": [");
    for (size_t s = 0; s < r.sites.size(); ++s)
        std::printf("%s\"%s\"", s ? ", " : "", json_escape(r.sites[s]).c_str());
    std::printf("], \"failure\": \"%s\"}\n", json_escape(r.failure).c_str());
}

// The report as text, for a person.
void print_text(const Options& o, const Report& r) {
    const double rtf = r.cpu > 0 ? r.simulated / r.cpu : 0.0;
    std::printf("gimbal_bench: %s, fidelity %s, method %s, rtol %s, atol %s\n", r.mode.c_str(), o.fidelity.c_str(),
                o.method < 0 ? "FMU default" : std::to_string(o.method).c_str(),
                std::isnan(o.rtol) ? "default" : std::to_string(o.rtol).c_str(),
                std::isnan(o.atol) ? "default" : std::to_string(o.atol).c_str());
    if (!r.failure.empty()) std::printf("  FAILED: %s\n", r.failure.c_str());
    std::printf("  simulated          %.6g s in %ld doStep calls of %g s (%ld states)\n", r.simulated, r.dostep_calls,
                r.mode == "overhead" ? o.overhead_step : o.step, r.states);
    std::printf("  wall time          %.6g s", r.wall);
    if (!std::isnan(r.dostep_wall)) std::printf(" (inside doStep %.6g s)", r.dostep_wall);
    if (!std::isnan(r.dostep_p50))
        std::printf("\n  single doStep      median %.3g us, p99 %.3g us, p99.9 %.3g us, max %.3g us (wall)",
                    1e6 * r.dostep_p50, 1e6 * r.dostep_p99, 1e6 * r.dostep_p999, 1e6 * r.dostep_max);
    if (!std::isnan(r.dostep_cpu_p50))
        std::printf("\n                     median %.3g us, p99 %.3g us, p99.9 %.3g us, max %.3g us (the thread's CPU time)",
                    1e6 * r.dostep_cpu_p50, 1e6 * r.dostep_cpu_p99, 1e6 * r.dostep_cpu_p999, 1e6 * r.dostep_cpu_max);
    if (!std::isnan(r.slowest_with_events))
        std::printf("\n  by mode changes    none: median %.3g us (%ld doSteps), one: %.3g us (%ld), more: %.3g us (%ld); "
                    "%.0f %% of the slowest 0.1 %% had one or more\n"
                    "  right-hand sides  per doStep: median %.0f, p99.9 %.0f, max %.0f; median %.0f in the slowest 0.1 %% (wall)",
                    1e6 * r.dostep_median_by_events[0], r.dostep_count_by_events[0], 1e6 * r.dostep_median_by_events[1],
                    r.dostep_count_by_events[1], 1e6 * r.dostep_median_by_events[2], r.dostep_count_by_events[2],
                    100.0 * r.slowest_with_events, r.rhs_per_dostep_median, r.rhs_per_dostep_p999, r.rhs_per_dostep_max,
                    r.rhs_per_slowest_median);
    std::printf("\n  CPU time           %.6g s = %.4g us per doStep\n", r.cpu, 1e6 * r.cpu / std::max(1L, r.dostep_calls));
    std::printf("  real-time factor   %.6g (simulated / CPU time)\n", rtf);
    if (!std::isnan(r.master_cpu))
        std::printf("  master's share     %.6g s CPU (same loop without doStep): FMU alone %.4g us per doStep, "
                    "real-time factor %.6g\n",
                    r.master_cpu, 1e6 * (r.cpu - r.master_cpu) / std::max(1L, r.dostep_calls),
                    r.simulated / std::max(1e-12, r.cpu - r.master_cpu));
    for (int c = 0; c < 5; ++c) std::printf("  %-27s %ld\n", kCounterNames[c], r.counters[c]);
    std::printf("  instance memory    %lld bytes in %llu allocations (instantiate + initialization)\n",
                (long long)r.instance_bytes, (unsigned long long)r.instance_allocations);
    std::printf("  first doStep       %llu allocations\n", (unsigned long long)r.first_step_allocations);
    std::printf("  later doSteps      %llu allocations, %llu bytes\n", (unsigned long long)r.dostep_allocations,
                (unsigned long long)r.dostep_alloc_bytes);
    for (const std::string& site : r.sites) std::printf("    %s\n", site.c_str());
}

void print_report(const Options& o, const Report& r) {
    if (o.json)
        print_json(o, r);
    else
        print_text(o, r);
}

struct Run {
    Options o;
    Fmi2 fmi;
    ModelDescription md;
    fmi2Component component = nullptr;
    fmi2CallbackFunctions callbacks{fmu_logger, calloc, free, nullptr, nullptr};
    Report report;

    void set_real(const std::string& name, double v) {
        const fmi2ValueReference vr = md.vr(name, 'R');
        check(fmi.set_real(component, &vr, 1, &v), ("fmi2SetReal " + name).c_str());
    }
    void set_integer(const std::string& name, int v) {
        const fmi2ValueReference vr = md.vr(name, 'I');
        const fmi2Integer value = v;
        check(fmi.set_integer(component, &vr, 1, &value), ("fmi2SetInteger " + name).c_str());
    }
    void set_boolean(const std::string& name, bool v) {
        const fmi2ValueReference vr = md.vr(name, 'B');
        const fmi2Boolean value = v ? fmi2True : fmi2False;
        check(fmi.set_boolean(component, &vr, 1, &value), ("fmi2SetBoolean " + name).c_str());
    }
    double get_real(const std::string& name) {
        const fmi2ValueReference vr = md.vr(name, 'R');
        double v = 0;
        check(fmi.get_real(component, &vr, 1, &v), ("fmi2GetReal " + name).c_str());
        return v;
    }

    // Instantiate and set the structural parameters and tolerances (counted as instance memory).
    void instantiate() {
        const uint64_t a0 = g_alloc.allocations;
        const int64_t live0 = g_alloc.live;
        const std::string name = md.model_identifier.empty() ? "Gimbal2Axis" : md.model_identifier;
        component = fmi.instantiate("bench", fmi2CoSimulation, md.guid.c_str(), "", &callbacks, fmi2False, fmi2False);
        if (component == nullptr) die("fmi2Instantiate failed");
        if (g_alloc.allocations == a0)
            die("no heap allocation seen in fmi2Instantiate: the malloc interposition does not work");
        if (o.method >= 0) {
            if (!md.has("solver.method"))
                die("--method " + std::to_string(o.method) +
                    ": this FMU has no Integer parameter 'solver.method' (integrator choice not available yet)");
            set_integer("solver.method", o.method);
        }
        if (o.fidelity == "reduced") {
            for (const char* v : {"gear1.model", "gear2.model", "motor1.model", "motor2.model"}) {
                if (!md.has(v)) die(std::string("--fidelity reduced: the FMU has no parameter '") + v + "'");
                set_integer(v, 0);
            }
        }
        if (!std::isnan(o.rtol)) set_real("solver.rtol", o.rtol);
        if (!std::isnan(o.atol)) set_real("solver.atol", o.atol);
        for (const auto& [name, v] : o.real_parameters) {
            if (!md.has(name)) die("--set: the FMU has no variable '" + name + "'");
            if (md.variables.at(name).type == 'I') {
                if (v != std::floor(v)) die("--set " + name + ": an Integer variable takes a whole number");
                set_integer(name, static_cast<int>(v));
            } else {
                set_real(name, v);
            }
        }
        report.instance_allocations = g_alloc.allocations - a0;
        report.instance_bytes = g_alloc.live - live0;
        (void)name;
    }

    void finish_instance_memory(uint64_t a0, int64_t live0) {
        report.instance_allocations = g_alloc.allocations - a0;
        report.instance_bytes = g_alloc.live - live0;
    }

    void read_counters() {
        for (int c = 0; c < 5; ++c) {
            if (!md.has(kCounterNames[c])) continue;
            const fmi2ValueReference vr = md.vr(kCounterNames[c], 'I');
            fmi2Integer v = 0;
            if (fmi.get_integer(component, &vr, 1, &v) <= fmi2Warning) report.counters[c] = v;
        }
        if (md.has("solver.states")) {
            const fmi2ValueReference vr = md.vr("solver.states", 'I');
            fmi2Integer v = 0;
            if (fmi.get_integer(component, &vr, 1, &v) <= fmi2Warning) report.states = v;
        }
    }

    // ------------------------------------------------------------------ ship stabilization
    void ship_stabilization() {
        report.mode = "ship_stabilization";
        const long n = std::lround(o.duration / o.step);
        const double h = o.step;
        report.simulated = n * h;

        SeaState sea;
        sea.setup(o.seed, h);
        Controller controller;
        const double az = o.target_azimuth_deg * M_PI / 180.0, el = o.target_elevation_deg * M_PI / 180.0;
        controller.target[0] = -std::sin(az) * std::cos(el);
        controller.target[1] = std::cos(az) * std::cos(el);
        controller.target[2] = std::sin(el);

        const uint64_t a0 = g_alloc.allocations;
        const int64_t live0 = g_alloc.live;
        instantiate();
        double base[15];
        sea.inputs(base);
        double alpha0, beta0;
        gimbal_angles_for(controller.target, base[0], base[1], base[2], 0.0, alpha0, beta0);
        // Stop time with half a step of slack: the accumulated time may pass n * h by rounding.
        check(fmi.setup_experiment(component, fmi2False, 0.0, 0.0, fmi2True, (n + 0.5) * h), "fmi2SetupExperiment");
        check(fmi.enter_initialization_mode(component), "fmi2EnterInitializationMode");
        const double u_limit[2] = {get_real("motor1.U_L"), get_real("motor2.U_L")};
        controller.setup(u_limit);
        const double N1 = get_real("gear1.N"), N2 = get_real("gear2.N");
        // Start on target with relaxed gears (rotor angle = N times the load's), at rest on the base.
        set_real("alpha", alpha0);
        set_real("alpha_m", N1 * alpha0);
        set_real("beta", beta0);
        set_real("beta_m", N2 * beta0);

        static const char* kInputs[17] = {"u_R1", "u_R2", "base.delta", "base.psi", "base.gamma",
                                          "base.delta_dot", "base.psi_dot", "base.gamma_dot", "base.delta_ddot",
                                          "base.psi_ddot", "base.gamma_ddot", "base.v_a[1]", "base.v_a[2]",
                                          "base.v_a[3]", "base.a_a[1]", "base.a_a[2]", "base.a_a[3]"};
        static const char* kOutputs[5] = {"alpha", "beta", "los.omega[1]", "los.omega[2]", "los.omega[3]"};
        fmi2ValueReference in_vr[17], out_vr[5];
        for (int i = 0; i < 17; ++i) in_vr[i] = md.vr(kInputs[i], 'R');
        for (int i = 0; i < 5; ++i) out_vr[i] = md.vr(kOutputs[i], 'R');
        double in[17] = {0.0};
        std::memcpy(in + 2, base, sizeof base);
        check(fmi.set_real(component, in_vr, 17, in), "fmi2SetReal inputs");
        check(fmi.exit_initialization_mode(component), "fmi2ExitInitializationMode");
        finish_instance_memory(a0, live0);

        const bool record = !o.trajectory.empty();
        std::vector<double> trajectory;
        if (record) trajectory.reserve(static_cast<size_t>(n + 1) * 6);
        double y[5];
        double u_next[2] = {0.0, 0.0};  // computed at t_k, applied over [t_{k+1}, t_{k+2}]
        // The master's work at communication point `step` once the outputs are in y: the controller's
        // command (applied one step later), the base inputs and the previous command to the FMU.
        const auto command = [&](long step) {
            sea.inputs(base);
            double u[2];
            controller.compute(step, h, y[0], y[1], y + 2, base, u);
            in[0] = u_next[0];
            in[1] = u_next[1];
            std::memcpy(in + 2, base, sizeof base);
            u_next[0] = u[0];
            u_next[1] = u[1];
            check(fmi.set_real(component, in_vr, 17, in), "fmi2SetReal inputs");
        };
        backtrace(reinterpret_cast<void**>(y), 1);  // loads libgcc's unwinder now, not inside a measured step

        const double wall0 = clock_seconds(CLOCK_MONOTONIC), cpu0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
        double in_step = 0.0;
        // Reserved before the loop: the driver allocates nothing while doSteps are counted.
        std::vector<double> step_times, step_cpu_times;
        std::vector<int> step_events;  // mode changes in each timed doStep
        std::vector<long> step_rhs;     // right-hand sides in each timed doStep
        if (o.time_dostep) {
            step_times.reserve(static_cast<size_t>(n) + 1);
            step_cpu_times.reserve(static_cast<size_t>(n) + 1);
            step_events.reserve(static_cast<size_t>(n) + 1);
            step_rhs.reserve(static_cast<size_t>(n) + 1);
        }
        const bool count_events = o.time_dostep && md.has("events.total") && md.has("solver.rhs_evaluations");
        const fmi2ValueReference counter_vr[2] = {count_events ? md.vr("events.total", 'I') : 0,
                                                  count_events ? md.vr("solver.rhs_evaluations", 'I') : 0};
        fmi2Integer counters_before[2] = {0, 0};
        long k = 0;
        // The communication points are accumulated (t += h), as the FMU accumulates its own time:
        // the FMU refuses a currentCommunicationPoint more than 1e-12 relative from its time, and
        // k * h drifts that far from the running sum after ~1e5 steps of 1 ms.
        double t = 0.0;
        for (; k < n; ++k, t += h) {
            check(fmi.get_real(component, out_vr, 5, y), "fmi2GetReal outputs");
            if (record) trajectory.insert(trajectory.end(), {t, y[0], y[1], y[2], y[3], y[4]});
            command(k);

            const uint64_t before = g_alloc.allocations, bytes_before = g_alloc.bytes;
            g_current_time = t;
            g_trace = k > 0 && o.trace_allocations;
            fmi2Status status;
            if (o.time_dostep) {
                const double c0 = clock_seconds(CLOCK_THREAD_CPUTIME_ID);
                const double s0 = clock_seconds(CLOCK_MONOTONIC);
                status = fmi.do_step(component, t, h, fmi2True);
                const double spent = clock_seconds(CLOCK_MONOTONIC) - s0;
                const double cpu_spent = clock_seconds(CLOCK_THREAD_CPUTIME_ID) - c0;
                in_step += spent;
                if (step_times.size() < step_times.capacity()) step_times.push_back(spent);
                if (step_cpu_times.size() < step_cpu_times.capacity()) step_cpu_times.push_back(cpu_spent);
                fmi2Integer counters_after[2] = {counters_before[0], counters_before[1]};
                if (count_events) fmi.get_integer(component, counter_vr, 2, counters_after);
                if (step_events.size() < step_events.capacity()) {
                    step_events.push_back(counters_after[0] - counters_before[0]);
                    step_rhs.push_back(counters_after[1] - counters_before[1]);
                }
                counters_before[0] = counters_after[0], counters_before[1] = counters_after[1];
            } else {
                status = fmi.do_step(component, t, h, fmi2True);
            }
            g_trace = false;
            if (k == 0) {
                report.first_step_allocations = g_alloc.allocations - before;
            } else {
                report.dostep_allocations += g_alloc.allocations - before;
                report.dostep_alloc_bytes += g_alloc.bytes - bytes_before;
            }
            if (status > fmi2Warning) {
                report.failure = "fmi2DoStep returned status " + std::to_string(status) + " at t = " + std::to_string(t);
                break;
            }
            sea.advance();
        }
        report.cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
        report.wall = clock_seconds(CLOCK_MONOTONIC) - wall0;
        if (o.time_dostep) {
            report.dostep_wall = in_step;
            if (!step_times.empty() && step_events.size() == step_times.size()) {
                std::vector<double> by_events[3];
                for (size_t k = 0; k < step_times.size(); ++k)
                    by_events[std::min(step_events[k], 2)].push_back(step_times[k]);
                for (int e = 0; e < 3; ++e) {
                    report.dostep_count_by_events[e] = static_cast<long>(by_events[e].size());
                    if (by_events[e].empty()) continue;
                    std::sort(by_events[e].begin(), by_events[e].end());
                    report.dostep_median_by_events[e] = by_events[e][by_events[e].size() / 2];
                }
                std::vector<size_t> order(step_times.size());
                for (size_t k = 0; k < order.size(); ++k) order[k] = k;
                std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return step_times[a] > step_times[b]; });
                const size_t slowest = std::max<size_t>(1, order.size() / 1000);
                size_t with_events = 0;
                std::vector<long> slowest_rhs, all_rhs(step_rhs);
                for (size_t k = 0; k < slowest; ++k) {
                    with_events += step_events[order[k]] > 0;
                    slowest_rhs.push_back(step_rhs[order[k]]);
                }
                report.slowest_with_events = static_cast<double>(with_events) / static_cast<double>(slowest);
                std::sort(slowest_rhs.begin(), slowest_rhs.end());
                std::sort(all_rhs.begin(), all_rhs.end());
                report.rhs_per_slowest_median = static_cast<double>(slowest_rhs[slowest_rhs.size() / 2]);
                report.rhs_per_dostep_median = static_cast<double>(all_rhs[all_rhs.size() / 2]);
                report.rhs_per_dostep_p999 = static_cast<double>(all_rhs[std::min(all_rhs.size() - 1, all_rhs.size() * 999 / 1000)]);
                report.rhs_per_dostep_max = static_cast<double>(all_rhs.back());
            }
            // Median, 99th and 99.9th percentile and maximum of one clock's doStep times.
            const auto percentiles = [](std::vector<double>& times, double& p50, double& p99, double& p999, double& max) {
                if (times.empty()) return;
                std::sort(times.begin(), times.end());
                const auto at = [&](double q) { return times[std::min(times.size() - 1, static_cast<size_t>(q * times.size()))]; };
                p50 = at(0.5), p99 = at(0.99), p999 = at(0.999), max = times.back();
            };
            percentiles(step_times, report.dostep_p50, report.dostep_p99, report.dostep_p999, report.dostep_max);
            percentiles(step_cpu_times, report.dostep_cpu_p50, report.dostep_cpu_p99, report.dostep_cpu_p999,
                        report.dostep_cpu_max);
        }
        report.dostep_calls = k + (report.failure.empty() ? 0 : 1);
        report.simulated = k * h;
        if (report.failure.empty() && fmi.get_real(component, out_vr, 5, y) <= fmi2Warning && record)
            trajectory.insert(trajectory.end(), {t, y[0], y[1], y[2], y[3], y[4]});
        read_counters();
        if (report.failure.empty()) {
            // The master's own share: the same loop (outputs, sea state, controller, inputs) without
            // doStep, on the final state. The FMU's share is cpu - master_cpu.
            sea.reset(0);
            controller.setup(u_limit);
            u_next[0] = u_next[1] = 0.0;
            const double m0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
            for (long j = 0; j < k; ++j) {
                check(fmi.get_real(component, out_vr, 5, y), "fmi2GetReal outputs");
                if (record) trajectory[static_cast<size_t>(j) * 6] = j * h;  // same memory traffic
                command(j);
                sea.advance();
            }
            report.master_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - m0;
        }
        collect_sites(report);
        if (record) write_trajectory(trajectory);
        fmi.terminate(component);
        fmi.free_instance(component);
    }

    void write_trajectory(const std::vector<double>& data) {
        const std::string& path = o.trajectory;
        const bool csv = path.size() >= 4 && path.compare(path.size() - 4, 4, ".csv") == 0;
        FILE* f = std::fopen(path.c_str(), csv ? "w" : "wb");
        if (f == nullptr) die("cannot write " + path);
        if (csv) {
            std::fprintf(f, "time,alpha,beta,los.omega[1],los.omega[2],los.omega[3]\n");
            for (size_t i = 0; i + 6 <= data.size(); i += 6)
                std::fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", data[i], data[i + 1], data[i + 2], data[i + 3],
                             data[i + 4], data[i + 5]);
        } else {
            std::fwrite(data.data(), sizeof(double), data.size(), f);
        }
        std::fclose(f);
    }

    // ------------------------------------------------------------------ FMI overhead
    void fmi_overhead() {
        report.mode = "overhead";
        const double h = o.overhead_step;
        const long n = o.overhead_steps;
        const uint64_t a0 = g_alloc.allocations;
        const int64_t live0 = g_alloc.live;
        instantiate();
        set_boolean("base.fixed", true);
        set_real("g", 0.0);  // at rest: no gravity torque, zero state, zero inputs
        check(fmi.setup_experiment(component, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
        check(fmi.enter_initialization_mode(component), "fmi2EnterInitializationMode");
        check(fmi.exit_initialization_mode(component), "fmi2ExitInitializationMode");
        finish_instance_memory(a0, live0);
        void* frames[2];
        backtrace(frames, 1);

        const uint64_t before_first = g_alloc.allocations;
        check(fmi.do_step(component, 0.0, h, fmi2True), "fmi2DoStep");
        report.first_step_allocations = g_alloc.allocations - before_first;

        const uint64_t before = g_alloc.allocations, bytes_before = g_alloc.bytes;
        g_trace = o.trace_allocations;
        const double wall0 = clock_seconds(CLOCK_MONOTONIC), cpu0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
        double t = h;
        long k = 1;
        for (; k < n; ++k) {
            if (fmi.do_step(component, t, h, fmi2True) > fmi2Warning) {
                report.failure = "fmi2DoStep failed at t = " + std::to_string(t);
                break;
            }
            t += h;
        }
        report.cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
        report.wall = clock_seconds(CLOCK_MONOTONIC) - wall0;
        g_trace = false;
        report.dostep_allocations = g_alloc.allocations - before;
        report.dostep_alloc_bytes = g_alloc.bytes - bytes_before;
        report.dostep_calls = k - 1;  // timed calls (the first is not)
        report.simulated = report.dostep_calls * h;
        read_counters();
        collect_sites(report);
        fmi.terminate(component);
        fmi.free_instance(component);
    }
};

}  // namespace

int main(int argc, char** argv) {
    Run run;
    run.o = parse(argc, argv);
    run.md.load(run.o.model_description);
    run.fmi.load(run.o.fmu);
    if (run.o.fmi_overhead) run.fmi_overhead();
    else run.ship_stabilization();
    print_report(run.o, run.report);
    return run.report.failure.empty() ? 0 : 1;
}
