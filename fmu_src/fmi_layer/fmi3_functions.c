/* The FMI 3.0 face of every FMU of the project (fmu_model.h): every fmi3* function of Model Exchange and
 * Co-Simulation (with Event Mode and early return when the model has them), over the same model table
 * as the FMI 2.0 face, the shared part (fmu_model.c), the layer and its FMI 3.0 face (fmi3_face.h:
 * the states, instantiation, the FMU-state functions; fmi3_not_offered.c: what no FMU offers). What the
 * table leaves NULL is refused naming the model description's declaration. Value references: the
 * model's Fmi3Variables, or common/fmi3_value_references.h. Every exported function runs in the
 * default floating-point environment whatever the host's (host_fp_environment.h), so that the outputs
 * are the bits of the FMI 2.0 FMU.
 *
 * Co-Simulation handles every mode change inside fmi3DoStep; an importer that allows an early return
 * gets the step back right after the first one (earlyReturn, and eventHandlingNeeded if it uses Event
 * Mode, where there is no discrete state left to update). */
#include <math.h>
#include <stddef.h>

#include "common/fmi3_value_references.h"
#include "fmi_layer/fmi3_face.h"
#include "fmi_layer/fmu_model.h"
#include "fmi_layer/host_fp_environment.h"

_Static_assert(sizeof(fmi3ValueReference) == sizeof(unsigned), "value references are the layer's unsigned");
_Static_assert(sizeof(fmi3Int32) == sizeof(int), "an Int32 is the model's int");

static const FmuModel* const kModel = &kFmuModel;

