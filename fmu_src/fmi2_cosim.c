/* FMI 2.0 Co-Simulation wrapper: the state machine, argument checks and logging of the standard,
 * over the C interface of the dynamics core (model_core/include/gimbal/gimbal_c_api.h).
 *
 * Every exported fmi2* function is a thin shell (at the end of this file) that holds the host's
 * floating-point environment around the implementation of the same name in lower case. */
#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_instance.h"
#include "gimbal_guid.h"
#include "common/communication_point.h"

static const struct {
    const char* name;
    int states;
} kFunctions[FUNCTION_COUNT] = {
    [FN_SetDebugLogging] = {"fmi2SetDebugLogging", ANY_STATE},
    [FN_SetupExperiment] = {"fmi2SetupExperiment", STATE_INSTANTIATED},
    [FN_EnterInitializationMode] = {"fmi2EnterInitializationMode", STATE_INSTANTIATED},
    [FN_ExitInitializationMode] = {"fmi2ExitInitializationMode", STATE_INITIALIZATION},
    [FN_Terminate] = {"fmi2Terminate", STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_EVENT_MODE | STATE_CONTINUOUS_TIME},
    [FN_Reset] = {"fmi2Reset", ANY_STATE},
    [FN_GetReal] = {"fmi2GetReal", GET_STATES},
    [FN_GetInteger] = {"fmi2GetInteger", GET_STATES},
    [FN_GetBoolean] = {"fmi2GetBoolean", GET_STATES},
    [FN_GetString] = {"fmi2GetString", GET_STATES},
    [FN_SetReal] = {"fmi2SetReal", SET_STATES},
    [FN_SetInteger] = {"fmi2SetInteger", SET_STATES},
    [FN_SetBoolean] = {"fmi2SetBoolean", SET_STATES},
    [FN_SetString] = {"fmi2SetString", SET_STATES},
    [FN_GetFMUstate] = {"fmi2GetFMUstate", FMU_STATE_STATES},
    [FN_SetFMUstate] = {"fmi2SetFMUstate", FMU_STATE_STATES},
    [FN_FreeFMUstate] = {"fmi2FreeFMUstate", ANY_STATE},
    [FN_SerializedFMUstateSize] = {"fmi2SerializedFMUstateSize", ANY_STATE},
    [FN_SerializeFMUstate] = {"fmi2SerializeFMUstate", ANY_STATE},
    [FN_DeSerializeFMUstate] = {"fmi2DeSerializeFMUstate", ANY_STATE},
    /* After initialization only: the derivatives of the InitialUnknowns are not provided. */
    [FN_GetDirectionalDerivative] = {"fmi2GetDirectionalDerivative", STATUS_STATES | EVALUATION_STATES},
    [FN_SetRealInputDerivatives] = {"fmi2SetRealInputDerivatives", STATE_INITIALIZATION | STATE_STEP_COMPLETE},
    [FN_GetRealOutputDerivatives] = {"fmi2GetRealOutputDerivatives", ANY_STATE},
    [FN_DoStep] = {"fmi2DoStep", STATE_STEP_COMPLETE},
    [FN_CancelStep] = {"fmi2CancelStep", 0}, /* doStep never runs asynchronously */
    [FN_GetStatus] = {"fmi2GetStatus", STATUS_STATES},
    [FN_GetRealStatus] = {"fmi2GetRealStatus", STATUS_STATES},
    [FN_GetIntegerStatus] = {"fmi2GetIntegerStatus", STATUS_STATES},
    [FN_GetBooleanStatus] = {"fmi2GetBooleanStatus", STATUS_STATES},
    [FN_GetStringStatus] = {"fmi2GetStringStatus", STATUS_STATES},
    /* Model Exchange (FMI 2.0, section 3.2.3) */
    [FN_EnterEventMode] = {"fmi2EnterEventMode", STATE_CONTINUOUS_TIME},
    [FN_NewDiscreteStates] = {"fmi2NewDiscreteStates", STATE_EVENT_MODE},
    [FN_EnterContinuousTimeMode] = {"fmi2EnterContinuousTimeMode", STATE_EVENT_MODE},
    [FN_CompletedIntegratorStep] = {"fmi2CompletedIntegratorStep", STATE_CONTINUOUS_TIME},
    [FN_SetTime] = {"fmi2SetTime", STATE_EVENT_MODE | STATE_CONTINUOUS_TIME},
    [FN_SetContinuousStates] = {"fmi2SetContinuousStates", STATE_CONTINUOUS_TIME},
    [FN_GetDerivatives] = {"fmi2GetDerivatives", EVALUATION_STATES},
    [FN_GetEventIndicators] = {"fmi2GetEventIndicators", STATE_INITIALIZATION | EVALUATION_STATES},
    [FN_GetContinuousStates] = {"fmi2GetContinuousStates", STATE_INITIALIZATION | EVALUATION_STATES},
    [FN_GetNominalsOfContinuousStates] = {"fmi2GetNominalsOfContinuousStates", STATE_INSTANTIATED | EVALUATION_STATES},
};

