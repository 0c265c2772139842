/* The FMI 3.0 Co-Simulation face of the small FMUs (small_cosim_model.h): every fmi3* function, over
 * the same model table as the FMI 2.0 face, the shared part (small_cosim.c), the layer and its FMI
 * 3.0 face (fmi3_face.h). Co-Simulation only, without Event Mode or early return; FMU states are
 * offered (the model's snapshot, FmiModel). Value references: common/fmi3_value_references.h. Every
 * exported function runs in the default floating-point environment whatever the host's
 * (host_fp_environment.h), so that the outputs are the bits of the FMI 2.0 FMU. */
#include <stddef.h>

#include "common/fmi3_value_references.h"
#include "fmi_layer/fmi3_face.h"
#include "fmi_layer/small_cosim_model.h"
#include "host_fp_environment.h"

_Static_assert(sizeof(fmi3ValueReference) == sizeof(unsigned), "value references are the layer's unsigned");
_Static_assert(sizeof(fmi3Int32) == sizeof(int), "an Int32 is the model's int");

static const SmallCosimModel* const kModel = &kSmallCosimModel;

/* The table's masks of FMI 2.0's states, as FMI 3.0's. */
static int fmi3_states(int fmi2_states) {
    static const struct { int fmi2, fmi3; } kStates[] = {
        {STATE_INSTANTIATED, S_INSTANTIATED}, {STATE_INITIALIZATION, S_INITIALIZATION}, {STATE_STEP_COMPLETE, S_STEP},
        {STATE_STEP_FAILED, S_STEP_DISCARDED}, {STATE_TERMINATED, S_TERMINATED},        {STATE_ERROR, S_ERROR},
    };
    int states = 0;
    for (size_t k = 0; k < sizeof kStates / sizeof kStates[0]; ++k)
        if (fmi2_states & kStates[k].fmi2) states |= kStates[k].fmi3;
    return states;
}

/* The instance when `function` may be called in its state; NULL (logged when it can be) otherwise. */
static FmiInstance* usable(fmi3Instance handle, const char* function, int states) {
    FmiInstance* instance = (FmiInstance*)handle;
    return fmi_allowed(instance, function, states) ? instance : NULL;
}

static const char* const kCoSimulationOnly = "this FMU offers Co-Simulation only";

/* ---------------------------------------------------------------- values */

/* Every variable is a scalar: one value per value reference. */
static int counts_agree(FmiInstance* instance, const char* function, size_t nvr, size_t nvalues) {
    if (nvalues == nvr) return 1;
    fmi_log_error(instance, "%s: nValues = %zu, but the %zu variables hold %zu values", function, nvalues, nvr, nvr);
    return 0;
}

static fmi3Status get_values(fmi3Instance handle, const char* function, const SmallCosimVariables* variables,
                             const char* type, unsigned base, const fmi3ValueReference vr[], size_t nvr, void* values,
                             size_t nvalues, size_t size, SmallValueLayout layout) {
    FmiInstance* instance = usable(handle, function, fmi3_states(kModel->get_states));
    if (instance == NULL || !counts_agree(instance, function, nvr, nvalues)) return fmi3Error;
    return (fmi3Status)small_cosim_get(instance, function, variables, type, base, vr, nvr, values, size, layout);
}

static fmi3Status set_values(fmi3Instance handle, const char* function, const SmallCosimVariables* variables,
                             const char* type, unsigned base, const fmi3ValueReference vr[], size_t nvr,
                             const void* values, size_t nvalues, size_t size, SmallValueLayout layout) {
    FmiInstance* instance = usable(handle, function, fmi3_states(kModel->set_states));
    if (instance == NULL || !counts_agree(instance, function, nvr, nvalues)) return fmi3Error;
    return (fmi3Status)small_cosim_set(instance, function, variables, type, base, vr, nvr, values, size, layout);
}

/* fmi3GetFloat64: the model's Float64 variables and `time`, the independent variable (the instance's). */
static fmi3Status get_float64(fmi3Instance handle, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                              size_t nvalues) {
    const char* function = "fmi3GetFloat64";
    FmiInstance* instance = usable(handle, function, fmi3_states(kModel->get_states));
    if (instance == NULL || !counts_agree(instance, function, nvr, nvalues)) return fmi3Error;
    for (size_t i = 0; i < nvr; ++i) { /* one by one: `time` may be anywhere among them */
        if (vr != NULL && values != NULL && vr[i] == SMALL_FMI3_TIME) {
            values[i] = instance->time;
            continue;
        }
        const FmiStatus status = small_cosim_get(instance, function, &kModel->real, "Float64", SMALL_FMI3_FLOAT64_BASE,
                                                 vr == NULL ? NULL : vr + i, 1, values == NULL ? NULL : values + i,
                                                 sizeof(fmi3Float64), SMALL_VALUES_AS_THE_MODELS);
        if (status != FMI_OK) return (fmi3Status)status;
    }
    return fmi3OK;
}

