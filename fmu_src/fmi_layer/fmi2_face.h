/* The FMI 2.0 face of the FMI instance layer: FMI 2.0's states, as bits of one mask each, the masks
 * of the states the standard's groups of functions may be called in, and the face's table (its
 * logger, state names, FMU-state record identity), for the FMI 2.0 functions of every FMU. */
#ifndef GIMBAL_FMI2_FACE_H
#define GIMBAL_FMI2_FACE_H

#include "fmi2Functions.h"
#include "fmi_layer/fmi_instance.h"

FMI_STATIC_ASSERT((int)fmi2OK == (int)FMI_OK && (int)fmi2Warning == (int)FMI_WARNING &&
                   (int)fmi2Discard == (int)FMI_DISCARD && (int)fmi2Error == (int)FMI_ERROR &&
                   (int)fmi2Fatal == (int)FMI_FATAL,
               "fmi2Status is the layer's status");

/* The bits are those the gimbal's FMU-state records of the FMI 2.0 binary hold. */
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

extern const FmiFace kFmi2Face;

/* fmi2Instantiate of an FMU whose model is `model`: Co-Simulation, and Model Exchange when
 * `model_exchange_offered`; any other fmuType is refused naming what the FMU offers. */
fmi2Component fmi2_instantiate(const FmiModel* model, int model_exchange_offered, fmi2String instance_name,
                               fmi2Type type, fmi2String guid, const fmi2CallbackFunctions* functions,
                               fmi2Boolean logging_on);

#endif
