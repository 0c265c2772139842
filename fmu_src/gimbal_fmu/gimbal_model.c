/* The gimbal's model file: its table for the FMI faces (fmi_layer/fmu_model.h) over the core's C
 * interface (gimbal_c_api.h): the core's lifetime and snapshots, initialization, the step, Model
 * Exchange's equations and the derivatives; its variables' access is in gimbal_variables.c. */
#include <math.h>

#include "gimbal_guid.h"
#include "gimbal_model.h"

_Static_assert((int)GIMBAL_INPUT == (int)FMI_INPUT && (int)GIMBAL_PARAMETER == (int)FMI_PARAMETER &&
                   (int)GIMBAL_TUNABLE == (int)FMI_TUNABLE && (int)GIMBAL_INITIAL_EXACT == (int)FMI_INITIAL_EXACT &&
                   (int)GIMBAL_INITIAL_APPROX == (int)FMI_INITIAL_APPROX,
               "the core's variable attributes are the layer's");

/* The <LogCategories> of both model descriptions, in their order. */
static const char* const kLogCategories[] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logAll"};

static void core_log(void* context, GimbalStatus status, const char* category, const char* message) {
    fmi_log_from_model((FmiInstance*)context, gimbal_status(status), category, message);
}

static int core_log_enabled(void* context, const char* category) {
    return fmi_log_enabled((const FmiInstance*)context, category);
}

/* ---------------------------------------------------------------- the core's lifetime and snapshots */

/* A Model Exchange instance's core evaluates the equations at the host's points instead of stepping. */
static void* create(FmiInstance* instance) {
    GimbalCore* core = gimbal_core_create(core_log, core_log_enabled, instance);
    if (core != NULL && instance->model_exchange && gimbal_core_use_continuous_time(core) != GIMBAL_OK) {
        gimbal_core_destroy(core);
        return NULL;
    }
    return core;
}

static void destroy(void* model) { gimbal_core_destroy((GimbalCore*)model); }

static FmiStatus reset(void* model) { return gimbal_status(gimbal_core_reset((GimbalCore*)model)); }

static FmiStatus save(void* model, unsigned char* snapshot) {
    return gimbal_status(gimbal_core_save((GimbalCore*)model, snapshot));
}

static FmiStatus check_snapshot(void* model, const unsigned char* snapshot, int* initialized) {
    return gimbal_status(gimbal_core_check_snapshot((GimbalCore*)model, snapshot, initialized));
}

static FmiStatus restore(void* model, const unsigned char* snapshot) {
    return gimbal_status(gimbal_core_restore((GimbalCore*)model, snapshot));
}

/* ---------------------------------------------------------------- initialization and the step */

static FmiStatus tolerance(FmiInstance* instance, const char* function, int defined, double value) {
    (void)function; /* the core names the tolerance it refuses */
    return gimbal_status(gimbal_core_set_master_tolerance(gimbal_core_of(instance), defined, value));
}

static FmiStatus exit_initialization(FmiInstance* instance, const char* function) {
    const FmiStatus status = gimbal_status(gimbal_core_initialize(gimbal_core_of(instance), instance->time));
    if (status <= FMI_WARNING) return status;
    fmi_log_error(instance, "%s: initialization refused; fix the values above and retry", function);
    return FMI_ERROR; /* still in initialization mode: the master may correct and retry */
}

/* With early return allowed, the step ends right after the first mode change inside it: the importer
 * sees the event where it happens (and handles it in Event Mode if it uses that). */
static FmiStatus do_step(FmiInstance* instance, const char* function, double point, double step, int* ended_early) {
    (void)function;
    GimbalCore* core = gimbal_core_of(instance);
    double elapsed = step; /* how far the step went: all of it, or to the first mode change */
    const FmiStatus status = gimbal_status(instance->early_return_allowed
                                               ? gimbal_core_do_step_until_mode_change(core, point, step, &elapsed)
                                               : gimbal_core_do_step(core, point, step));
    if (status > FMI_WARNING) {
        instance->state = status == FMI_DISCARD ? instance->face->step_failed_state : instance->face->error_state;
        return status;
    }
    *ended_early = instance->early_return_allowed && elapsed < step;
    instance->time = *ended_early ? point + elapsed : point + step;
    return status;
}

/* ---------------------------------------------------------------- derivatives */

/* The `index`-th unknown or known (`role`) of a Co-Simulation instance's directional derivative: a
 * Real variable of the given causality, whose description it writes to `info`; else logged, 0. */
static int directional_variable(FmiInstance* instance, const char* function, const char* role, size_t index,
                                unsigned vr, GimbalCausality causality, GimbalVariableInfo* info) {
    const char* kind = causality == GIMBAL_OUTPUT ? "output" : "input";
    if (!gimbal_variable_info(GIMBAL_REAL, vr, info)) {
        fmi_log_error(instance, "%s: %s %zu: value reference %u is not a real-valued variable", function, role, index, vr);
        return 0;
    }
    if (info->causality == causality) return 1;
    fmi_log_error(instance, "%s: %s %s is not an %s: in Co-Simulation the %ss are the %ss", function, role, info->name,
                  kind, role, kind);
    return 0;
}

