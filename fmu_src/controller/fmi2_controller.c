/* The controller FMU's model file: controller_model.c behind the small FMUs' FMI 2.0 Co-Simulation
 * face (fmi_layer/small_fmi2_cosim.h), which checks the states, pointers and value references and
 * exports the fmi2* functions; here are the controller's values, parameter checks and step. */
#include <math.h>
#include <stdlib.h>

#include "controller_guid.h"
#include "controller_model.h"
#include "fmi_layer/small_fmi2_cosim.h"

static ControllerModel* model_of(const FmiInstance* instance) { return (ControllerModel*)instance->model_data; }

static void* create_model(FmiInstance* instance) {
    (void)instance;
    ControllerModel* model = (ControllerModel*)malloc(sizeof(ControllerModel));
    if (model != NULL) controller_model_reset(model);
    return model;
}

/* Which variables may be set now: inputs always; parameters before initialization ends. */
static int settable_now(const FmiInstance* instance, int parameter) {
    return !parameter || (instance->state & (STATE_INSTANTIATED | STATE_INITIALIZATION));
}

/* ---------------------------------------------------------------- Real variables */

static FmiStatus get_real(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    *(double*)value = model_of(instance)->real[vr];
    return FMI_OK;
}

static int real_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    const ControllerReal* variable = &kControllerReals[vr];
    const double x = *(const double*)value;
    if (variable->causality == OUTPUT || !settable_now(instance, variable->causality == PARAMETER)) {
        fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, variable->name,
                      instance->face->state_name(instance->state));
        return 0;
    }
    if (!isfinite(x)) {
        fmi_log_error(instance, "%s: %s = %g is not finite", function, variable->name, x);
        return 0;
    }
    return 1;
}

static FmiStatus set_real(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    model_of(instance)->real[vr] = *(const double*)value;
    return FMI_OK;
}

/* ---------------------------------------------------------------- Integer and Boolean parameters */

/* They are all parameters, stored as int (fmi2Integer and fmi2Boolean are int too). */
static int parameter_settable(FmiInstance* instance, const char* function, const char* name) {
    if (settable_now(instance, 1)) return 1;
    fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, name, instance->face->state_name(instance->state));
    return 0;
}

static FmiStatus get_integer(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    *(int*)value = model_of(instance)->integer[vr];
    return FMI_OK;
}
static int integer_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)value;
    return parameter_settable(instance, function, kControllerIntegers[vr].name);
}
static FmiStatus set_integer(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    model_of(instance)->integer[vr] = *(const int*)value;
    return FMI_OK;
}

static FmiStatus get_boolean(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    *(int*)value = model_of(instance)->boolean[vr] ? fmi2True : fmi2False;
    return FMI_OK;
}
static int boolean_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)value;
    return parameter_settable(instance, function, kControllerBooleans[vr].name);
}
static FmiStatus set_boolean(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    model_of(instance)->boolean[vr] = *(const int*)value != fmi2False;
    return FMI_OK;
}

/* ---------------------------------------------------------------- initialization, reset, step */

static FmiStatus reset(FmiInstance* instance, const char* function) {
    (void)function;
    controller_model_reset(model_of(instance));
    return FMI_OK;
}

static FmiStatus exit_initialization(FmiInstance* instance, const char* function) {
    char why[512];
    if (!controller_model_check(model_of(instance), why, sizeof why)) {
        fmi_log_error(instance, "%s: %s", function, why);
        return FMI_ERROR;
    }
    controller_model_start(model_of(instance));
    return FMI_OK;
}

static FmiStatus do_step(FmiInstance* instance, const char* function, double point, double step) {
    ControllerModel* model = model_of(instance);
    controller_model_step(model, step);
    /* A step far below the controller's sampling (h = 5e-324: its backward differences divide by h)
     * or gains that overflow leave no usable command: the host gets an error, never a NaN voltage. */
    for (int k = OUT_U_R1; k <= OUT_BETA_REF; ++k) {
        if (isfinite(model->real[k])) continue;
        fmi_log_error(instance, "%s: %s = %g after the step of %g s: the controller cannot continue (fmi2Reset)",
                      function, kControllerReals[k].name, model->real[k], step);
        instance->state = STATE_ERROR;
        return FMI_ERROR;
    }
    instance->time = point + step;
    return FMI_OK;
}

static const char* const kLogCategories[] = {"logStatusError", "logAll"};

/* The controller's step never fails but into the error state, so fmi2GetStatus is asked only after
 * successful steps (status_states): it is fmi2OK. */
const SmallFmi2Model kSmallFmi2Model = {
    .layer = {CONTROLLER_GUID, sizeof(FmiInstance), kLogCategories,
              (int)(sizeof kLogCategories / sizeof kLogCategories[0]), create_model, free, NULL, NULL, NULL, NULL, NULL},
    .get_states = STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_TERMINATED,
    .set_states = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE,
    .terminate_states = STATE_STEP_COMPLETE,
    .status_states = STATE_STEP_COMPLETE | STATE_TERMINATED,
    .real = {REAL_COUNT, get_real, real_settable, set_real},
    .integer = {INTEGER_COUNT, get_integer, integer_settable, set_integer},
    .boolean = {BOOLEAN_COUNT, get_boolean, boolean_settable, set_boolean},
    .string = {0, NULL, NULL, NULL},
    .reset = reset,
    .exit_initialization = exit_initialization,
    .do_step = do_step,
};