const char* function_name(Function function) { return kFunctions[function].name; }

/* Log categories of modelDescription.xml, in the order of its <LogCategories>. */
static const char* const kLogCategories[LOG_CATEGORY_COUNT] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard",
                                                             "logStatusError", "logAll"};

static int category_index(const char* category) {
    for (int k = 0; k < LOG_CATEGORY_COUNT; ++k)
        if (strcmp(category, kLogCategories[k]) == 0) return k;
    return -1;
}

/* Refusals and failures are always reported; other categories only when the host enabled them. */
void log_message(const Instance* instance, fmi2Status status, const char* category, const char* format, ...) {
    if (instance == NULL || instance->logger == NULL) return;
    const int index = category_index(category);
    const int always = status == fmi2Error || status == fmi2Discard || status == fmi2Fatal;
    if (!always && (index < 0 || !instance->category_enabled[index]) &&
        !instance->category_enabled[LOG_CATEGORY_COUNT - 1])
        return;
    char text[1024];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    /* The logger treats its message as a format string: escape every '%'. */
    char escaped[2 * sizeof text];
    size_t j = 0;
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; ++i) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    instance->logger(instance->environment, instance->instance_name, status, category, escaped);
}

static void core_log(void* context, GimbalStatus status, const char* category, const char* message) {
    static const fmi2Status kStatus[] = {fmi2OK, fmi2Warning, fmi2Discard, fmi2Error};
    const Instance* instance = (const Instance*)context;
    /* The core names no interface function: say which one the message comes from. */
    if (instance->calling != NULL)
        log_message(instance, kStatus[status], category, "%s: %s", instance->calling, message);
    else
        log_message(instance, kStatus[status], category, "%s", message);
}

static int core_log_enabled(void* context, const char* category) {
    const Instance* instance = (const Instance*)context;
    const int index = category_index(category);
    return instance->logger != NULL &&
           ((index >= 0 && instance->category_enabled[index]) || instance->category_enabled[LOG_CATEGORY_COUNT - 1]);
}

fmi2Status from_core(GimbalStatus status) {
    switch (status) {
        case GIMBAL_OK: return fmi2OK;
        case GIMBAL_WARNING: return fmi2Warning;
        case GIMBAL_DISCARD: return fmi2Discard;
        default: return fmi2Error;
    }
}

const char* state_name(InstanceState state) {
    switch (state) {
        case STATE_INSTANTIATED: return "instantiated";
        case STATE_INITIALIZATION: return "initialization mode";
        case STATE_STEP_COMPLETE: return "step complete";
        case STATE_STEP_FAILED: return "step failed";
        case STATE_TERMINATED: return "terminated";
        case STATE_EVENT_MODE: return "event mode";
        case STATE_CONTINUOUS_TIME: return "continuous-time mode";
        default: return "error";
    }
}

/* NULL-safe check that a call is allowed in the instance's current state. */
int allowed(Instance* instance, Function function) {
    if (instance == NULL) return 0;
    if (instance->state & kFunctions[function].states) {
        instance->calling = kFunctions[function].name; /* the prefix of the core's messages in this call */
        return 1;
    }
    log_message(instance, fmi2Error, "logStatusError", "%s is not allowed in state '%s'", kFunctions[function].name,
                state_name(instance->state));
    return 0;
}

int not_null(Instance* instance, const char* function, const void* pointer, const char* argument) {
    if (pointer != NULL) return 1;
    log_message(instance, fmi2Error, "logStatusError", "%s: argument %s is a null pointer", function, argument);
    return 0;
}

/* ---------------------------------------------------------------- inquiry, logging, lifetime */

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

