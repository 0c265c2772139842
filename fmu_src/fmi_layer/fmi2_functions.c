/* The FMI 2.0 face of every FMU of the project (fmu_model.h): every fmi2* function, Co-Simulation and
 * Model Exchange, over the model's table, the shared part (fmu_model.c) and the layer. What the table
 * leaves NULL is refused naming the model description's declaration. Every exported function runs in
 * the default floating-point environment whatever the host's (host_fp_environment.h), so that the
 * outputs are the bits the scene runner's compiled loop computes. */
#include "fmi_layer/fmu_model.h"

#include <math.h>
#include <stddef.h>

#include "fmi_layer/host_fp_environment.h"

static const FmuModel* const kModel = &kFmuModel;

_Static_assert(sizeof(fmi2ValueReference) == sizeof(unsigned), "value references are the layer's unsigned");

/* The instance when `function` may be called in its state; NULL (logged when it can be) otherwise. */
static FmiInstance* usable(fmi2Component c, const char* function, int states) {
    FmiInstance* instance = (FmiInstance*)c;
    return fmi_allowed(instance, function, states) ? instance : NULL;
}

/* fmi2Get<type>: `value` is the host's array of elements of `size` bytes. */
static fmi2Status get_values(fmi2Component c, const char* function, const FmuVariables* variables, const char* type,
                             const fmi2ValueReference vr[], size_t nvr, void* value, size_t size) {
    FmiInstance* instance = usable(c, function, kModel->get_states);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmu_model_get(instance, function, variables, type, 0, vr, nvr, value, size,
                                     FMU_VALUES_AS_THE_MODELS);
}

/* fmi2Set<type>: all or nothing, every value checked before any is set. */
static fmi2Status set_values(fmi2Component c, const char* function, const FmuVariables* variables, const char* type,
                             const fmi2ValueReference vr[], size_t nvr, const void* value, size_t size) {
    FmiInstance* instance = usable(c, function, kModel->set_states);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmu_model_set(instance, function, variables, type, 0, vr, nvr, value, size,
                                     FMU_VALUES_AS_THE_MODELS);
}

/* What the model description declares absent, refused naming the declaration. */
static fmi2Status not_offered(fmi2Component c, const char* function, const char* declaration) {
    FmiInstance* instance = usable(c, function, ANY_STATE);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_refuse(instance, function, declaration);
}

/* ---------------------------------------------------------------- lifetime */

static fmi2Component instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resource_location,
                                 const fmi2CallbackFunctions* functions, fmi2Boolean logging_on) {
    FmiInstance* instance =
        fmi2_instantiate(&kModel->layer, kModel->model_exchange != NULL, name, type, guid, functions, logging_on);
    return fmu_model_instantiated(instance, "fmi2Instantiate", resource_location);
}

static fmi2Status set_debug_logging(fmi2Component c, fmi2Boolean on, size_t count, const fmi2String categories[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_set_debug_logging(instance, "fmi2SetDebugLogging", on != fmi2False, count, categories);
}

/* ---------------------------------------------------------------- initialization, termination, reset */

static fmi2Status setup_experiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                                   fmi2Boolean stop_defined, fmi2Real stop) {
    FmiInstance* instance = usable(c, "fmi2SetupExperiment", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmu_model_start_experiment(instance, "fmi2SetupExperiment", tolerance_defined != fmi2False,
                                                  tolerance, start, stop_defined != fmi2False, stop);
}

static fmi2Status enter_initialization_mode(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2EnterInitializationMode", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_INITIALIZATION;
    return fmi2OK;
}

/* Model Exchange starts in event mode: the host settles the modes with fmi2NewDiscreteStates. */
static fmi2Status exit_initialization_mode(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2ExitInitializationMode", STATE_INITIALIZATION);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmu_model_exit_initialization(instance, "fmi2ExitInitializationMode",
                                                     instance->model_exchange ? STATE_EVENT_MODE : STATE_STEP_COMPLETE);
}

static fmi2Status terminate(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2Terminate", kModel->terminate_states);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_TERMINATED;
    return fmi2OK;
}

static fmi2Status reset(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2Reset", ANY_STATE);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmu_model_reset(instance, "fmi2Reset");
}

/* ---------------------------------------------------------------- stepping and its status */

