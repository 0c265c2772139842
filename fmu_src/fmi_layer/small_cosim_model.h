/* The table of a small Co-Simulation FMU (ship motion, controller), read by both of its faces: the FMI
 * 2.0 one (small_fmi2_cosim.c) and the FMI 3.0 one (small_fmi3_cosim.c), each every exported function
 * of its version written once, over the FMI instance layer. A small FMU is its model and one
 * SmallCosimModel table: its variables' access by value reference, its initialization, step and
 * reset, its FMU-state snapshot (FmiModel), and the states its calls are allowed in. The faces check
 * the state, the pointers and the value references, and refuse what the model descriptions declare
 * absent.
 *
 * The states of the table are masks of FMI 2.0's states (fmi2_face.h); the FMI 3.0 face maps them onto
 * its own (step complete is step mode, step failed step discarded). A model that changes the
 * instance's state does so through the face (instance->face->error_state ...), so that it is right
 * under either version. */
#ifndef GIMBAL_SMALL_COSIM_MODEL_H
#define GIMBAL_SMALL_COSIM_MODEL_H

#include "fmi_layer/fmi2_face.h"

/* The variables of one type (FMI 2.0's Real, Integer, Boolean, String; FMI 3.0's Float64, Int32,
 * Boolean, String). Value references are 0 .. count - 1 within the type (FMI 3.0 adds the type's
 * base, common/fmi3_value_references.h); the faces refuse the others before the model sees them.
 * Values are passed as double, int, int (0 or 1) and const char*. Every callback logs its refusal,
 * prefixed with `function`. */
typedef struct {
    unsigned count;
    /* The value of variable `vr`; not FMI_OK when it cannot be computed (logged). */
    FmiStatus (*get)(FmiInstance* instance, const char* function, unsigned vr, void* value);
    /* 1 when `value` (a pointer to the host's element) may be set into `vr` now; 0, logged, otherwise.
     * Every value of a call is checked before any is set: a refused call changes nothing. */
    int (*settable)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
    /* Stores a checked value; not FMI_OK (logged) only when memory is short. */
    FmiStatus (*set)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
} SmallCosimVariables;

typedef struct {
    FmiModel layer;
    /* The states (masks of FMI 2.0's InstanceState) the calls are allowed in, beyond those the
     * standard fixes. */
    int get_states, set_states, terminate_states, status_states;
    SmallCosimVariables real, integer, boolean, string;
    /* After instantiation made the instance: the model's own setup, given the host's resource location
     * (a file: URI or a path: instance->face->resource_location_is_uri); -1 when memory is short.
     * NULL: none. */
    int (*instantiated)(FmiInstance* instance, const char* resource_location);
    /* Before the instance is freed: what `instantiated` and the model allocated beyond the layer. NULL: none. */
    void (*release)(FmiInstance* instance);
    /* fmiXReset: the model back to its start values; not FMI_OK (logged) leaves the instance as it was. */
    FmiStatus (*reset)(FmiInstance* instance, const char* function);
    /* The experiment's start time, after the face stored the instance's times. NULL: not needed. */
    void (*experiment_start)(FmiInstance* instance, double start_time);
    /* fmiXExitInitializationMode: the parameters checked and the model started; refused (logged), the
     * instance stays in initialization mode, for the master to correct them. */
    FmiStatus (*exit_initialization)(FmiInstance* instance, const char* function);
    /* A step the face checked (state, communication point): the model's outputs at point + step, the
     * instance's time and, when it fails, its state and last_step_status (what fmi2GetStatus says). */
    FmiStatus (*do_step)(FmiInstance* instance, const char* function, double point, double step);
    /* After a successful set of one value or more. NULL: nothing to do. */
    void (*values_set)(FmiInstance* instance);
} SmallCosimModel;

/* The table of the FMU the face is linked into (one per binary: each small FMU's model file defines it). */
extern const SmallCosimModel kSmallCosimModel;

/* ---------------------------------------------------------------- what both faces do alike (small_cosim.c)
 * Each after the face's own state check, with the face's function name for the messages. */

/* The model's own setup of a new instance (NULL passes through); NULL, logged, when memory is short. */
FmiInstance* small_cosim_instantiated(FmiInstance* instance, const char* function, const char* resource_location);
void small_cosim_free_instance(FmiInstance* instance);

/* How the host's elements are stored: as the model's (double, int, const char*), or, FMI 3.0's
 * fmi3Boolean, as a C bool the face converts to and from the model's int. */
typedef enum { SMALL_VALUES_AS_THE_MODELS = 0, SMALL_VALUES_C_BOOL = 1 } SmallValueLayout;

/* Get<type>: `values`, the host's array of `nvr` elements of `size` bytes; the value references are
 * the model's plus `base` (FMI 3.0's per-type ranges; 0 for FMI 2.0). */
FmiStatus small_cosim_get(FmiInstance* instance, const char* function, const SmallCosimVariables* variables,
                          const char* type, unsigned base, const unsigned vr[], size_t nvr, void* values, size_t size,
                          SmallValueLayout layout);
/* Set<type>: all or nothing, every value checked before any is set. */
FmiStatus small_cosim_set(FmiInstance* instance, const char* function, const SmallCosimVariables* variables,
                          const char* type, unsigned base, const unsigned vr[], size_t nvr, const void* values,
                          size_t size, SmallValueLayout layout);

/* The experiment's times, checked and stored, and the model told its start. */
FmiStatus small_cosim_start_experiment(FmiInstance* instance, const char* function, double start, int stop_defined,
                                       double stop);
/* The model back to its start values, the instance to instantiated. */
FmiStatus small_cosim_reset(FmiInstance* instance, const char* function);
/* The model started; the instance then in `stepping_state` (the face's step complete / step mode). */
FmiStatus small_cosim_exit_initialization(FmiInstance* instance, const char* function, int stepping_state);

#endif
