/* The gimbal's variables for the FMI faces (gimbal_model.h): the core's Reals, Integers and Booleans by
 * value reference, and FMI 3.0's layout of them (gimbal_c_api.h, GIMBAL_FMI3_*): a Float64 is the core's
 * Real of the same reference, `time` and the scalar event indicators follow the Booleans; an
 * Enumeration is an Int64 (fmi3GetInt64/fmi3SetInt64, as FMI 3.0 says), every other Integer an Int32. */
#include "gimbal_model.h"

/* ---------------------------------------------------------------- Reals (FMI 3.0: Float64) */

/* A call's Reals: settable ones found in one pass through the core's table (the master's inputs at
 * every step), the first refused then named; the core checks every value before it applies any (all
 * or nothing) and names a non-finite one. */
static FmiStatus set_reals(FmiInstance* instance, const char* function, const char* type, const unsigned vr[],
                           size_t nvr, const double values[]) {
    const int initialized = !(instance->state & instance->face->before_initialized_states);
    const size_t first_refused = gimbal_first_unsettable(GIMBAL_REAL, vr, nvr, initialized);
    for (size_t i = first_refused; i < nvr; ++i) {
        GimbalVariableInfo info;
        if (!gimbal_variable_info(GIMBAL_REAL, vr[i], &info)) {
            fmi_log_error(instance, "%s: value reference %u is not a %s", function, vr[i], type);
            return FMI_ERROR;
        }
        if (!gimbal_variable_settable(instance, &info)) {
            fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, info.name,
                          instance->face->state_name(instance->state));
            return FMI_ERROR;
        }
    }
    return gimbal_status(gimbal_core_set_reals(gimbal_core_of(instance), vr, nvr, values));
}

FmiStatus gimbal_set_reals(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                           const double values[]) {
    return set_reals(instance, function, "Real variable", vr, nvr, values);
}

static FmiStatus set_float64(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                             const double values[]) {
    return set_reals(instance, function, "Float64 variable that can be set", vr, nvr, values);
}

FmiStatus gimbal_get_reals(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr, double values[]) {
    (void)function; /* the core names a reference it has no Real of */
    FmiStatus worst = FMI_OK;
    for (size_t i = 0; i < nvr && worst <= FMI_WARNING; ++i) {
        const FmiStatus status = gimbal_status(gimbal_core_get_real(gimbal_core_of(instance), vr[i], &values[i]));
        if (status > worst) worst = status;
    }
    return worst;
}

static int is_event_indicator(unsigned vr) {
    return vr >= FMI3_FIRST_EVENT_INDICATOR && vr < FMI3_FIRST_EVENT_INDICATOR + GIMBAL_EVENT_INDICATORS;
}

static FmiStatus float64_value(FmiInstance* instance, const char* function, unsigned vr, double* value) {
    GimbalVariableInfo info;
    if (vr >= FMI3_INTEGER_BASE || !gimbal_variable_info(GIMBAL_REAL, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not a Float64 variable", function, vr);
        return FMI_ERROR;
    }
    return gimbal_status(gimbal_core_get_real(gimbal_core_of(instance), vr, value));
}

/* The core computes the event indicators all at once: read once per call (`*read`). Co-Simulation
 * locates the events itself: no indicator is exposed (each reads 1). */
static FmiStatus event_indicator(FmiInstance* instance, unsigned vr, double indicators[], int* read, double* value) {
    if (!*read) {
        for (int z = 0; z < GIMBAL_EVENT_INDICATORS; ++z) indicators[z] = 1.0;
        if (instance->model_exchange) {
            const FmiStatus status =
                gimbal_status(gimbal_core_get_event_indicators(gimbal_core_of(instance), indicators));
            if (status > FMI_WARNING) return status;
        }
        *read = 1;
    }
    *value = indicators[vr - FMI3_FIRST_EVENT_INDICATOR];
    return FMI_OK;
}

/* The Reals, `time` and the event indicators. */
static FmiStatus get_float64(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                             double values[]) {
    double indicators[GIMBAL_EVENT_INDICATORS];
    int indicators_read = 0;
    FmiStatus worst = FMI_OK;
    for (size_t k = 0; k < nvr && worst <= FMI_WARNING; ++k) {
        FmiStatus status = FMI_OK;
        if (vr[k] == FMI3_TIME)
            values[k] = instance->time;
        else if (is_event_indicator(vr[k]))
            status = event_indicator(instance, vr[k], indicators, &indicators_read, &values[k]);
        else
            status = float64_value(instance, function, vr[k], &values[k]);
        if (status > worst) worst = status;
    }
    return worst;
}

/* ---------------------------------------------------------------- Integers (FMI 3.0: Int32, and Int64 for the
 * Enumerations) and Booleans, one by one */

/* A settable variable of the type; else logged, 0. */
static int settable(FmiInstance* instance, const char* function, GimbalType type, unsigned vr) {
    GimbalVariableInfo info;
    if (!gimbal_variable_info(type, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not a variable of its type", function, vr);
        return 0;
    }
    if (gimbal_variable_settable(instance, &info)) return 1;
    fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, info.name,
                  instance->face->state_name(instance->state));
    return 0;
}

FmiStatus gimbal_get_integer(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    return gimbal_status(gimbal_core_get_integer(gimbal_core_of(instance), vr, (int*)value));
}

int gimbal_integer_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)value; /* the core checks the value when it is set, naming the variable */
    return settable(instance, function, GIMBAL_INTEGER, vr);
}

