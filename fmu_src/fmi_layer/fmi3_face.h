/* The FMI 3.0 face of the FMI instance layer: FMI 3.0's states, as bits of one mask each, the masks
 * of the states the standard's groups of functions may be called in, and the face's table (its
 * logger, state names, FMU-state record identity), for the FMI 3.0 functions of every FMU
 * (fmi3_functions.c), with the refusals (here), the exported FMU-state functions (fmi3_face.c), and
 * the functions no FMU offers (fmi3_not_offered.c). */
#ifndef GIMBAL_FMI3_FACE_H
#define GIMBAL_FMI3_FACE_H

#include "fmi3Functions.h"
#include "fmi_layer/fmi_instance.h"

_Static_assert((int)fmi3OK == (int)FMI_OK && (int)fmi3Warning == (int)FMI_WARNING &&
                   (int)fmi3Discard == (int)FMI_DISCARD && (int)fmi3Error == (int)FMI_ERROR &&
                   (int)fmi3Fatal == (int)FMI_FATAL,
               "fmi3Status is the layer's status");

/* The bits are those FMU-state records of the FMI 3.0 binaries hold. */
typedef enum {
    S_INSTANTIATED = 1 << 0,
    S_INITIALIZATION = 1 << 1,
    S_EVENT = 1 << 2,
    S_CONTINUOUS_TIME = 1 << 3, /* Model Exchange */
    S_STEP = 1 << 4,            /* Co-Simulation */
    S_STEP_DISCARDED = 1 << 5,  /* Co-Simulation: a step failed; get, roll back, terminate or reset */
    S_TERMINATED = 1 << 6,
    S_ERROR = 1 << 7,
} State3;

#define S_ANY 0xFF
#define S_RUNNING (S_EVENT | S_CONTINUOUS_TIME | S_STEP | S_STEP_DISCARDED)
#define S_GET (S_INITIALIZATION | S_RUNNING | S_TERMINATED | S_ERROR)
#define S_SET (S_INSTANTIATED | S_INITIALIZATION | S_EVENT | S_CONTINUOUS_TIME | S_STEP)
#define S_FMU_STATE (S_INSTANTIATED | S_INITIALIZATION | S_RUNNING | S_TERMINATED)
#define S_EVALUATE (S_EVENT | S_CONTINUOUS_TIME | S_TERMINATED | S_ERROR)

extern const FmiFace kFmi3Face;

/* fmi3Instantiate<interface> of an FMU whose model is `model` (layer's fmi_instantiate): the face's
 * probe, with FMI 3.0's flags, refused with `type_refusal` when not NULL. */
FmiInstance* fmi3_instantiate(const FmiModel* model, const char* function, const char* type_refusal, fmi3String name,
                              fmi3String token, int model_exchange, int event_mode_used, int early_return_allowed,
                              fmi3Boolean logging_on, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log);

/* A getter or setter of a type the model has no variables of: the state checked, a value reference
 * refused ("the model has no variable of this type"); no value reference is no error. */
fmi3Status fmi3_refuse_absent_type(FmiInstance* instance, const char* function, int set, const fmi3ValueReference vr[],
                                   size_t nvr);
/* fmi3Get<name> and fmi3Set<name> of a type the model has no variables of (host_fp_environment.h
 * included before): each refused by fmi3_refuse_absent_type in the FMU's floating-point environment. */
#define FMI3_ABSENT_TYPE(name, type)                                                                         \
    fmi3Status fmi3Get##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, type values[],  \
                             size_t nValues) {                                                               \
        (void)values, (void)nValues;                                                                         \
        IN_FMU_FP_ENVIRONMENT(fmi3Status,                                                                    \
                              fmi3_refuse_absent_type((FmiInstance*)instance, "fmi3Get" #name, 0, vr, nvr)); \
    }                                                                                                        \
    fmi3Status fmi3Set##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,               \
                             const type values[], size_t nValues) {                                          \
        (void)values, (void)nValues;                                                                         \
        IN_FMU_FP_ENVIRONMENT(fmi3Status,                                                                    \
                              fmi3_refuse_absent_type((FmiInstance*)instance, "fmi3Set" #name, 1, vr, nvr)); \
    }

/* What the model description declares absent: refused, in any state, naming `why`. */
fmi3Status fmi3_refuse_not_offered(FmiInstance* instance, const char* function, const char* why);

/* fmi3GetVersion, fmi3SetDebugLogging and the six FMU-state functions (fmi3GetFMUState ...) are
 * exported by fmi3_face.c: every FMU's the same. */

#endif