static fmi2Status do_step(fmi2Component c, fmi2Real point, fmi2Real step) {
    FmiInstance* instance = usable(c, "fmi2DoStep", STATE_STEP_COMPLETE);
    if (instance == NULL || !fmi_step_valid(instance, "fmi2DoStep", point, step)) return fmi2Error;
    int ended_early; /* never: FMI 2.0 has no early return */
    return (fmi2Status)fmu_model_do_step(instance, "fmi2DoStep", point, step, &ended_early);
}

/* The status calls' common checks: the state, the pointer, the kind. */
static FmiInstance* status_usable(fmi2Component c, const char* function, const void* value, fmi2StatusKind kind,
                                  fmi2StatusKind provided, const char* kind_refusal) {
    FmiInstance* instance = usable(c, function, kModel->status_states);
    if (instance == NULL || !fmi_not_null(instance, function, value, "value")) return NULL;
    if (kind == provided) return instance;
    fmi_log_error(instance, "%s: status kind %d %s", function, (int)kind, kind_refusal);
    return NULL;
}

static fmi2Status get_status(fmi2Component c, fmi2StatusKind kind, fmi2Status* value) {
    FmiInstance* instance = status_usable(c, "fmi2GetStatus", value, kind, fmi2DoStepStatus, "is not a fmi2Status");
    if (instance == NULL) return fmi2Error;
    *value = (fmi2Status)instance->last_step_status;
    return fmi2OK;
}

static fmi2Status get_real_status(fmi2Component c, fmi2StatusKind kind, fmi2Real* value) {
    FmiInstance* instance =
        status_usable(c, "fmi2GetRealStatus", value, kind, fmi2LastSuccessfulTime, "is not a Real status");
    if (instance == NULL) return fmi2Error;
    *value = instance->last_successful_time;
    return fmi2OK;
}

static fmi2Status get_integer_status(fmi2Component c, fmi2StatusKind kind, fmi2Integer* value) {
    (void)kind;
    FmiInstance* instance = usable(c, "fmi2GetIntegerStatus", kModel->status_states);
    if (instance == NULL || !fmi_not_null(instance, "fmi2GetIntegerStatus", value, "value")) return fmi2Error;
    return (fmi2Status)fmi_refuse(instance, "fmi2GetIntegerStatus", "no status kind has an Integer value");
}

static fmi2Status get_boolean_status(fmi2Component c, fmi2StatusKind kind, fmi2Boolean* value) {
    FmiInstance* instance =
        status_usable(c, "fmi2GetBooleanStatus", value, kind, fmi2Terminated, "has no Boolean value");
    if (instance == NULL) return fmi2Error;
    *value = fmi2False; /* no FMU of the project asks to end the simulation */
    return fmi2OK;
}

static fmi2Status get_string_status(fmi2Component c, fmi2StatusKind kind, fmi2String* value) {
    FmiInstance* instance =
        status_usable(c, "fmi2GetStringStatus", value, kind, fmi2PendingStatus, "has no String value");
    if (instance == NULL) return fmi2Error;
    *value = ""; /* doStep is synchronous: never pending */
    return fmi2OK;
}

/* ---------------------------------------------------------------- FMU states */

/* The state check, then the layer's call; refused naming the capability when the model offers none. */
#define FMU_STATE_CALL(function, states, capability, call)                               \
    FmiInstance* instance = (FmiInstance*)c;                                            \
    if (!kModel->fmi2_fmu_state) return not_offered(c, function, capability " is false"); \
    if (!fmi_allowed(instance, function, states)) return fmi2Error;                     \
    return (fmi2Status)call

