/* A plain C master for one fixed scene, built twice from this file: natively (loads the linux64
 * shared object with dlopen) and with the mingw-w64 tool chain (loads the win64 DLL with
 * LoadLibrary/GetProcAddress, run under Wine). tests/fmu/test_win64_binary.py runs both and compares
 * their CSV files, so the two binaries are checked on the same scene.
 *
 *   fmu_scene_driver [--fmi3] BINARY GUID OUT.csv [REFUSED_METHOD...]
 *
 * With --fmi3 BINARY is the FMI 3.0 binary (GUID its instantiation token), driven through the fmi3*
 * functions with the same calls in the same order (Co-Simulation without Event Mode): its CSV equals
 * the FMI 2.0 binary's bit for bit on the same platform.
 *
 * The scene: 3 s in steps of 1 ms at the default parameters (full fidelity, backlash in both gears),
 * the carrier rolling, pitching, yawing and heaving (sinusoids with their exact derivatives, set at
 * each step start; the scene runner's sums of sinusoids, c_kernel/include/gimbal_kernel/sum_of_sines.h), and a PD
 * loop that slews the gimbal to fixed angles (0.1 rad azimuth, -0.05 rad elevation) against that
 * motion with the payload gyro as its rate signal (the scene runner's PID,
 * c_kernel/include/gimbal_kernel/controllers.h, with kp and k_gyro): the voltages saturate at first and the
 * current limiters and backlash stops switch. Every 10th step writes a CSV row of outputs and
 * voltages.
 *
 * Then, in the same process (one Wine start), each REFUSED_METHOD is set as solver.method on a fresh
 * instance, and the status of fmi2ExitInitializationMode is printed ("refusal: solver.method = M
 * status = S") after the FMU's log messages, which go to stdout. Exit status 0 when the scene ran,
 * 1 otherwise. */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%.17g round trips) in mingw-w64's runtime */
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char* path) { return LoadLibraryA(path); }
static void* find_symbol(Library library, const char* name) {
    FARPROC address = GetProcAddress(library, name);
    void* pointer;
    memcpy(&pointer, &address, sizeof pointer);
    return pointer;
}
static void close_library(Library library) { FreeLibrary(library); }
#else
#include <dlfcn.h>
typedef void* Library;
static Library open_library(const char* path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void* find_symbol(Library library, const char* name) { return dlsym(library, name); }
static void close_library(Library library) { dlclose(library); }
#endif

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/sum_of_sines.h"

/* Value references: the position in the FMU's variable tables (the same tables it is built from). */
enum {
#define X(id, ...) VR_##id,
#include "gimbal/real_variables.def"
#undef X
};
enum {
#define X(id, ...) VI_##id,
#include "gimbal/integer_variables.def"
#undef X
};
/* The FMI 3.0 binary's Integer variables (Int32, Enumerations as Int64) sit 1000 above their FMI 2.0
 * value references (docs/fmi_interfaces.md). */
enum { FMI3_INTEGER_BASE = 1000 };

typedef struct {
    int fmi3;
    fmi2InstantiateTYPE* instantiate;
    fmi2FreeInstanceTYPE* free_instance;
    fmi2SetupExperimentTYPE* setup_experiment;
    fmi2EnterInitializationModeTYPE* enter_initialization;
    fmi2ExitInitializationModeTYPE* exit_initialization;
    fmi2TerminateTYPE* terminate;
    fmi2SetRealTYPE* set_real;
    fmi2GetRealTYPE* get_real;
    fmi2SetIntegerTYPE* set_integer;
    fmi2GetIntegerTYPE* get_integer;
    fmi2DoStepTYPE* do_step;
    fmi3InstantiateCoSimulationTYPE* instantiate3;
    fmi3FreeInstanceTYPE* free_instance3;
    fmi3EnterInitializationModeTYPE* enter_initialization3;
    fmi3ExitInitializationModeTYPE* exit_initialization3;
    fmi3TerminateTYPE* terminate3;
    fmi3SetFloat64TYPE* set_float64;
    fmi3GetFloat64TYPE* get_float64;
    fmi3GetInt32TYPE* get_int32;
    fmi3SetInt64TYPE* set_int64;
    fmi3DoStepTYPE* do_step3;
} Api;

static void logger(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)environment;
    printf("[%s] %s (status %d): ", instance, category, (int)status);
    va_list args;
    va_start(args, message);
    vprintf(message, args);
    va_end(args);
    printf("\n");
    fflush(stdout);
}

static void logger3(fmi3InstanceEnvironment environment, fmi3Status status, fmi3String category, fmi3String message) {
    (void)environment;
    printf("[fmi3] %s (status %d): %s\n", category, (int)status, message);
    fflush(stdout);
}

