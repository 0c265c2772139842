/* FMI 2.0 Model Exchange face of the FMU: the host integrates the continuous states and handles the
 * events; the core (gimbal_c_api.h, "continuous-time interface") evaluates derivatives, event
 * indicators and outputs at the point the host sets, and decides the modes at each event update.
 * The instance, its state machine and the functions both interfaces share are in fmi2_cosim.c. */
#include <math.h>
#include <stddef.h>

#include "fmu_instance.h"

/* The state masks let a Co-Simulation instance through in the states both interfaces share
 * (instantiated, initialization mode): these functions are Model Exchange's alone. */
static int model_exchange_instance(Instance* instance, Function function) {
    if (instance->type == fmi2ModelExchange) return 1;
    log_message(instance, fmi2Error, "logStatusError",
                "%s is a Model Exchange function: instance '%s' was instantiated for Co-Simulation", function_name(function),
                instance->instance_name);
    return 0;
}

static int count_is(Instance* instance, Function function, size_t given, size_t expected, const char* argument) {
    if (given == expected) return 1;
    log_message(instance, fmi2Error, "logStatusError", "%s: %s = %zu, but the model has %zu (modelDescription.xml)",
                function_name(function), argument, given, expected);
    return 0;
}

/* State, pointer and size checks of the vector getters and setters; names the culprit. */
static int check_vector(Instance* instance, Function function, const void* values, size_t given, size_t expected,
                        const char* argument, const char* count_name) {
    if (!allowed(instance, function) || !model_exchange_instance(instance, function)) return 0;
    if (!count_is(instance, function, given, expected, count_name)) return 0;
    return not_null(instance, function_name(function), values, argument);
}

static fmi2Status impl_EnterEventMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_EnterEventMode)) return fmi2Error;
    instance->state = STATE_EVENT_MODE;
    return fmi2OK;
}

static fmi2Status impl_NewDiscreteStates(fmi2Component c, fmi2EventInfo* eventInfo) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_NewDiscreteStates)) return fmi2Error;
    if (!not_null(instance, "fmi2NewDiscreteStates", eventInfo, "fmi2eventInfo")) return fmi2Error;
    GimbalDiscreteUpdate update;
    const fmi2Status status =
        from_core(gimbal_core_update_discrete_states(instance->core, &update));
    if (status > fmi2Warning) return status;
    /* The modes are decided whole in one call: the iteration ends here. */
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = update.states_changed ? fmi2True : fmi2False;
    eventInfo->nextEventTimeDefined = update.next_time_defined ? fmi2True : fmi2False;
    eventInfo->nextEventTime = update.next_time_defined ? update.next_time : 0.0;
    return status;
}

static fmi2Status impl_EnterContinuousTimeMode(fmi2Component c) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_EnterContinuousTimeMode)) return fmi2Error;
    instance->state = STATE_CONTINUOUS_TIME;
    return fmi2OK;
}

static fmi2Status impl_CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                               fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    Instance* instance = (Instance*)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(instance, FN_CompletedIntegratorStep)) return fmi2Error;
    if (!not_null(instance, "fmi2CompletedIntegratorStep", enterEventMode, "enterEventMode") ||
        !not_null(instance, "fmi2CompletedIntegratorStep", terminateSimulation, "terminateSimulation"))
        return fmi2Error;
    /* Every mode change shows in an event indicator: no step events. */
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

static fmi2Status impl_SetTime(fmi2Component c, fmi2Real time) {
    Instance* instance = (Instance*)c;
    if (!allowed(instance, FN_SetTime)) return fmi2Error;
    if (!isfinite(time)) {
        log_message(instance, fmi2Error, "logStatusError", "fmi2SetTime: time = %g must be finite", time);
        return fmi2Error;
    }
    const fmi2Status status = from_core(gimbal_core_set_time(instance->core, time));
    if (status <= fmi2Warning) instance->time = time;
    return status;
}

static fmi2Status impl_SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Instance* instance = (Instance*)c;
    if (!check_vector(instance, FN_SetContinuousStates, x, nx, GIMBAL_CONTINUOUS_STATES, "x", "nx")) return fmi2Error;
    return from_core(gimbal_core_set_continuous_states(instance->core, x));
}

static fmi2Status impl_GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    Instance* instance = (Instance*)c;
    if (!check_vector(instance, FN_GetDerivatives, derivatives, nx, GIMBAL_CONTINUOUS_STATES, "derivatives", "nx"))
        return fmi2Error;
    return from_core(gimbal_core_get_derivatives(instance->core, derivatives));
}

static fmi2Status impl_GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    Instance* instance = (Instance*)c;
    if (!check_vector(instance, FN_GetEventIndicators, eventIndicators, ni, GIMBAL_EVENT_INDICATORS, "eventIndicators",
                      "ni"))
        return fmi2Error;
    return from_core(gimbal_core_get_event_indicators(instance->core, eventIndicators));
}

static fmi2Status impl_GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Instance* instance = (Instance*)c;
    if (!check_vector(instance, FN_GetContinuousStates, x, nx, GIMBAL_CONTINUOUS_STATES, "x", "nx")) return fmi2Error;
    return from_core(gimbal_core_get_continuous_states(instance->core, x));
}

static fmi2Status impl_GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    Instance* instance = (Instance*)c;
    if (!check_vector(instance, FN_GetNominalsOfContinuousStates, x_nominal, nx, GIMBAL_CONTINUOUS_STATES, "x_nominal",
                      "nx"))
        return fmi2Error;
    return from_core(gimbal_core_get_nominal_states(instance->core, x_nominal));
}

/* Unknowns are state derivatives or outputs, knowns states or inputs (FMI 2.0, section 3.2.1): the core
 * checks which, and names a variable that is neither. */
fmi2Status model_exchange_directional_derivative(Instance* instance, const fmi2ValueReference unknowns[],
                                                 size_t unknown_count, const fmi2ValueReference knowns[],
                                                 size_t known_count, const fmi2Real seed[], fmi2Real result[]) {
    const char* function = "fmi2GetDirectionalDerivative";
    if (unknown_count > 0 && (!not_null(instance, function, unknowns, "vUnknown_ref") ||
                              !not_null(instance, function, result, "dvUnknown")))
        return fmi2Error;
    if (known_count > 0 && (!not_null(instance, function, knowns, "vKnown_ref") ||
                            !not_null(instance, function, seed, "dvKnown")))
        return fmi2Error;
    for (size_t j = 0; j < known_count; ++j) {
        if (isfinite(seed[j])) continue;
        log_message(instance, fmi2Error, "logStatusError", "%s: the seed of known %zu must be finite", function, j);
        return fmi2Error;
    }
    return from_core(gimbal_core_directional_derivative(instance->core, unknowns, unknown_count, knowns, known_count,
                                                        seed, result));
}

/* ---------------------------------------------------------------- the exported functions */

fmi2Status fmi2EnterEventMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_EnterEventMode(c)); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* fmi2eventInfo) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_NewDiscreteStates(c, fmi2eventInfo));
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_EnterContinuousTimeMode(c));
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_CompletedIntegratorStep(c, noSetFMUStatePriorToCurrentPoint, enterEventMode,
                                                                   terminateSimulation));
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetTime(c, time)); }

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetContinuousStates(c, x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetDerivatives(c, derivatives, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetEventIndicators(c, eventIndicators, ni));
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetContinuousStates(c, x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetNominalsOfContinuousStates(c, x_nominal, nx));
}