/* The table's masks of FMI 2.0's states, as FMI 3.0's. */
static int fmi3_states(int fmi2_states) {
    static const struct { int fmi2, fmi3; } kStates[] = {
        {STATE_INSTANTIATED, S_INSTANTIATED}, {STATE_INITIALIZATION, S_INITIALIZATION}, {STATE_STEP_COMPLETE, S_STEP},
        {STATE_STEP_FAILED, S_STEP_DISCARDED}, {STATE_TERMINATED, S_TERMINATED},        {STATE_ERROR, S_ERROR},
        {STATE_EVENT_MODE, S_EVENT},           {STATE_CONTINUOUS_TIME, S_CONTINUOUS_TIME},
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

/* What the model description declares absent: refused, in any state, naming `why`. */
static fmi3Status not_offered(fmi3Instance handle, const char* function, const char* why) {
    return fmi3_refuse_not_offered((FmiInstance*)handle, function, why);
}

static const char* interfaces_offered(void) {
    return kModel->model_exchange != NULL ? "this FMU offers Model Exchange and Co-Simulation only"
                                          : "this FMU offers Co-Simulation only";
}

/* ---------------------------------------------------------------- values */

typedef enum { FLOAT64, INT32, INT64, BOOLEAN, STRING } Type3;
static const char* const kTypeName[] = {"Float64", "Int32", "Int64", "Boolean", "String"};

/* A type's variables and the base of their value references. */
static const FmuVariables* variables_of(Type3 type, unsigned* base) {
    static const FmuVariables kNone = {0};
    const Fmi3Variables* own = kModel->fmi3;
    switch (type) {
        case FLOAT64:
            *base = own ? own->float64_base : SMALL_FMI3_FLOAT64_BASE;
            return own ? &own->float64 : &kModel->real;
        case INT32:
            *base = own ? own->int32_base : SMALL_FMI3_INT32_BASE;
            return own ? &own->int32 : &kModel->integer;
        case INT64:
            *base = own ? own->int64_base : 0;
            return own ? &own->int64 : &kNone;
        case BOOLEAN:
            *base = own ? own->boolean_base : SMALL_FMI3_BOOLEAN_BASE;
            return own ? &own->boolean : &kModel->boolean;
        default:
            *base = own ? own->string_base : SMALL_FMI3_STRING_BASE;
            return own ? &own->string : &kModel->string;
    }
}

static FmuValueLayout layout_of(Type3 type) {
    return type == BOOLEAN ? FMU_VALUES_C_BOOL : type == INT64 ? FMU_VALUES_INT64 : FMU_VALUES_AS_THE_MODELS;
}

/* Every variable is a scalar: one value per value reference. */
static int counts_agree(FmiInstance* instance, const char* function, size_t nvr, size_t nvalues) {
    if (nvalues == nvr) return 1;
    fmi_log_error(instance, "%s: nValues = %zu, but the %zu variables hold %zu values", function, nvalues, nvr, nvr);
    return 0;
}

/* The getters and setters: the state, the counts, then the values through the model's table (a type
 * it has none of refused as fmi3_not_offered.c refuses the types no FMU has). */
static fmi3Status access_values(fmi3Instance handle, const char* function, int set, Type3 type,
                                const fmi3ValueReference vr[], size_t nvr, void* values, size_t nvalues, size_t size) {
    unsigned base = 0;
    const FmuVariables* variables = variables_of(type, &base);
    if (variables->count == 0 && variables->get_all == NULL)
        return fmi3_refuse_absent_type((FmiInstance*)handle, function, set, vr, nvr);
    FmiInstance* instance = usable(handle, function, fmi3_states(set ? kModel->set_states : kModel->get_states));
    if (instance == NULL || !counts_agree(instance, function, nvr, nvalues)) return fmi3Error;
    if (set)
        return (fmi3Status)fmu_model_set(instance, function, variables, kTypeName[type], base, vr, nvr, values, size,
                                         layout_of(type));
    return (fmi3Status)fmu_model_get(instance, function, variables, kTypeName[type], base, vr, nvr, values, size,
                                     layout_of(type));
}

/* fmi3GetFloat64 of a model that reads its Float64 values one by one: `time`, the independent variable,
 * is the instance's and may be anywhere among them. */
static fmi3Status get_float64(fmi3Instance handle, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                              size_t nvalues) {
    const char* function = "fmi3GetFloat64";
    unsigned base = 0;
    const FmuVariables* variables = variables_of(FLOAT64, &base);
    if (variables->get_all != NULL)
        return access_values(handle, function, 0, FLOAT64, vr, nvr, values, nvalues, sizeof(fmi3Float64));
    const unsigned time = kModel->fmi3 != NULL ? kModel->fmi3->time : SMALL_FMI3_TIME;
    FmiInstance* instance = usable(handle, function, fmi3_states(kModel->get_states));
    if (instance == NULL || !counts_agree(instance, function, nvr, nvalues)) return fmi3Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr != NULL && values != NULL && vr[i] == time) {
            values[i] = instance->time;
            continue;
        }
        const FmiStatus status = fmu_model_get(instance, function, variables, "Float64", base, vr == NULL ? NULL : vr + i,
                                               1, values == NULL ? NULL : values + i, sizeof(fmi3Float64),
                                               FMU_VALUES_AS_THE_MODELS);
        if (status > FMI_WARNING) return (fmi3Status)status;
    }
    return fmi3OK;
}

/* ---------------------------------------------------------------- lifetime */

static fmi3Instance instantiate(const char* function, fmi3String name, fmi3String token, fmi3String resource_path,
                                fmi3Boolean logging_on, const char* type_refusal, int model_exchange,
                                int event_mode_used, int early_return_allowed, fmi3InstanceEnvironment environment,
                                fmi3LogMessageCallback log) {
    FmiInstance* instance = fmi3_instantiate(&kModel->layer, function, type_refusal, name, token, model_exchange,
                                             event_mode_used, early_return_allowed, logging_on, environment, log);
    return fmu_model_instantiated(instance, function, resource_path);
}

/* ---------------------------------------------------------------- initialization, termination, reset */

static fmi3Status enter_initialization_mode(fmi3Instance handle, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                            fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    const char* function = "fmi3EnterInitializationMode";
    FmiInstance* instance = usable(handle, function, S_INSTANTIATED);
    if (instance == NULL) return fmi3Error;
    const FmiStatus status = fmu_model_start_experiment(instance, function, tolerance_defined ? 1 : 0, tolerance,
                                                        start, stop_defined ? 1 : 0, stop);
    if (status > FMI_WARNING) return (fmi3Status)status;
    instance->state = S_INITIALIZATION;
    return fmi3OK;
}

