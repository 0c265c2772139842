/* FMI 2.0 Co-Simulation wrapper: the state machine, argument checks and logging of the standard,
 * over the C interface of the dynamics core (model_core/include/gimbal/gimbal_c_api.h). */
#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "gimbal/gimbal_c_api.h"

typedef enum {
    STATE_INSTANTIATED = 1 << 0,
    STATE_INITIALIZATION = 1 << 1,
    STATE_STEP_COMPLETE = 1 << 2,
    STATE_STEP_FAILED = 1 << 3,
    STATE_TERMINATED = 1 << 4,
    STATE_ERROR = 1 << 5,
} InstanceState;

#define GET_STATES (STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED | STATE_ERROR)
#define SET_STATES (STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE)
#define ANY_STATE (STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED | STATE_ERROR)

/* Log categories of modelDescription.xml, in the order of its <LogCategories>. */
static const char* const kLogCategories[] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logAll"};
enum { LOG_CATEGORY_COUNT = sizeof kLogCategories / sizeof kLogCategories[0] };

typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char* instance_name;
    GimbalCore* core;
    InstanceState state;
    int category_enabled[LOG_CATEGORY_COUNT];
    double time;
    double stop_time;
    int stop_time_defined;
    double last_successful_time;
    fmi2Status last_step_status;
} Instance;

static int category_index(const char* category) {
    for (int k = 0; k < LOG_CATEGORY_COUNT; ++k)
        if (strcmp(category, kLogCategories[k]) == 0) return k;
    return -1;
}

/* Refusals and failures are always reported; other categories only when the host enabled them. */
static void log_message(const Instance* instance, fmi2Status status, const char* category, const char* format, ...) {
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
    log_message((const Instance*)context, kStatus[status], category, "%s", message);
}

static int core_log_enabled(void* context, const char* category) {
    const Instance* instance = (const Instance*)context;
    const int index = category_index(category);
    return instance->logger != NULL &&
           ((index >= 0 && instance->category_enabled[index]) || instance->category_enabled[LOG_CATEGORY_COUNT - 1]);
}

static fmi2Status from_core(GimbalStatus status) {
    switch (status) {
        case GIMBAL_OK: return fmi2OK;
        case GIMBAL_WARNING: return fmi2Warning;
        case GIMBAL_DISCARD: return fmi2Discard;
        default: return fmi2Error;
    }
}

static const char* state_name(InstanceState state) {
    switch (state) {
        case STATE_INSTANTIATED: return "instantiated";
        case STATE_INITIALIZATION: return "initialization mode";
        case STATE_STEP_COMPLETE: return "step complete";
        case STATE_STEP_FAILED: return "step failed";
        case STATE_TERMINATED: return "terminated";
        default: return "error";
    }
}

/* NULL-safe check that a call is allowed in the instance's current state. */
static int allowed(Instance* instance, const char* function, int states) {
    if (instance == NULL) return 0;
    if (instance->state & states) return 1;
    log_message(instance, fmi2Error, "logStatusError", "%s is not allowed in state '%s'", function,
                state_name(instance->state));
    return 0;
}

static int not_null(Instance* instance, const char* function, const void* pointer, const char* argument) {
    if (pointer != NULL) return 1;
    log_message(instance, fmi2Error, "logStatusError", "%s: argument %s is a null pointer", function, argument);
    return 0;
}

/* ---------------------------------------------------------------- inquiry, logging, lifetime */

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetDebugLogging", ANY_STATE)) return fmi2Error;
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

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
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
    if (fmuType != fmi2CoSimulation) {
        log_message(&probe, fmi2Error, "logStatusError",
                    "fmi2Instantiate: this FMU supports Co-Simulation only (fmuType = %d)", (int)fmuType);
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
    instance->core = gimbal_core_create(core_log, core_log_enabled, instance);
    if (instance->core == NULL) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2Instantiate: out of memory");
        free(name);
        free(instance);
        return NULL;
    }
    instance->state = STATE_INSTANTIATED;
    return instance;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (instance == NULL) return;
    gimbal_core_destroy(instance->core);
    free(instance->instance_name);
    free(instance);
}

