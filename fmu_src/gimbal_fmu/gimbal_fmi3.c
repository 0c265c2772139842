/* The gimbal's FMI 3.0 face (Model Exchange and Co-Simulation), beside the FMI 2.0 one: FMI 3.0's state
 * machine, types and value references over the FMI instance layer (fmi_layer/fmi_instance.h), its FMI
 * 3.0 face (fmi_layer/fmi3_face.h: the states, instantiation, and the functions every FMU of the
 * project has alike, the FMU-state ones and, in fmi3_not_offered.c, those none offers) and the
 * core's C interface (gimbal_c_api.h).
 *
 * Value references: gimbal_model.h (FMI3_INTEGER_BASE ...). The event indicators are scalar Float64
 * locals, not one array: a host without array support reads each Float64 as one value. Enumerations
 * are accessed with fmi3GetInt64/fmi3SetInt64, as FMI 3.0 says; the model has no other types.
 *
 * Co-Simulation handles every mode change inside fmi3DoStep; an importer that allows an early return
 * gets the step back right after the first one (earlyReturn, and eventHandlingNeeded if it uses Event
 * Mode, where there is no discrete state left to update). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "fmi_layer/fmi3_face.h"
#include "gimbal_model.h"
#include "host_fp_environment.h"

_Static_assert(sizeof(fmi3ValueReference) == sizeof(unsigned), "value references are passed to the core as unsigned");

static fmi3Status refuse(FmiInstance* i, const char* function, const char* why) {
    return (fmi3Status)fmi_refuse(i, function, why);
}

static fmi3Status from_core(GimbalStatus status) { return (fmi3Status)gimbal_status(status); }

/* ---------------------------------------------------------------- lifetime */

static fmi3Instance instantiate(fmi3String name, fmi3String token, int model_exchange, int event_mode_used,
                                int early_return_allowed, fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                fmi3LogMessageCallback log, const char* function) {
    return fmi3_instantiate(&kGimbalModel, function, NULL, name, token, model_exchange, event_mode_used,
                            early_return_allowed, loggingOn, environment, log);
}

static fmi3Status enter_initialization(FmiInstance* i, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    const char* f = "fmi3EnterInitializationMode";
    if (!fmi_allowed(i, f, S_INSTANTIATED) || !fmi_experiment_times_valid(i, f, start, stop_defined ? 1 : 0, stop))
        return fmi3Error;
    const fmi3Status status = from_core(gimbal_core_set_master_tolerance(gimbal_core_of(i), tolerance_defined ? 1 : 0, tolerance));
    if (status > fmi3Warning) return status;
    i->time = start;
    i->stop_time = stop;
    i->stop_time_defined = stop_defined ? 1 : 0;
    i->state = S_INITIALIZATION;
    return fmi3OK;
}

static fmi3Status exit_initialization(FmiInstance* i) {
    if (!fmi_allowed(i, "fmi3ExitInitializationMode", S_INITIALIZATION)) return fmi3Error;
    const fmi3Status status = from_core(gimbal_core_initialize(gimbal_core_of(i), i->time));
    if (status > fmi3Warning) {
        fmi_log_error(i, "fmi3ExitInitializationMode: initialization refused; fix the values above and retry");
        return fmi3Error;
    }
    /* Model Exchange, and Co-Simulation with Event Mode, start in event mode (FMI 3.0, 3.2 and 4.2). */
    i->state = i->model_exchange || i->event_mode_used ? S_EVENT : S_STEP;
    return status;
}

/* ---------------------------------------------------------------- values */

typedef enum { KIND_FLOAT64, KIND_INT32, KIND_ENUMERATION, KIND_BOOLEAN } Kind;
static const char* const kKindName[] = {"Float64", "Int32", "Enumeration (fmi3GetInt64/fmi3SetInt64)", "Boolean"};

/* One of the scalar event indicators (no core variable: the core computes them all at once). */
static int is_event_indicator(fmi3ValueReference vr) {
    return vr >= FMI3_FIRST_EVENT_INDICATOR && vr < FMI3_FIRST_EVENT_INDICATOR + GIMBAL_EVENT_INDICATORS;
}