static fmi2Status impl_SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetDebugLogging)) return fmi2Error;
    if (nCategories == 0) {
        for (int k = 0; k < LOG_CATEGORY_COUNT; ++k) instance->category_enabled[k] = loggingOn ? 1 : 0;
        return fmi2OK;
    }
    if (!not_null(instance, "fmi2SetDebugLogging", categories, "categories")) return fmi2Error;
    for (size_t i = 0; i < nCategories; ++i) {
        const int index = categories[i] != NULL ? category_index(categories[i]) : -1;
        if (index < 0) {
            log_message(instance, fmi2Error, "logStatusError", "fmi2SetDebugLogging: unknown log category '%s'",
                        categories[i] != NULL ? categories[i] : "(null)");
            return fmi2Error;
        }
        instance->category_enabled[index] = loggingOn ? 1 : 0;
    }
    return fmi2OK;
}

static fmi2Component impl_Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->logger == NULL) return NULL; /* nowhere to say why */
    Instance probe = {0};
    probe.logger = functions->logger;
    probe.environment = functions->componentEnvironment;
    probe.instance_name = (char*)(instanceName != NULL ? instanceName : "?");
    if (instanceName == NULL || instanceName[0] == '\0') {
        log_message(&probe, fmi2Error, "logStatusError", "fmi2Instantiate: instanceName must be a non-empty string");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange) {
        log_message(&probe, fmi2Error, "logStatusError",
                    "fmi2Instantiate: fmuType = %d is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)", (int)fmuType);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, GIMBAL_GUID) != 0) {
        log_message(&probe, fmi2Error, "logStatusError", "fmi2Instantiate: GUID '%s' does not match this FMU's '%s'",
                    fmuGUID != NULL ? fmuGUID : "(null)", GIMBAL_GUID);
        return NULL;
    }
    Instance* instance = (Instance*)calloc(1, sizeof(Instance));
    char* name = (char*)malloc(strlen(instanceName) + 1);
    if (instance == NULL || name == NULL) {
        free(instance);
        free(name);
        log_message(&probe, fmi2Error, "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    strcpy(name, instanceName);
    instance->logger = functions->logger;
    instance->environment = functions->componentEnvironment;
    instance->instance_name = name;
    for (int k = 0; k < LOG_CATEGORY_COUNT; ++k) instance->category_enabled[k] = loggingOn ? 1 : 0;
    instance->type = fmuType;
    instance->calling = "fmi2Instantiate";
    instance->core = gimbal_core_create(core_log, core_log_enabled, instance);
    if (instance->core != NULL && fmuType == fmi2ModelExchange &&
        gimbal_core_use_continuous_time(instance->core) != GIMBAL_OK) {
        gimbal_core_destroy(instance->core);
        instance->core = NULL;
    }
    if (instance->core == NULL) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2Instantiate: out of memory");
        free(name);
        free(instance);
        return NULL;
    }
    instance->state = STATE_INSTANTIATED;
    return instance;
}

static void impl_FreeInstance(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (instance == NULL) return;
    fmu_states_release_all(&instance->states);
    gimbal_core_destroy(instance->core);
    free(instance->instance_name);
    free(instance);
}

/* ---------------------------------------------------------------- initialization and termination */

static fmi2Status impl_SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetupExperiment)) return fmi2Error;
    if (!isfinite(startTime) || (stopTimeDefined && (!isfinite(stopTime) || stopTime < startTime))) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2SetupExperiment: startTime = %g, stopTime = %g: times must be finite and stopTime >= startTime",
                    startTime, stopTime);
        return fmi2Error;
    }
    const fmi2Status status = from_core(gimbal_core_set_master_tolerance(instance->core, toleranceDefined != fmi2False, tolerance));
    if (status > fmi2Warning) return status;
    instance->time = startTime;
    instance->stop_time = stopTime;
    instance->stop_time_defined = stopTimeDefined ? 1 : 0;
    return fmi2OK;
}

static fmi2Status impl_EnterInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_EnterInitializationMode)) return fmi2Error;
    instance->state = STATE_INITIALIZATION;
    return fmi2OK;
}

