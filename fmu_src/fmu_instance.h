/* The FMI 2.0 instance shared by the Co-Simulation (fmi2_cosim.c) and Model Exchange
 * (fmi2_model_exchange.c) faces of the one FMU: its state machine, the table of the states each
 * function may be called in, logging through the host's callback, and the common checks. */
#ifndef GIMBAL_FMU_INSTANCE_H
#define GIMBAL_FMU_INSTANCE_H

#include "fmi2Functions.h"
#include "fmu_state.h"
#include "gimbal/gimbal_c_api.h"
#include "host_fp_environment.h"

typedef enum {
    STATE_INSTANTIATED = 1 << 0,
    STATE_INITIALIZATION = 1 << 1,
    STATE_STEP_COMPLETE = 1 << 2,     /* Co-Simulation */
    STATE_STEP_FAILED = 1 << 3,       /* Co-Simulation */
    STATE_TERMINATED = 1 << 4,
    STATE_ERROR = 1 << 5,
    STATE_EVENT_MODE = 1 << 6,        /* Model Exchange */
    STATE_CONTINUOUS_TIME = 1 << 7,   /* Model Exchange */
} InstanceState;

#define ANY_STATE (STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_STEP_FAILED | \
                   STATE_TERMINATED | STATE_ERROR | STATE_EVENT_MODE | STATE_CONTINUOUS_TIME)
/* Initialized: the states after fmi2ExitInitializationMode. */
#define RUNNING_STATES (STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_EVENT_MODE | STATE_CONTINUOUS_TIME)
#define GET_STATES (STATE_INITIALIZATION | RUNNING_STATES | STATE_TERMINATED | STATE_ERROR)
#define SET_STATES (STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_STEP_COMPLETE | STATE_EVENT_MODE | STATE_CONTINUOUS_TIME)
#define FMU_STATE_STATES (STATE_INSTANTIATED | STATE_INITIALIZATION | RUNNING_STATES | STATE_TERMINATED)
#define STATUS_STATES (STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED)
/* Model Exchange: where the model's equations can be evaluated. */
#define EVALUATION_STATES (STATE_EVENT_MODE | STATE_CONTINUOUS_TIME | STATE_TERMINATED | STATE_ERROR)

/* Every fmi2* function that checks its state, for the table of states (fmi2_cosim.c, kFunctions). */
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

enum { LOG_CATEGORY_COUNT = 6 }; /* the <LogCategories> of modelDescription.xml */

typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char* instance_name;
    fmi2Type type;
    GimbalCore* core;
    InstanceState state;
    int category_enabled[LOG_CATEGORY_COUNT];
    double time;
    double stop_time;
    int stop_time_defined;
    double last_successful_time;
    fmi2Status last_step_status;
    FmuStateRegistry states; /* the FMU states this instance handed out */
    /* The fmi2* function running, whose name prefixes the core's messages that name none (the
     * continuous-time interface's); NULL outside such calls. */
    const char* calling;
} Instance;

const char* function_name(Function function);
void log_message(const Instance* instance, fmi2Status status, const char* category, const char* format, ...);
fmi2Status from_core(GimbalStatus status);
const char* state_name(InstanceState state);
/* NULL-safe: whether the function may be called in the instance's state; logged if not. */
int allowed(Instance* instance, Function function);
int not_null(Instance* instance, const char* function, const void* pointer, const char* argument);

/* fmi2GetDirectionalDerivative of a Model Exchange instance (fmi2_model_exchange.c), once its state
 * is checked. */
fmi2Status model_exchange_directional_derivative(Instance* instance, const fmi2ValueReference unknowns[],
                                                 size_t unknown_count, const fmi2ValueReference knowns[],
                                                 size_t known_count, const fmi2Real seed[], fmi2Real result[]);

#endif