/* The core's type and reference of an FMI 3 value reference, or 0 (with *info unset). */
static int core_variable(fmi3ValueReference vr, Kind* kind, unsigned* core_vr, GimbalVariableInfo* info) {
    if (vr < FMI3_INTEGER_BASE && gimbal_variable_info(GIMBAL_REAL, vr, info)) {
        *kind = KIND_FLOAT64, *core_vr = vr;
        return 1;
    }
    if (vr >= FMI3_INTEGER_BASE && vr < FMI3_BOOLEAN_BASE &&
        gimbal_variable_info(GIMBAL_INTEGER, vr - FMI3_INTEGER_BASE, info)) {
        *kind = info->declared_type[0] != '\0' ? KIND_ENUMERATION : KIND_INT32, *core_vr = vr - FMI3_INTEGER_BASE;
        return 1;
    }
    if (vr >= FMI3_BOOLEAN_BASE && vr < FMI3_TIME &&
        gimbal_variable_info(GIMBAL_BOOLEAN, vr - FMI3_BOOLEAN_BASE, info)) {
        *kind = KIND_BOOLEAN, *core_vr = vr - FMI3_BOOLEAN_BASE;
        return 1;
    }
    return 0;
}

/* The master's inputs at every step: Float64 scalars all settable, found in one pass through the
 * core's table (check_access's loop then names whatever this refused). */
static int settable_reals(const FmiInstance* i, const fmi3ValueReference vr[], size_t nvr) {
    for (size_t k = 0; k < nvr; ++k)
        if (vr[k] >= FMI3_INTEGER_BASE) return 0;
    const int initialized = !(i->state & (S_INSTANTIATED | S_INITIALIZATION));
    return gimbal_first_unsettable(GIMBAL_REAL, (const unsigned*)vr, nvr, initialized) == nvr;
}

/* One variable of a getter or setter of `kind`: 1 when it may be accessed so, else logged. */
static int variable_accessible(FmiInstance* i, const char* f, int set, Kind kind, fmi3ValueReference vr) {
    if (kind == KIND_FLOAT64 && (is_event_indicator(vr) || vr == FMI3_TIME) && !set) return 1;
    Kind actual;
    unsigned core_vr;
    GimbalVariableInfo info;
    if (!core_variable(vr, &actual, &core_vr, &info)) {
        fmi_log_error(i, "%s: value reference %u is not a variable of this FMU%s", f, (unsigned)vr,
            is_event_indicator(vr) || vr == FMI3_TIME ? " that can be set" : "");
        return 0;
    }
    if (actual != kind) {
        fmi_log_error(i, "%s: %s is a%s %s variable", f, info.name,
            actual == KIND_INT32 || actual == KIND_ENUMERATION ? "n" : "", kKindName[actual]);
        return 0;
    }
    if (set && !gimbal_variable_settable(i, &info)) {
        fmi_log_error(i, "%s: %s cannot be set in state '%s'", f, info.name, i->face->state_name(i->state));
        return 0;
    }
    return 1;
}

/* The common checks of a getter or setter; `values` and the count of values must match the variables
 * (every variable of this FMU is a scalar). */
static int check_access(FmiInstance* i, const char* f, int set, Kind kind, const fmi3ValueReference vr[], size_t nvr,
                        const void* values, size_t nvalues) {
    if (!fmi_allowed(i, f, set ? S_SET : S_GET)) return 0;
    if (nvr == 0) return 1;
    if (!fmi_not_null(i, f, vr, "valueReferences") || !fmi_not_null(i, f, values, "values")) return 0;
    if (set && kind == KIND_FLOAT64 && nvalues == nvr && settable_reals(i, vr, nvr)) return 1;
    for (size_t k = 0; k < nvr; ++k)
        if (!variable_accessible(i, f, set, kind, vr[k])) return 0;
    if (nvalues != nvr) {
        fmi_log_error(i, "%s: nValues = %zu, but the variables hold %zu values", f, nvalues, nvr);
        return 0;
    }
    return 1;
}

