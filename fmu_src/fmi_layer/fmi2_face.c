/* The FMI 2.0 face of the FMI instance layer (fmi2_face.h). */
#include "fmi2_face.h"

#include <stdio.h>

static const char* state_name(int state) {
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

static void deliver(const FmiInstance* instance, FmiStatus status, const char* category, const char* message) {
    ((fmi2CallbackLogger)instance->logger)(instance->environment, instance->name != NULL ? instance->name : "?",
                                           (fmi2Status)status, category, message);
}

const FmiFace kFmi2Face = {
    .deliver = deliver,
    .logger_formats_message = 1,
    .resource_location_is_uri = 1,
    .instantiated_state = STATE_INSTANTIATED,
    .any_state = ANY_STATE,
    .step_failed_state = STATE_STEP_FAILED,
    .error_state = STATE_ERROR,
    .before_initialized_states = STATE_INSTANTIATED | STATE_INITIALIZATION,
    .state_name = state_name,
    .state_magic = STATE_MAGIC,
    .state_rules = {FMU_STATE_STATES, RUNNING_STATES | STATE_TERMINATED, fmi2Pending, 1, 0, 0, state_name},
    .get_fmu_state = "fmi2GetFMUstate",
    .deserialize_fmu_state = "fmi2DeSerializeFMUstate",
    .fmu_state_argument = "FMUstate",
};


fmi2Component fmi2_instantiate(const FmiModel* model, int model_exchange_offered, fmi2String instance_name,
                               fmi2Type type, fmi2String guid, const fmi2CallbackFunctions* functions,
                               fmi2Boolean logging_on) {
    if (functions == NULL) return NULL; /* nowhere to say why */
    FmiInstance probe = {0};
    probe.face = &kFmi2Face;
    probe.model = model;
    probe.logger = (FmiHostLogger)functions->logger;
    probe.environment = functions->componentEnvironment;
    probe.name = (char*)instance_name;
    probe.model_exchange = type == fmi2ModelExchange;
    char type_refusal[96];
    if (model_exchange_offered)
        snprintf(type_refusal, sizeof type_refusal,
                 "fmuType = %d is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)", (int)type);
    else
        snprintf(type_refusal, sizeof type_refusal,
                 "fmuType = %d: this FMU is Co-Simulation only (fmi2CoSimulation = 1)", (int)type);
    const int offered = type == fmi2CoSimulation || (model_exchange_offered && type == fmi2ModelExchange);
    return fmi_instantiate(&probe, "fmi2Instantiate", offered ? NULL : type_refusal, guid, "GUID", logging_on != fmi2False);
}
