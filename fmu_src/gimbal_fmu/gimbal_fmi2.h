/* The gimbal's FMI 2.0 functions, shared by its Co-Simulation (gimbal_fmi2.c) and Model Exchange
 * (gimbal_fmi2_model_exchange.c) files: the table of the states each function may be called in,
 * over the FMI 2.0 face of the FMI instance layer (fmi_layer/fmi2_face.h). */
#ifndef GIMBAL_GIMBAL_FMI2_H
#define GIMBAL_GIMBAL_FMI2_H

#include "fmi_layer/fmi2_face.h"
#include "gimbal_model.h"
#include "host_fp_environment.h"

/* Every fmi2* function that checks its state, for the table of states (gimbal_fmi2.c, kFunctions). */
typedef enum {
    FN_SetDebugLogging, FN_SetupExperiment, FN_EnterInitializationMode, FN_ExitInitializationMode, FN_Terminate,
    FN_Reset, FN_GetReal, FN_GetInteger, FN_GetBoolean, FN_GetString, FN_SetReal, FN_SetInteger, FN_SetBoolean,
    FN_SetString, FN_GetFMUstate, FN_SetFMUstate, FN_FreeFMUstate, FN_SerializedFMUstateSize, FN_SerializeFMUstate,
    FN_DeSerializeFMUstate, FN_GetDirectionalDerivative, FN_SetRealInputDerivatives, FN_GetRealOutputDerivatives,
    FN_DoStep, FN_CancelStep, FN_GetStatus, FN_GetRealStatus, FN_GetIntegerStatus, FN_GetBooleanStatus,
    FN_GetStringStatus,
    FN_EnterEventMode, FN_NewDiscreteStates, FN_EnterContinuousTimeMode, FN_CompletedIntegratorStep, FN_SetTime,
    FN_SetContinuousStates, FN_GetDerivatives, FN_GetEventIndicators, FN_GetContinuousStates,
    FN_GetNominalsOfContinuousStates, FUNCTION_COUNT
} Function;

const char* function_name(Function function);
/* NULL-safe: whether the function may be called in the instance's state; logged if not. */
int allowed(FmiInstance* instance, Function function);

/* fmi2GetDirectionalDerivative of a Model Exchange instance (gimbal_fmi2_model_exchange.c), once its
 * state is checked. */
FmiStatus model_exchange_directional_derivative(FmiInstance* instance, const fmi2ValueReference unknowns[],
                                                size_t unknown_count, const fmi2ValueReference knowns[],
                                                size_t known_count, const fmi2Real seed[], fmi2Real result[]);

#endif