static fmi3Status get_float64(FmiInstance* i, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[], size_t n) {
    if (!check_access(i, "fmi3GetFloat64", 0, KIND_FLOAT64, vr, nvr, values, n)) return fmi3Error;
    fmi3Float64 indicators[GIMBAL_EVENT_INDICATORS];
    int indicators_read = 0; /* the core hands out all of them at once: read them once per call */
    for (size_t k = 0; k < nvr; ++k) {
        fmi3Status status = fmi3OK;
        if (vr[k] == FMI3_TIME) {
            values[k] = i->time;
            continue;
        }
        if (is_event_indicator(vr[k])) {
            if (!indicators_read) {
                if (!i->model_exchange) { /* Co-Simulation locates the events itself: no indicator is exposed */
                    for (int z = 0; z < GIMBAL_EVENT_INDICATORS; ++z) indicators[z] = 1.0;
                } else {
                    status = from_core(gimbal_core_get_event_indicators(gimbal_core_of(i), indicators));
                    if (status > fmi3Warning) return status;
                }
                indicators_read = 1;
            }
            values[k] = indicators[vr[k] - FMI3_FIRST_EVENT_INDICATOR];
        } else {
            status = from_core(gimbal_core_get_real(gimbal_core_of(i), vr[k], &values[k]));
        }
        if (status > fmi3Warning) return status;
    }
    return fmi3OK;
}

static fmi3Status set_float64(FmiInstance* i, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[], size_t n) {
    if (!check_access(i, "fmi3SetFloat64", 1, KIND_FLOAT64, vr, nvr, values, n)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) { /* all or nothing */
        if (isfinite(values[k])) continue;
        GimbalVariableInfo info;
        gimbal_variable_info(GIMBAL_REAL, vr[k], &info);
        fmi_log_error(i, "fmi3SetFloat64: %s = %g refused: values must be finite", info.name, values[k]);
        return fmi3Error;
    }
    return nvr == 0 ? fmi3OK : from_core(gimbal_core_set_reals(gimbal_core_of(i), vr, nvr, values));
}

static fmi3Status get_integers(FmiInstance* i, const char* f, Kind kind, const fmi3ValueReference vr[], size_t nvr,
                               void* values, size_t n, int wide) {
    if (!check_access(i, f, 0, kind, vr, nvr, values, n)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) {
        int value = 0;
        const fmi3Status status = from_core(gimbal_core_get_integer(gimbal_core_of(i), vr[k] - FMI3_INTEGER_BASE, &value));
        if (status > fmi3Warning) return status;
        if (wide) ((fmi3Int64*)values)[k] = value;
        else ((fmi3Int32*)values)[k] = value;
    }
    return fmi3OK;
}

static fmi3Status set_integers(FmiInstance* i, const char* f, Kind kind, const fmi3ValueReference vr[], size_t nvr,
                               const void* values, size_t n, int wide) {
    if (!check_access(i, f, 1, kind, vr, nvr, values, n)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) {
        const long long value = wide ? ((const fmi3Int64*)values)[k] : ((const fmi3Int32*)values)[k];
        if (value < INT32_MIN || value > INT32_MAX) {
            GimbalVariableInfo info;
            gimbal_variable_info(GIMBAL_INTEGER, vr[k] - FMI3_INTEGER_BASE, &info);
            fmi_log_error(i, "%s: %s = %lld lies outside the Int32 range", f, info.name, value);
            return fmi3Error;
        }
    }
    for (size_t k = 0; k < nvr; ++k) {
        const int value = (int)(wide ? ((const fmi3Int64*)values)[k] : ((const fmi3Int32*)values)[k]);
        const fmi3Status status = from_core(gimbal_core_set_integer(gimbal_core_of(i), vr[k] - FMI3_INTEGER_BASE, value));
        if (status > fmi3Warning) return status;
    }
    return fmi3OK;
}

static fmi3Status get_boolean(FmiInstance* i, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[], size_t n) {
    if (!check_access(i, "fmi3GetBoolean", 0, KIND_BOOLEAN, vr, nvr, values, n)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) {
        int value = 0;
        const fmi3Status status = from_core(gimbal_core_get_boolean(gimbal_core_of(i), vr[k] - FMI3_BOOLEAN_BASE, &value));
        if (status > fmi3Warning) return status;
        values[k] = value != 0;
    }
    return fmi3OK;
}

static fmi3Status set_boolean(FmiInstance* i, const fmi3ValueReference vr[], size_t nvr, const fmi3Boolean values[], size_t n) {
    if (!check_access(i, "fmi3SetBoolean", 1, KIND_BOOLEAN, vr, nvr, values, n)) return fmi3Error;
    for (size_t k = 0; k < nvr; ++k) {
        const fmi3Status status = from_core(gimbal_core_set_boolean(gimbal_core_of(i), vr[k] - FMI3_BOOLEAN_BASE, values[k] ? 1 : 0));
        if (status > fmi3Warning) return status;
    }
    return fmi3OK;
}

