/* The FMI 2.0 Co-Simulation face of the small FMUs (small_cosim_model.h): every fmi2* function, over
 * the model's table, the shared part (small_cosim.c) and the layer. Every exported function runs
 * in the default floating-point environment whatever the host's (host_fp_environment.h), so that the
 * outputs are the bits the scene runner's compiled loop computes. */
#include "fmi_layer/small_cosim_model.h"

#include <stddef.h>

#include "host_fp_environment.h"

static const SmallCosimModel* const kModel = &kSmallCosimModel;

enum { kAnyState = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR };

/* The instance when `function` may be called in its state; NULL (logged when it can be) otherwise. */
static FmiInstance* usable(fmi2Component c, const char* function, int states) {
    FmiInstance* instance = (FmiInstance*)c;
    return fmi_allowed(instance, function, states) ? instance : NULL;
}

_Static_assert(sizeof(fmi2ValueReference) == sizeof(unsigned), "value references are the layer's unsigned");

/* fmi2Get<type>: `value` is the host's array of elements of `size` bytes. */
static fmi2Status get_values(fmi2Component c, const char* function, const SmallCosimVariables* variables, const char* type,
                             const fmi2ValueReference vr[], size_t nvr, void* value, size_t size) {
    FmiInstance* instance = usable(c, function, kModel->get_states);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)small_cosim_get(instance, function, variables, type, 0, vr, nvr, value, size,
                                       SMALL_VALUES_AS_THE_MODELS);
}

/* fmi2Set<type>: all or nothing, every value checked before any is set. */
static fmi2Status set_values(fmi2Component c, const char* function, const SmallCosimVariables* variables, const char* type,
                             const fmi2ValueReference vr[], size_t nvr, const void* value, size_t size) {
    FmiInstance* instance = usable(c, function, kModel->set_states);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)small_cosim_set(instance, function, variables, type, 0, vr, nvr, value, size,
                                       SMALL_VALUES_AS_THE_MODELS);
}

/* ---------------------------------------------------------------- lifetime */

static fmi2Component instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resource_location,
                                 const fmi2CallbackFunctions* functions, fmi2Boolean logging_on) {
    FmiInstance* instance = fmi2_instantiate(&kModel->layer, 0, name, type, guid, functions, logging_on);
    return small_cosim_instantiated(instance, "fmi2Instantiate", resource_location);
}

static fmi2Status set_debug_logging(fmi2Component c, fmi2Boolean on, size_t count, const fmi2String categories[]) {
    FmiInstance* instance = (FmiInstance*)c;
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_set_debug_logging(instance, "fmi2SetDebugLogging", on != fmi2False, count, categories);
}

/* ---------------------------------------------------------------- initialization, termination, reset */

static fmi2Status setup_experiment(fmi2Component c, fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    FmiInstance* instance = usable(c, "fmi2SetupExperiment", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)small_cosim_start_experiment(instance, "fmi2SetupExperiment", start, stop_defined != fmi2False,
                                                    stop);
}

static fmi2Status enter_initialization_mode(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2EnterInitializationMode", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_INITIALIZATION;
    return fmi2OK;
}

static fmi2Status exit_initialization_mode(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2ExitInitializationMode", STATE_INITIALIZATION);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)small_cosim_exit_initialization(instance, "fmi2ExitInitializationMode", STATE_STEP_COMPLETE);
}

static fmi2Status terminate(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2Terminate", kModel->terminate_states);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_TERMINATED;
    return fmi2OK;
}

static fmi2Status reset(fmi2Component c) {
    FmiInstance* instance = usable(c, "fmi2Reset", kAnyState);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)small_cosim_reset(instance, "fmi2Reset");
}

/* ---------------------------------------------------------------- stepping and its status */

static fmi2Status do_step(fmi2Component c, fmi2Real point, fmi2Real step) {
    FmiInstance* instance = usable(c, "fmi2DoStep", STATE_STEP_COMPLETE);
    if (instance == NULL || !fmi_step_valid(instance, "fmi2DoStep", point, step)) return fmi2Error;
    return (fmi2Status)kModel->do_step(instance, "fmi2DoStep", point, step);
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
    *value = instance->time;
    return fmi2OK;
}

static fmi2Status get_boolean_status(fmi2Component c, fmi2StatusKind kind, fmi2Boolean* value) {
    FmiInstance* instance =
        status_usable(c, "fmi2GetBooleanStatus", value, kind, fmi2Terminated, "has no Boolean value");
    if (instance == NULL) return fmi2Error;
    *value = fmi2False; /* a small FMU never asks to end the simulation */
    return fmi2OK;
}

static fmi2Status get_string_status(fmi2Component c, fmi2StatusKind kind, fmi2String* value) {
    FmiInstance* instance =
        status_usable(c, "fmi2GetStringStatus", value, kind, fmi2PendingStatus, "has no String value");
    if (instance == NULL) return fmi2Error;
    *value = ""; /* doStep is synchronous: never pending */
    return fmi2OK;
}

/* What the model descriptions declare absent, refused naming the declaration. */
static fmi2Status not_offered(fmi2Component c, const char* function, const char* declaration) {
    FmiInstance* instance = usable(c, function, kAnyState);
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_refuse(instance, function, declaration);
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
    small_cosim_free_instance((FmiInstance*)c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tolerance_defined, (void)tolerance; /* nothing is integrated: no tolerance to meet */
    IN_FMU_FP_ENVIRONMENT(fmi2Status, setup_experiment(c, start, stop_defined, stop));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, enter_initialization_mode(c)); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, exit_initialization_mode(c)); }
fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, terminate(c)); }
fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, reset(c)); }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real point, fmi2Real step, fmi2Boolean no_set_prior_state) {
    (void)no_set_prior_state; /* no FMU states are offered */
    IN_FMU_FP_ENVIRONMENT(fmi2Status, do_step(c, point, step));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_status(c, kind, value));
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_real_status(c, kind, value));
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_boolean_status(c, kind, value));
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_string_status(c, kind, value));
}

/* The refusals take no floating-point environment: they compute nothing. */
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value) {
    (void)kind, (void)value;
    return not_offered(c, "fmi2GetIntegerStatus", "no status kind has an Integer value");
}
fmi2Status fmi2CancelStep(fmi2Component c) {
    return not_offered(c, "fmi2CancelStep", "fmi2DoStep never runs asynchronously");
}
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
    (void)state;
    return not_offered(c, "fmi2GetFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    return not_offered(c, "fmi2SetFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
    (void)state;
    return not_offered(c, "fmi2FreeFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
    (void)state, (void)size;
    return not_offered(c, "fmi2SerializedFMUstateSize", "canSerializeFMUstate is false");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)state, (void)bytes, (void)size;
    return not_offered(c, "fmi2SerializeFMUstate", "canSerializeFMUstate is false");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state) {
    (void)bytes, (void)size, (void)state;
    return not_offered(c, "fmi2DeSerializeFMUstate", "canSerializeFMUstate is false");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[], size_t n_unknowns,
                                        const fmi2ValueReference knowns[], size_t n_knowns, const fmi2Real d_knowns[],
                                        fmi2Real d_unknowns[]) {
    (void)unknowns, (void)n_unknowns, (void)knowns, (void)n_knowns, (void)d_knowns, (void)d_unknowns;
    return not_offered(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return not_offered(c, "fmi2SetRealInputDerivatives",
                       "canInterpolateInputs is false: inputs are sampled at the step's start");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return not_offered(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0: the outputs are held");
}
