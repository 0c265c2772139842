/* The controller FMU's model file: controller_model.c behind the FMI 2.0 and FMI 3.0 faces
 * (fmi_layer/fmu_model.h), which check the states, pointers and value references and export the
 * fmi2* or fmi3* functions; here are the controller's values, parameter
 * checks and step, and its FMU-state snapshot (offered by the FMI 3.0 FMU). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "controller_guid.h"
#include "controller_model.h"
#include "fmi_layer/fmu_model.h"

/* The model follows the FmiInstance in one allocation (fmi_instantiate's, zeroed): the snapshot calls,
 * which the layer hands the model, can then log through the instance. */
typedef struct {
    FmiInstance common;
    ControllerModel model;
} ControllerInstance;
_Static_assert(offsetof(ControllerInstance, common) == 0, "the FmiInstance must be the instance's first member");

static ControllerModel* model_of(const FmiInstance* instance) { return &((ControllerInstance*)instance->model_data)->model; }

static void* create_model(FmiInstance* instance) {
    controller_model_reset(&((ControllerInstance*)instance)->model);
    return instance;
}
static void no_own_allocation(void* model) { (void)model; }

/* Which variables may be set now: inputs always; parameters before initialization ends. */
static int settable_now(const FmiInstance* instance, int parameter) {
    return !parameter || (instance->state & instance->face->before_initialized_states);
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
    *(int*)value = model_of(instance)->boolean[vr] ? 1 : 0;
    return FMI_OK;
}
static int boolean_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)value;
    return parameter_settable(instance, function, kControllerBooleans[vr].name);
}
static FmiStatus set_boolean(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    model_of(instance)->boolean[vr] = *(const int*)value != 0;
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

static FmiStatus do_step(FmiInstance* instance, const char* function, double point, double step, int* ended_early) {
    (void)ended_early; /* no mode changes: never early */
    ControllerModel* model = model_of(instance);
    char why[512];
    const int held = controller_model_step(model, step, why, sizeof why) == 2;
    /* A step far below the controller's sampling (h = 5e-324: its backward differences divide by h)
     * or gains that overflow leave no usable command: the host gets an error, never a NaN voltage. */
    for (int k = OUT_U_R1; k <= OUT_BETA_REF; ++k) {
        if (isfinite(model->real[k])) continue;
        fmi_log_error(instance, "%s: %s = %g after the step of %g s: the controller cannot continue (reset it)",
                      function, kControllerReals[k].name, model->real[k], step);
        instance->state = instance->face->error_state;
        return FMI_ERROR;
    }
    instance->time = point + step;
    if (held) {
        fmi_log(instance, FMI_WARNING, "logStatusWarning", "%s: at t = %.17g s: %s", function, point, why);
        return FMI_WARNING;
    }
    return FMI_OK;
}

/* ---------------------------------------------------------------- FMU states */

/* The snapshot is the model as it is: its variables and the kernel's sensors and controller. The
 * kernel's pointers (the noise, carrier-rate, replay and set-point tables of a scene) are NULL in
 * this FMU, which takes its inputs per step; a snapshot with one set is refused, never followed. */
static size_t snapshot_size(void) { return sizeof(ControllerModel); }

static FmiStatus save(void* model, unsigned char* bytes) {
    memcpy(bytes, model_of((FmiInstance*)model), sizeof(ControllerModel));
    return FMI_OK;
}

/* A snapshot's pointers: this FMU's sensors and controller hold no table (a snapshot that names one
 * was not saved by it). */
static int refers_to_tables(const ControllerModel* m) {
    const void* const tables[] = {m->sensors.gyro_noise, m->sensors.carrier_rate, m->sensors.gyro.error,
                                  m->controller.replayed, m->controller.set_points.values,
                                  m->controller.set_points.rates, m->controller.set_points.accelerations,
                                  m->controller.set_points.gyro_rates};
    for (size_t k = 0; k < sizeof tables / sizeof tables[0]; ++k)
        if (tables[k] != NULL) return 1;
    return 0;
}

/* The variables' values outside what they may hold, or NULL. */
static const char* variables_problem(const ControllerModel* m) {
    for (int i = 0; i < REAL_COUNT; ++i)
        if (!isfinite(m->real[i])) return "a Real variable is not finite";
    for (int i = 0; i < INTEGER_COUNT; ++i)
        if (m->integer[i] < kControllerIntegers[i].min || m->integer[i] > kControllerIntegers[i].max)
            return "an Integer parameter lies outside its bounds";
    for (int i = 0; i < BOOLEAN_COUNT; ++i)
        if ((m->boolean[i] & ~1) != 0) return "a Boolean parameter is neither 0 nor 1";
    return NULL;
}

/* What in a snapshot this FMU could not have saved, or NULL. */
static const char* snapshot_problem(const ControllerModel* m) {
    if (refers_to_tables(m)) return "it refers to tables this FMU has none of";
    if ((m->started & ~1) != 0 || m->step < 0 || (!m->started && m->step != 0)) return "its step count is not one a run reaches";
    if (m->sensors.gyro.delay < 0 || m->sensors.gyro.delay > GIMBAL_GYRO_MAX_DELAY) return "its gyro delay is out of range";
    return variables_problem(m);
}

static FmiStatus check_snapshot(void* model, const unsigned char* bytes, int* initialized) {
    ControllerModel snapshot;
    memcpy(&snapshot, bytes, sizeof snapshot);
    return fmi_snapshot_verdict((FmiInstance*)model, snapshot_problem(&snapshot), snapshot.started, initialized);
}

static FmiStatus restore(void* model, const unsigned char* bytes) {
    memcpy(model_of((FmiInstance*)model), bytes, sizeof(ControllerModel));
    return FMI_OK;
}

static const char* const kLogCategories[] = {"logStatusError", "logStatusWarning", "logAll"};

/* The controller's step never fails but into the error state, so fmi2GetStatus is asked only after
 * successful steps (status_states): it is fmi2OK. */
const FmuModel kFmuModel = {
    .layer = {CONTROLLER_GUID, sizeof(ControllerInstance), kLogCategories,
              (int)(sizeof kLogCategories / sizeof kLogCategories[0]), create_model, no_own_allocation, NULL,
              snapshot_size, save, check_snapshot, restore},
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
