/* clock_stress: one long run of the gimbal FMU's binary under one master clock, for
 * benchmarks/clock_stress.py (a stress test of the communication-point rule, not part of CI).
 *
 *   clock_stress fmi2|fmi3 BINARY TOKEN FIXED_BASE_VR CLOCK START STEP STEPS
 *
 * CLOCK is how the master keeps time: kh (t0 + k*h from the integer k), sum (t += h), kahan (a
 * compensated sum) or ns (int64 nanoseconds converted at each call, as libcosim does). The gimbal
 * runs on a fixed base at 0 V (the payload swings down and settles under friction): what is
 * stressed is the clock rule and the instance's memory, not the physics. Prints one JSON object:
 * the steps taken, the first refused point (if any) with the FMU's message, the FMU's last reported
 * time against the master's, and the resident set size sampled every 2^20 steps. */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

static char last_message[1024];

static void fmi2_logger(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status,
                        fmi2String category, fmi2String message, ...) {
    (void)environment, (void)instance, (void)status, (void)category;
    snprintf(last_message, sizeof last_message, "%s", message != NULL ? message : "");
}

static void fmi3_logger(fmi3InstanceEnvironment environment, fmi3Status status, fmi3String category,
                        fmi3String message) {
    (void)environment, (void)status, (void)category;
    snprintf(last_message, sizeof last_message, "%s", message != NULL ? message : "");
}

static long resident_kib(const char* field) {
    FILE* status = fopen("/proc/self/status", "r");
    if (status == NULL) return -1;
    char line[256];
    long kib = -1;
    const size_t length = strlen(field);
    while (fgets(line, sizeof line, status) != NULL)
        if (strncmp(line, field, length) == 0) kib = strtol(line + length, NULL, 10);
    fclose(status);
    return kib;
}

typedef struct {
    int kind; /* 0 kh, 1 sum, 2 kahan, 3 ns */
    double start, step, sum, compensation;
    int64_t start_ns, step_ns;
} Clock;

/* The point of step k and the step the master passes there. */
static void clock_point(Clock* clock, long k, double* point, double* step) {
    switch (clock->kind) {
        case 0: *point = clock->start + (double)k * clock->step, *step = clock->step; return;
        case 1: *point = clock->sum, *step = clock->step, clock->sum += clock->step; return;
        case 2: {
            *point = clock->sum, *step = clock->step;
            const double y = clock->step - clock->compensation, s = clock->sum + y;
            clock->compensation = (s - clock->sum) - y;
            clock->sum = s;
            return;
        }
        default:
            *point = (double)(clock->start_ns + k * clock->step_ns) / 1e9;
            *step = (double)clock->step_ns / 1e9;
    }
}

static void* symbol(void* library, const char* name) {
    void* found = dlsym(library, name);
    if (found == NULL) {
        fprintf(stderr, "clock_stress: %s is not exported\n", name);
        exit(2);
    }
    return found;
}

/* The clock of the command line's CLOCK START STEP. */
static Clock parse_clock(char** argv) {
    Clock clock = {0};
    const char* kinds[] = {"kh", "sum", "kahan", "ns"};
    for (int i = 0; i < 4; ++i)
        if (strcmp(argv[5], kinds[i]) == 0) clock.kind = i;
    clock.start = clock.sum = strtod(argv[6], NULL);
    clock.step = strtod(argv[7], NULL);
    clock.start_ns = llround(clock.start * 1e9);
    clock.step_ns = llround(clock.step * 1e9) > 0 ? llround(clock.step * 1e9) : 1;
    return clock;
}

/* An initialized FMI 3.0 instance on a fixed base, or NULL. */
static void* instantiate_fmi3(void* library, const char* token, unsigned fixed_base_vr, double start) {
    fmi3InstanceEnvironment environment = NULL;
    void* instance = ((fmi3InstantiateCoSimulationTYPE*)symbol(library, "fmi3InstantiateCoSimulation"))(
        "stress", token, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, environment, fmi3_logger, NULL);
    const fmi3ValueReference vr = fixed_base_vr;
    const fmi3Boolean yes = fmi3True;
    if (instance == NULL ||
        ((fmi3EnterInitializationModeTYPE*)symbol(library, "fmi3EnterInitializationMode"))(
            instance, fmi3False, 0.0, start, fmi3False, 0.0) != fmi3OK ||
        ((fmi3SetBooleanTYPE*)symbol(library, "fmi3SetBoolean"))(instance, &vr, 1, &yes, 1) != fmi3OK ||
        ((fmi3ExitInitializationModeTYPE*)symbol(library, "fmi3ExitInitializationMode"))(instance) != fmi3OK)
        return NULL;
    return instance;
}