FmiStatus gimbal_set_integer(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    return gimbal_status(gimbal_core_set_integer(gimbal_core_of(instance), vr, *(const int*)value));
}

int gimbal_integer_known(unsigned vr) {
    GimbalVariableInfo info;
    return gimbal_variable_info(GIMBAL_INTEGER, vr, &info);
}

/* FMI 3.0 tells the Enumerations (Int64) from the other Integers (Int32): a call of the other type is
 * refused naming the variable and the type it is. */
static int of_kind(FmiInstance* instance, const char* function, unsigned vr, int enumeration) {
    GimbalVariableInfo info;
    if (!gimbal_variable_info(GIMBAL_INTEGER, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not an Integer variable", function, vr);
        return 0;
    }
    if ((info.declared_type[0] != '\0') == enumeration) return 1;
    fmi_log_error(instance, "%s: %s is %s", function, info.name,
                  enumeration ? "an Int32 variable" : "an Enumeration (fmi3GetInt64/fmi3SetInt64)");
    return 0;
}

static FmiStatus get_int32(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    return of_kind(instance, function, vr, 0) ? gimbal_get_integer(instance, function, vr, value) : FMI_ERROR;
}
static int int32_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    return of_kind(instance, function, vr, 0) && gimbal_integer_settable(instance, function, vr, value);
}
static FmiStatus get_enumeration(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    return of_kind(instance, function, vr, 1) ? gimbal_get_integer(instance, function, vr, value) : FMI_ERROR;
}
static int enumeration_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    return of_kind(instance, function, vr, 1) && gimbal_integer_settable(instance, function, vr, value);
}

FmiStatus gimbal_get_boolean(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    (void)function;
    return gimbal_status(gimbal_core_get_boolean(gimbal_core_of(instance), vr, (int*)value));
}

int gimbal_boolean_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)value;
    return settable(instance, function, GIMBAL_BOOLEAN, vr);
}

FmiStatus gimbal_set_boolean(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    (void)function;
    return gimbal_status(gimbal_core_set_boolean(gimbal_core_of(instance), vr, *(const int*)value != 0));
}

int gimbal_boolean_known(unsigned vr) {
    GimbalVariableInfo info;
    return gimbal_variable_info(GIMBAL_BOOLEAN, vr, &info);
}

const Fmi3Variables kGimbalFmi3Variables = {
    .float64 = {.count = FMI3_FIRST_EVENT_INDICATOR + GIMBAL_EVENT_INDICATORS, .get_all = get_float64,
                .set_all = set_float64},
    .int32 = {.count = FMI3_BOOLEAN_BASE - FMI3_INTEGER_BASE, .get = get_int32, .settable = int32_settable,
              .set = gimbal_set_integer, .known = gimbal_integer_known},
    .int64 = {.count = FMI3_BOOLEAN_BASE - FMI3_INTEGER_BASE, .get = get_enumeration,
              .settable = enumeration_settable, .set = gimbal_set_integer, .known = gimbal_integer_known},
    .boolean = GIMBAL_BOOLEAN_VARIABLES,
    .string = {0},
    .float64_base = 0,
    .int32_base = FMI3_INTEGER_BASE,
    .int64_base = FMI3_INTEGER_BASE,
    .boolean_base = FMI3_BOOLEAN_BASE,
    .string_base = 0,
    .time = FMI3_TIME,
};