static fmi2Status impl_ExitInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_ExitInitializationMode)) return fmi2Error;
    const fmi2Status status = from_core(gimbal_core_initialize(instance->core, instance->time));
    if (status > fmi2Warning) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2ExitInitializationMode: initialization refused; fix the values above and retry");
        return fmi2Error; /* still in initialization mode: the master may correct and retry */
    }
    instance->last_successful_time = instance->time;
    /* Model Exchange starts in event mode: the host settles the modes with fmi2NewDiscreteStates. */
    instance->state = instance->type == fmi2ModelExchange ? STATE_EVENT_MODE : STATE_STEP_COMPLETE;
    return status;
}

static fmi2Status impl_Terminate(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_Terminate)) return fmi2Error;
    instance->state = STATE_TERMINATED;
    return fmi2OK;
}

static fmi2Status impl_Reset(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_Reset)) return fmi2Error;
    const fmi2Status status = from_core(gimbal_core_reset(instance->core));
    if (status > fmi2Warning) {
        instance->state = STATE_ERROR;
        return status;
    }
    instance->time = 0.0;
    instance->stop_time_defined = 0;
    instance->last_successful_time = 0.0;
    instance->last_step_status = fmi2OK;
    instance->state = STATE_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- getting and setting values */

static int settable(Instance* instance, const GimbalVariableInfo* info) {
    switch (instance->state) {
        case STATE_INSTANTIATED:
        case STATE_INITIALIZATION:
            /* The rotors (initial="approx") stay settable in Initialization Mode as when they were
               "exact": scripts that set them there keep working. */
            return info->causality == GIMBAL_INPUT || info->initial == GIMBAL_INITIAL_EXACT ||
                   info->initial == GIMBAL_INITIAL_APPROX;
        case STATE_STEP_COMPLETE:
        case STATE_EVENT_MODE:
        case STATE_CONTINUOUS_TIME:
            return info->causality == GIMBAL_INPUT ||
                   (info->causality == GIMBAL_PARAMETER && info->variability == GIMBAL_TUNABLE);
        default:
            return 0;
    }
}

static const char* const kTypeName[] = {"Real", "Integer", "Boolean"};

/* Common checks of every fmi2Set*: state, pointers, value reference, and the variable's settability. */
static int check_set(Instance* instance, Function id, GimbalType type, const fmi2ValueReference vr[], size_t nvr,
                     const void* value) {
    if (!allowed(instance, id)) return 0;
    const char* function = kFunctions[id].name;
    if (nvr == 0) return 1;
    if (!not_null(instance, function, vr, "vr") || !not_null(instance, function, value, "value")) return 0;
    /* The common case in one pass through the core's table; the variable at fault is then named below. */
    const int initialized = !(instance->state & (STATE_INSTANTIATED | STATE_INITIALIZATION));
    const size_t first_refused = gimbal_first_unsettable(type, vr, nvr, initialized);
    for (size_t i = first_refused; i < nvr; ++i) {
        GimbalVariableInfo info;
        if (!gimbal_variable_info(type, vr[i], &info)) {
            log_message(instance, fmi2Error, "logStatusError", "%s: value reference %u is not a%s %s variable", function,
                        (unsigned)vr[i], type == GIMBAL_INTEGER ? "n" : "", kTypeName[type]);
            return 0;
        }
        if (!settable(instance, &info)) {
            log_message(instance, fmi2Error, "logStatusError", "%s: %s cannot be set in state '%s'", function, info.name,
                        state_name(instance->state));
            return 0;
        }
    }
    return 1;
}

static int check_get(Instance* instance, Function id, const fmi2ValueReference vr[], size_t nvr, const void* value) {
    if (!allowed(instance, id)) return 0;
    const char* function = kFunctions[id].name;
    if (nvr == 0) return 1;
    return not_null(instance, function, vr, "vr") && not_null(instance, function, value, "value");
}

static fmi2Status impl_SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, FN_SetReal, GIMBAL_REAL, vr, nvr, value)) return fmi2Error;
    /* The core checks every value before it applies any (all or nothing) and names a non-finite one. */
    return nvr == 0 ? fmi2OK : from_core(gimbal_core_set_reals(instance->core, vr, nvr, value));
}

static fmi2Status impl_GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, FN_GetReal, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_get_real(instance->core, vr[i], &value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

static fmi2Status impl_SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, FN_SetInteger, GIMBAL_INTEGER, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_set_integer(instance->core, vr[i], value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

static fmi2Status impl_GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, FN_GetInteger, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const fmi2Status status = from_core(gimbal_core_get_integer(instance->core, vr[i], &v));
        if (status > fmi2Warning) return status;
        value[i] = v;
    }
    return fmi2OK;
}