/* ---------------------------------------------------------------- lifetime */

static fmi3Instance instantiate(const char* function, fmi3String name, fmi3String token, fmi3String resource_path,
                                fmi3Boolean logging_on, const char* type_refusal, fmi3InstanceEnvironment environment,
                                fmi3LogMessageCallback log) {
    FmiInstance* instance =
        fmi3_instantiate(&kModel->layer, function, type_refusal, name, token, 0, 0, 0, logging_on, environment, log);
    return small_cosim_instantiated(instance, function, resource_path);
}

/* ---------------------------------------------------------------- initialization, termination, reset */

static fmi3Status enter_initialization_mode(fmi3Instance handle, fmi3Float64 start, fmi3Boolean stop_defined,
                                            fmi3Float64 stop) {
    const char* function = "fmi3EnterInitializationMode";
    FmiInstance* instance = usable(handle, function, S_INSTANTIATED);
    if (instance == NULL) return fmi3Error;
    const FmiStatus status = small_cosim_start_experiment(instance, function, start, stop_defined ? 1 : 0, stop);
    if (status != FMI_OK) return (fmi3Status)status;
    instance->state = S_INITIALIZATION;
    return fmi3OK;
}

static fmi3Status exit_initialization_mode(fmi3Instance handle) {
    FmiInstance* instance = usable(handle, "fmi3ExitInitializationMode", S_INITIALIZATION);
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)small_cosim_exit_initialization(instance, "fmi3ExitInitializationMode", S_STEP);
}

static fmi3Status terminate(fmi3Instance handle) {
    FmiInstance* instance = usable(handle, "fmi3Terminate", fmi3_states(kModel->terminate_states));
    if (instance == NULL) return fmi3Error;
    instance->state = S_TERMINATED;
    return fmi3OK;
}

static fmi3Status reset(fmi3Instance handle) {
    FmiInstance* instance = usable(handle, "fmi3Reset", S_ANY);
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)small_cosim_reset(instance, "fmi3Reset");
}

/* ---------------------------------------------------------------- stepping */

static fmi3Status do_step(fmi3Instance handle, fmi3Float64 point, fmi3Float64 step, fmi3Boolean* event_handling_needed,
                          fmi3Boolean* terminate_simulation, fmi3Boolean* early_return, fmi3Float64* last_successful_time) {
    const char* function = "fmi3DoStep";
    FmiInstance* instance = usable(handle, function, S_STEP);
    if (instance == NULL || !fmi_not_null(instance, function, event_handling_needed, "eventHandlingNeeded") ||
        !fmi_not_null(instance, function, terminate_simulation, "terminateSimulation") ||
        !fmi_not_null(instance, function, early_return, "earlyReturn") ||
        !fmi_not_null(instance, function, last_successful_time, "lastSuccessfulTime"))
        return fmi3Error;
    *event_handling_needed = *terminate_simulation = *early_return = fmi3False; /* no events, never early */
    *last_successful_time = instance->time;
    if (!fmi_step_valid(instance, function, point, step)) return fmi3Error;
    const FmiStatus status = kModel->do_step(instance, function, point, step);
    *last_successful_time = instance->time;
    return (fmi3Status)status;
}

/* ---------------------------------------------------------------- the exported functions */

#define OWN_INSTANCE ((FmiInstance*)instance)

#define GET(type_name, variables, c_type, base, layout)                                                          \
    fmi3Status fmi3Get##type_name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, c_type values[], \
                                  size_t nValues) {                                                              \
        IN_FMU_FP_ENVIRONMENT(fmi3Status, get_values(instance, "fmi3Get" #type_name, &kModel->variables, #type_name,  \
                                                     base, vr, nvr, values, nValues, sizeof(c_type), layout));   \
    }
#define SET(type_name, variables, c_type, base, layout)                                                          \
    fmi3Status fmi3Set##type_name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,              \
                                  const c_type values[], size_t nValues) {                                       \
        IN_FMU_FP_ENVIRONMENT(fmi3Status, set_values(instance, "fmi3Set" #type_name, &kModel->variables, #type_name,  \
                                                     base, vr, nvr, values, nValues, sizeof(c_type), layout));   \
    }