/* Model Exchange: unknowns are state derivatives or outputs, knowns states or inputs (FMI 2.0, section
 * 3.2.1); the core checks which, and names a variable that is neither.
 *
 * Co-Simulation, at a communication point (FMI 2.0, section 4.2.1 with 3.2.1): the unknowns are outputs
 * and the knowns inputs; a Co-Simulation FMU exposes no states. The outputs are computed by the step and
 * held until the next one: setting an input changes no output before the next step, which is why
 * ModelStructure declares every output with dependencies="". The partial derivatives at the current
 * point are therefore exactly zero; what is computed here is the check of the arguments. The
 * linearization of the continuous model itself (A, B, C, D, with the direct feedthrough of e.g. a
 * quasi-static motor's current) is a different quantity. */
static FmiStatus directional_derivative(FmiInstance* instance, const char* function, const unsigned unknowns[],
                                        size_t unknown_count, const unsigned knowns[], size_t known_count,
                                        const double seed[], double sensitivity[]) {
    if (instance->model_exchange) {
        for (size_t j = 0; j < known_count; ++j) {
            if (isfinite(seed[j])) continue;
            fmi_log_error(instance, "%s: the seed of known %zu must be finite", function, j);
            return FMI_ERROR;
        }
        return gimbal_status(gimbal_core_directional_derivative(gimbal_core_of(instance), unknowns, unknown_count,
                                                                knowns, known_count, seed, sensitivity));
    }
    GimbalVariableInfo info;
    for (size_t i = 0; i < unknown_count; ++i)
        if (!directional_variable(instance, function, "unknown", i, unknowns[i], GIMBAL_OUTPUT, &info)) return FMI_ERROR;
    for (size_t j = 0; j < known_count; ++j) {
        if (!directional_variable(instance, function, "known", j, knowns[j], GIMBAL_INPUT, &info)) return FMI_ERROR;
        if (!isfinite(seed[j])) {
            fmi_log_error(instance, "%s: the seed of %s must be finite", function, info.name);
            return FMI_ERROR;
        }
    }
    for (size_t i = 0; i < unknown_count; ++i) sensitivity[i] = 0.0;
    return FMI_OK;
}

static FmiStatus set_input_derivative(FmiInstance* instance, const char* function, unsigned vr, int order, double value) {
    (void)function; /* the core names the input and the order it refuses */
    return gimbal_status(gimbal_core_set_input_derivative(gimbal_core_of(instance), vr, order, value));
}

/* ---------------------------------------------------------------- Model Exchange */

static FmiStatus set_time(FmiInstance* instance, double time) {
    return gimbal_status(gimbal_core_set_time(gimbal_core_of(instance), time));
}

static FmiStatus set_continuous_states(FmiInstance* instance, const double states[]) {
    return gimbal_status(gimbal_core_set_continuous_states(gimbal_core_of(instance), states));
}

static FmiStatus get_derivatives(FmiInstance* instance, double derivatives[]) {
    return gimbal_status(gimbal_core_get_derivatives(gimbal_core_of(instance), derivatives));
}

static FmiStatus get_event_indicators(FmiInstance* instance, double indicators[]) {
    return gimbal_status(gimbal_core_get_event_indicators(gimbal_core_of(instance), indicators));
}

static FmiStatus get_continuous_states(FmiInstance* instance, double states[]) {
    return gimbal_status(gimbal_core_get_continuous_states(gimbal_core_of(instance), states));
}

static FmiStatus get_nominals(FmiInstance* instance, double nominals[]) {
    return gimbal_status(gimbal_core_get_nominal_states(gimbal_core_of(instance), nominals));
}

static FmiStatus update_discrete_states(FmiInstance* instance, FmuDiscreteUpdate* update) {
    GimbalDiscreteUpdate core_update;
    const FmiStatus status =
        gimbal_status(gimbal_core_update_discrete_states(gimbal_core_of(instance), &core_update));
    if (status > FMI_WARNING) return status;
    update->states_changed = core_update.states_changed;
    update->next_time_defined = core_update.next_time_defined;
    update->next_time = core_update.next_time;
    return status;
}

static const FmuModelExchange kModelExchange = {
    .continuous_states = GIMBAL_CONTINUOUS_STATES,
    .event_indicators = GIMBAL_EVENT_INDICATORS,
    .set_time = set_time,
    .set_continuous_states = set_continuous_states,
    .get_derivatives = get_derivatives,
    .get_event_indicators = get_event_indicators,
    .get_continuous_states = get_continuous_states,
    .get_nominals = get_nominals,
    .update_discrete_states = update_discrete_states,
};

/* ---------------------------------------------------------------- the table */

const FmuModel kFmuModel = {
    .layer = {GIMBAL_GUID, sizeof(FmiInstance), kLogCategories, (int)(sizeof kLogCategories / sizeof kLogCategories[0]),
              create, destroy, reset, gimbal_core_snapshot_size, save, check_snapshot, restore},
    .get_states = GET_STATES,
    .set_states = SET_STATES,
    .terminate_states = RUNNING_STATES,
    .status_states = STATUS_STATES,
    .real = GIMBAL_REAL_VARIABLES,
    .integer = GIMBAL_INTEGER_VARIABLES,
    .boolean = GIMBAL_BOOLEAN_VARIABLES,
    .string = {0},
    .fmi3 = &kGimbalFmi3Variables,
    .tolerance = tolerance,
    .exit_initialization = exit_initialization,
    .do_step = do_step,
    .directional_derivative = directional_derivative,
    .set_input_derivative = set_input_derivative,
    .model_exchange = &kModelExchange,
    .has_event_mode = 1,
    .fmi2_fmu_state = 1,
};
