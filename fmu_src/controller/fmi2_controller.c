/* FMI 2.0 Co-Simulation interface of the controller FMU: the state machine, argument checks and
 * logging of the standard around controller_model.c. Every fmi2* function checks its instance's state
 * and its arguments and, refusing, returns fmi2Error with a message naming the function and the
 * culprit; nothing else leaves the FMU (no output on stdout or stderr, no exit). Each call runs in the
 * default floating-point environment whatever the host's (host_fp_environment.h), so that the
 * voltages are the bits the scene runner's compiled loop computes. */
#include <math.h>
#include <stddef.h>

#include <stdlib.h>

#include "controller_guid.h"
#include "controller_model.h"
#include "fmi_layer/fmi2_face.h"
#include "host_fp_environment.h"

enum { kAnyState = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED | STATE_ERROR,
       kGetStates = STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED,
       kSetStates = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE };

typedef FmiInstance Instance;

static ControllerModel* model_of(const Instance* instance) { return (ControllerModel*)instance->model_data; }

/* ---------------------------------------------------------------- the model's table */

static const char* const kLogCategories[] = {"logStatusError", "logAll"};

static void* create_model(FmiInstance* instance) {
    (void)instance;
    ControllerModel* model = (ControllerModel*)malloc(sizeof(ControllerModel));
    if (model != NULL) controller_model_reset(model);
    return model;
}

/* canGetAndSetFMUstate is false: the FMU-state calls are refused before they reach the layer. */
static const FmiModel kControllerModel = {
    CONTROLLER_GUID, sizeof(FmiInstance), kLogCategories, (int)(sizeof kLogCategories / sizeof kLogCategories[0]), create_model, free,
    NULL, NULL, NULL, NULL, NULL,
};

/* The instance when `function` may be called in its state; NULL (logged when it can be) otherwise. */
static Instance* usable(fmi2Component c, const char* function, int states) {
    Instance* instance = (Instance*)c;
    return fmi_allowed(instance, function, states) ? instance : NULL;
}

static int arrays_given(const Instance* instance, const char* function, size_t nvr, const void* vr, const void* value) {
    return nvr == 0 || (fmi_not_null(instance, function, vr, "vr") && fmi_not_null(instance, function, value, "value"));
}

static fmi2Status refused(fmi2Component c, const char* function, const char* why) {
    return (fmi2Status)fmi_refuse((const Instance*)c, function, why);
}

/* ---------------------------------------------------------------- lifetime */

static fmi2Component impl_Instantiate(fmi2String name, fmi2Type type, fmi2String guid, const fmi2CallbackFunctions* functions,
                                      fmi2Boolean logging_on) {
    return fmi2_instantiate(&kControllerModel, 0, name, type, guid, functions, logging_on);
}

static void impl_FreeInstance(fmi2Component c) { fmi_free_instance((Instance*)c); }

static fmi2Status impl_SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t count, const fmi2String categories[]) {
    Instance* instance = (Instance*)c;
    if (instance == NULL) return fmi2Error;
    return (fmi2Status)fmi_set_debug_logging(instance, "fmi2SetDebugLogging", on != fmi2False, count, categories);
}

/* ---------------------------------------------------------------- initialization and termination */

static fmi2Status impl_SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                                       fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tolerance_defined, (void)tolerance; /* nothing is integrated */
    Instance* instance = usable(c, "fmi2SetupExperiment", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    if (!fmi_experiment_times_valid(instance, "fmi2SetupExperiment", start, stop_defined != fmi2False, stop))
        return fmi2Error;
    instance->time = start, instance->stop_time = stop, instance->stop_time_defined = stop_defined ? 1 : 0;
    return fmi2OK;
}

static fmi2Status impl_EnterInitializationMode(fmi2Component c) {
    Instance* instance = usable(c, "fmi2EnterInitializationMode", STATE_INSTANTIATED);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_INITIALIZATION;
    return fmi2OK;
}

