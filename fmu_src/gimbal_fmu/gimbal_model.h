/* The gimbal's model for the FMI faces (fmi_layer/fmu_model.h): what its model file (gimbal_model.c)
 * and its variables' access (gimbal_variables.c) share to reach the core. */
#ifndef GIMBAL_FMI_MODEL_H
#define GIMBAL_FMI_MODEL_H

#include "fmi_layer/fmu_model.h"
#include "gimbal/gimbal_c_api.h"

/* The FMI 3.0 value references (docs/fmi_interfaces.md), defined once in gimbal_c_api.h (GIMBAL_FMI3_*),
 * which the model description generator (model_core/tools/model_description_generator.cpp) numbers by
 * too: a Float64 is the core's Real of the same reference, an Int32 or Enumeration the core's Integer at
 * FMI3_INTEGER_BASE + its reference, a Boolean the core's Boolean at FMI3_BOOLEAN_BASE + its reference,
 * then the independent variable and the GIMBAL_EVENT_INDICATORS scalar event indicators. */
enum {
    FMI3_INTEGER_BASE = GIMBAL_FMI3_INTEGER_BASE,
    FMI3_BOOLEAN_BASE = GIMBAL_FMI3_BOOLEAN_BASE,
    FMI3_TIME = GIMBAL_FMI3_TIME,
    FMI3_FIRST_EVENT_INDICATOR = GIMBAL_FMI3_FIRST_EVENT_INDICATOR
};

static inline GimbalCore* gimbal_core_of(const FmiInstance* instance) { return (GimbalCore*)instance->model_data; }

static inline FmiStatus gimbal_status(GimbalStatus status) {
    switch (status) {
        case GIMBAL_OK: return FMI_OK;
        case GIMBAL_WARNING: return FMI_WARNING;
        case GIMBAL_DISCARD: return FMI_DISCARD;
        default: return FMI_ERROR;
    }
}

/* The layer's settable rule over the core's variable table. */
static inline int gimbal_variable_settable(const FmiInstance* instance, const GimbalVariableInfo* info) {
    return fmi_settable(instance, (FmiCausality)info->causality, (FmiVariability)info->variability,
                        (FmiInitial)info->initial);
}

/* The variables by FMI 2.0 type (gimbal_variables.c): the Reals all at once (the core checks and sets a
 * call's inputs together), the Integers (the Enumerations among them) and Booleans one by one. */
FmiStatus gimbal_get_reals(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr, double values[]);
FmiStatus gimbal_set_reals(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                           const double values[]);
FmiStatus gimbal_get_integer(FmiInstance* instance, const char* function, unsigned vr, void* value);
int gimbal_integer_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value);
FmiStatus gimbal_set_integer(FmiInstance* instance, const char* function, unsigned vr, const void* value);
int gimbal_integer_known(unsigned vr);
FmiStatus gimbal_get_boolean(FmiInstance* instance, const char* function, unsigned vr, void* value);
int gimbal_boolean_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value);
FmiStatus gimbal_set_boolean(FmiInstance* instance, const char* function, unsigned vr, const void* value);
int gimbal_boolean_known(unsigned vr);

/* Every value reference below the next type's FMI 3.0 base may be one of the type's. */
#define GIMBAL_REAL_VARIABLES {.count = FMI3_INTEGER_BASE, .get_all = gimbal_get_reals, .set_all = gimbal_set_reals}
#define GIMBAL_INTEGER_VARIABLES                                                                        \
    {.count = FMI3_BOOLEAN_BASE - FMI3_INTEGER_BASE, .get = gimbal_get_integer, .settable = gimbal_integer_settable, \
     .set = gimbal_set_integer, .known = gimbal_integer_known}
#define GIMBAL_BOOLEAN_VARIABLES                                                                        \
    {.count = FMI3_TIME - FMI3_BOOLEAN_BASE, .get = gimbal_get_boolean, .settable = gimbal_boolean_settable, \
     .set = gimbal_set_boolean, .known = gimbal_boolean_known}

/* FMI 3.0's: the Float64 include `time` and the event indicators, the Enumerations are Int64. */
extern const Fmi3Variables kGimbalFmi3Variables;

#endif
