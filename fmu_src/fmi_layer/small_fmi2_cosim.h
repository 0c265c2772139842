/* The FMI 2.0 Co-Simulation face of the small FMUs (ship motion, controller): every exported fmi2*
 * function written once, over the FMI instance layer and its FMI 2.0 face (fmi2_face.h). A small FMU
 * is its model and one SmallFmi2Model table: its variables' access by value reference, its
 * initialization, step and reset, and the states its calls are allowed in. The face checks the state,
 * the pointers and the value references, and refuses what the model descriptions declare absent
 * (FMU states, directional derivatives, input and output derivatives, asynchronous steps). */
#ifndef GIMBAL_SMALL_FMI2_COSIM_H
#define GIMBAL_SMALL_FMI2_COSIM_H

#include "fmi_layer/fmi2_face.h"

/* The variables of one FMI 2.0 type. Value references are 0 .. count - 1; the face refuses the others
 * before the model sees them. Every callback logs its refusal, prefixed with `function`. */
typedef struct {
    unsigned count;
    /* The value of variable `vr`; not FMI_OK when it cannot be computed (logged). */
    FmiStatus (*get)(FmiInstance* instance, const char* function, unsigned vr, void* value);
    /* 1 when `value` (a pointer to the host's element) may be set into `vr` now; 0, logged, otherwise.
     * Every value of a call is checked before any is set: a refused call changes nothing. */
    int (*settable)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
    /* Stores a checked value; not FMI_OK (logged) only when memory is short. */
    FmiStatus (*set)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
} SmallFmi2Variables;

typedef struct {
    FmiModel layer;
    /* The states (masks of InstanceState) the calls are allowed in, beyond those the standard fixes. */
    int get_states, set_states, terminate_states, status_states;
    SmallFmi2Variables real, integer, boolean, string;
    /* After fmi2Instantiate made the instance: the model's own setup; -1 when memory is short. NULL: none. */
    int (*instantiated)(FmiInstance* instance, const char* resource_location);
    /* Before the instance is freed: what `instantiated` and the model allocated beyond the layer. NULL: none. */
    void (*release)(FmiInstance* instance);
    /* fmi2Reset: the model back to its start values; not FMI_OK (logged) leaves the instance as it was. */
    FmiStatus (*reset)(FmiInstance* instance, const char* function);
    /* fmi2SetupExperiment's start time, after the face stored the instance's times. NULL: not needed. */
    void (*experiment_start)(FmiInstance* instance, double start_time);
    /* fmi2ExitInitializationMode: the parameters checked and the model started; refused (logged), the
     * instance stays in initialization mode, for the master to correct them. */
    FmiStatus (*exit_initialization)(FmiInstance* instance, const char* function);
    /* A step the face checked (state, communication point): the model's outputs at point + step, the
     * instance's time and, when it fails, its state and last_step_status (what fmi2GetStatus says). */
    FmiStatus (*do_step)(FmiInstance* instance, const char* function, double point, double step);
    /* After a successful set of one value or more. NULL: nothing to do. */
    void (*values_set)(FmiInstance* instance);
} SmallFmi2Model;

/* The table of the FMU the face is linked into (one per binary: each small FMU's model file defines it). */
extern const SmallFmi2Model kSmallFmi2Model;

#endif
