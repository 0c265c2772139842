/* The gimbal's FMI 2.0 Model Exchange functions: the host integrates the continuous states and handles
 * the events; the core (gimbal_c_api.h, "continuous-time interface") evaluates derivatives, event
 * indicators and outputs at the point the host sets, and decides the modes at each event update.
 * The face's states and the functions both interfaces share are in gimbal_fmi2.c. */
#include <math.h>
#include <stddef.h>

#include "gimbal_fmi2.h"

/* The state masks let a Co-Simulation instance through in the states both interfaces share
 * (instantiated, initialization mode): these functions are Model Exchange's alone. */
static int model_exchange_instance(FmiInstance* instance, Function function) {
    if (instance->model_exchange) return 1;
    fmi_log_error(instance, "%s is a Model Exchange function: instance '%s' was instantiated for Co-Simulation", function_name(function),
                instance->name);
    return 0;
}

static int count_is(FmiInstance* instance, Function function, size_t given, size_t expected, const char* argument) {
    if (given == expected) return 1;
    fmi_log_error(instance, "%s: %s = %zu, but the model has %zu (modelDescription.xml)",
                function_name(function), argument, given, expected);
    return 0;
}

/* State, pointer and size checks of the vector getters and setters; names the culprit. */
static int check_vector(FmiInstance* instance, Function function, const void* values, size_t given, size_t expected,
                        const char* argument, const char* count_name) {
    if (!allowed(instance, function) || !model_exchange_instance(instance, function)) return 0;
    if (!count_is(instance, function, given, expected, count_name)) return 0;
    return fmi_not_null(instance, function_name(function), values, argument);
}

static FmiStatus impl_EnterEventMode(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_EnterEventMode)) return FMI_ERROR;
    instance->state = STATE_EVENT_MODE;
    return FMI_OK;
}

static FmiStatus impl_NewDiscreteStates(fmi2Component c, fmi2EventInfo* eventInfo) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_NewDiscreteStates)) return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2NewDiscreteStates", eventInfo, "fmi2eventInfo")) return FMI_ERROR;
    GimbalDiscreteUpdate update;
    const FmiStatus status =
        gimbal_status(gimbal_core_update_discrete_states(gimbal_core_of(instance), &update));
    if (status > FMI_WARNING) return status;
    /* The modes are decided whole in one call: the iteration ends here. */
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = update.states_changed ? fmi2True : fmi2False;
    eventInfo->nextEventTimeDefined = update.next_time_defined ? fmi2True : fmi2False;
    eventInfo->nextEventTime = update.next_time_defined ? update.next_time : 0.0;
    return status;
}

static FmiStatus impl_EnterContinuousTimeMode(fmi2Component c) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_EnterContinuousTimeMode)) return FMI_ERROR;
    instance->state = STATE_CONTINUOUS_TIME;
    return FMI_OK;
}

static FmiStatus impl_CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                               fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    FmiInstance* instance = (FmiInstance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, FN_CompletedIntegratorStep)) return FMI_ERROR;
    if (!fmi_not_null(instance, "fmi2CompletedIntegratorStep", enterEventMode, "enterEventMode") ||
        !fmi_not_null(instance, "fmi2CompletedIntegratorStep", terminateSimulation, "terminateSimulation"))
        return FMI_ERROR;
    /* Every mode change shows in an event indicator: no step events. */
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return FMI_OK;
}

static FmiStatus impl_SetTime(fmi2Component c, fmi2Real time) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!allowed(instance, FN_SetTime)) return FMI_ERROR;
    if (!isfinite(time)) {
        fmi_log_error(instance, "fmi2SetTime: time = %g must be finite", time);
        return FMI_ERROR;
    }
    const FmiStatus status = gimbal_status(gimbal_core_set_time(gimbal_core_of(instance), time));
    if (status <= FMI_WARNING) instance->time = time;
    return status;
}

static FmiStatus impl_SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_vector(instance, FN_SetContinuousStates, x, nx, GIMBAL_CONTINUOUS_STATES, "x", "nx")) return FMI_ERROR;
    return gimbal_status(gimbal_core_set_continuous_states(gimbal_core_of(instance), x));
}

/* The core's vectors the host reads: one check (state, count, pointer) and the core's reader. */
typedef GimbalStatus (*CoreVectorReader)(GimbalCore* core, double* values);
static FmiStatus read_vector(fmi2Component c, Function id, fmi2Real values[], size_t given, size_t expected,
                             const char* argument, const char* count_name, CoreVectorReader read) {
    FmiInstance* instance = (FmiInstance*)c;
    if (!check_vector(instance, id, values, given, expected, argument, count_name)) return FMI_ERROR;
    return gimbal_status(read(gimbal_core_of(instance), values));
}

static FmiStatus impl_GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    return read_vector(c, FN_GetDerivatives, derivatives, nx, GIMBAL_CONTINUOUS_STATES, "derivatives", "nx",
                       gimbal_core_get_derivatives);
}

static FmiStatus impl_GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    return read_vector(c, FN_GetEventIndicators, eventIndicators, ni, GIMBAL_EVENT_INDICATORS, "eventIndicators", "ni",
                       gimbal_core_get_event_indicators);
}

static FmiStatus impl_GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    return read_vector(c, FN_GetContinuousStates, x, nx, GIMBAL_CONTINUOUS_STATES, "x", "nx",
                       gimbal_core_get_continuous_states);
}

static FmiStatus impl_GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    return read_vector(c, FN_GetNominalsOfContinuousStates, x_nominal, nx, GIMBAL_CONTINUOUS_STATES, "x_nominal", "nx",
                       gimbal_core_get_nominal_states);
}

/* Unknowns are state derivatives or outputs, knowns states or inputs (FMI 2.0, section 3.2.1): the core
 * checks which, and names a variable that is neither. */
FmiStatus model_exchange_directional_derivative(FmiInstance* instance, const fmi2ValueReference unknowns[],
                                                 size_t unknown_count, const fmi2ValueReference knowns[],
                                                 size_t known_count, const fmi2Real seed[], fmi2Real result[]) {
    const char* function = "fmi2GetDirectionalDerivative";
    if (unknown_count > 0 && (!fmi_not_null(instance, function, unknowns, "vUnknown_ref") ||
                              !fmi_not_null(instance, function, result, "dvUnknown")))
        return FMI_ERROR;
    if (known_count > 0 && (!fmi_not_null(instance, function, knowns, "vKnown_ref") ||
                            !fmi_not_null(instance, function, seed, "dvKnown")))
        return FMI_ERROR;
    for (size_t j = 0; j < known_count; ++j) {
        if (isfinite(seed[j])) continue;
        fmi_log_error(instance, "%s: the seed of known %zu must be finite", function, j);
        return FMI_ERROR;
    }
    return gimbal_status(gimbal_core_directional_derivative(gimbal_core_of(instance), unknowns, unknown_count, knowns, known_count,
                                                        seed, result));
}

/* ---------------------------------------------------------------- the exported functions */

fmi2Status fmi2EnterEventMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_EnterEventMode(c)); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* fmi2eventInfo) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_NewDiscreteStates(c, fmi2eventInfo));
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_EnterContinuousTimeMode(c));
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_CompletedIntegratorStep(c, noSetFMUStatePriorToCurrentPoint, enterEventMode,
                                                                   terminateSimulation));
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetTime(c, time)); }

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_SetContinuousStates(c, x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetDerivatives(c, derivatives, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetEventIndicators(c, eventIndicators, ni));
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetContinuousStates(c, x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, (fmi2Status)impl_GetNominalsOfContinuousStates(c, x_nominal, nx));
}