static fmi2Status impl_SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, FN_SetBoolean, GIMBAL_BOOLEAN, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_set_boolean(instance->core, vr[i], value[i] != fmi2False));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

static fmi2Status impl_GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, FN_GetBoolean, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const fmi2Status status = from_core(gimbal_core_get_boolean(instance->core, vr[i], &v));
        if (status > fmi2Warning) return status;
        value[i] = v ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

/* The model has no String variables: any value reference is refused. */
static fmi2Status impl_GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, FN_GetString, vr, nvr, value)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    log_message(instance, fmi2Error, "logStatusError", "fmi2GetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return fmi2Error;
}

static fmi2Status impl_SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetString)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (!not_null(instance, "fmi2SetString", vr, "vr") || !not_null(instance, "fmi2SetString", value, "value"))
        return fmi2Error;
    log_message(instance, fmi2Error, "logStatusError", "fmi2SetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return fmi2Error;
}

/* ---------------------------------------------------------------- capabilities not offered (yet) */

static fmi2Status unsupported(fmi2Component c, Function function, const char* declaration) {
    Instance* instance = (Instance*)c;
    if (instance != NULL)
        log_message(instance, fmi2Error, "logStatusError", "%s is not supported: modelDescription.xml declares %s",
                    kFunctions[function].name, declaration);
    return fmi2Error;
}

/* ---------------------------------------------------------------- FMU states */

static size_t state_record_size(void) { return sizeof(StateHeader) + gimbal_core_snapshot_size(); }

/* A registered record of this instance, or NULL with the refusal logged. */
static unsigned char* own_state(Instance* instance, Function function, const void* state) {
    if (state == NULL) {
        log_message(instance, fmi2Error, "logStatusError", "%s: argument FMUstate is a null pointer", kFunctions[function].name);
        return NULL;
    }
    if (fmu_states_find(&instance->states, state) < 0) {
        log_message(instance, fmi2Error, "logStatusError",
                    "%s: FMUstate %p is not an FMU state of instance '%s' (not handed out by its fmi2GetFMUstate or "
                    "fmi2DeSerializeFMUstate, or already freed)",
                    kFunctions[function].name, state, instance->instance_name);
        return NULL;
    }
    return (unsigned char*)state;
}

static const char* state_name_of(int32_t state) { return state_name((InstanceState)state); }

static const FmuStateRules kStateRules = {
    FMU_STATE_STATES, RUNNING_STATES | STATE_TERMINATED, fmi2Pending, 1, 0, 0, state_name_of,
};

/* The wrapper's fields of a record, range-checked, and the core's snapshot checked by the core; a
 * record that could not have been saved by this FMU is refused with the reason. */
static int valid_state_content(Instance* instance, Function function, const unsigned char* record) {
    StateHeader header;
    memcpy(&header, record, sizeof header);
    char text[160];
    const char* problem = fmu_state_header_problem(&header, &kStateRules, instance->type == fmi2ModelExchange);
    if (problem == NULL) {
        int initialized = 0;
        if (from_core(gimbal_core_check_snapshot(instance->core, record + sizeof header, &initialized)) > fmi2Warning)
            return 0;
        problem = fmu_state_model_problem(&header, &kStateRules, initialized, text, sizeof text);
    }
    if (problem != NULL) {
        log_message(instance, fmi2Error, "logStatusError", "%s: the FMU state is refused: %s", kFunctions[function].name,
                    problem);
        return 0;
    }
    return 1;
}

static fmi2Status impl_GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetFMUstate)) return fmi2Error;
    if (!not_null(instance, "fmi2GetFMUstate", FMUstate, "FMUstate")) return fmi2Error;
    /* Overwrite the host's previous state when it hands back one of ours, as the standard allows.
     * Anything else (FMI4j passes an uninitialised pointer) is not ours to touch: take a new record. */
    unsigned char* record = fmu_states_find(&instance->states, *FMUstate) >= 0 ? (unsigned char*)*FMUstate : NULL;
    const int fresh = record == NULL;
    if (fresh) {
        record = (unsigned char*)calloc(1, state_record_size());
        if (record == NULL || !fmu_states_add(&instance->states, record)) {
            free(record);
            log_message(instance, fmi2Error, "logStatusError", "fmi2GetFMUstate: out of memory");
            return fmi2Error;
        }
    }
    StateHeader header;
    fmu_state_header_init(&header, STATE_MAGIC, state_record_size(), GIMBAL_GUID);
    header.state = (int32_t)instance->state;
    header.time = instance->time;
    header.stop_time = instance->stop_time;
    header.stop_time_defined = instance->stop_time_defined;
    header.last_successful_time = instance->last_successful_time;
    header.last_step_status = (int32_t)instance->last_step_status;
    if (from_core(gimbal_core_save(instance->core, record + sizeof header)) > fmi2Warning) {
        if (fresh) fmu_states_release(&instance->states, fmu_states_find(&instance->states, record));
        return fmi2Error;
    }
    memcpy(record, &header, sizeof header);
    *FMUstate = record;
    return fmi2OK;
}

