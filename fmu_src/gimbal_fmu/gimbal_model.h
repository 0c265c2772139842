/* The gimbal's model for the FMI instance layer: its table (GUID, log categories, the core's
 * lifetime and snapshots) and the glue both of its FMI faces use to reach the core. */
#ifndef GIMBAL_FMI_MODEL_H
#define GIMBAL_FMI_MODEL_H

#include "fmi_layer/fmi_instance.h"
#include "gimbal/gimbal_c_api.h"

extern const FmiModel kGimbalModel;

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

#endif