/* ---------------------------------------------------------------- derivatives */

/* The arguments of fmi3GetDirectionalDerivative: pointers, counts, finite seeds, and a point where
 * the derivatives are offered; logged naming the culprit. */
static int directional_arguments_valid(FmiInstance* i, const char* f, const fmi3ValueReference unknowns[], size_t nu,
                                       const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                                       size_t nseed, const fmi3Float64 sensitivity[], size_t nsens) {
    if ((nu > 0 && (!fmi_not_null(i, f, unknowns, "unknowns") || !fmi_not_null(i, f, sensitivity, "sensitivity"))) ||
        (nk > 0 && (!fmi_not_null(i, f, knowns, "knowns") || !fmi_not_null(i, f, seed, "seed"))))
        return 0;
    if (nseed != nk || nsens != nu) {
        fmi_log_error(i, "%s: nSeed = %zu and nSensitivity = %zu must equal nKnowns = %zu and nUnknowns = %zu",
            f, nseed, nsens, nk, nu);
        return 0;
    }
    const char* why = NULL;
    for (size_t k = 0; k < nk && why == NULL; ++k)
        if (!isfinite(seed[k])) why = "every seed must be finite";
    if (why == NULL && i->state == S_INITIALIZATION) why = "the derivatives are offered once initialization has ended";
    if (why != NULL) fmi_refuse(i, f, why);
    return why == NULL;
}

/* Co-Simulation: the outputs are held between steps, so their derivatives with respect to the inputs
 * are 0 (the FMI 2.0 face explains); unknowns must be outputs, knowns inputs. */
static fmi3Status cosimulation_derivatives(FmiInstance* i, const char* f, const unsigned u[], size_t nu,
                                           const unsigned kn[], size_t nk, fmi3Float64 sensitivity[]) {
    GimbalVariableInfo info;
    for (size_t k = 0; k < nu; ++k)
        if (!gimbal_variable_info(GIMBAL_REAL, u[k], &info) || info.causality != GIMBAL_OUTPUT)
            return refuse(i, f, "in Co-Simulation the unknowns are outputs");
    for (size_t k = 0; k < nk; ++k)
        if (!gimbal_variable_info(GIMBAL_REAL, kn[k], &info) || info.causality != GIMBAL_INPUT)
            return refuse(i, f, "in Co-Simulation the knowns are inputs");
    for (size_t k = 0; k < nu; ++k) sensitivity[k] = 0.0;
    return fmi3OK;
}

static fmi3Status directional_derivative(FmiInstance* i, const fmi3ValueReference unknowns[], size_t nu,
                                         const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                                         size_t nseed, fmi3Float64 sensitivity[], size_t nsens) {
    const char* f = "fmi3GetDirectionalDerivative";
    if (!fmi_allowed(i, f, i->model_exchange ? (S_INITIALIZATION | S_EVALUATE) : (S_INITIALIZATION | S_RUNNING | S_TERMINATED)) ||
        !directional_arguments_valid(i, f, unknowns, nu, knowns, nk, seed, nseed, sensitivity, nsens))
        return fmi3Error;
    unsigned* u = (unsigned*)malloc((nu + 1) * sizeof *u);
    unsigned* kn = (unsigned*)malloc((nk + 1) * sizeof *kn);
    if (u == NULL || kn == NULL) {
        free(u), free(kn);
        return refuse(i, f, "out of memory");
    }
    int ok = 1;
    for (size_t k = 0; k < nu && ok; ++k) ok = unknowns[k] < FMI3_INTEGER_BASE, u[k] = unknowns[k];
    for (size_t k = 0; k < nk && ok; ++k) ok = knowns[k] < FMI3_INTEGER_BASE, kn[k] = knowns[k];
    fmi3Status status;
    if (!ok)
        status = refuse(i, f, "unknowns and knowns are Float64 variables");
    else if (i->model_exchange)
        status = from_core(gimbal_core_directional_derivative(gimbal_core_of(i), u, nu, kn, nk, seed, sensitivity));
    else
        status = cosimulation_derivatives(i, f, u, nu, kn, nk, sensitivity);
    free(u);
    free(kn);
    return status;
}