static fmi2Status impl_SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetFMUstate)) return fmi2Error;
    const unsigned char* record = own_state(instance, FN_SetFMUstate, FMUstate);
    /* A registered record was made by fmi2GetFMUstate or checked whole by fmi2DeSerializeFMUstate;
     * the core's restore checks its snapshot once more before committing anything. */
    if (record == NULL) return fmi2Error;
    StateHeader header;
    memcpy(&header, record, sizeof header);
    /* A refused snapshot leaves the core as it was: so does the wrapper. */
    const fmi2Status status = from_core(gimbal_core_restore(instance->core, record + sizeof header));
    if (status > fmi2Warning) return status;
    instance->state = (InstanceState)header.state;
    instance->time = header.time;
    instance->stop_time = header.stop_time;
    instance->stop_time_defined = header.stop_time_defined;
    instance->last_successful_time = header.last_successful_time;
    instance->last_step_status = (fmi2Status)header.last_step_status;
    return fmi2OK;
}

static fmi2Status impl_FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_FreeFMUstate)) return fmi2Error;
    if (FMUstate == NULL) return fmi2OK;
    /* The Reference-FMUs' fmusim passes the state itself instead of its address: recognised before
     * anything behind the pointer is read. */
    if (fmu_states_find(&instance->states, FMUstate) >= 0) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2FreeFMUstate: the argument is an FMU state, not the address of one (pass &state); nothing was "
                    "freed");
        return fmi2Error;
    }
    if (*FMUstate == NULL) return fmi2OK;
    const long index = fmu_states_find(&instance->states, *FMUstate);
    if (index < 0) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2FreeFMUstate: *FMUstate = %p is not an FMU state of instance '%s' (never handed out, or "
                    "already freed); nothing was freed",
                    *FMUstate, instance->instance_name);
        return fmi2Error;
    }
    fmu_states_release(&instance->states, index);
    *FMUstate = NULL;
    return fmi2OK;
}

static fmi2Status impl_SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SerializedFMUstateSize)) return fmi2Error;
    if (own_state(instance, FN_SerializedFMUstateSize, FMUstate) == NULL ||
        !not_null(instance, "fmi2SerializedFMUstateSize", size, "size"))
        return fmi2Error;
    *size = state_record_size();
    return fmi2OK;
}

static fmi2Status impl_SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SerializeFMUstate)) return fmi2Error;
    const unsigned char* record = own_state(instance, FN_SerializeFMUstate, FMUstate);
    if (record == NULL || !not_null(instance, "fmi2SerializeFMUstate", serializedState, "serializedState"))
        return fmi2Error;
    if (size < state_record_size()) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2SerializeFMUstate: size %zu is below the %zu bytes needed",
                    size, state_record_size());
        return fmi2Error;
    }
    fmu_state_serialize(record, state_record_size(), (unsigned char*)serializedState);
    return fmi2OK;
}