/* ---------------------------------------------------------------- initialization and termination */

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance* instance = (Instance*)c;
    (void)toleranceDefined; /* solver.rtol is the tolerance of this FMU; a master's is advisory */
    (void)tolerance;
    if (!allowed(instance, "fmi2SetupExperiment", STATE_INSTANTIATED)) return fmi2Error;
    if (!isfinite(startTime) || (stopTimeDefined && (!isfinite(stopTime) || stopTime < startTime))) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2SetupExperiment: startTime = %g, stopTime = %g: times must be finite and stopTime >= startTime",
                    startTime, stopTime);
        return fmi2Error;
    }
    instance->time = startTime;
    instance->stop_time = stopTime;
    instance->stop_time_defined = stopTimeDefined ? 1 : 0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2EnterInitializationMode", STATE_INSTANTIATED)) return fmi2Error;
    instance->state = STATE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2ExitInitializationMode", STATE_INITIALIZATION)) return fmi2Error;
    const fmi2Status status = from_core(gimbal_core_initialize(instance->core, instance->time));
    if (status > fmi2Warning) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2ExitInitializationMode: initialization refused; fix the values above and retry");
        return fmi2Error; /* still in initialization mode: the master may correct and retry */
    }
    instance->last_successful_time = instance->time;
    instance->state = STATE_STEP_COMPLETE;
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2Terminate", STATE_STEP_COMPLETE | STATE_STEP_FAILED)) return fmi2Error;
    instance->state = STATE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2Reset", ANY_STATE)) return fmi2Error;
    gimbal_core_reset(instance->core);
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
            return info->causality == GIMBAL_INPUT || info->initial == GIMBAL_INITIAL_EXACT;
        case STATE_STEP_COMPLETE:
            return info->causality == GIMBAL_INPUT ||
                   (info->causality == GIMBAL_PARAMETER && info->variability == GIMBAL_TUNABLE);
        default:
            return 0;
    }
}

static const char* const kTypeName[] = {"Real", "Integer", "Boolean"};