static fmi2Status impl_ExitInitializationMode(fmi2Component c) {
    Instance* instance = usable(c, "fmi2ExitInitializationMode", STATE_INITIALIZATION);
    if (instance == NULL) return fmi2Error;
    char why[512];
    if (!controller_model_check(model_of(instance), why, sizeof why)) {
        /* still in initialization mode: the master may correct the parameter and retry */
        fmi_log_error(instance, "fmi2ExitInitializationMode: %s", why);
        return fmi2Error;
    }
    controller_model_start(model_of(instance));
    instance->state = STATE_STEP_COMPLETE;
    return fmi2OK;
}

static fmi2Status impl_Terminate(fmi2Component c) {
    Instance* instance = usable(c, "fmi2Terminate", STATE_STEP_COMPLETE);
    if (instance == NULL) return fmi2Error;
    instance->state = STATE_TERMINATED;
    return fmi2OK;
}

static fmi2Status impl_Reset(fmi2Component c) {
    Instance* instance = usable(c, "fmi2Reset", kAnyState);
    if (instance == NULL) return fmi2Error;
    controller_model_reset(model_of(instance));
    instance->time = 0.0, instance->stop_time_defined = 0;
    instance->state = STATE_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- values */

/* Which variables may be set now: inputs always; parameters before initialization ends. */
static int settable(const Instance* instance, int parameter) {
    return !parameter || (instance->state & (STATE_INSTANTIATED | STATE_INITIALIZATION));
}

static fmi2Status impl_SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance* instance = usable(c, "fmi2SetReal", kSetStates);
    if (instance == NULL || !arrays_given(instance, "fmi2SetReal", nvr, vr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) { /* all checked before any is applied */
        if (vr[i] >= REAL_COUNT) {
            fmi_log_error(instance, "fmi2SetReal: value reference %u is not a Real variable", (unsigned)vr[i]);
            return fmi2Error;
        }
        const ControllerReal* v = &kControllerReals[vr[i]];
        if (v->causality == OUTPUT || !settable(instance, v->causality == PARAMETER)) {
            fmi_log_error(instance, "fmi2SetReal: %s cannot be set in state '%s'", v->name, instance->face->state_name(instance->state));
            return fmi2Error;
        }
        if (!isfinite(value[i])) {
            fmi_log_error(instance, "fmi2SetReal: %s = %g is not finite", v->name, value[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; ++i) model_of(instance)->real[vr[i]] = value[i];
    return fmi2OK;
}

static fmi2Status impl_GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance* instance = usable(c, "fmi2GetReal", kGetStates);
    if (instance == NULL || !arrays_given(instance, "fmi2GetReal", nvr, vr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        if (vr[i] >= REAL_COUNT) {
            fmi_log_error(instance, "fmi2GetReal: value reference %u is not a Real variable", (unsigned)vr[i]);
            return fmi2Error;
        }
        value[i] = model_of(instance)->real[vr[i]];
    }
    return fmi2OK;
}

/* Integer and Boolean variables are all parameters, stored as int (fmi2Boolean is an int too). */
static int* int_store(Instance* instance, int boolean, int* count) {
    *count = boolean ? BOOLEAN_COUNT : INTEGER_COUNT;
    return boolean ? model_of(instance)->boolean : model_of(instance)->integer;
}

static const char* int_name(int boolean, fmi2ValueReference vr) {
    return boolean ? kControllerBooleans[vr].name : kControllerIntegers[vr].name;
}

static int int_reference_known(const Instance* instance, const char* function, fmi2ValueReference vr, int count,
                               int boolean) {
    if (vr < (unsigned)count) return 1;
    fmi_log_error(instance, "%s: value reference %u is not a%s variable", function, (unsigned)vr,
              boolean ? " Boolean" : "n Integer");
    return 0;
}

static fmi2Status set_ints(fmi2Component c, const char* function, const fmi2ValueReference vr[], size_t nvr,
                           const fmi2Integer value[], int boolean) {
    Instance* instance = usable(c, function, kSetStates);
    if (instance == NULL || !arrays_given(instance, function, nvr, vr, value)) return fmi2Error;
    int count;
    int* store = int_store(instance, boolean, &count);
    for (size_t i = 0; i < nvr; ++i) {
        if (!int_reference_known(instance, function, vr[i], count, boolean)) return fmi2Error;
        if (!settable(instance, 1)) {
            fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, int_name(boolean, vr[i]),
                      instance->face->state_name(instance->state));
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; ++i) store[vr[i]] = boolean ? (value[i] != fmi2False) : value[i];
    return fmi2OK;
}

static fmi2Status get_ints(fmi2Component c, const char* function, const fmi2ValueReference vr[], size_t nvr,
                           fmi2Integer value[], int boolean) {
    Instance* instance = usable(c, function, kGetStates);
    if (instance == NULL || !arrays_given(instance, function, nvr, vr, value)) return fmi2Error;
    int count;
    const int* store = int_store(instance, boolean, &count);
    for (size_t i = 0; i < nvr; ++i) {
        if (!int_reference_known(instance, function, vr[i], count, boolean)) return fmi2Error;
        value[i] = boolean ? (store[vr[i]] ? fmi2True : fmi2False) : store[vr[i]];
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- stepping */

static fmi2Status impl_DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior_state) {
    (void)no_set_prior_state;
    Instance* instance = usable(c, "fmi2DoStep", STATE_STEP_COMPLETE);
    if (instance == NULL) return fmi2Error;
    if (!fmi_step_valid(instance, "fmi2DoStep", t, h)) return fmi2Error;
    const double end = t + h;
    ControllerModel* model = model_of(instance);
    controller_model_step(model, h);
    /* A step far below the controller's sampling (h = 5e-324: its backward differences divide by h)
     * or gains that overflow leave no usable command: the host gets an error, never a NaN voltage. */
    for (int k = OUT_U_R1; k <= OUT_BETA_REF; ++k) {
        if (isfinite(model->real[k])) continue;
        fmi_log_error(instance, "fmi2DoStep: %s = %g after the step of %g s: the controller cannot continue (fmi2Reset)",
                      kControllerReals[k].name, model->real[k], h);
        instance->state = STATE_ERROR;
        return fmi2Error;
    }
    instance->time = end;
    return fmi2OK;
}

static fmi2Status impl_GetStatus(fmi2Component c, fmi2StatusKind kind, fmi2Status* value) {
    Instance* instance = usable(c, "fmi2GetStatus", STATE_STEP_COMPLETE | STATE_TERMINATED);
    if (instance == NULL) return fmi2Error;
    if (value == NULL) return refused(c, "fmi2GetStatus", "argument value is a null pointer");
    if (kind != fmi2DoStepStatus) return refused(c, "fmi2GetStatus", "only fmi2DoStepStatus is provided");
    *value = fmi2OK; /* fmi2DoStep never runs asynchronously */
    return fmi2OK;
}

static fmi2Status impl_GetRealStatus(fmi2Component c, fmi2StatusKind kind, fmi2Real* value) {
    Instance* instance = usable(c, "fmi2GetRealStatus", STATE_STEP_COMPLETE | STATE_TERMINATED);
    if (instance == NULL) return fmi2Error;
    if (value == NULL) return refused(c, "fmi2GetRealStatus", "argument value is a null pointer");
    if (kind != fmi2LastSuccessfulTime) return refused(c, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is provided");
    *value = instance->time;
    return fmi2OK;
}

static fmi2Status impl_GetBooleanStatus(fmi2Component c, fmi2StatusKind kind, fmi2Boolean* value) {
    Instance* instance = usable(c, "fmi2GetBooleanStatus", STATE_STEP_COMPLETE | STATE_TERMINATED);
    if (instance == NULL) return fmi2Error;
    if (value == NULL) return refused(c, "fmi2GetBooleanStatus", "argument value is a null pointer");
    if (kind != fmi2Terminated) return refused(c, "fmi2GetBooleanStatus", "only fmi2Terminated is provided");
    *value = fmi2False; /* the controller never ends a simulation */
    return fmi2OK;
}

/* ---------------------------------------------------------------- the exported functions */

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t count, const fmi2String categories[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetDebugLogging(c, on, count, categories));
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible, fmi2Boolean logging_on) {
    (void)resources, (void)visible;
    IN_FMU_FP_ENVIRONMENT(fmi2Component, impl_Instantiate(name, type, guid, functions, logging_on));
}

void fmi2FreeInstance(fmi2Component c) {
    HostFpEnvironment host_environment;
    enter_fmu_fp(&host_environment);
    impl_FreeInstance(c);
    leave_fmu_fp(&host_environment);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetupExperiment(c, tolerance_defined, tolerance, start, stop_defined, stop));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_EnterInitializationMode(c)); }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_ExitInitializationMode(c)); }
fmi2Status fmi2Terminate(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Terminate(c)); }
fmi2Status fmi2Reset(fmi2Component c) { IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_Reset(c)); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetReal(c, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_ints(c, "fmi2GetInteger", vr, nvr, value, 0));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, get_ints(c, "fmi2GetBoolean", vr, nvr, value, 1));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr, (void)value;
    if (usable(c, "fmi2GetString", kGetStates) == NULL) return fmi2Error;
    return nvr == 0 ? fmi2OK : refused(c, "fmi2GetString", "this FMU has no String variables");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_SetReal(c, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_ints(c, "fmi2SetInteger", vr, nvr, value, 0));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, set_ints(c, "fmi2SetBoolean", vr, nvr, value, 1));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr, (void)value;
    if (usable(c, "fmi2SetString", kSetStates) == NULL) return fmi2Error;
    return nvr == 0 ? fmi2OK : refused(c, "fmi2SetString", "this FMU has no String variables");
}

