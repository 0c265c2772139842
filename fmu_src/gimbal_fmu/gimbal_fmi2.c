/* The gimbal's FMI 2.0 face: the standard's state machine, arguments and types over the FMI instance
 * layer (fmi_layer/fmi_instance.h) and the core's C interface (gimbal_c_api.h); its Co-Simulation
 * functions here, its Model Exchange ones in gimbal_fmi2_model_exchange.c.
 *
 * Every exported fmi2* function is a thin shell (at the end of this file) that holds the host's
 * floating-point environment around the implementation of the same name. */
#include <math.h>
#include <string.h>

#include "gimbal_fmi2.h"

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

int allowed(FmiInstance* instance, Function function) {
    return fmi_allowed(instance, kFunctions[function].name, kFunctions[function].states);
}

/* ---------------------------------------------------------------- inquiry, logging, lifetime */

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

static FmiStatus impl_SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                      const fmi2String categories[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (instance == NULL) return FMI_ERROR;
    return fmi_set_debug_logging(instance, "fmi2SetDebugLogging", loggingOn != fmi2False, nCategories, categories);
}

static fmi2Component impl_Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                      const fmi2CallbackFunctions* functions, fmi2Boolean loggingOn) {
    return fmi2_instantiate(&kGimbalModel, 1, instanceName, fmuType, fmuGUID, functions, loggingOn);
}

/* ---------------------------------------------------------------- initialization and termination */

static FmiStatus impl_SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SetupExperiment)) return FMI_ERROR;
    if (!fmi_experiment_times_valid(instance, "fmi2SetupExperiment", startTime, stopTimeDefined != fmi2False, stopTime))
        return FMI_ERROR;
    const FmiStatus status = gimbal_status(gimbal_core_set_master_tolerance(gimbal_core_of(instance), toleranceDefined != fmi2False, tolerance));
    if (status > FMI_WARNING) return status;
    instance->time = startTime;
    instance->stop_time = stopTime;
    instance->stop_time_defined = stopTimeDefined ? 1 : 0;
    return FMI_OK;
}

static FmiStatus impl_EnterInitializationMode(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_EnterInitializationMode)) return FMI_ERROR;
    instance->state = STATE_INITIALIZATION;
    return FMI_OK;
}

static FmiStatus impl_ExitInitializationMode(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_ExitInitializationMode)) return FMI_ERROR;
    const FmiStatus status = gimbal_status(gimbal_core_initialize(gimbal_core_of(instance), instance->time));
    if (status > FMI_WARNING) {
        fmi_log_error(instance, "fmi2ExitInitializationMode: initialization refused; fix the values above and retry");
        return FMI_ERROR; /* still in initialization mode: the master may correct and retry */
    }
    instance->last_successful_time = instance->time;
    /* Model Exchange starts in event mode: the host settles the modes with fmi2NewDiscreteStates. */
    instance->state = instance->model_exchange ? STATE_EVENT_MODE : STATE_STEP_COMPLETE;
    return status;
}

static FmiStatus impl_Terminate(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_Terminate)) return FMI_ERROR;
    instance->state = STATE_TERMINATED;
    return FMI_OK;
}

static FmiStatus impl_Reset(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_Reset)) return FMI_ERROR;
    return fmi_reset(instance);
}

/* ---------------------------------------------------------------- getting and setting values */

static const char* const kTypeName[] = {"Real", "Integer", "Boolean"};

/* Common checks of every fmi2Set*: state, pointers, value reference, and the variable's settability. */
static int check_set(FmiInstance* instance, Function id, GimbalType type, const fmi2ValueReference vr[], size_t nvr,
                     const void* value) {
    if (!allowed(instance, id)) return 0;
    const char* function = kFunctions[id].name;
    if (nvr == 0) return 1;
    if (!fmi_not_null(instance, function, vr, "vr") || !fmi_not_null(instance, function, value, "value")) return 0;
    /* The common case in one pass through the core's table; the variable at fault is then named below. */
    const int initialized = !(instance->state & (STATE_INSTANTIATED | STATE_INITIALIZATION));
    const size_t first_refused = gimbal_first_unsettable(type, vr, nvr, initialized);
    for (size_t i = first_refused; i < nvr; ++i) {
        GimbalVariableInfo info;
        if (!gimbal_variable_info(type, vr[i], &info)) {
            fmi_log_error(instance, "%s: value reference %u is not a%s %s variable", function,
                        (unsigned)vr[i], type == GIMBAL_INTEGER ? "n" : "", kTypeName[type]);
            return 0;
        }
        if (!gimbal_variable_settable(instance, &info)) {
            fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, info.name,
                        instance->face->state_name(instance->state));
            return 0;
        }
    }
    return 1;
}