static fmi2Status impl_DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                           fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_DeSerializeFMUstate)) return fmi2Error;
    if (!not_null(instance, "fmi2DeSerializeFMUstate", serializedState, "serializedState") ||
        !not_null(instance, "fmi2DeSerializeFMUstate", FMUstate, "FMUstate"))
        return fmi2Error;
    const char* problem = fmu_state_integrity_problem((const unsigned char*)serializedState, size, state_record_size(),
                                                      GIMBAL_GUID, STATE_MAGIC);
    if (problem != NULL) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2DeSerializeFMUstate: the %zu bytes are refused: %s (an FMU state of this FMU, GUID %s, has %zu "
                    "bytes)",
                    size, problem, GIMBAL_GUID, state_record_size());
        return fmi2Error;
    }
    if (!valid_state_content(instance, FN_DeSerializeFMUstate, (const unsigned char*)serializedState)) return fmi2Error;
    void* record = malloc(size);
    if (record == NULL || !fmu_states_add(&instance->states, record)) {
        free(record);
        log_message(instance, fmi2Error, "logStatusError", "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    memcpy(record, serializedState, size);
    *FMUstate = record;
    return fmi2OK;
}

/* The `index`-th unknown or known (`role`) of fmi2GetDirectionalDerivative: a Real variable of the
 * given causality, whose description it writes to `info`; else logged, 0. */
static int directional_variable(Instance* instance, const char* role, size_t index, fmi2ValueReference vr,
                                GimbalCausality causality, GimbalVariableInfo* info) {
    const char* function = "fmi2GetDirectionalDerivative";
    const char* kind = causality == GIMBAL_OUTPUT ? "output" : "input";
    if (!gimbal_variable_info(GIMBAL_REAL, vr, info)) {
        log_message(instance, fmi2Error, "logStatusError", "%s: %s %zu: value reference %u is not a Real variable",
                    function, role, index, (unsigned)vr);
        return 0;
    }
    if (info->causality != causality) {
        log_message(instance, fmi2Error, "logStatusError", "%s: %s %s is not an %s: in Co-Simulation the %ss are the %ss",
                    function, role, info->name, kind, role, kind);
        return 0;
    }
    return 1;
}

/* Directional derivatives at a communication point (FMI 2.0, section 4.2.1 with 3.2.1): dvUnknown =
 * (d h / d vKnown) dvKnown, where the unknowns are outputs (ModelStructure <Outputs>) and the knowns
 * inputs; a Co-Simulation FMU exposes no states, so no <Derivatives> are unknowns or knowns here.
 * The outputs of this FMU are computed by fmi2DoStep and held until the next one: setting an input
 * changes no output before the next step, which is why ModelStructure declares every output with
 * dependencies="". The partial derivatives at the current point are therefore exactly zero (no
 * difference quotient, no analytic term is needed); what is computed here is the check of the
 * arguments. The linearization of the continuous model itself (A, B, C, D, with the direct
 * feedthrough of e.g. a quasi-static motor's current) is a different quantity. */
static fmi2Status impl_GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetDirectionalDerivative)) return fmi2Error;
    if (instance->type == fmi2ModelExchange)
        return model_exchange_directional_derivative(instance, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown,
                                                     dvUnknown);
    const char* function = "fmi2GetDirectionalDerivative";
    if (nUnknown > 0 && (!not_null(instance, function, vUnknown_ref, "vUnknown_ref") ||
                         !not_null(instance, function, dvUnknown, "dvUnknown")))
        return fmi2Error;
    if (nKnown > 0 && (!not_null(instance, function, vKnown_ref, "vKnown_ref") ||
                       !not_null(instance, function, dvKnown, "dvKnown")))
        return fmi2Error;
    GimbalVariableInfo info;
    for (size_t i = 0; i < nUnknown; ++i)
        if (!directional_variable(instance, "unknown", i, vUnknown_ref[i], GIMBAL_OUTPUT, &info)) return fmi2Error;
    for (size_t j = 0; j < nKnown; ++j) {
        if (!directional_variable(instance, "known", j, vKnown_ref[j], GIMBAL_INPUT, &info)) return fmi2Error;
        if (!isfinite(dvKnown[j])) {
            log_message(instance, fmi2Error, "logStatusError", "%s: the seed of %s must be finite", function, info.name);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nUnknown; ++i) dvUnknown[i] = 0.0;
    return fmi2OK;
}

static fmi2Status impl_SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetRealInputDerivatives)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (!not_null(instance, "fmi2SetRealInputDerivatives", vr, "vr") ||
        !not_null(instance, "fmi2SetRealInputDerivatives", order, "order") ||
        !not_null(instance, "fmi2SetRealInputDerivatives", value, "value"))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status =
            from_core(gimbal_core_set_input_derivative(instance->core, vr[i], (int)order[i], value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

static fmi2Status impl_GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, FN_GetRealOutputDerivatives, "maxOutputDerivativeOrder=\"0\"");
}

/* ---------------------------------------------------------------- stepping */

