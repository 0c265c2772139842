/* What the FMI 2.0 and FMI 3.0 faces do alike over an FMU's table (fmu_model.h): the value access,
 * instantiation's and reset's part of the model, the experiment's times, the step's bookkeeping, the
 * derivatives' arguments, Model Exchange's checks. The faces own their versions' state checks and
 * signatures. */
#include "fmi_layer/fmu_model.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

static const FmuModel* const kModel = &kFmuModel;

FmiInstance* fmu_model_instantiated(FmiInstance* instance, const char* function, const char* resource_location) {
    if (instance == NULL || kModel->instantiated == NULL) return instance;
    if (kModel->instantiated(instance, resource_location) != 0) {
        fmi_log_error(instance, "%s: out of memory", function);
        fmu_model_free_instance(instance);
        return NULL;
    }
    return instance;
}

void fmu_model_free_instance(FmiInstance* instance) {
    if (instance == NULL) return;
    if (kModel->release != NULL) kModel->release(instance);
    fmi_free_instance(instance);
}

/* ---------------------------------------------------------------- values */

static int arrays_given(const FmiInstance* instance, const char* function, size_t nvr, const void* vr, const void* values) {
    return nvr == 0 || (fmi_not_null(instance, function, vr, "vr") && fmi_not_null(instance, function, values, "value"));
}

static int reference_known(const FmiInstance* instance, const char* function, const FmuVariables* variables,
                           const char* type, unsigned base, unsigned vr) {
    if (vr >= base && vr - base < variables->count && (variables->known == NULL || variables->known(vr - base)))
        return 1;
    const int vowel = type[0] == 'I';
    fmi_log_error(instance, "%s: value reference %u is not a%s %s variable%s", function, vr, vowel ? "n" : "", type,
                  variables->count == 0 ? " (this FMU has none)" : "");
    return 0;
}

/* A model's int from a host's element of another layout (a C bool, an Int64), and back. */
static int model_int(const void* element, FmuValueLayout layout) {
    return layout == FMU_VALUES_C_BOOL ? (*(const bool*)element ? 1 : 0) : (int)*(const int64_t*)element;
}

static int int64_fits(const FmiInstance* instance, const char* function, unsigned vr, const void* element) {
    const int64_t value = *(const int64_t*)element;
    if (value >= INT32_MIN && value <= INT32_MAX) return 1;
    fmi_log_error(instance, "%s: value reference %u: %lld lies outside the Int32 range", function, vr, (long long)value);
    return 0;
}

FmiStatus fmu_model_get(FmiInstance* instance, const char* function, const FmuVariables* variables,
                        const char* type, unsigned base, const unsigned vr[], size_t nvr, void* values, size_t size,
                        FmuValueLayout layout) {
    if (!arrays_given(instance, function, nvr, vr, values)) return FMI_ERROR;
    if (variables->get_all != NULL) return nvr == 0 ? FMI_OK : variables->get_all(instance, function, vr, nvr, values);
    FmiStatus worst = FMI_OK;
    for (size_t i = 0; i < nvr; ++i) {
        if (!reference_known(instance, function, variables, type, base, vr[i])) return FMI_ERROR;
        unsigned char* element = (unsigned char*)values + i * size;
        int converted = 0;
        const FmiStatus status = variables->get(instance, function, vr[i] - base,
                                                layout == FMU_VALUES_AS_THE_MODELS ? (void*)element : (void*)&converted);
        if (status > FMI_WARNING) return status;
        if (status > worst) worst = status;
        if (layout == FMU_VALUES_C_BOOL) *(bool*)element = converted != 0;
        if (layout == FMU_VALUES_INT64) *(int64_t*)element = converted;
    }
    return worst;
}

/* One value of a set: the model's value of the host's element (converted into `converted` when the
 * layouts differ), and whether it may be set (its reference, its range, the model's check). */
static const void* model_value(const unsigned char* element, FmuValueLayout layout, int* converted) {
    if (layout == FMU_VALUES_AS_THE_MODELS) return element;
    *converted = model_int(element, layout);
    return converted;
}