/* An initialized FMI 2.0 instance on a fixed base, or NULL. */
static void* instantiate_fmi2(void* library, const char* token, unsigned fixed_base_vr, double start) {
    static fmi2CallbackFunctions callbacks = {fmi2_logger, calloc, free, NULL, NULL};
    void* instance = ((fmi2InstantiateTYPE*)symbol(library, "fmi2Instantiate"))("stress", fmi2CoSimulation, token, NULL,
                                                                               &callbacks, fmi2False, fmi2False);
    const fmi2ValueReference vr = fixed_base_vr;
    const fmi2Boolean yes = fmi2True;
    if (instance == NULL ||
        ((fmi2SetupExperimentTYPE*)symbol(library, "fmi2SetupExperiment"))(instance, fmi2False, 0.0, start,
                                                                           fmi2False, 0.0) != fmi2OK ||
        ((fmi2SetBooleanTYPE*)symbol(library, "fmi2SetBoolean"))(instance, &vr, 1, &yes) != fmi2OK ||
        ((fmi2EnterInitializationModeTYPE*)symbol(library, "fmi2EnterInitializationMode"))(instance) != fmi2OK ||
        ((fmi2ExitInitializationModeTYPE*)symbol(library, "fmi2ExitInitializationMode"))(instance) != fmi2OK)
        return NULL;
    return instance;
}

/* Where a run ended: the steps taken, the last point and step passed, the FMU's time and status. */
typedef struct {
    long taken;
    double point, step, reported;
    int status;
} Run;

/* Up to `steps` doSteps on `clock`, printing the resident set size every 2^20 steps. */
static Run run_steps(void* library, void* instance, int fmi3, Clock* clock, long steps) {
    fmi2DoStepTYPE* fmi2_do_step = fmi3 ? NULL : (fmi2DoStepTYPE*)symbol(library, "fmi2DoStep");
    fmi3DoStepTYPE* fmi3_do_step = fmi3 ? (fmi3DoStepTYPE*)symbol(library, "fmi3DoStep") : NULL;
    Run run = {0, clock->start, clock->step, clock->start, 0};
    for (long k = 0; k < steps; ++k) {
        clock_point(clock, k, &run.point, &run.step);
        if (fmi3) {
            fmi3Boolean event, terminate, early;
            run.status = fmi3_do_step(instance, run.point, run.step, fmi3True, &event, &terminate, &early, &run.reported);
        } else {
            run.status = fmi2_do_step(instance, run.point, run.step, fmi2True);
        }
        if (run.status > 1) break;
        ++run.taken;
        if ((k & ((1L << 20) - 1)) == 0) printf("%s%ld", k == 0 ? "" : ", ", resident_kib("VmRSS:"));
    }
    if (!fmi3 && run.status <= 1)
        ((fmi2GetRealStatusTYPE*)symbol(library, "fmi2GetRealStatus"))(instance, fmi2LastSuccessfulTime, &run.reported);
    return run;
}

int main(int argc, char** argv) {
    if (argc != 9) {
        fprintf(stderr, "usage: clock_stress fmi2|fmi3 BINARY TOKEN FIXED_BASE_VR kh|sum|kahan|ns START STEP STEPS\n");
        return 2;
    }
    const int fmi3 = strcmp(argv[1], "fmi3") == 0;
    const unsigned fixed_base_vr = (unsigned)strtoul(argv[4], NULL, 10);
    Clock clock = parse_clock(argv);
    const long steps = strtol(argv[8], NULL, 10);

    void* library = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        fprintf(stderr, "clock_stress: dlopen(%s): %s\n", argv[2], dlerror());
        return 2;
    }
    void* instance = fmi3 ? instantiate_fmi3(library, argv[3], fixed_base_vr, clock.start)
                          : instantiate_fmi2(library, argv[3], fixed_base_vr, clock.start);
    if (instance == NULL) {
        fprintf(stderr, "clock_stress: initialization failed: %s\n", last_message);
        return 2;
    }

    printf("{\"rss_kib\": [");
    const Run run = run_steps(library, instance, fmi3, &clock, steps);
    printf("], \"peak_rss_kib\": %ld, \"steps\": %ld, \"refused\": %s, \"point\": %.17g, \"step\": %.17g, "
           "\"reported_time\": %.17g, \"master_end\": %.17g, \"message\": \"",
           resident_kib("VmHWM:"), run.taken, run.status > 1 ? "true" : "false", run.point, run.step, run.reported,
           run.point + run.step);
    for (const char* c = last_message; run.status > 1 && *c; ++c)
        printf(*c == '"' || *c == '\\' ? "\\%c" : "%c", *c);
    printf("\"}\n");
    if (fmi3)
        ((fmi3FreeInstanceTYPE*)symbol(library, "fmi3FreeInstance"))(instance);
    else
        ((fmi2FreeInstanceTYPE*)symbol(library, "fmi2FreeInstance"))(instance);
    return run.status > 1 ? 1 : 0;
}