/* ---------------------------------------------------------------- Model Exchange */

static int me_vector(FmiInstance* i, const char* f, int states, const void* values, size_t given, size_t expected,
                     const char* argument) {
    if (!fmi_allowed(i, f, states)) return 0;
    if (!i->model_exchange) {
        fmi_log_error(i, "%s is a Model Exchange function: instance '%s' was instantiated for Co-Simulation",
            f, i->name);
        return 0;
    }
    if (given != expected) {
        fmi_log_error(i, "%s: the count is %zu, but the model has %zu", f, given, expected);
        return 0;
    }
    return fmi_not_null(i, f, values, argument);
}

static fmi3Status update_discrete_states(FmiInstance* i, fmi3Boolean* need, fmi3Boolean* terminate, fmi3Boolean* nominals,
                                         fmi3Boolean* values, fmi3Boolean* next_defined, fmi3Float64* next) {
    const char* f = "fmi3UpdateDiscreteStates";
    if (!fmi_allowed(i, f, S_EVENT)) return fmi3Error;
    if (!fmi_not_null(i, f, need, "discreteStatesNeedUpdate") || !fmi_not_null(i, f, terminate, "terminateSimulation") ||
        !fmi_not_null(i, f, nominals, "nominalsOfContinuousStatesChanged") ||
        !fmi_not_null(i, f, values, "valuesOfContinuousStatesChanged") || !fmi_not_null(i, f, next_defined, "nextEventTimeDefined") ||
        !fmi_not_null(i, f, next, "nextEventTime"))
        return fmi3Error;
    *need = *terminate = *nominals = *values = *next_defined = fmi3False;
    *next = 0.0;
    if (!i->model_exchange) return fmi3OK; /* Co-Simulation has handled its mode changes in fmi3DoStep */
    GimbalDiscreteUpdate update;
    const fmi3Status status = from_core(gimbal_core_update_discrete_states(gimbal_core_of(i), &update));
    if (status > fmi3Warning) return status;
    *values = update.states_changed != 0;
    *next_defined = update.next_time_defined != 0;
    *next = update.next_time_defined ? update.next_time : 0.0;
    return status;
}

/* ---------------------------------------------------------------- Co-Simulation */

static fmi3Status do_step(FmiInstance* i, fmi3Float64 t, fmi3Float64 h, fmi3Boolean* event, fmi3Boolean* terminate,
                          fmi3Boolean* early, fmi3Float64* last) {
    const char* f = "fmi3DoStep";
    if (!fmi_allowed(i, f, S_STEP)) return fmi3Error;
    if (!fmi_not_null(i, f, event, "eventHandlingNeeded") || !fmi_not_null(i, f, terminate, "terminateSimulation") ||
        !fmi_not_null(i, f, early, "earlyReturn") || !fmi_not_null(i, f, last, "lastSuccessfulTime"))
        return fmi3Error;
    *event = *terminate = *early = fmi3False;
    *last = i->time;
    if (!fmi_step_valid(i, f, t, h)) return fmi3Error;
    const double end = t + h;
    /* With early return allowed, the step ends right after the first mode change inside it: the
     * importer sees the event where it happens (and handles it in Event Mode if it uses that). */
    double elapsed = h; /* how far the step went: all of it, or to the first mode change */
    const fmi3Status status = from_core(i->early_return_allowed
                                            ? gimbal_core_do_step_until_mode_change(gimbal_core_of(i), t, h, &elapsed)
                                            : gimbal_core_do_step(gimbal_core_of(i), t, h));
    if (status > fmi3Warning) {
        i->state = status == fmi3Discard ? S_STEP_DISCARDED : S_ERROR;
        return status;
    }
    const int ended_early = i->early_return_allowed && elapsed < h;
    i->time = ended_early ? t + elapsed : end;
    *last = i->time;
    *early = ended_early ? fmi3True : fmi3False;
    *event = ended_early && i->event_mode_used ? fmi3True : fmi3False;
    return status;
}

/* ---------------------------------------------------------------- the exported functions */

/* Every entry runs in the FMU's own floating-point environment and restores the host's on the way out
 * (IN_FMU_FP_ENVIRONMENT, host_fp_environment.h); OWN_INSTANCE is the host's opaque handle as ours. */