/* Model Exchange, and Co-Simulation with Event Mode, start in event mode (FMI 3.0, 3.2 and 4.2). */
static fmi3Status exit_initialization_mode(fmi3Instance handle) {
    FmiInstance* instance = usable(handle, "fmi3ExitInitializationMode", S_INITIALIZATION);
    if (instance == NULL) return fmi3Error;
    const int event_mode = instance->model_exchange || instance->event_mode_used;
    return (fmi3Status)fmu_model_exit_initialization(instance, "fmi3ExitInitializationMode",
                                                     event_mode ? S_EVENT : S_STEP);
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
    return (fmi3Status)fmu_model_reset(instance, "fmi3Reset");
}

/* ---------------------------------------------------------------- Event Mode (Model Exchange's, and
 * Co-Simulation's when the model has it) */

static const char* const kNoEventMode = "hasEventMode is false";

static fmi3Status enter_event_mode(fmi3Instance handle) {
    const char* function = "fmi3EnterEventMode";
    FmiInstance* instance = (FmiInstance*)handle;
    if (!kModel->has_event_mode && kModel->model_exchange == NULL) return not_offered(handle, function, kNoEventMode);
    const int states = instance != NULL && instance->model_exchange ? S_CONTINUOUS_TIME : S_STEP;
    if (!fmi_allowed(instance, function, states)) return fmi3Error;
    if (!instance->model_exchange && !instance->event_mode_used)
        return (fmi3Status)fmi_refuse(instance, function, "the instance was made with eventModeUsed = false");
    instance->state = S_EVENT;
    return fmi3OK;
}

static fmi3Status enter_step_mode(fmi3Instance handle) {
    const char* function = "fmi3EnterStepMode";
    if (!kModel->has_event_mode)
        return not_offered(handle, function, "hasEventMode is false: the instance never leaves step mode");
    FmiInstance* instance = usable(handle, function, S_EVENT);
    if (instance == NULL) return fmi3Error;
    if (instance->model_exchange)
        return (fmi3Status)fmi_refuse(instance, function, "a Model Exchange instance has no step mode");
    instance->state = S_STEP;
    return fmi3OK;
}

static fmi3Status update_discrete_states(fmi3Instance handle, fmi3Boolean* need, fmi3Boolean* terminate_simulation,
                                         fmi3Boolean* nominals, fmi3Boolean* values, fmi3Boolean* next_defined,
                                         fmi3Float64* next) {
    const char* function = "fmi3UpdateDiscreteStates";
    if (!kModel->has_event_mode && kModel->model_exchange == NULL) return not_offered(handle, function, kNoEventMode);
    FmiInstance* instance = usable(handle, function, S_EVENT);
    if (instance == NULL || !fmi_not_null(instance, function, need, "discreteStatesNeedUpdate") ||
        !fmi_not_null(instance, function, terminate_simulation, "terminateSimulation") ||
        !fmi_not_null(instance, function, nominals, "nominalsOfContinuousStatesChanged") ||
        !fmi_not_null(instance, function, values, "valuesOfContinuousStatesChanged") ||
        !fmi_not_null(instance, function, next_defined, "nextEventTimeDefined") ||
        !fmi_not_null(instance, function, next, "nextEventTime"))
        return fmi3Error;
    *need = *terminate_simulation = *nominals = *values = *next_defined = fmi3False;
    *next = 0.0;
    if (!instance->model_exchange) return fmi3OK; /* Co-Simulation has handled its mode changes in fmi3DoStep */
    FmuDiscreteUpdate update;
    const FmiStatus status = kModel->model_exchange->update_discrete_states(instance, &update);
    if (status > FMI_WARNING) return (fmi3Status)status;
    *values = update.states_changed != 0;
    *next_defined = update.next_time_defined != 0;
    *next = update.next_time_defined ? update.next_time : 0.0;
    return (fmi3Status)status;
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
    *event_handling_needed = *terminate_simulation = *early_return = fmi3False;
    *last_successful_time = instance->time;
    if (!fmi_step_valid(instance, function, point, step)) return fmi3Error;
    int ended_early = 0;
    const FmiStatus status = fmu_model_do_step(instance, function, point, step, &ended_early);
    if (status > FMI_WARNING) return (fmi3Status)status;
    *last_successful_time = instance->time;
    *early_return = ended_early ? fmi3True : fmi3False;
    *event_handling_needed = ended_early && instance->event_mode_used ? fmi3True : fmi3False;
    return (fmi3Status)status;
}