static int value_settable(FmiInstance* instance, const char* function, const FmuVariables* variables,
                          const char* type, unsigned base, unsigned vr, const unsigned char* element,
                          FmuValueLayout layout) {
    int converted = 0;
    return reference_known(instance, function, variables, type, base, vr) &&
           (layout != FMU_VALUES_INT64 || int64_fits(instance, function, vr, element)) &&
           variables->settable(instance, function, vr - base, model_value(element, layout, &converted));
}

FmiStatus fmu_model_set(FmiInstance* instance, const char* function, const FmuVariables* variables,
                        const char* type, unsigned base, const unsigned vr[], size_t nvr, const void* values,
                        size_t size, FmuValueLayout layout) {
    if (!arrays_given(instance, function, nvr, vr, values)) return FMI_ERROR;
    if (nvr == 0) return FMI_OK;
    const unsigned char* elements = (const unsigned char*)values;
    FmiStatus status = FMI_OK;
    if (variables->set_all != NULL) {
        status = variables->set_all(instance, function, vr, nvr, (const double*)values);
    } else {
        for (size_t i = 0; i < nvr; ++i) /* every value checked before any is set */
            if (!value_settable(instance, function, variables, type, base, vr[i], elements + i * size, layout))
                return FMI_ERROR;
        for (size_t i = 0; i < nvr && status <= FMI_WARNING; ++i) {
            int converted = 0;
            const FmiStatus set = variables->set(instance, function, vr[i] - base,
                                                 model_value(elements + i * size, layout, &converted));
            if (set > status) status = set;
        }
    }
    if (status <= FMI_WARNING && kModel->values_set != NULL) kModel->values_set(instance);
    return status;
}

/* ---------------------------------------------------------------- initialization and reset */

FmiStatus fmu_model_start_experiment(FmiInstance* instance, const char* function, int tolerance_defined,
                                     double tolerance, double start, int stop_defined, double stop) {
    if (!fmi_experiment_times_valid(instance, function, start, stop_defined, stop)) return FMI_ERROR;
    if (kModel->tolerance != NULL) {
        const FmiStatus status = kModel->tolerance(instance, function, tolerance_defined, tolerance);
        if (status > FMI_WARNING) return status;
    }
    instance->time = start, instance->stop_time = stop, instance->stop_time_defined = stop_defined ? 1 : 0;
    if (kModel->experiment_start != NULL) kModel->experiment_start(instance, start);
    return FMI_OK;
}

FmiStatus fmu_model_reset(FmiInstance* instance, const char* function) {
    if (kModel->reset == NULL) return fmi_reset(instance);
    const FmiStatus status = kModel->reset(instance, function);
    if (status != FMI_OK) return status;
    instance->time = 0.0, instance->stop_time = 0.0, instance->stop_time_defined = 0;
    instance->last_successful_time = 0.0;
    instance->last_step_status = FMI_OK;
    instance->state = instance->face->instantiated_state;
    return FMI_OK;
}

FmiStatus fmu_model_exit_initialization(FmiInstance* instance, const char* function, int stepping_state) {
    const FmiStatus status = kModel->exit_initialization(instance, function);
    if (status > FMI_WARNING) return status;
    instance->last_successful_time = instance->time;
    instance->state = stepping_state;
    return status;
}

FmiStatus fmu_model_do_step(FmiInstance* instance, const char* function, double point, double step, int* ended_early) {
    *ended_early = 0;
    const FmiStatus status = kModel->do_step(instance, function, point, step, ended_early);
    instance->last_step_status = status; /* what fmi2GetStatus says */
    if (status <= FMI_WARNING) instance->last_successful_time = instance->time;
    return status;
}

/* ---------------------------------------------------------------- Model Exchange */

int fmu_model_exchange_instance(FmiInstance* instance, const char* function) {
    if (instance->model_exchange) return 1;
    fmi_log_error(instance, "%s is a Model Exchange function: instance '%s' was instantiated for Co-Simulation",
                  function, instance->name);
    return 0;
}

int fmu_model_count_is(FmiInstance* instance, const char* function, size_t given, size_t expected,
                       const char* count_name) {
    if (given == expected) return 1;
    fmi_log_error(instance, "%s: %s = %zu, but the model has %zu (modelDescription.xml)", function, count_name, given,
                  expected);
    return 0;
}