/* What the model description declares absent (canGetAndSetFMUstate="false", no directional
 * derivatives, canInterpolateInputs="false", maxOutputDerivativeOrder="0", asynchronous steps). */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* s) {
    (void)s;
    return refused(c, "fmi2GetFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    (void)s;
    return refused(c, "fmi2SetFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* s) {
    (void)s;
    return refused(c, "fmi2FreeFMUstate", "canGetAndSetFMUstate is false");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t* size) {
    (void)s, (void)size;
    return refused(c, "fmi2SerializedFMUstateSize", "canSerializeFMUstate is false");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size) {
    (void)s, (void)bytes, (void)size;
    return refused(c, "fmi2SerializeFMUstate", "canSerializeFMUstate is false");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* s) {
    (void)bytes, (void)size, (void)s;
    return refused(c, "fmi2DeSerializeFMUstate", "canSerializeFMUstate is false");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference z[],
                                        size_t nz, const fmi2Real dz[], fmi2Real du[]) {
    (void)u, (void)nu, (void)z, (void)nz, (void)dz, (void)du;
    return refused(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return refused(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false: inputs are sampled at the step's start");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return refused(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0: the outputs are held");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior_state) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_DoStep(c, t, h, no_set_prior_state));
}

fmi2Status fmi2CancelStep(fmi2Component c) { return refused(c, "fmi2CancelStep", "fmi2DoStep never runs asynchronously"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetStatus(c, s, value));
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetRealStatus(c, s, value));
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    (void)s, (void)value;
    return refused(c, "fmi2GetIntegerStatus", "no Integer status is provided");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    IN_FMU_FP_ENVIRONMENT(fmi2Status, impl_GetBooleanStatus(c, s, value));
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    (void)s, (void)value;
    return refused(c, "fmi2GetStringStatus", "no String status is provided");
}
