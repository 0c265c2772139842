/* The table of an FMU of the project (the gimbal, the ship motion, the controller), read by both of its
 * faces: the FMI 2.0 one (fmi2_functions.c) and the FMI 3.0 one (fmi3_functions.c), each every exported
 * function of its version written once, over the FMI instance layer. An FMU is its model and one
 * FmuModel table: its variables' access by value reference, its initialization, step and reset, its
 * FMU-state snapshot (FmiModel), the states its calls are allowed in, and what it offers beyond
 * Co-Simulation (Model Exchange, Event Mode and early return, directional and input derivatives).
 * The faces check the state, the pointers, the counts and the value references, and refuse what the
 * model descriptions declare absent (a NULL entry) naming the declaration.
 *
 * The states of the table are masks of FMI 2.0's states (fmi2_face.h); the FMI 3.0 face maps them onto
 * its own (step complete is step mode, step failed step discarded). A model that changes the
 * instance's state does so through the face (instance->face->error_state ...), so that it is right
 * under either version. */
#ifndef GIMBAL_FMU_MODEL_H
#define GIMBAL_FMU_MODEL_H

#include "fmi_layer/fmi2_face.h"

/* The variables of one type (FMI 2.0's Real, Integer, Boolean, String; FMI 3.0's Float64, Int32,
 * Int64, Boolean, String). Value references are 0 .. count - 1 within the type (FMI 3.0 adds the
 * type's base); the faces refuse the others before the model sees them. Values are passed as double,
 * int, int (0 or 1) and const char*. Every callback logs its refusal, prefixed with `function`. */
typedef struct {
    unsigned count;
    /* The value of variable `vr`; not FMI_OK when it cannot be computed (logged). */
    FmiStatus (*get)(FmiInstance* instance, const char* function, unsigned vr, void* value);
    /* 1 when `value` (a pointer to the model's value) may be set into `vr` now; 0, logged, otherwise.
     * Every value of a call is checked before any is set: a refused call changes nothing. */
    int (*settable)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
    /* Stores a checked value; not FMI_OK (logged) only when memory is short. */
    FmiStatus (*set)(FmiInstance* instance, const char* function, unsigned vr, const void* value);
    /* Which of 0 .. count - 1 are variables of the type; NULL: all of them. */
    int (*known)(unsigned vr);
    /* A model that takes a call's values at once (the host's arrays of doubles, FMI 2.0's Real and FMI
     * 3.0's Float64 only), instead of get/settable/set one by one: the value references as the host
     * passed them (the model checks them and names the culprit), all or nothing. NULL: one by one. */
    FmiStatus (*get_all)(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr, double values[]);
    FmiStatus (*set_all)(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                         const double values[]);
} FmuVariables;

/* The FMI 3.0 value references of a model whose FMI 3.0 variables are not its FMI 2.0 ones with the
 * bases of common/fmi3_value_references.h (the gimbal's enumerations are Int64, its event indicators
 * Float64 locals). */
typedef struct {
    FmuVariables float64, int32, int64, boolean, string;
    unsigned float64_base, int32_base, int64_base, boolean_base, string_base;
    unsigned time; /* `time`, the independent variable: read-only, the instance's */
} Fmi3Variables;

/* What the host's continuous-time solver reads and sets (Model Exchange), after the face's checks of
 * the state, the interface, the counts and the pointers. */
typedef struct {
    int states_changed;
    int next_time_defined;
    double next_time;
} FmuDiscreteUpdate;

typedef struct {
    size_t continuous_states, event_indicators;
    FmiStatus (*set_time)(FmiInstance* instance, double time);
    FmiStatus (*set_continuous_states)(FmiInstance* instance, const double states[]);
    FmiStatus (*get_derivatives)(FmiInstance* instance, double derivatives[]);
    FmiStatus (*get_event_indicators)(FmiInstance* instance, double indicators[]);
    FmiStatus (*get_continuous_states)(FmiInstance* instance, double states[]);
    FmiStatus (*get_nominals)(FmiInstance* instance, double nominals[]);
    /* The modes decided whole at an event: one call ends the event iteration. */
    FmiStatus (*update_discrete_states)(FmiInstance* instance, FmuDiscreteUpdate* update);
} FmuModelExchange;