static int check_get(FmiInstance* instance, Function id, const fmi2ValueReference vr[], size_t nvr, const void* value) {
    if (!allowed(instance, id)) return 0;
    const char* function = kFunctions[id].name;
    if (nvr == 0) return 1;
    return fmi_not_null(instance, function, vr, "vr") && fmi_not_null(instance, function, value, "value");
}

static FmiStatus impl_SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_set(instance, FN_SetReal, GIMBAL_REAL, vr, nvr, value)) return FMI_ERROR;
    /* The core checks every value before it applies any (all or nothing) and names a non-finite one. */
    return nvr == 0 ? FMI_OK : gimbal_status(gimbal_core_set_reals(gimbal_core_of(instance), vr, nvr, value));
}

static FmiStatus impl_GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_get(instance, FN_GetReal, vr, nvr, value)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        const FmiStatus status = gimbal_status(gimbal_core_get_real(gimbal_core_of(instance), vr[i], &value[i]));
        if (status > FMI_WARNING) return status;
    }
    return FMI_OK;
}

static FmiStatus impl_SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_set(instance, FN_SetInteger, GIMBAL_INTEGER, vr, nvr, value)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        const FmiStatus status = gimbal_status(gimbal_core_set_integer(gimbal_core_of(instance), vr[i], value[i]));
        if (status > FMI_WARNING) return status;
    }
    return FMI_OK;
}

static FmiStatus impl_GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_get(instance, FN_GetInteger, vr, nvr, value)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const FmiStatus status = gimbal_status(gimbal_core_get_integer(gimbal_core_of(instance), vr[i], &v));
        if (status > FMI_WARNING) return status;
        value[i] = v;
    }
    return FMI_OK;
}

static FmiStatus impl_SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_set(instance, FN_SetBoolean, GIMBAL_BOOLEAN, vr, nvr, value)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        const FmiStatus status = gimbal_status(gimbal_core_set_boolean(gimbal_core_of(instance), vr[i], value[i] != fmi2False));
        if (status > FMI_WARNING) return status;
    }
    return FMI_OK;
}

static FmiStatus impl_GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_get(instance, FN_GetBoolean, vr, nvr, value)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        int v = 0;
        const FmiStatus status = gimbal_status(gimbal_core_get_boolean(gimbal_core_of(instance), vr[i], &v));
        if (status > FMI_WARNING) return status;
        value[i] = v ? fmi2True : fmi2False;
    }
    return FMI_OK;
}

/* The model has no String variables: any value reference is refused. */
static FmiStatus impl_GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_get(instance, FN_GetString, vr, nvr, value)) return FMI_ERROR;
    if (nvr == 0) return FMI_OK;
    fmi_log_error(instance, "fmi2GetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return FMI_ERROR;
}

static FmiStatus impl_SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SetString)) return FMI_ERROR;
    if (nvr == 0) return FMI_OK;
    if (!fmi_not_null(instance, "fmi2SetString", vr, "vr") || !fmi_not_null(instance, "fmi2SetString", value, "value"))
        return FMI_ERROR;
    fmi_log_error(instance, "fmi2SetString: value reference %u is not a String variable",
                (unsigned)vr[0]);
    return FMI_ERROR;
}

/* ---------------------------------------------------------------- capabilities not offered (yet) */

static FmiStatus unsupported(fmi2Component c, Function function, const char* declaration) {
    FmiInstance* instance = (FmiInstance*)c;
    if (instance != NULL)
        fmi_log_error(instance, "%s is not supported: modelDescription.xml declares %s",
                    kFunctions[function].name, declaration);
    return FMI_ERROR;
}

/* ---------------------------------------------------------------- FMU states */

static FmiStatus impl_GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetFMUstate)) return FMI_ERROR;
    return fmi_get_fmu_state(instance, "fmi2GetFMUstate", FMUstate);
}