GET(Int32, integer, fmi3Int32, SMALL_FMI3_INT32_BASE, SMALL_VALUES_AS_THE_MODELS)
GET(Boolean, boolean, fmi3Boolean, SMALL_FMI3_BOOLEAN_BASE, SMALL_VALUES_C_BOOL)
GET(String, string, fmi3String, SMALL_FMI3_STRING_BASE, SMALL_VALUES_AS_THE_MODELS)
SET(Float64, real, fmi3Float64, SMALL_FMI3_FLOAT64_BASE, SMALL_VALUES_AS_THE_MODELS)
SET(Int32, integer, fmi3Int32, SMALL_FMI3_INT32_BASE, SMALL_VALUES_AS_THE_MODELS)
SET(Boolean, boolean, fmi3Boolean, SMALL_FMI3_BOOLEAN_BASE, SMALL_VALUES_C_BOOL)
SET(String, string, fmi3String, SMALL_FMI3_STRING_BASE, SMALL_VALUES_AS_THE_MODELS)

/* Int64: the one type without variables that not every FMU of the project lacks (the gimbal's
 * enumerations are Int64; fmi3_not_offered.c refuses the other types). */
FMI3_ABSENT_TYPE(Int64, fmi3Int64)

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* Early return is allowed, never taken; no intermediate update is provided. */
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables,
        (void)intermediateUpdate;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance,
                          instantiate("fmi3InstantiateCoSimulation", instanceName, instantiationToken, resourcePath,
                                      loggingOn, eventModeUsed ? "eventModeUsed is true, but hasEventMode is false" : NULL,
                                      instanceEnvironment, logMessage));
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                          fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate("fmi3InstantiateModelExchange", instanceName, instantiationToken,
                                                    resourcePath, loggingOn, kCoSimulationOnly, instanceEnvironment,
                                                    logMessage));
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)visible, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate("fmi3InstantiateScheduledExecution", instanceName, instantiationToken,
                                                    resourcePath, loggingOn, kCoSimulationOnly, instanceEnvironment,
                                                    logMessage));
}

void fmi3FreeInstance(fmi3Instance instance) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    small_cosim_free_instance(OWN_INSTANCE);
    leave_fmu_fp(&host_environment);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined, (void)tolerance; /* nothing is integrated: no tolerance to meet */
    IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_initialization_mode(instance, startTime, stopTimeDefined, stopTime));
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, exit_initialization_mode(instance));
}
fmi3Status fmi3Terminate(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, terminate(instance)); }
fmi3Status fmi3Reset(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, reset(instance)); }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* eventHandlingNeeded,
                      fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, do_step(instance, currentCommunicationPoint, communicationStepSize,
                                              eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime));
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_float64(instance, vr, nvr, values, nValues));
}


/* ---------------------------------------------------------------- what is not offered */
/* (Beyond what no FMU of the project offers: fmi3_not_offered.c.) */

#define NOT_OFFERED(function, why) IN_FMU_FP_ENVIRONMENT(fmi3Status, fmi3_refuse_not_offered(OWN_INSTANCE, function, why))

fmi3Status fmi3EnterEventMode(fmi3Instance instance) { NOT_OFFERED("fmi3EnterEventMode", "hasEventMode is false"); }
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    NOT_OFFERED("fmi3EnterStepMode", "hasEventMode is false: the instance never leaves step mode");
}
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined,
                                    fmi3Float64* nextEventTime) {
    (void)discreteStatesNeedUpdate, (void)terminateSimulation, (void)nominalsOfContinuousStatesChanged,
        (void)valuesOfContinuousStatesChanged, (void)nextEventTimeDefined, (void)nextEventTime;
    NOT_OFFERED("fmi3UpdateDiscreteStates", "hasEventMode is false");
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
        (void)nSensitivity;
    NOT_OFFERED("fmi3GetDirectionalDerivative", "providesDirectionalDerivatives is false");
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    NOT_OFFERED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0: the outputs are held");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    NOT_OFFERED("fmi3ActivateModelPartition", kCoSimulationOnly);
}

/* Model Exchange's functions: an instance of this FMU is never a Model Exchange one. */
#define MODEL_EXCHANGE_ONLY(function) NOT_OFFERED(function, "a Model Exchange function; this FMU offers Co-Simulation only")
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) { MODEL_EXCHANGE_ONLY("fmi3EnterContinuousTimeMode"); }
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    MODEL_EXCHANGE_ONLY("fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    MODEL_EXCHANGE_ONLY("fmi3SetTime");
}
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    (void)x, (void)n;
    MODEL_EXCHANGE_ONLY("fmi3SetContinuousStates");
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t n) {
    (void)dx, (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetContinuousStateDerivatives");
}
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t n) {
    (void)z, (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetEventIndicators");
}
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    (void)x, (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetContinuousStates");
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t n) {
    (void)nominals, (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetNominalsOfContinuousStates");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* n) {
    (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* n) {
    (void)n;
    MODEL_EXCHANGE_ONLY("fmi3GetNumberOfContinuousStates");
}