/* ---------------------------------------------------------------- derivatives */

/* Offered after initialization (the derivatives of the InitialUnknowns are not): the state check lets
 * initialization mode through for the message to say so. */
static fmi3Status get_directional_derivative(fmi3Instance handle, const fmi3ValueReference unknowns[], size_t nu,
                                             const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                                             size_t nseed, fmi3Float64 sensitivity[], size_t nsensitivity) {
    const char* function = "fmi3GetDirectionalDerivative";
    if (kModel->directional_derivative == NULL)
        return not_offered(handle, function, "providesDirectionalDerivatives is false");
    FmiInstance* instance = (FmiInstance*)handle;
    const int states = instance != NULL && instance->model_exchange ? S_INITIALIZATION | S_EVALUATE
                                                                    : S_INITIALIZATION | S_RUNNING | S_TERMINATED;
    if (!fmi_allowed(instance, function, states)) return fmi3Error;
    if ((nu > 0 && (!fmi_not_null(instance, function, unknowns, "unknowns") ||
                    !fmi_not_null(instance, function, sensitivity, "sensitivity"))) ||
        (nk > 0 && (!fmi_not_null(instance, function, knowns, "knowns") || !fmi_not_null(instance, function, seed, "seed"))))
        return fmi3Error;
    if (nseed != nk || nsensitivity != nu) {
        fmi_log_error(instance, "%s: nSeed = %zu and nSensitivity = %zu must equal nKnowns = %zu and nUnknowns = %zu",
                      function, nseed, nsensitivity, nk, nu);
        return fmi3Error;
    }
    if (instance->state == S_INITIALIZATION)
        return (fmi3Status)fmi_refuse(instance, function, "the derivatives are offered once initialization has ended");
    return (fmi3Status)kModel->directional_derivative(instance, function, unknowns, nu, knowns, nk, seed, sensitivity);
}

/* ---------------------------------------------------------------- Model Exchange */

static const char* const kCoSimulationOnly = "a Model Exchange function; this FMU offers Co-Simulation only";

/* The state, the interface, the count, the pointer: NULL, logged, when one is wrong. */
static FmiInstance* model_exchange_usable(fmi3Instance handle, const char* function, int states, const void* values,
                                          size_t given, size_t expected, const char* argument, const char* count_name) {
    FmiInstance* instance = usable(handle, function, states);
    if (instance == NULL || !fmu_model_exchange_instance(instance, function)) return NULL;
    if (count_name != NULL && (!fmu_model_count_is(instance, function, given, expected, count_name) ||
                               !fmi_not_null(instance, function, values, argument)))
        return NULL;
    return instance;
}

static fmi3Status enter_continuous_time_mode(fmi3Instance handle) {
    if (kModel->model_exchange == NULL) return not_offered(handle, "fmi3EnterContinuousTimeMode", kCoSimulationOnly);
    FmiInstance* instance = model_exchange_usable(handle, "fmi3EnterContinuousTimeMode", S_EVENT, NULL, 0, 0, NULL, NULL);
    if (instance == NULL) return fmi3Error;
    instance->state = S_CONTINUOUS_TIME;
    return fmi3OK;
}

static fmi3Status completed_integrator_step(fmi3Instance handle, fmi3Boolean* enter_event_mode,
                                            fmi3Boolean* terminate_simulation) {
    const char* function = "fmi3CompletedIntegratorStep";
    if (kModel->model_exchange == NULL) return not_offered(handle, function, kCoSimulationOnly);
    FmiInstance* instance = model_exchange_usable(handle, function, S_CONTINUOUS_TIME, NULL, 0, 0, NULL, NULL);
    if (instance == NULL || !fmi_not_null(instance, function, enter_event_mode, "enterEventMode") ||
        !fmi_not_null(instance, function, terminate_simulation, "terminateSimulation"))
        return fmi3Error;
    *enter_event_mode = *terminate_simulation = fmi3False; /* every mode change shows in an event indicator */
    return fmi3OK;
}