static const fmi2CallbackFunctions kCallbacks = {logger, calloc, free, NULL, NULL};

static int load(Library library, Api* api) {
#define LOAD(field, name)                                                       \
    do {                                                                        \
        void* pointer = find_symbol(library, name);                             \
        if (pointer == NULL) {                                                  \
            fprintf(stderr, "fmu_scene_driver: %s is not exported\n", name);    \
            return 0;                                                           \
        }                                                                       \
        memcpy(&api->field, &pointer, sizeof pointer);                          \
    } while (0)
    if (api->fmi3) {
        LOAD(instantiate3, "fmi3InstantiateCoSimulation");
        LOAD(free_instance3, "fmi3FreeInstance");
        LOAD(enter_initialization3, "fmi3EnterInitializationMode");
        LOAD(exit_initialization3, "fmi3ExitInitializationMode");
        LOAD(terminate3, "fmi3Terminate");
        LOAD(set_float64, "fmi3SetFloat64");
        LOAD(get_float64, "fmi3GetFloat64");
        LOAD(get_int32, "fmi3GetInt32");
        LOAD(set_int64, "fmi3SetInt64");
        LOAD(do_step3, "fmi3DoStep");
        return 1;
    }
    LOAD(instantiate, "fmi2Instantiate");
    LOAD(free_instance, "fmi2FreeInstance");
    LOAD(setup_experiment, "fmi2SetupExperiment");
    LOAD(enter_initialization, "fmi2EnterInitializationMode");
    LOAD(exit_initialization, "fmi2ExitInitializationMode");
    LOAD(terminate, "fmi2Terminate");
    LOAD(set_real, "fmi2SetReal");
    LOAD(get_real, "fmi2GetReal");
    LOAD(set_integer, "fmi2SetInteger");
    LOAD(get_integer, "fmi2GetInteger");
    LOAD(do_step, "fmi2DoStep");
#undef LOAD
    return 1;
}

/* The calls of the scene in either FMI version; each returns 1 when the FMU answered OK or Warning
 * (fmi2Status and fmi3Status agree on those). */
static void* instantiate(const Api* api, const char* name, const char* guid) {
    if (api->fmi3)
        return api->instantiate3(name, guid, "file:///unused", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                 logger3, NULL);
    return api->instantiate(name, fmi2CoSimulation, guid, "file:///unused", &kCallbacks, fmi2False, fmi2False);
}

static int enter_initialization(const Api* api, void* c, double stop_time) {
    if (api->fmi3) return api->enter_initialization3(c, fmi3False, 0.0, 0.0, stop_time > 0.0, stop_time) <= fmi3Warning;
    return api->setup_experiment(c, fmi2False, 0.0, 0.0, stop_time > 0.0, stop_time) <= fmi2Warning &&
           api->enter_initialization(c) <= fmi2Warning;
}

static int exit_initialization(const Api* api, void* c, int* status) {
    *status = api->fmi3 ? (int)api->exit_initialization3(c) : (int)api->exit_initialization(c);
    return *status <= fmi2Warning;
}

static int set_reals(const Api* api, void* c, const unsigned* vr, size_t n, const double* values) {
    if (api->fmi3) return api->set_float64(c, vr, n, values, n) <= fmi3Warning;
    return api->set_real(c, vr, n, values) <= fmi2Warning;
}

static int get_reals(const Api* api, void* c, const unsigned* vr, size_t n, double* values) {
    if (api->fmi3) return api->get_float64(c, vr, n, values, n) <= fmi3Warning;
    return api->get_real(c, vr, n, values) <= fmi2Warning;
}

static int get_integers(const Api* api, void* c, const unsigned* vr, size_t n, int* values) {
    if (api->fmi3) {
        unsigned shifted[8];
        fmi3Int32 read[8];
        if (n > 8) return 0;
        for (size_t k = 0; k < n; ++k) shifted[k] = FMI3_INTEGER_BASE + vr[k];
        if (api->get_int32(c, shifted, n, read, n) > fmi3Warning) return 0;
        for (size_t k = 0; k < n; ++k) values[k] = read[k];
        return 1;
    }
    fmi2Integer read[8];
    if (n > 8 || api->get_integer(c, vr, n, read) > fmi2Warning) return 0;
    for (size_t k = 0; k < n; ++k) values[k] = read[k];
    return 1;
}

