/* What the small FMUs' FMI 2.0 and FMI 3.0 Co-Simulation faces do alike (small_cosim_model.h): the
 * value access through the model's table, instantiation's and reset's part of the model, the
 * experiment's times. The faces own their versions' state checks and signatures. */
#include "fmi_layer/small_cosim_model.h"

#include <stdbool.h>

static const SmallCosimModel* const kModel = &kSmallCosimModel;

FmiInstance* small_cosim_instantiated(FmiInstance* instance, const char* function, const char* resource_location) {
    if (instance == NULL || kModel->instantiated == NULL) return instance;
    if (kModel->instantiated(instance, resource_location) != 0) {
        fmi_log_error(instance, "%s: out of memory", function);
        small_cosim_free_instance(instance);
        return NULL;
    }
    return instance;
}

void small_cosim_free_instance(FmiInstance* instance) {
    if (instance == NULL) return;
    if (kModel->release != NULL) kModel->release(instance);
    fmi_free_instance(instance);
}

/* ---------------------------------------------------------------- values */

static int arrays_given(const FmiInstance* instance, const char* function, size_t nvr, const void* vr, const void* values) {
    return nvr == 0 || (fmi_not_null(instance, function, vr, "vr") && fmi_not_null(instance, function, values, "value"));
}

static int reference_known(const FmiInstance* instance, const char* function, const SmallCosimVariables* variables,
                           const char* type, unsigned base, unsigned vr) {
    if (vr >= base && vr - base < variables->count) return 1;
    const int vowel = type[0] == 'I';
    fmi_log_error(instance, "%s: value reference %u is not a%s %s variable%s", function, vr, vowel ? "n" : "", type,
                  variables->count == 0 ? " (this FMU has none)" : "");
    return 0;
}

/* A model's int from a host's C bool, and back. */
static int model_boolean(const void* element) { return *(const bool*)element ? 1 : 0; }

FmiStatus small_cosim_get(FmiInstance* instance, const char* function, const SmallCosimVariables* variables,
                          const char* type, unsigned base, const unsigned vr[], size_t nvr, void* values, size_t size,
                          SmallValueLayout layout) {
    if (!arrays_given(instance, function, nvr, vr, values)) return FMI_ERROR;
    for (size_t i = 0; i < nvr; ++i) {
        if (!reference_known(instance, function, variables, type, base, vr[i])) return FMI_ERROR;
        unsigned char* element = (unsigned char*)values + i * size;
        int boolean = 0;
        const FmiStatus status =
            variables->get(instance, function, vr[i] - base, layout == SMALL_VALUES_C_BOOL ? (void*)&boolean : element);
        if (status != FMI_OK) return status;
        if (layout == SMALL_VALUES_C_BOOL) *(bool*)element = boolean != 0;
    }
    return FMI_OK;
}

FmiStatus small_cosim_set(FmiInstance* instance, const char* function, const SmallCosimVariables* variables,
                          const char* type, unsigned base, const unsigned vr[], size_t nvr, const void* values,
                          size_t size, SmallValueLayout layout) {
    if (!arrays_given(instance, function, nvr, vr, values)) return FMI_ERROR;
    for (int setting = 0; setting <= 1; ++setting) { /* check every value, then set them */
        for (size_t i = 0; i < nvr; ++i) {
            const unsigned char* element = (const unsigned char*)values + i * size;
            const int boolean = layout == SMALL_VALUES_C_BOOL ? model_boolean(element) : 0;
            const void* value = layout == SMALL_VALUES_C_BOOL ? (const void*)&boolean : (const void*)element;
            if (!setting) {
                if (!reference_known(instance, function, variables, type, base, vr[i]) ||
                    !variables->settable(instance, function, vr[i] - base, value))
                    return FMI_ERROR;
                continue;
            }
            const FmiStatus status = variables->set(instance, function, vr[i] - base, value);
            if (status != FMI_OK) return status;
        }
    }
    if (nvr > 0 && kModel->values_set != NULL) kModel->values_set(instance);
    return FMI_OK;
}

/* ---------------------------------------------------------------- initialization and reset */

FmiStatus small_cosim_start_experiment(FmiInstance* instance, const char* function, double start, int stop_defined,
                                       double stop) {
    if (!fmi_experiment_times_valid(instance, function, start, stop_defined, stop)) return FMI_ERROR;
    instance->time = start, instance->stop_time = stop, instance->stop_time_defined = stop_defined ? 1 : 0;
    if (kModel->experiment_start != NULL) kModel->experiment_start(instance, start);
    return FMI_OK;
}

FmiStatus small_cosim_reset(FmiInstance* instance, const char* function) {
    const FmiStatus status = kModel->reset(instance, function);
    if (status != FMI_OK) return status;
    instance->time = 0.0, instance->stop_time = 0.0, instance->stop_time_defined = 0;
    instance->last_step_status = FMI_OK;
    instance->state = instance->face->instantiated_state;
    return FMI_OK;
}

FmiStatus small_cosim_exit_initialization(FmiInstance* instance, const char* function, int stepping_state) {
    const FmiStatus status = kModel->exit_initialization(instance, function);
    if (status != FMI_OK) return status;
    instance->state = stepping_state;
    return FMI_OK;
}