#define OWN_INSTANCE ((FmiInstance*)instance)

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                          fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    (void)resourcePath, (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate(instanceName, instantiationToken, 1, 0, 0, loggingOn, instanceEnvironment, logMessage,
                                   "fmi3InstantiateModelExchange"));
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath, (void)visible, (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables,
        (void)intermediateUpdate;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate(instanceName, instantiationToken, 0, eventModeUsed ? 1 : 0, earlyReturnAllowed ? 1 : 0,
                                   loggingOn, instanceEnvironment, logMessage, "fmi3InstantiateCoSimulation"));
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn, (void)clockUpdate,
        (void)lockPreemption, (void)unlockPreemption;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    fmi_free_instance(OWN_INSTANCE);
    leave_fmu_fp(&host_environment);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_initialization(OWN_INSTANCE, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, exit_initialization(OWN_INSTANCE)); }

static fmi3Status enter_event_mode(FmiInstance* i) {
    if (!fmi_allowed(i, "fmi3EnterEventMode", i->model_exchange ? S_CONTINUOUS_TIME : S_STEP)) return fmi3Error;
    if (!i->model_exchange && !i->event_mode_used)
        return refuse(i, "fmi3EnterEventMode", "the instance was made with eventModeUsed = false");
    i->state = S_EVENT;
    return fmi3OK;
}
fmi3Status fmi3EnterEventMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_event_mode(OWN_INSTANCE)); }

static fmi3Status terminate(FmiInstance* i) {
    if (!fmi_allowed(i, "fmi3Terminate", S_RUNNING)) return fmi3Error;
    i->state = S_TERMINATED;
    return fmi3OK;
}
fmi3Status fmi3Terminate(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, terminate(OWN_INSTANCE)); }

static fmi3Status reset(FmiInstance* i) {
    if (!fmi_allowed(i, "fmi3Reset", S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_reset(i);
}
fmi3Status fmi3Reset(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, reset(OWN_INSTANCE)); }

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_float64(OWN_INSTANCE, vr, nvr, values, n));
}
fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[],
                          size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_float64(OWN_INSTANCE, vr, nvr, values, n));
}
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_integers(OWN_INSTANCE, "fmi3GetInt32", KIND_INT32, vr, nvr, values, n, 0));
}
fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_integers(OWN_INSTANCE, "fmi3SetInt32", KIND_INT32, vr, nvr, values, n, 0));
}
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int64 values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_integers(OWN_INSTANCE, "fmi3GetInt64", KIND_ENUMERATION, vr, nvr, values, n, 1));
}
fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int64 values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_integers(OWN_INSTANCE, "fmi3SetInt64", KIND_ENUMERATION, vr, nvr, values, n, 1));
}
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_boolean(OWN_INSTANCE, vr, nvr, values, n));
}
fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Boolean values[],
                          size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_boolean(OWN_INSTANCE, vr, nvr, values, n));
}

/* String: the one type without variables that not every FMU of the project lacks (fmi3_not_offered.c
 * refuses the others). */
FMI3_ABSENT_TYPE(String, fmi3String)

/* What this FMU does not offer, as its model description says: refused with the reason. */
#define NOT_OFFERED(call, why) IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_not_offered(OWN_INSTANCE, call, why))


fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, directional_derivative(OWN_INSTANCE, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity));
}
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined,
                                    fmi3Float64* nextEventTime) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, update_discrete_states(OWN_INSTANCE, discreteStatesNeedUpdate, terminateSimulation,
                                            nominalsOfContinuousStatesChanged, valuesOfContinuousStatesChanged,
                                            nextEventTimeDefined, nextEventTime));
}

static fmi3Status enter_continuous_time_mode(FmiInstance* i) {
    if (!me_vector(i, "fmi3EnterContinuousTimeMode", S_EVENT, i, 0, 0, "instance")) return fmi3Error;
    i->state = S_CONTINUOUS_TIME;
    return fmi3OK;
}
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_continuous_time_mode(OWN_INSTANCE)); }

static fmi3Status completed_integrator_step(FmiInstance* i, fmi3Boolean* enter, fmi3Boolean* terminate) {
    const char* f = "fmi3CompletedIntegratorStep";
    if (!me_vector(i, f, S_CONTINUOUS_TIME, i, 0, 0, "instance") || !fmi_not_null(i, f, enter, "enterEventMode") ||
        !fmi_not_null(i, f, terminate, "terminateSimulation"))
        return fmi3Error;
    *enter = *terminate = fmi3False; /* every mode change shows in an event indicator */
    return fmi3OK;
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, completed_integrator_step(OWN_INSTANCE, enterEventMode, terminateSimulation));
}

