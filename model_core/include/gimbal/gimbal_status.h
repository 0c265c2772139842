/* The status of every call from the host's FMI function down to the core's answer: FMI's five, with
 * the values of fmi2Status and fmi3Status (the FMI faces assert it). One type for the core (its C
 * interface, gimbal_c_api.h, and the FMU's model table, model_core/src/simulation/fmu_model_table.cpp)
 * and the FMI layer (fmu_src/fmi_layer/fmi_instance.h, whose FmiStatus it is), so that no layer
 * between them translates one status into another. The core itself never answers GIMBAL_FATAL. */
#ifndef GIMBAL_STATUS_H
#define GIMBAL_STATUS_H

typedef enum { GIMBAL_OK = 0, GIMBAL_WARNING = 1, GIMBAL_DISCARD = 2, GIMBAL_ERROR = 3, GIMBAL_FATAL = 4 } GimbalStatus;

#endif