static fmi3Status set_time(fmi3Instance handle, fmi3Float64 time) {
    if (kModel->model_exchange == NULL) return not_offered(handle, "fmi3SetTime", kCoSimulationOnly);
    FmiInstance* instance =
        model_exchange_usable(handle, "fmi3SetTime", S_EVENT | S_CONTINUOUS_TIME, NULL, 0, 0, NULL, NULL);
    if (instance == NULL) return fmi3Error;
    if (!isfinite(time)) {
        fmi_log_error(instance, "fmi3SetTime: time = %g must be finite", time);
        return fmi3Error;
    }
    const FmiStatus status = kModel->model_exchange->set_time(instance, time);
    if (status <= FMI_WARNING) instance->time = time;
    return (fmi3Status)status;
}

static fmi3Status set_continuous_states(fmi3Instance handle, const fmi3Float64 x[], size_t n) {
    const char* function = "fmi3SetContinuousStates";
    if (kModel->model_exchange == NULL) return not_offered(handle, function, kCoSimulationOnly);
    FmiInstance* instance = model_exchange_usable(handle, function, S_CONTINUOUS_TIME, x, n,
                                                  kModel->model_exchange->continuous_states, "continuousStates",
                                                  "nContinuousStates");
    return instance == NULL ? fmi3Error : (fmi3Status)kModel->model_exchange->set_continuous_states(instance, x);
}

typedef enum { DERIVATIVES, EVENT_INDICATORS, CONTINUOUS_STATES, NOMINALS } Vector;
static fmi3Status read_vector(fmi3Instance handle, const char* function, int states, fmi3Float64 values[], size_t n,
                              Vector vector, const char* argument) {
    const FmuModelExchange* model = kModel->model_exchange;
    if (model == NULL) return not_offered(handle, function, kCoSimulationOnly);
    const int indicators = vector == EVENT_INDICATORS;
    const size_t expected = indicators ? model->event_indicators : model->continuous_states;
    FmiInstance* instance = model_exchange_usable(handle, function, states, values, n, expected, argument,
                                                  indicators ? "nEventIndicators" : "nContinuousStates");
    if (instance == NULL) return fmi3Error;
    switch (vector) {
        case DERIVATIVES: return (fmi3Status)model->get_derivatives(instance, values);
        case EVENT_INDICATORS: return (fmi3Status)model->get_event_indicators(instance, values);
        case CONTINUOUS_STATES: return (fmi3Status)model->get_continuous_states(instance, values);
        default: return (fmi3Status)model->get_nominals(instance, values);
    }
}

static fmi3Status count(fmi3Instance handle, const char* function, size_t* n, int event_indicators) {
    const FmuModelExchange* model = kModel->model_exchange;
    if (model == NULL) return not_offered(handle, function, kCoSimulationOnly);
    FmiInstance* instance = usable(handle, function, S_ANY);
    if (instance == NULL || !fmi_not_null(instance, function, n, "count")) return fmi3Error;
    *n = event_indicators ? model->event_indicators : model->continuous_states;
    return fmi3OK;
}

/* ---------------------------------------------------------------- the exported functions */

#define OWN_INSTANCE ((FmiInstance*)instance)

#define GET(type_name, type, c_type)                                                                          \
    fmi3Status fmi3Get##type_name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, c_type values[], \
                                  size_t nValues) {                                                           \
        IN_FMU_FP_ENVIRONMENT(fmi3Status, access_values(instance, "fmi3Get" #type_name, 0, type, vr, nvr, values, \
                                                        nValues, sizeof(c_type)));                            \
    }
#define SET(type_name, type, c_type)                                                                          \
    fmi3Status fmi3Set##type_name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,           \
                                  const c_type values[], size_t nValues) {                                    \
        IN_FMU_FP_ENVIRONMENT(fmi3Status, access_values(instance, "fmi3Set" #type_name, 1, type, vr, nvr,        \
                                                        (void*)values, nValues, sizeof(c_type)));             \
    }