typedef struct {
    FmiModel layer;
    /* The states (masks of FMI 2.0's InstanceState) the calls are allowed in, beyond those the
     * standard fixes. */
    int get_states, set_states, terminate_states, status_states;
    FmuVariables real, integer, boolean, string;
    /* NULL: FMI 3.0's Float64, Int32, Boolean and String are the four above at the bases of
     * common/fmi3_value_references.h, with no Int64. */
    const Fmi3Variables* fmi3;
    /* After instantiation made the instance: the model's own setup, given the host's resource location
     * (a file: URI or a path: instance->face->resource_location_is_uri); -1 when memory is short.
     * NULL: none. */
    int (*instantiated)(FmiInstance* instance, const char* resource_location);
    /* Before the instance is freed: what `instantiated` and the model allocated beyond the layer. NULL: none. */
    void (*release)(FmiInstance* instance);
    /* fmiXReset: the model back to its start values; not FMI_OK (logged) leaves the instance as it was.
     * NULL: the layer's reset (fmi_reset, through FmiModel). */
    FmiStatus (*reset)(FmiInstance* instance, const char* function);
    /* The master's tolerance (fmi2SetupExperiment, fmi3EnterInitializationMode), before the
     * experiment's times are stored; refused (logged), nothing is. NULL: nothing is integrated. */
    FmiStatus (*tolerance)(FmiInstance* instance, const char* function, int defined, double tolerance);
    /* The experiment's start time, after the face stored the instance's times. NULL: not needed. */
    void (*experiment_start)(FmiInstance* instance, double start_time);
    /* fmiXExitInitializationMode: the parameters checked and the model started; refused (logged), the
     * instance stays in initialization mode, for the master to correct them. */
    FmiStatus (*exit_initialization)(FmiInstance* instance, const char* function);
    /* A step the face checked (state, communication point): the model's outputs at point + step (or,
     * with instance->early_return_allowed, at the first mode change inside it: *ended_early = 1), the
     * instance's time and, when it fails, its state; the face records the status (fmi2GetStatus). */
    FmiStatus (*do_step)(FmiInstance* instance, const char* function, double point, double step, int* ended_early);
    /* After a successful set of one value or more. NULL: nothing to do. */
    void (*values_set)(FmiInstance* instance);
    /* Directional derivatives of Float64 (Real) unknowns with respect to knowns, after the face's
     * pointer and count checks; the model checks the seeds and which variables may be which. NULL: not
     * offered. */
    FmiStatus (*directional_derivative)(FmiInstance* instance, const char* function, const unsigned unknowns[],
                                        size_t unknown_count, const unsigned knowns[], size_t known_count,
                                        const double seed[], double sensitivity[]);
    /* fmi2SetRealInputDerivatives, one value. NULL: canInterpolateInputs is false. */
    FmiStatus (*set_input_derivative)(FmiInstance* instance, const char* function, unsigned vr, int order,
                                      double value);
    /* NULL: Co-Simulation only. */
    const FmuModelExchange* model_exchange;
    /* FMI 3.0 Co-Simulation with Event Mode and early return (hasEventMode). */
    int has_event_mode;
    /* The FMI 2.0 FMU-state functions (canGetAndSetFMUstate, canSerializeFMUstate); FMI 3.0's are
     * always offered. */
    int fmi2_fmu_state;
} FmuModel;

/* The table of the FMU the face is linked into (one per binary: each FMU's model file defines it; the
 * gimbal's is the core's, model_core/src/simulation/fmu_model_table.cpp, which includes this header). */
extern const FmuModel kFmuModel;

/* ---------------------------------------------------------------- what both faces do alike (fmu_model.c)
 * Each after the face's own state check, with the face's function name for the messages. */

/* The model's own setup of a new instance (NULL passes through); NULL, logged, when memory is short. */
FmiInstance* fmu_model_instantiated(FmiInstance* instance, const char* function, const char* resource_location);
void fmu_model_free_instance(FmiInstance* instance);

/* How the host's elements are stored: as the model's (double, int, const char*), or as FMI 3.0's
 * fmi3Boolean (a C bool) and fmi3Int64 the face converts to and from the model's int. */
typedef enum { FMU_VALUES_AS_THE_MODELS = 0, FMU_VALUES_C_BOOL = 1, FMU_VALUES_INT64 = 2 } FmuValueLayout;

/* Get<type>: `values`, the host's array of `nvr` elements of `size` bytes; the value references are
 * the model's plus `base` (FMI 3.0's per-type ranges; 0 for FMI 2.0). */
FmiStatus fmu_model_get(FmiInstance* instance, const char* function, const FmuVariables* variables,
                        const char* type, unsigned base, const unsigned vr[], size_t nvr, void* values, size_t size,
                        FmuValueLayout layout);
/* Set<type>: all or nothing, every value checked before any is set. */
FmiStatus fmu_model_set(FmiInstance* instance, const char* function, const FmuVariables* variables,
                        const char* type, unsigned base, const unsigned vr[], size_t nvr, const void* values,
                        size_t size, FmuValueLayout layout);

/* The experiment's times and tolerance, checked and stored, and the model told its start. */
FmiStatus fmu_model_start_experiment(FmiInstance* instance, const char* function, int tolerance_defined,
                                     double tolerance, double start, int stop_defined, double stop);
/* The model back to its start values, the instance to instantiated. */
FmiStatus fmu_model_reset(FmiInstance* instance, const char* function);
/* The model started; the instance then in `stepping_state` (the face's step complete / step mode,
 * or event mode), its last successful time its start. */
FmiStatus fmu_model_exit_initialization(FmiInstance* instance, const char* function, int stepping_state);
/* A checked step through the model's do_step; the last successful time follows a successful one. */
FmiStatus fmu_model_do_step(FmiInstance* instance, const char* function, double point, double step, int* ended_early);

/* Model Exchange: whether the instance is one (logged if not), and whether a vector's count is the
 * model's (logged naming `count_name` if not). */
int fmu_model_exchange_instance(FmiInstance* instance, const char* function);
int fmu_model_count_is(FmiInstance* instance, const char* function, size_t given, size_t expected,
                       const char* count_name);

#endif