static fmi3Status set_time(FmiInstance* i, fmi3Float64 t) {
    if (!me_vector(i, "fmi3SetTime", S_EVENT | S_CONTINUOUS_TIME, i, 0, 0, "instance")) return fmi3Error;
    const fmi3Status status = from_core(gimbal_core_set_time(gimbal_core_of(i), t));
    if (status <= fmi3Warning) i->time = t;
    return status;
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) { IN_FMU_FP_ENVIRONMENT(fmi3Status, set_time(OWN_INSTANCE, time)); }

static fmi3Status set_continuous_states(FmiInstance* i, const fmi3Float64 x[], size_t n) {
    if (!me_vector(i, "fmi3SetContinuousStates", S_CONTINUOUS_TIME, x, n, GIMBAL_CONTINUOUS_STATES, "continuousStates"))
        return fmi3Error;
    return from_core(gimbal_core_set_continuous_states(gimbal_core_of(i), x));
}
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_continuous_states(OWN_INSTANCE, continuousStates, n));
}

/* The core's vectors the host reads: one check (state, count, pointer) and the core's reader. */
typedef GimbalStatus (*CoreVectorReader)(GimbalCore* core, double* values);
static fmi3Status read_vector(FmiInstance* i, const char* f, int states, fmi3Float64 values[], size_t given,
                              size_t expected, const char* argument, CoreVectorReader read) {
    if (!me_vector(i, f, states, values, given, expected, argument)) return fmi3Error;
    return from_core(read(gimbal_core_of(i), values));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(OWN_INSTANCE, "fmi3GetContinuousStateDerivatives", S_EVALUATE,
                                                  derivatives, n, GIMBAL_CONTINUOUS_STATES, "derivatives",
                                                  gimbal_core_get_derivatives));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(OWN_INSTANCE, "fmi3GetEventIndicators", S_INITIALIZATION | S_EVALUATE,
                                                  eventIndicators, n, GIMBAL_EVENT_INDICATORS, "eventIndicators",
                                                  gimbal_core_get_event_indicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(OWN_INSTANCE, "fmi3GetContinuousStates", S_INITIALIZATION | S_EVALUATE,
                                                  continuousStates, n, GIMBAL_CONTINUOUS_STATES, "continuousStates",
                                                  gimbal_core_get_continuous_states));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(OWN_INSTANCE, "fmi3GetNominalsOfContinuousStates",
                                                  S_INSTANTIATED | S_EVALUATE, nominals, n, GIMBAL_CONTINUOUS_STATES,
                                                  "nominals", gimbal_core_get_nominal_states));
}

static fmi3Status count(FmiInstance* i, const char* f, size_t* n, size_t value) {
    if (!fmi_allowed(i, f, S_ANY) || !fmi_not_null(i, f, n, "count")) return fmi3Error;
    *n = value;
    return fmi3OK;
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, count(OWN_INSTANCE, "fmi3GetNumberOfEventIndicators", n, GIMBAL_EVENT_INDICATORS));
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, count(OWN_INSTANCE, "fmi3GetNumberOfContinuousStates", n, GIMBAL_CONTINUOUS_STATES));
}

static fmi3Status enter_step_mode(FmiInstance* i) {
    if (!fmi_allowed(i, "fmi3EnterStepMode", S_EVENT)) return fmi3Error;
    if (i->model_exchange) return refuse(i, "fmi3EnterStepMode", "a Model Exchange instance has no step mode");
    i->state = S_STEP;
    return fmi3OK;
}
fmi3Status fmi3EnterStepMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_step_mode(OWN_INSTANCE)); }

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t n) {
    (void)vr, (void)nvr, (void)orders, (void)values, (void)n;
    NOT_OFFERED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* eventHandlingNeeded,
                      fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, do_step(OWN_INSTANCE, currentCommunicationPoint, communicationStepSize, eventHandlingNeeded, terminateSimulation,
                             earlyReturn, lastSuccessfulTime));
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    NOT_OFFERED("fmi3ActivateModelPartition", "this FMU offers Model Exchange and Co-Simulation only");
}
