/* The FMI 3.0 face of the FMI instance layer (fmi3_face.h). */
#include "fmi_layer/fmi3_face.h"

#include "fmi_layer/host_fp_environment.h"

static const char* state_name(int state) {
    switch (state) {
        case S_INSTANTIATED: return "instantiated";
        case S_INITIALIZATION: return "initialization mode";
        case S_EVENT: return "event mode";
        case S_CONTINUOUS_TIME: return "continuous-time mode";
        case S_STEP: return "step mode";
        case S_STEP_DISCARDED: return "step discarded";
        case S_TERMINATED: return "terminated";
        default: return "error";
    }
}

static void deliver(const FmiInstance* instance, FmiStatus status, const char* category, const char* message) {
    ((fmi3LogMessageCallback)instance->logger)(instance->environment, (fmi3Status)status, category, message);
}

/* FMI 3.0's header records no step status; the interface an instance serves shows in its state. */
const FmiFace kFmi3Face = {
    .deliver = deliver,
    .logger_formats_message = 0,
    .resource_location_is_uri = 0,
    .instantiated_state = S_INSTANTIATED,
    .any_state = S_ANY,
    .step_failed_state = S_STEP_DISCARDED,
    .error_state = S_ERROR,
    .before_initialized_states = S_INSTANTIATED | S_INITIALIZATION,
    .state_name = state_name,
    .state_magic = STATE_MAGIC_FMI3,
    .state_rules = {S_FMU_STATE, S_RUNNING | S_TERMINATED, -1, 0, S_CONTINUOUS_TIME, S_STEP | S_STEP_DISCARDED,
                    state_name},
    .get_fmu_state = "fmi3GetFMUState",
    .deserialize_fmu_state = "fmi3DeserializeFMUState",
    .fmu_state_argument = "FMUState",
};

FmiInstance* fmi3_instantiate(const FmiModel* model, const char* function, const char* type_refusal, fmi3String name,
                              fmi3String token, int model_exchange, int event_mode_used, int early_return_allowed,
                              fmi3Boolean logging_on, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log) {
    FmiInstance probe = {0};
    probe.face = &kFmi3Face;
    probe.model = model;
    probe.logger = (FmiHostLogger)log;
    probe.environment = environment;
    probe.name = (char*)name;
    probe.model_exchange = model_exchange;
    probe.event_mode_used = event_mode_used;
    probe.early_return_allowed = early_return_allowed;
    return fmi_instantiate(&probe, function, type_refusal, token, "instantiationToken", logging_on ? 1 : 0);
}

static fmi3Status set_debug_logging(FmiInstance* instance, fmi3Boolean on, size_t count, const fmi3String categories[]) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi_set_debug_logging(instance, "fmi3SetDebugLogging", on ? 1 : 0, count, categories);
}

/* ---------------------------------------------------------------- refusals */

fmi3Status fmi3_refuse_absent_type(FmiInstance* instance, const char* function, int set, const fmi3ValueReference vr[],
                                   size_t nvr) {
    if (!fmi_allowed(instance, function, set ? S_SET : S_GET)) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    if (!fmi_not_null(instance, function, vr, "valueReferences")) return fmi3Error;
    fmi_log_error(instance, "%s: value reference %u: the model has no variable of this type", function, (unsigned)vr[0]);
    return fmi3Error;
}

fmi3Status fmi3_refuse_not_offered(FmiInstance* instance, const char* function, const char* why) {
    if (!fmi_allowed(instance, function, S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_refuse(instance, function, why);
}

/* ---------------------------------------------------------------- FMU states: each function's state check, then
 * the layer's call; exported here, as every FMU of the project offers them alike. */

static fmi3Status get_fmu_state(FmiInstance* instance, fmi3FMUState* state) {
    const char* function = "fmi3GetFMUState";
    if (!fmi_allowed(instance, function, S_FMU_STATE)) return fmi3Error;
    return (fmi3Status)fmi_get_fmu_state(instance, function, state);
}

/* A discarded step is rolled back with an earlier state. */
static fmi3Status set_fmu_state(FmiInstance* instance, fmi3FMUState state) {
    const char* function = "fmi3SetFMUState";
    if (!fmi_allowed(instance, function, S_FMU_STATE | S_STEP_DISCARDED)) return fmi3Error;
    return (fmi3Status)fmi_set_fmu_state(instance, function, state);
}

static fmi3Status free_fmu_state(FmiInstance* instance, fmi3FMUState* state) {
    const char* function = "fmi3FreeFMUState";
    if (!fmi_allowed(instance, function, S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_free_fmu_state(instance, function, state);
}

static fmi3Status serialized_fmu_state_size(FmiInstance* instance, fmi3FMUState state, size_t* size) {
    const char* function = "fmi3SerializedFMUStateSize";
    if (!fmi_allowed(instance, function, S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_serialized_fmu_state_size(instance, function, state, size);
}

static fmi3Status serialize_fmu_state(FmiInstance* instance, fmi3FMUState state, fmi3Byte bytes[], size_t size) {
    const char* function = "fmi3SerializeFMUState";
    if (!fmi_allowed(instance, function, S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_serialize_fmu_state(instance, function, state, bytes, size);
}

static fmi3Status deserialize_fmu_state(FmiInstance* instance, const fmi3Byte bytes[], size_t size, fmi3FMUState* state) {
    const char* function = "fmi3DeserializeFMUState";
    if (!fmi_allowed(instance, function, S_ANY)) return fmi3Error;
    return (fmi3Status)fmi_deserialize_fmu_state(instance, function, bytes, size, state);
}

#define OWN_INSTANCE ((FmiInstance*)instance)

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_debug_logging(OWN_INSTANCE, loggingOn, nCategories, categories));
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_fmu_state(OWN_INSTANCE, FMUState));
}
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_fmu_state(OWN_INSTANCE, FMUState));
}
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, free_fmu_state(OWN_INSTANCE, FMUState));
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, serialized_fmu_state_size(OWN_INSTANCE, FMUState, size));
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, serialize_fmu_state(OWN_INSTANCE, FMUState, serializedState, size));
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState* FMUState) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, deserialize_fmu_state(OWN_INSTANCE, serializedState, size, FMUState));
}
