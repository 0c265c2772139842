/* The small FMUs' FMI 3.0 value references: FMI 3.0 gives every variable its own value reference,
 * FMI 2.0 numbers each type from 0. A Float64 keeps its FMI 2.0 Real's reference, an Int32, a Boolean
 * and a String their FMI 2.0 reference plus their type's base (as the gimbal's, gimbal_c_api.h).
 * Shared by the FMI 3.0 face (fmi_layer/fmi3_functions.c) and the model-description generators. */
#ifndef GIMBAL_SMALL_FMI3_VALUE_REFERENCES_H
#define GIMBAL_SMALL_FMI3_VALUE_REFERENCES_H

enum {
    SMALL_FMI3_FLOAT64_BASE = 0,
    SMALL_FMI3_INT32_BASE = 1000,
    SMALL_FMI3_BOOLEAN_BASE = 2000,
    SMALL_FMI3_STRING_BASE = 3000,
    SMALL_FMI3_TIME = 4000,         /* `time`, the independent variable FMI 3.0 requires: read-only */
    SMALL_FMI3_TYPE_CAPACITY = 1000 /* the variables of one type, at most */
};

#endif