static fmi2Status impl_DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance* instance = (Instance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, FN_DoStep)) return fmi2Error;
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize)) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2DoStep: communicationStepSize = %g must be finite and > 0",
                    communicationStepSize);
        return fmi2Error;
    }
    /* The master's point becomes the FMU's time (common/communication_point.h). */
    if (!communication_point_matches(instance->time, currentCommunicationPoint, communicationStepSize)) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2DoStep: currentCommunicationPoint = %.17g does not match the FMU's time %.17g",
                    currentCommunicationPoint, instance->time);
        return fmi2Error;
    }
    const double end_time = currentCommunicationPoint + communicationStepSize;
    if (instance->stop_time_defined &&
        communication_step_passes_stop_time(end_time, instance->stop_time, communicationStepSize)) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2DoStep: step to t = %.17g passes the stopTime %.17g",
                    end_time, instance->stop_time);
        return fmi2Error;
    }
    const fmi2Status status =
        from_core(gimbal_core_do_step(instance->core, currentCommunicationPoint, communicationStepSize));
    instance->last_step_status = status;
    if (status > fmi2Warning) {
        instance->state = status == fmi2Discard ? STATE_STEP_FAILED : STATE_ERROR;
        return status;
    }
    instance->time = end_time;
    instance->last_successful_time = end_time;
    return status;
}

static fmi2Status impl_CancelStep(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_CancelStep)) return fmi2Error; /* doStep never runs asynchronously */
    return fmi2Error;
}

static fmi2Status impl_GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetStatus)) return fmi2Error;
    if (!not_null(instance, "fmi2GetStatus", value, "value")) return fmi2Error;
    if (s != fmi2DoStepStatus) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetStatus: status kind %d is not a fmi2Status", (int)s);
        return fmi2Error;
    }
    *value = instance->last_step_status;
    return fmi2OK;
}

static fmi2Status impl_GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetRealStatus))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetRealStatus", value, "value")) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetRealStatus: status kind %d is not a Real status", (int)s);
        return fmi2Error;
    }
    *value = instance->last_successful_time;
    return fmi2OK;
}

static fmi2Status impl_GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetIntegerStatus)) return fmi2Error;
    if (!not_null(instance, "fmi2GetIntegerStatus", value, "value")) return fmi2Error;
    log_message(instance, fmi2Error, "logStatusError", "fmi2GetIntegerStatus: status kind %d has no Integer value", (int)s);
    return fmi2Error;
}

static fmi2Status impl_GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetBooleanStatus))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetBooleanStatus", value, "value")) return fmi2Error;
    if (s != fmi2Terminated) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetBooleanStatus: status kind %d has no Boolean value", (int)s);
        return fmi2Error;
    }
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return fmi2OK;
}

static fmi2Status impl_GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_GetStringStatus))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetStringStatus", value, "value")) return fmi2Error;
    if (s != fmi2PendingStatus) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetStringStatus: status kind %d has no String value", (int)s);
        return fmi2Error;
    }
    *value = ""; /* doStep is synchronous: never pending */
    return fmi2OK;
}

/* ---------------------------------------------------------------- the exported functions */

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetDebugLogging(c, loggingOn, nCategories, categories));
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    IN_FMU_FP_ENVIRONMENT(fmi2Component,
                          impl_Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions, visible, loggingOn));
}

void fmi2FreeInstance(fmi2Component c) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    impl_FreeInstance(c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          impl_SetupExperiment(c, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_EnterInitializationMode(c));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_ExitInitializationMode(c));
}

fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Terminate(c)); }

fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Reset(c)); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetReal(c, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetInteger(c, vr, nvr, value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetBoolean(c, vr, nvr, value));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetString(c, vr, nvr, value));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetReal(c, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetInteger(c, vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetBoolean(c, vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetString(c, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetFMUstate(c, FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetFMUstate(c, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_FreeFMUstate(c, FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SerializedFMUstateSize(c, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SerializeFMUstate(c, FMUstate, serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_DeSerializeFMUstate(c, serializedState, size, FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          impl_GetDirectionalDerivative(c, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetRealInputDerivatives(c, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetRealOutputDerivatives(c, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          impl_DoStep(c, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint));
}

fmi2Status fmi2CancelStep(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_CancelStep(c)); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetStatus(c, s, value));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetRealStatus(c, s, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetIntegerStatus(c, s, value));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetBooleanStatus(c, s, value));
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetStringStatus(c, s, value));
}