static fmi2Status get_fmu_state(fmi2Component c, fmi2FMUstate* state) {
    FMU_STATE_CALL("fmi2GetFMUstate", FMU_STATE_STATES, "canGetAndSetFMUstate",
                   fmi_get_fmu_state(instance, "fmi2GetFMUstate", state));
}
static fmi2Status set_fmu_state(fmi2Component c, fmi2FMUstate state) {
    FMU_STATE_CALL("fmi2SetFMUstate", FMU_STATE_STATES, "canGetAndSetFMUstate",
                   fmi_set_fmu_state(instance, "fmi2SetFMUstate", state));
}
static fmi2Status free_fmu_state(fmi2Component c, fmi2FMUstate* state) {
    FMU_STATE_CALL("fmi2FreeFMUstate", ANY_STATE, "canGetAndSetFMUstate",
                   fmi_free_fmu_state(instance, "fmi2FreeFMUstate", state));
}
static fmi2Status serialized_fmu_state_size(fmi2Component c, fmi2FMUstate state, size_t* size) {
    FMU_STATE_CALL("fmi2SerializedFMUstateSize", ANY_STATE, "canSerializeFMUstate",
                   fmi_serialized_fmu_state_size(instance, "fmi2SerializedFMUstateSize", state, size));
}
static fmi2Status serialize_fmu_state(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    FMU_STATE_CALL("fmi2SerializeFMUstate", ANY_STATE, "canSerializeFMUstate",
                   fmi_serialize_fmu_state(instance, "fmi2SerializeFMUstate", state, (unsigned char*)bytes, size));
}
static fmi2Status deserialize_fmu_state(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state) {
    FMU_STATE_CALL("fmi2DeSerializeFMUstate", ANY_STATE, "canSerializeFMUstate",
                   fmi_deserialize_fmu_state(instance, "fmi2DeSerializeFMUstate", (const unsigned char*)bytes, size,
                                             state));
}

/* ---------------------------------------------------------------- derivatives */

/* After initialization only: the derivatives of the InitialUnknowns are not provided. */
static fmi2Status get_directional_derivative(fmi2Component c, const fmi2ValueReference unknowns[], size_t nu,
                                             const fmi2ValueReference knowns[], size_t nk, const fmi2Real seed[],
                                             fmi2Real sensitivity[]) {
    const char* function = "fmi2GetDirectionalDerivative";
    if (kModel->directional_derivative == NULL) return not_offered(c, function, "providesDirectionalDerivative is false");
    FmiInstance* instance = usable(c, function, STATUS_STATES | EVALUATION_STATES);
    if (instance == NULL) return fmi2Error;
    if ((nu > 0 && (!fmi_not_null(instance, function, unknowns, "vUnknown_ref") ||
                    !fmi_not_null(instance, function, sensitivity, "dvUnknown"))) ||
        (nk > 0 && (!fmi_not_null(instance, function, knowns, "vKnown_ref") ||
                    !fmi_not_null(instance, function, seed, "dvKnown"))))
        return fmi2Error;
    return (fmi2Status)kModel->directional_derivative(instance, function, unknowns, nu, knowns, nk, seed, sensitivity);
}