static FmiStatus impl_SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SetFMUstate)) return FMI_ERROR;
    return fmi_set_fmu_state(instance, "fmi2SetFMUstate", FMUstate);
}

static FmiStatus impl_FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_FreeFMUstate)) return FMI_ERROR;
    return fmi_free_fmu_state(instance, "fmi2FreeFMUstate", FMUstate);
}

static FmiStatus impl_SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SerializedFMUstateSize)) return FMI_ERROR;
    return fmi_serialized_fmu_state_size(instance, "fmi2SerializedFMUstateSize", FMUstate, size);
}

static FmiStatus impl_SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SerializeFMUstate)) return FMI_ERROR;
    return fmi_serialize_fmu_state(instance, "fmi2SerializeFMUstate", FMUstate, (unsigned char*)serializedState, size);
}

static FmiStatus impl_DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                          fmi2FMUstate* FMUstate) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_DeSerializeFMUstate)) return FMI_ERROR;
    return fmi_deserialize_fmu_state(instance, "fmi2DeSerializeFMUstate", (const unsigned char*)serializedState, size,
                                     FMUstate);
}

/* The `index`-th unknown or known (`role`) of fmi2GetDirectionalDerivative: a Real variable of the
 * given causality, whose description it writes to `info`; else logged, 0. */
static int directional_variable(FmiInstance* instance, const char* role, size_t index, fmi2ValueReference vr,
                                GimbalCausality causality, GimbalVariableInfo* info) {
    const char* function = "fmi2GetDirectionalDerivative";
    const char* kind = causality == GIMBAL_OUTPUT ? "output" : "input";
    if (!gimbal_variable_info(GIMBAL_REAL, vr, info)) {
        fmi_log_error(instance, "%s: %s %zu: value reference %u is not a Real variable",
                    function, role, index, (unsigned)vr);
        return 0;
    }
    if (info->causality != causality) {
        fmi_log_error(instance, "%s: %s %s is not an %s: in Co-Simulation the %ss are the %ss",
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
static FmiStatus impl_GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetDirectionalDerivative)) return FMI_ERROR;
    if (instance->model_exchange)
        return model_exchange_directional_derivative(instance, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown,
                                                     dvUnknown);
    const char* function = "fmi2GetDirectionalDerivative";
    if (nUnknown > 0 && (!fmi_not_null(instance, function, vUnknown_ref, "vUnknown_ref") ||
                         !fmi_not_null(instance, function, dvUnknown, "dvUnknown")))
        return FMI_ERROR;
    if (nKnown > 0 && (!fmi_not_null(instance, function, vKnown_ref, "vKnown_ref") ||
                       !fmi_not_null(instance, function, dvKnown, "dvKnown")))
        return FMI_ERROR;
    GimbalVariableInfo info;
    for (size_t i = 0; i < nUnknown; ++i)
        if (!directional_variable(instance, "unknown", i, vUnknown_ref[i], GIMBAL_OUTPUT, &info)) return FMI_ERROR;
    for (size_t j = 0; j < nKnown; ++j) {
        if (!directional_variable(instance, "known", j, vKnown_ref[j], GIMBAL_INPUT, &info)) return FMI_ERROR;
        if (!isfinite(dvKnown[j])) {
            fmi_log_error(instance, "%s: the seed of %s must be finite", function, info.name);
            return FMI_ERROR;
        }
    }
    for (size_t i = 0; i < nUnknown; ++i) dvUnknown[i] = 0.0;
    return FMI_OK;
}

static FmiStatus impl_SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SetRealInputDerivatives)) return FMI_ERROR;
    if (nvr == 0) return FMI_OK;
    if (!fmi_not_null(instance, "fmi2SetRealInputDerivatives", vr, "vr") ||
        !fmi_not_null(instance, "fmi2SetRealInputDerivatives", order, "order") ||
        !fmi_not_null(instance, "fmi2SetRealInputDerivatives", value, "value"))
        return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        const FmiStatus status =
            gimbal_status(gimbal_core_set_input_derivative(gimbal_core_of(instance), vr[i], (int)order[i], value[i]));
        if (status > FMI_WARNING) return status;
    }
    return FMI_OK;
}

static FmiStatus impl_GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, FN_GetRealOutputDerivatives, "maxOutputDerivativeOrder=\"0\"");
}