static int set_method(const Api* api, void* c, int method, int* status) {
    const unsigned vr = VI_solver_method;
    if (api->fmi3) {
        const unsigned shifted = FMI3_INTEGER_BASE + vr;
        const fmi3Int64 value = method;
        *status = (int)api->set_int64(c, &shifted, 1, &value, 1);
    } else {
        const fmi2Integer value = method;
        *status = (int)api->set_integer(c, &vr, 1, &value);
    }
    return *status <= fmi2Warning;
}

static int do_step(const Api* api, void* c, double t, double h) {
    if (api->fmi3) {
        fmi3Boolean event_needed = fmi3False, terminate = fmi3False, early_return = fmi3False;
        fmi3Float64 last_time = t;
        return api->do_step3(c, t, h, fmi3True, &event_needed, &terminate, &early_return, &last_time) <= fmi3Warning &&
               !terminate && !early_return;
    }
    return api->do_step(c, t, h, fmi2True) <= fmi2Warning;
}

static void terminate(const Api* api, void* c) {
    if (api->fmi3)
        api->terminate3(c);
    else
        api->terminate(c);
}

static void free_instance(const Api* api, void* c) {
    if (api->fmi3)
        api->free_instance3(c);
    else
        api->free_instance(c);
}

/* The carrier's motion at t_k = k h, k = 0 .. steps: attitude, rates, accelerations (pitch delta, yaw
 * psi, roll gamma; one sinusoid each) and the velocity and acceleration of point a (cruising along y,
 * heaving along z), row k of a (steps + 1) x 15 table. 0 when out of memory. */
enum { BASE_AXES = 4 }; /* pitch, yaw, roll, heave */
static double* base_motion(long steps, double h) {
    static const double amplitude[BASE_AXES] = {0.03, 0.015, 0.08, 0.5}; /* rad: pitch, yaw, roll; m: heave */
    static const double phase[BASE_AXES] = {0.5, 1.0, 0.0, 0.0};
    const double omega[BASE_AXES] = {0.9 * 2.0 * 3.14159265358979323846, 0.5 * 2.0 * 3.14159265358979323846,
                                      0.7 * 2.0 * 3.14159265358979323846, 2.0 * 3.14159265358979323846 / 8.0};
    const long rows = steps + 1;
    double* table = calloc((size_t)rows * 15, sizeof(double));
    double* sums = malloc((size_t)rows * 3 * sizeof(double));
    int ok = table != NULL && sums != NULL;
    for (int axis = 0; ok && axis < BASE_AXES; ++axis) {
        double weights[3];
        gimbal_sum_of_sines_weights(1, &amplitude[axis], &omega[axis], weights);
        ok = gimbal_sum_of_sines(rows, 0.0, h, 1, &omega[axis], &phase[axis], weights, sums, sums + rows,
                                 sums + 2 * rows) == 0;
        /* attitude axes: the angle and its derivatives; heave: the velocity and acceleration of point a */
        const int value_column = axis < 3 ? axis : -1, rate_column = axis < 3 ? 3 + axis : 11,
                  acceleration_column = axis < 3 ? 6 + axis : 14;
        for (long k = 0; ok && k < rows; ++k) {
            if (value_column >= 0) table[15 * k + value_column] = sums[k];
            table[15 * k + rate_column] = sums[rows + k];
            table[15 * k + acceleration_column] = sums[2 * rows + k];
        }
    }
    for (long k = 0; ok && k < rows; ++k) table[15 * k + 10] = 6.0; /* cruising: constant velocity along y */
    free(sums);
    if (!ok) {
        free(table);
        return NULL;
    }
    return table;
}

static const unsigned kBaseInputs[15] = {
    VR_base_delta,      VR_base_psi,        VR_base_gamma,      VR_base_delta_dot, VR_base_psi_dot,
    VR_base_gamma_dot,  VR_base_delta_ddot, VR_base_psi_ddot,   VR_base_gamma_ddot, VR_base_v_a_1,
    VR_base_v_a_2,      VR_base_v_a_3,      VR_base_a_a_1,      VR_base_a_a_2,     VR_base_a_a_3};

static const unsigned kOutputs[] = {
    VR_alpha, VR_alpha_m, VR_beta,  VR_beta_m, VR_alpha_dot, VR_alpha_m_dot, VR_beta_dot, VR_beta_m_dot, VR_i_R1,
    VR_i_R2,  VR_theta_b1, VR_theta_b2, VR_T_E1, VR_T_E2, VR_los_omega_1, VR_los_omega_2, VR_los_omega_3};
static const char* const kOutputNames =
    "alpha,alpha_m,beta,beta_m,alpha_dot,alpha_m_dot,beta_dot,beta_m_dot,i_R1,i_R2,theta_b1,theta_b2,T_E1,T_E2,"
    "los.omega[1],los.omega[2],los.omega[3]";