/* Common checks of every fmi2Set*: state, pointers, value reference, and the variable's settability. */
static int check_set(Instance* instance, const char* function, GimbalType type, const fmi2ValueReference vr[],
                     size_t nvr, const void* value) {
    if (!allowed(instance, function, SET_STATES)) return 0;
    if (nvr == 0) return 1;
    if (!not_null(instance, function, vr, "vr") || !not_null(instance, function, value, "value")) return 0;
    for (size_t i = 0; i < nvr; ++i) {
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

static int check_get(Instance* instance, const char* function, const fmi2ValueReference vr[], size_t nvr,
                     const void* value) {
    if (!allowed(instance, function, GET_STATES)) return 0;
    if (nvr == 0) return 1;
    return not_null(instance, function, vr, "vr") && not_null(instance, function, value, "value");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, "fmi2SetReal", GIMBAL_REAL, vr, nvr, value)) return fmi2Error;
    /* All or nothing: a refused call must not leave some of its values applied. */
    for (size_t i = 0; i < nvr; ++i) {
        if (!isfinite(value[i])) {
            GimbalVariableInfo info;
            gimbal_variable_info(GIMBAL_REAL, vr[i], &info);
            log_message(instance, fmi2Error, "logStatusError", "fmi2SetReal: %s = %g refused: values must be finite",
                        info.name, value[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_set_real(instance->core, vr[i], value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, "fmi2GetReal", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_get_real(instance->core, vr[i], &value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, "fmi2SetInteger", GIMBAL_INTEGER, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_set_integer(instance->core, vr[i], value[i]));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, "fmi2GetInteger", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const fmi2Status status = from_core(gimbal_core_get_integer(instance->core, vr[i], &v));
        if (status > fmi2Warning) return status;
        value[i] = v;
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    Instance* instance = (Instance*)c;
    if (!check_set(instance, "fmi2SetBoolean", GIMBAL_BOOLEAN, vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const fmi2Status status = from_core(gimbal_core_set_boolean(instance->core, vr[i], value[i] != fmi2False));
        if (status > fmi2Warning) return status;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, "fmi2GetBoolean", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const fmi2Status status = from_core(gimbal_core_get_boolean(instance->core, vr[i], &v));
        if (status > fmi2Warning) return status;
        value[i] = v ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

/* The model has no String variables: any value reference is refused. */
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!check_get(instance, "fmi2GetString", vr, nvr, value)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    log_message(instance, fmi2Error, "logStatusError", "fmi2GetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetString", SET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (!not_null(instance, "fmi2SetString", vr, "vr") || !not_null(instance, "fmi2SetString", value, "value"))
        return fmi2Error;
    log_message(instance, fmi2Error, "logStatusError", "fmi2SetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return fmi2Error;
}

/* ---------------------------------------------------------------- capabilities not offered (yet) */

static fmi2Status unsupported(fmi2Component c, const char* function, const char* flag) {
    Instance* instance = (Instance*)c;
    if (instance != NULL)
        log_message(instance, fmi2Error, "logStatusError", "%s is not supported: modelDescription.xml declares %s=\"false\"",
                    function, flag);
    return fmi2Error;
}

/* An FMU state: the wrapper's own fields, then the core's snapshot bytes. Serialized as is. */
typedef struct {
    uint32_t magic;
    uint32_t size; /* of the whole record */
    char guid[64];
    int state;
    double time;
    double stop_time;
    int stop_time_defined;
    double last_successful_time;
    int last_step_status;
} StateHeader;

#define STATE_MAGIC 0x46535441u /* "FSTA" */
#define STATE_STATES (STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED)

static size_t state_record_size(void) { return sizeof(StateHeader) + gimbal_core_snapshot_size(); }

static int valid_state_record(Instance* instance, const char* function, const void* record, size_t size) {
    const StateHeader* header = (const StateHeader*)record;
    if (size != state_record_size() || header->magic != STATE_MAGIC || header->size != state_record_size() ||
        strncmp(header->guid, GIMBAL_GUID, sizeof header->guid) != 0) {
        log_message(instance, fmi2Error, "logStatusError",
                    "%s: the FMU state was not saved by this FMU (GUID %s, %u bytes expected)", function, GIMBAL_GUID,
                    (unsigned)state_record_size());
        return 0;
    }
    return 1;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetFMUstate", STATE_STATES)) return fmi2Error;
    if (!not_null(instance, "fmi2GetFMUstate", FMUstate, "FMUstate")) return fmi2Error;
    /* Reuse the host's previous state object when it hands one back, as the standard allows. */
    unsigned char* record = (unsigned char*)*FMUstate;
    if (record != NULL && !valid_state_record(instance, "fmi2GetFMUstate", record, state_record_size())) return fmi2Error;
    if (record == NULL) record = (unsigned char*)calloc(1, state_record_size());
    if (record == NULL) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetFMUstate: out of memory");
        return fmi2Error;
    }
    StateHeader* header = (StateHeader*)record;
    memset(header, 0, sizeof *header);
    header->magic = STATE_MAGIC;
    header->size = (uint32_t)state_record_size();
    strncpy(header->guid, GIMBAL_GUID, sizeof header->guid - 1);
    header->state = (int)instance->state;
    header->time = instance->time;
    header->stop_time = instance->stop_time;
    header->stop_time_defined = instance->stop_time_defined;
    header->last_successful_time = instance->last_successful_time;
    header->last_step_status = (int)instance->last_step_status;
    gimbal_core_save(instance->core, record + sizeof(StateHeader));
    *FMUstate = record;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetFMUstate", STATE_STATES)) return fmi2Error;
    if (!not_null(instance, "fmi2SetFMUstate", FMUstate, "FMUstate")) return fmi2Error;
    if (!valid_state_record(instance, "fmi2SetFMUstate", FMUstate, state_record_size())) return fmi2Error;
    const StateHeader* header = (const StateHeader*)FMUstate;
    const fmi2Status status =
        from_core(gimbal_core_restore(instance->core, (const unsigned char*)FMUstate + sizeof(StateHeader)));
    if (status > fmi2Warning) {
        instance->state = STATE_ERROR;
        return status;
    }
    instance->state = (InstanceState)header->state;
    instance->time = header->time;
    instance->stop_time = header->stop_time;
    instance->stop_time_defined = header->stop_time_defined;
    instance->last_successful_time = header->last_successful_time;
    instance->last_step_status = (fmi2Status)header->last_step_status;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2FreeFMUstate", ANY_STATE)) return fmi2Error;
    if (FMUstate == NULL) return fmi2OK;
    free(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SerializedFMUstateSize", ANY_STATE)) return fmi2Error;
    if (!not_null(instance, "fmi2SerializedFMUstateSize", FMUstate, "FMUstate") ||
        !not_null(instance, "fmi2SerializedFMUstateSize", size, "size"))
        return fmi2Error;
    *size = state_record_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SerializeFMUstate", ANY_STATE)) return fmi2Error;
    if (!not_null(instance, "fmi2SerializeFMUstate", FMUstate, "FMUstate") ||
        !not_null(instance, "fmi2SerializeFMUstate", serializedState, "serializedState"))
        return fmi2Error;
    if (!valid_state_record(instance, "fmi2SerializeFMUstate", FMUstate, state_record_size())) return fmi2Error;
    if (size < state_record_size()) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2SerializeFMUstate: size %u is below the %u bytes needed",
                    (unsigned)size, (unsigned)state_record_size());
        return fmi2Error;
    }
    memcpy(serializedState, FMUstate, state_record_size());
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* FMUstate) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2DeSerializeFMUstate", ANY_STATE)) return fmi2Error;
    if (!not_null(instance, "fmi2DeSerializeFMUstate", serializedState, "serializedState") ||
        !not_null(instance, "fmi2DeSerializeFMUstate", FMUstate, "FMUstate"))
        return fmi2Error;
    if (!valid_state_record(instance, "fmi2DeSerializeFMUstate", serializedState, size)) return fmi2Error;
    void* record = malloc(size);
    if (record == NULL) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    memcpy(record, serializedState, size);
    *FMUstate = record;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2SetRealInputDerivatives", STATE_INITIALIZATION | STATE_STEP_COMPLETE)) return fmi2Error;
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

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder");
}

/* ---------------------------------------------------------------- stepping */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance* instance = (Instance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, "fmi2DoStep", STATE_STEP_COMPLETE)) return fmi2Error;
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize)) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2DoStep: communicationStepSize = %g must be finite and > 0",
                    communicationStepSize);
        return fmi2Error;
    }
    /* Masters keep time as k*h or as a running sum: the two drift apart in the last bits over long
     * runs. A mismatch below a millionth of the step is that; the FMU keeps its own sum, so that every
     * master gets the same results. */
    const double tolerance = 1e-12 * fmax(1.0, fabs(instance->time)) + 1e-6 * communicationStepSize;
    if (!(fabs(currentCommunicationPoint - instance->time) <= tolerance)) {
        log_message(instance, fmi2Error, "logStatusError",
                    "fmi2DoStep: currentCommunicationPoint = %.17g does not match the FMU's time %.17g",
                    currentCommunicationPoint, instance->time);
        return fmi2Error;
    }
    const double end_time = instance->time + communicationStepSize;
    if (instance->stop_time_defined &&
        end_time > instance->stop_time + 1e-12 * fmax(1.0, fabs(instance->stop_time)) + 1e-6 * communicationStepSize) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2DoStep: step to t = %.17g passes the stopTime %.17g",
                    end_time, instance->stop_time);
        return fmi2Error;
    }
    const fmi2Status status =
        from_core(gimbal_core_do_step(instance->core, instance->time, communicationStepSize));
    instance->last_step_status = status;
    if (status > fmi2Warning) {
        instance->state = status == fmi2Discard ? STATE_STEP_FAILED : STATE_ERROR;
        return status;
    }
    instance->time = end_time;
    instance->last_successful_time = end_time;
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2CancelStep", 0)) return fmi2Error; /* doStep never runs asynchronously */
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetStatus", STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED)) return fmi2Error;
    if (!not_null(instance, "fmi2GetStatus", value, "value")) return fmi2Error;
    if (s != fmi2DoStepStatus) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetStatus: status kind %d is not a fmi2Status", (int)s);
        return fmi2Error;
    }
    *value = instance->last_step_status;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetRealStatus", STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetRealStatus", value, "value")) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetRealStatus: status kind %d is not a Real status", (int)s);
        return fmi2Error;
    }
    *value = instance->last_successful_time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    (void)value;
    Instance* instance = (Instance*)c;
    if (instance != NULL)
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetIntegerStatus: status kind %d has no Integer value", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetBooleanStatus", STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetBooleanStatus", value, "value")) return fmi2Error;
    if (s != fmi2Terminated) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetBooleanStatus: status kind %d has no Boolean value", (int)s);
        return fmi2Error;
    }
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, "fmi2GetStringStatus", STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED))
        return fmi2Error;
    if (!not_null(instance, "fmi2GetStringStatus", value, "value")) return fmi2Error;
    if (s != fmi2PendingStatus) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2GetStringStatus: status kind %d has no String value", (int)s);
        return fmi2Error;
    }
    *value = ""; /* doStep is synchronous: never pending */
    return fmi2OK;
}