/* ---------------------------------------------------------------- stepping */

static FmiStatus impl_DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    FmiInstance* instance = (FmiInstance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, FN_DoStep)) return FMI_ERROR;
    if (!fmi_step_valid(instance, "fmi2DoStep", currentCommunicationPoint, communicationStepSize)) return FMI_ERROR;
    const double end_time = currentCommunicationPoint + communicationStepSize;
    const FmiStatus status =
        gimbal_status(gimbal_core_do_step(gimbal_core_of(instance), currentCommunicationPoint, communicationStepSize));
    instance->last_step_status = status;
    if (status > FMI_WARNING) {
        instance->state = status == FMI_DISCARD ? STATE_STEP_FAILED : STATE_ERROR;
        return status;
    }
    instance->time = end_time;
    instance->last_successful_time = end_time;
    return status;
}

static FmiStatus impl_CancelStep(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_CancelStep)) return FMI_ERROR; /* doStep never runs asynchronously */
    return FMI_ERROR;
}

static FmiStatus impl_GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetStatus)) return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2GetStatus", value, "value")) return FMI_ERROR;
    if (s != fmi2DoStepStatus) {
        fmi_log_error(instance, "fmi2GetStatus: status kind %d is not a fmi2Status", (int)s);
        return FMI_ERROR;
    }
    *value = (fmi2Status)instance->last_step_status;
    return FMI_OK;
}

static FmiStatus impl_GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetRealStatus))
        return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2GetRealStatus", value, "value")) return FMI_ERROR;
    if (s != fmi2LastSuccessfulTime) {
        fmi_log_error(instance, "fmi2GetRealStatus: status kind %d is not a Real status", (int)s);
        return FMI_ERROR;
    }
    *value = instance->last_successful_time;
    return FMI_OK;
}

static FmiStatus impl_GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetIntegerStatus)) return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2GetIntegerStatus", value, "value")) return FMI_ERROR;
    fmi_log_error(instance, "fmi2GetIntegerStatus: status kind %d has no Integer value", (int)s);
    return FMI_ERROR;
}

static FmiStatus impl_GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetBooleanStatus))
        return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2GetBooleanStatus", value, "value")) return FMI_ERROR;
    if (s != fmi2Terminated) {
        fmi_log_error(instance, "fmi2GetBooleanStatus: status kind %d has no Boolean value", (int)s);
        return FMI_ERROR;
    }
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return FMI_OK;
}

static FmiStatus impl_GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_GetStringStatus))
        return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2GetStringStatus", value, "value")) return FMI_ERROR;
    if (s != fmi2PendingStatus) {
        fmi_log_error(instance, "fmi2GetStringStatus: status kind %d has no String value", (int)s);
        return FMI_ERROR;
    }
    *value = ""; /* doStep is synchronous: never pending */
    return FMI_OK;
}

/* ---------------------------------------------------------------- the exported functions */

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetDebugLogging(c, loggingOn, nCategories, categories));
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi2Component, impl_Instantiate(instanceName, fmuType, fmuGUID, functions, loggingOn));
}

void fmi2FreeInstance(fmi2Component c) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    fmi_free_instance((FmiInstance*)c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          (fmi2Status)impl_SetupExperiment(c, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_EnterInitializationMode(c));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_ExitInitializationMode(c));
}

fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_Terminate(c)); }

fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_Reset(c)); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetReal(c, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetInteger(c, vr, nvr, value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetBoolean(c, vr, nvr, value));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetString(c, vr, nvr, value));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetReal(c, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetInteger(c, vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetBoolean(c, vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetString(c, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetFMUstate(c, FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetFMUstate(c, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_FreeFMUstate(c, FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SerializedFMUstateSize(c, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SerializeFMUstate(c, FMUstate, serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* FMUstate) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_DeSerializeFMUstate(c, serializedState, size, FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          (fmi2Status)impl_GetDirectionalDerivative(c, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetRealInputDerivatives(c, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetRealOutputDerivatives(c, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          (fmi2Status)impl_DoStep(c, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint));
}

fmi2Status fmi2CancelStep(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_CancelStep(c)); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetStatus(c, s, value));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetRealStatus(c, s, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetIntegerStatus(c, s, value));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetBooleanStatus(c, s, value));
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetStringStatus(c, s, value));
}