GET(Int32, INT32, fmi3Int32)
GET(Int64, INT64, fmi3Int64)
GET(Boolean, BOOLEAN, fmi3Boolean)
GET(String, STRING, fmi3String)
SET(Float64, FLOAT64, fmi3Float64)
SET(Int32, INT32, fmi3Int32)
SET(Int64, INT64, fmi3Int64)
SET(Boolean, BOOLEAN, fmi3Boolean)
SET(String, STRING, fmi3String)

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_float64(instance, vr, nvr, values, nValues));
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* No intermediate update is provided; a model without Event Mode never returns early. */
    (void)visible, (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables, (void)intermediateUpdate;
    const int event_mode = kModel->has_event_mode;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance,
                          instantiate("fmi3InstantiateCoSimulation", instanceName, instantiationToken, resourcePath,
                                      loggingOn,
                                      eventModeUsed && !event_mode ? "eventModeUsed is true, but hasEventMode is false"
                                                                   : NULL,
                                      0, event_mode && eventModeUsed, event_mode && earlyReturnAllowed,
                                      instanceEnvironment, logMessage));
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                          fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate("fmi3InstantiateModelExchange", instanceName, instantiationToken,
                                                    resourcePath, loggingOn,
                                                    kModel->model_exchange != NULL ? NULL : interfaces_offered(), 1, 0,
                                                    0, instanceEnvironment, logMessage));
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)visible, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    IN_FMU_FP_ENVIRONMENT(fmi3Instance, instantiate("fmi3InstantiateScheduledExecution", instanceName, instantiationToken,
                                                    resourcePath, loggingOn, interfaces_offered(), 0, 0, 0,
                                                    instanceEnvironment, logMessage));
}

void fmi3FreeInstance(fmi3Instance instance) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    fmu_model_free_instance(OWN_INSTANCE);
    leave_fmu_fp(&host_environment);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status,
                          enter_initialization_mode(instance, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, exit_initialization_mode(instance));
}
fmi3Status fmi3Terminate(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, terminate(instance)); }
fmi3Status fmi3Reset(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, reset(instance)); }

fmi3Status fmi3EnterEventMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_event_mode(instance)); }
fmi3Status fmi3EnterStepMode(fmi3Instance instance) { IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_step_mode(instance)); }
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined,
                                    fmi3Float64* nextEventTime) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, update_discrete_states(instance, discreteStatesNeedUpdate, terminateSimulation,
                                                             nominalsOfContinuousStatesChanged,
                                                             valuesOfContinuousStatesChanged, nextEventTimeDefined,
                                                             nextEventTime));
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* eventHandlingNeeded,
                      fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, do_step(instance, currentCommunicationPoint, communicationStepSize,
                                              eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime));
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, get_directional_derivative(instance, unknowns, nUnknowns, knowns, nKnowns, seed,
                                                                 nSeed, sensitivity, nSensitivity));
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, enter_continuous_time_mode(instance));
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    IN_FMU_FP_ENVIRONMENT(fmi3Status, completed_integrator_step(instance, enterEventMode, terminateSimulation));
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) { IN_FMU_FP_ENVIRONMENT(fmi3Status, set_time(instance, time)); }
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, set_continuous_states(instance, continuousStates, n));
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(instance, "fmi3GetContinuousStateDerivatives", S_EVALUATE, derivatives,
                                                  n, DERIVATIVES, "derivatives"));
}
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(instance, "fmi3GetEventIndicators", S_INITIALIZATION | S_EVALUATE,
                                                  eventIndicators, n, EVENT_INDICATORS, "eventIndicators"));
}
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(instance, "fmi3GetContinuousStates", S_INITIALIZATION | S_EVALUATE,
                                                  continuousStates, n, CONTINUOUS_STATES, "continuousStates"));
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, read_vector(instance, "fmi3GetNominalsOfContinuousStates",
                                                  S_INSTANTIATED | S_EVALUATE, nominals, n, NOMINALS, "nominals"));
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, count(instance, "fmi3GetNumberOfEventIndicators", n, 1));
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* n) {
    IN_FMU_FP_ENVIRONMENT(fmi3Status, count(instance, "fmi3GetNumberOfContinuousStates", n, 0));
}

/* ---------------------------------------------------------------- what is not offered */
/* (Beyond what no FMU of the project offers: fmi3_not_offered.c.) */

#define NOT_OFFERED(function, why) IN_FMU_FP_ENVIRONMENT(fmi3Status, not_offered(instance, function, why))

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    NOT_OFFERED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder=\"0\": the outputs are held");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    NOT_OFFERED("fmi3ActivateModelPartition", interfaces_offered());
}