static fmi2Status set_real_input_derivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                             const fmi2Integer order[], const fmi2Real value[]) {
    const char* function = "fmi2SetRealInputDerivatives";
    if (kModel->set_input_derivative == NULL)
        return not_offered(c, function, "canInterpolateInputs is false: inputs are sampled at the step's start");
    FmiInstance* instance = usable(c, function, STATE_INITIALIZATION | STATE_STEP_COMPLETE);
    if (instance == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (!fmi_not_null(instance, function, vr, "vr") || !fmi_not_null(instance, function, order, "order") ||
        !fmi_not_null(instance, function, value, "value"))
        return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const FmiStatus status = kModel->set_input_derivative(instance, function, vr[i], (int)order[i], value[i]);
        if (status > FMI_WARNING) return (fmi2Status)status;
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- Model Exchange (FMI 2.0, section 3.2.3) */

/* The state masks let a Co-Simulation instance through in the states both interfaces share
 * (instantiated, initialization mode): these functions are Model Exchange's alone. */
static FmiInstance* model_exchange_usable(fmi2Component c, const char* function, int states) {
    if (kModel->model_exchange == NULL) {
        not_offered(c, function, "a Model Exchange function; this FMU offers Co-Simulation only");
        return NULL;
    }
    FmiInstance* instance = usable(c, function, states);
    return instance != NULL && fmu_model_exchange_instance(instance, function) ? instance : NULL;
}

static fmi2Status enter_mode(fmi2Component c, const char* function, int from, int to) {
    FmiInstance* instance = model_exchange_usable(c, function, from);
    if (instance == NULL) return fmi2Error;
    instance->state = to;
    return fmi2OK;
}

static fmi2Status new_discrete_states(fmi2Component c, fmi2EventInfo* info) {
    const char* function = "fmi2NewDiscreteStates";
    FmiInstance* instance = model_exchange_usable(c, function, STATE_EVENT_MODE);
    if (instance == NULL || !fmi_not_null(instance, function, info, "fmi2eventInfo")) return fmi2Error;
    FmuDiscreteUpdate update;
    const FmiStatus status = kModel->model_exchange->update_discrete_states(instance, &update);
    if (status > FMI_WARNING) return (fmi2Status)status;
    info->newDiscreteStatesNeeded = fmi2False; /* the modes are decided whole in one call */
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = update.states_changed ? fmi2True : fmi2False;
    info->nextEventTimeDefined = update.next_time_defined ? fmi2True : fmi2False;
    info->nextEventTime = update.next_time_defined ? update.next_time : 0.0;
    return (fmi2Status)status;
}

static fmi2Status completed_integrator_step(fmi2Component c, fmi2Boolean* enter_event_mode,
                                            fmi2Boolean* terminate_simulation) {
    const char* function = "fmi2CompletedIntegratorStep";
    FmiInstance* instance = model_exchange_usable(c, function, STATE_CONTINUOUS_TIME);
    if (instance == NULL || !fmi_not_null(instance, function, enter_event_mode, "enterEventMode") ||
        !fmi_not_null(instance, function, terminate_simulation, "terminateSimulation"))
        return fmi2Error;
    *enter_event_mode = fmi2False; /* every mode change shows in an event indicator: no step events */
    *terminate_simulation = fmi2False;
    return fmi2OK;
}

static fmi2Status set_time(fmi2Component c, fmi2Real time) {
    FmiInstance* instance = model_exchange_usable(c, "fmi2SetTime", STATE_EVENT_MODE | STATE_CONTINUOUS_TIME);
    if (instance == NULL) return fmi2Error;
    if (!isfinite(time)) {
        fmi_log_error(instance, "fmi2SetTime: time = %g must be finite", time);
        return fmi2Error;
    }
    const FmiStatus status = kModel->model_exchange->set_time(instance, time);
    if (status <= FMI_WARNING) instance->time = time;
    return (fmi2Status)status;
}

/* The vectors: the state, the interface, the count, the pointer; then the model's. */
static FmiInstance* vector_usable(fmi2Component c, const char* function, int states, const void* values, size_t given,
                                  int event_indicators, const char* argument) {
    FmiInstance* instance = model_exchange_usable(c, function, states);
    if (instance == NULL) return NULL;
    const FmuModelExchange* model = kModel->model_exchange;
    if (!fmu_model_count_is(instance, function, given,
                            event_indicators ? model->event_indicators : model->continuous_states,
                            event_indicators ? "ni" : "nx") ||
        !fmi_not_null(instance, function, values, argument))
        return NULL;
    return instance;
}

static fmi2Status set_continuous_states(fmi2Component c, const fmi2Real x[], size_t nx) {
    FmiInstance* instance = vector_usable(c, "fmi2SetContinuousStates", STATE_CONTINUOUS_TIME, x, nx, 0, "x");
    return instance == NULL ? fmi2Error : (fmi2Status)kModel->model_exchange->set_continuous_states(instance, x);
}

typedef enum { DERIVATIVES, EVENT_INDICATORS, CONTINUOUS_STATES, NOMINALS } Vector;
static fmi2Status read_vector(fmi2Component c, const char* function, int states, fmi2Real values[], size_t given,
                              Vector vector, const char* argument) {
    FmiInstance* instance = vector_usable(c, function, states, values, given, vector == EVENT_INDICATORS, argument);
    if (instance == NULL) return fmi2Error;
    const FmuModelExchange* model = kModel->model_exchange;
    switch (vector) {
        case DERIVATIVES: return (fmi2Status)model->get_derivatives(instance, values);
        case EVENT_INDICATORS: return (fmi2Status)model->get_event_indicators(instance, values);
        case CONTINUOUS_STATES: return (fmi2Status)model->get_continuous_states(instance, values);
        default: return (fmi2Status)model->get_nominals(instance, values);
    }
}

/* ---------------------------------------------------------------- the exported functions */

#define GET(type_name, variables, c_type)                                                                          \
    fmi2Status fmi2Get##type_name(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, c_type value[]) {    \
        IN_FMU_FP_ENVIRONMENT(fmi2Status, get_values(c, "fmi2Get" #type_name, &kModel->variables, #type_name, vr,  \
                                                     nvr, value, sizeof(c_type)));                                 \
    }
#define SET(type_name, variables, c_type)                                                                          \
    fmi2Status fmi2Set##type_name(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,                      \
                                  const c_type value[]) {                                                          \
        IN_FMU_FP_ENVIRONMENT(fmi2Status, set_values(c, "fmi2Set" #type_name, &kModel->variables, #type_name, vr,  \
                                                     nvr, value, sizeof(c_type)));                                 \
    }