enum { OUTPUT_COUNT = sizeof kOutputs / sizeof kOutputs[0], GYRO_COLUMN = OUTPUT_COUNT - 3 /* los.omega[1..3] */ };
static const unsigned kCounters[] = {VI_events_total, VI_solver_steps};

static int run_scene(const Api* api, const char* guid, const char* csv_path) {
    void* c = instantiate(api, "scene", guid);
    if (c == NULL) return 0;
    FILE* csv = fopen(csv_path, "w");
    if (csv == NULL) {
        fprintf(stderr, "fmu_scene_driver: cannot write %s\n", csv_path);
        free_instance(api, c);
        return 0;
    }
    const double h = 1e-3;
    const int steps = 3000, every = 10;
    double y[OUTPUT_COUNT], u[2] = {0.0, 0.0};
    int counters[2], status = 0;
    /* PD: kp on the encoder angles, k_gyro on the gyro rates; no limit here (the motors' own clamp). */
    GimbalController pd;
    memset(&pd, 0, sizeof pd);
    pd.kind = gimbal_controller_kind("pid");
    for (int axis = 0; axis < 2; ++axis) {
        pd.axis[axis].kp = 400.0;
        pd.axis[axis].k_gyro = 8.0;
        pd.axis[axis].u_limit = pd.axis[axis].i_limit = pd.u_limit[axis] = HUGE_VAL;
    }
    const double set_point[4] = {0.1, -0.05, 0.0, 0.0}; /* rad: azimuth, elevation; at rest */
    double* base = base_motion(steps, h);
    int ok = base != NULL && enter_initialization(api, c, steps * h);
    ok = ok && set_reals(api, c, kBaseInputs, 15, base) && exit_initialization(api, c, &status);
    fprintf(csv, "time,%s,u_R1,u_R2,events.total,solver.steps\n", kOutputNames);
    for (int k = 0; ok && k <= steps; ++k) {
        const double t = k * h;
        ok = get_reals(api, c, kOutputs, OUTPUT_COUNT, y) && get_integers(api, c, kCounters, 2, counters);
        if (!ok) break;
        /* the new voltages applied over this step */
        const double measured[5] = {y[0], y[2], y[GYRO_COLUMN], y[GYRO_COLUMN + 1], y[GYRO_COLUMN + 2]};
        double reference[2];
        gimbal_controller_step(&pd, k, h, measured, set_point, u, reference);
        if (k % every == 0) {
            fprintf(csv, "%.17g", t);
            for (int j = 0; j < OUTPUT_COUNT; ++j) fprintf(csv, ",%.17g", y[j]);
            fprintf(csv, ",%.17g,%.17g,%d,%d\n", u[0], u[1], counters[0], counters[1]);
        }
        if (k == steps) break;
        const unsigned voltages[2] = {VR_u_R1, VR_u_R2};
        ok = set_reals(api, c, voltages, 2, u) && set_reals(api, c, kBaseInputs, 15, base + 15 * k) &&
             do_step(api, c, t, h);
    }
    if (ok) terminate(api, c);
    free_instance(api, c);
    free(base);
    fclose(csv);
    if (!ok) fprintf(stderr, "fmu_scene_driver: the scene failed (see the FMU's messages above)\n");
    return ok;
}

static void check_refusal(const Api* api, const char* guid, int method) {
    void* c = instantiate(api, "refusal", guid);
    if (c == NULL) {
        printf("refusal: solver.method = %d: instantiation failed\n", method);
        return;
    }
    int status = 0;
    if (set_method(api, c, method, &status) && enter_initialization(api, c, 0.0)) exit_initialization(api, c, &status);
    printf("refusal: solver.method = %d status = %d\n", method, status);
    fflush(stdout);
    free_instance(api, c);
}

int main(int argc, char** argv) {
    Api api;
    memset(&api, 0, sizeof api);
    api.fmi3 = argc > 1 && strcmp(argv[1], "--fmi3") == 0;
    argv += api.fmi3;
    argc -= api.fmi3;
    if (argc < 4) {
        fprintf(stderr, "usage: fmu_scene_driver [--fmi3] BINARY GUID OUT.csv [REFUSED_METHOD...]\n");
        return 2;
    }
    Library library = open_library(argv[1]);
    if (library == NULL) {
        fprintf(stderr, "fmu_scene_driver: cannot load %s\n", argv[1]);
        return 1;
    }
    if (!load(library, &api)) return 1;
    const int ok = run_scene(&api, argv[2], argv[3]);
    for (int k = 4; k < argc; ++k) check_refusal(&api, argv[2], atoi(argv[k]));
    close_library(library);
    return ok ? 0 : 1;
}