GET(Real, real, fmi2Real)
GET(Integer, integer, fmi2Integer)
GET(Boolean, boolean, fmi2Boolean)
GET(String, string, fmi2String)
SET(Real, real, fmi2Real)
SET(Integer, integer, fmi2Integer)
SET(Boolean, boolean, fmi2Boolean)
SET(String, string, fmi2String)

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t count, const fmi2String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_debug_logging(c, on, count, categories));
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resource_location,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible, fmi2Boolean logging_on) {
    (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi2Component, instantiate(name, type, guid, resource_location, functions, logging_on));
}

void fmi2FreeInstance(fmi2Component c) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    fmu_model_free_instance((FmiInstance*)c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, setup_experiment(c, tolerance_defined, tolerance, start, stop_defined, stop));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, enter_initialization_mode(c)); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, exit_initialization_mode(c)); }
fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, terminate(c)); }
fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, reset(c)); }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real point, fmi2Real step, fmi2Boolean no_set_prior_state) {
    (void)no_set_prior_state; /* a state the host set before is no burden: nothing is kept for it */
    IN_FMU_FP_ENVIRONMENT(fmi2Status, do_step(c, point, step));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_status(c, kind, value));
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_real_status(c, kind, value));
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_integer_status(c, kind, value));
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_boolean_status(c, kind, value));
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_string_status(c, kind, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_fmu_state(c, state));
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_fmu_state(c, state));
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, free_fmu_state(c, state));
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, serialized_fmu_state_size(c, state, size));
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, serialize_fmu_state(c, state, bytes, size));
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, deserialize_fmu_state(c, bytes, size, state));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[], size_t n_unknowns,
                                        const fmi2ValueReference knowns[], size_t n_knowns, const fmi2Real d_knowns[],
                                        fmi2Real d_unknowns[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          get_directional_derivative(c, unknowns, n_unknowns, knowns, n_knowns, d_knowns, d_unknowns));
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_real_input_derivatives(c, vr, nvr, order, value));
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, enter_mode(c, "fmi2EnterEventMode", STATE_CONTINUOUS_TIME, STATE_EVENT_MODE));
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status,
                          enter_mode(c, "fmi2EnterContinuousTimeMode", STATE_EVENT_MODE, STATE_CONTINUOUS_TIME));
}
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* info) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, new_discrete_states(c, info));
}
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean no_set_prior_state, fmi2Boolean* enter_event_mode,
                                       fmi2Boolean* terminate_simulation) {
    (void)no_set_prior_state;
    IN_FMU_FP_ENVIRONMENT(fmi2Status, completed_integrator_step(c, enter_event_mode, terminate_simulation));
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { IN_FMU_FP_ENVIRONMENT(fmi2Status, set_time(c, time)); }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_continuous_states(c, x, nx));
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, read_vector(c, "fmi2GetDerivatives", EVALUATION_STATES, derivatives, nx,
                                                  DERIVATIVES, "derivatives"));
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real indicators[], size_t ni) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, read_vector(c, "fmi2GetEventIndicators", STATE_INITIALIZATION | EVALUATION_STATES,
                                                  indicators, ni, EVENT_INDICATORS, "eventIndicators"));
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, read_vector(c, "fmi2GetContinuousStates", STATE_INITIALIZATION | EVALUATION_STATES,
                                                  x, nx, CONTINUOUS_STATES, "x"));
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nominals[], size_t nx) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, read_vector(c, "fmi2GetNominalsOfContinuousStates",
                                                  STATE_INSTANTIATED | EVALUATION_STATES, nominals, nx, NOMINALS,
                                                  "x_nominal"));
}

/* The refusals take no floating-point environment: they compute nothing. */
fmi2Status fmi2CancelStep(fmi2Component c) {
    return not_offered(c, "fmi2CancelStep", "fmi2DoStep never runs asynchronously");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return not_offered(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder=\"0\": the outputs are held");
}
