/* The FMI instance layer: what every FMI face of every FMU of the project does the same way, written
 * once. An FMI 2.0 or FMI 3.0 face (fmi2_face.c, fmi3_face.c) maps the standard's functions and
 * types onto it; the model behind it is reached through a small table of functions (FmiModel).
 *
 * Here: the instance (name, host logger, state, log categories, times, the FMU states handed out),
 * the check of a call's state against the mask of the states it is allowed in, logging through the
 * host's callback, instantiation and its refusals, the rule of which variables may be set when, the
 * communication-point checks of a step, and the six FMU-state calls over the record of fmu_state.h.
 *
 * The two versions number their states differently (the bits are written into FMU-state records,
 * so they stay as they were): the face says which of its bits mean what (FmiFace). */
#ifndef GIMBAL_FMI_INSTANCE_H
#define GIMBAL_FMI_INSTANCE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "common/communication_point.h"
#include "gimbal/gimbal_status.h"
#include "fmi_layer/fmu_state.h"

/* gnu_printf on mingw-w64 too: the messages use C99's %zu, which its vsnprintf formats. */
#if defined(__MINGW32__)
#define FMI_PRINTF_FORMAT(format_index, first_argument) __attribute__((format(gnu_printf, format_index, first_argument)))
#elif defined(__GNUC__)
#define FMI_PRINTF_FORMAT(format_index, first_argument) __attribute__((format(printf, format_index, first_argument)))
#else
#define FMI_PRINTF_FORMAT(format_index, first_argument)
#endif

/* A check at compile time in C (C99 with the compilers' _Static_assert) and in C++ (the gimbal's model
 * table, model_core/src/simulation/fmu_model_table.cpp, includes the layer's headers). */
#ifdef __cplusplus
#define FMI_STATIC_ASSERT(condition, message) static_assert(condition, message)
#else
#define FMI_STATIC_ASSERT(condition, message) _Static_assert(condition, message)
#endif

/* The core's status (gimbal/gimbal_status.h): one type from the host's call to the core's answer.
 * fmi2Status and fmi3Status share its values (the faces assert it). */
typedef GimbalStatus FmiStatus;
#define FMI_OK GIMBAL_OK
#define FMI_WARNING GIMBAL_WARNING
#define FMI_DISCARD GIMBAL_DISCARD
#define FMI_ERROR GIMBAL_ERROR
#define FMI_FATAL GIMBAL_FATAL

/* A variable's role, as the model's variable table gives it: what the settable rule reads. */
typedef enum { FMI_PARAMETER = 0, FMI_INPUT = 1, FMI_OUTPUT = 2, FMI_LOCAL = 3 } FmiCausality;
typedef enum { FMI_FIXED = 0, FMI_TUNABLE = 1, FMI_CONTINUOUS = 2 } FmiVariability;
typedef enum { FMI_INITIAL_NONE = 0, FMI_INITIAL_EXACT = 1, FMI_INITIAL_CALCULATED = 2, FMI_INITIAL_APPROX = 3 } FmiInitial;

typedef struct FmiInstance FmiInstance;

/* What differs between the FMI 2.0 and FMI 3.0 faces of the layer. */
typedef struct {
    /* Hands a finished message to the host's callback (whose signature is the version's). */
    void (*deliver)(const FmiInstance* instance, FmiStatus status, const char* category, const char* message);
    int logger_formats_message;     /* FMI 2.0's logger takes its message as a format: '%' is doubled */
    int resource_location_is_uri;   /* FMI 2.0 names the resources folder with a file: URI, FMI 3.0 with a path */
    int instantiated_state;
    int any_state;                  /* every state bit of the version */
    int error_state;
    int step_failed_state;          /* Co-Simulation after a discarded step */
    int before_initialized_states;  /* instantiated and initialization mode */
    const char* (*state_name)(int state);
    /* FMU states: the record's magic, what its header may hold, the calls' names and argument name. */
    uint32_t state_magic;
    FmuStateRules state_rules;
    const char* get_fmu_state;
    const char* deserialize_fmu_state;
    const char* fmu_state_argument;
} FmiFace;

/* What the layer needs of a model. The model's value access, stepping and equations are the faces'
 * business with the model itself; these are the calls the layer makes on every model alike. */
typedef struct {
    const char* guid;
    /* The bytes of an instance: sizeof(FmiInstance), or more for a model whose own fields follow the
     * FmiInstance in one struct (its first member). */
    size_t instance_size;
    const char* const* log_categories; /* the <LogCategories> of the model description, logAll last */
    int log_category_count;
    /* A new model for `instance` (which its log messages go to), NULL when memory is short. */
    void* (*create)(FmiInstance* instance);
    void (*destroy)(void* model);
    /* Back to the start values (fmiXReset); NULL when the face resets the model itself. */
    FmiStatus (*reset)(void* model);
    size_t (*snapshot_size)(void);
    FmiStatus (*save)(void* model, unsigned char* snapshot);
    /* Whether `snapshot` is one this model could have saved; `initialized` says whether it was then. */
    FmiStatus (*check_snapshot)(void* model, const unsigned char* snapshot, int* initialized);
    FmiStatus (*restore)(void* model, const unsigned char* snapshot);
} FmiModel;

enum { FMI_MAX_LOG_CATEGORIES = 8 };

/* The generic host callback as stored; the face's `deliver` casts it back to its own type. */
typedef void (*FmiHostLogger)(void);

struct FmiInstance {
    const FmiFace* face;
    const FmiModel* model;
    void* model_data;
    FmiHostLogger logger;
    void* environment;
    char* name;
    int model_exchange;
    int state;
    int category_enabled[FMI_MAX_LOG_CATEGORIES];
    double time;
    double stop_time;
    int stop_time_defined;
    double last_successful_time; /* recorded in FMU states when the face's rules say so */
    int last_step_status;
    FmuStateRegistry states;     /* the FMU states this instance handed out */
    /* The function running, whose name prefixes the model's messages that name none; NULL outside. */
    const char* calling;
    /* The face's own fields (FMI 3.0's eventModeUsed and earlyReturnAllowed). */
    int event_mode_used;
    int early_return_allowed;
};

/* Logging. Refusals and failures (discard and worse) always reach the host, anything else only in a
 * category the host enabled (or with logAll). */
void fmi_log(const FmiInstance* instance, FmiStatus status, const char* category, const char* format, ...)
    FMI_PRINTF_FORMAT(4, 5);
/* An error in category logStatusError. NULL-safe. */
void fmi_log_error(const FmiInstance* instance, const char* format, ...) FMI_PRINTF_FORMAT(2, 3);
/* fmi_log_error "<function>: <why>", then FMI_ERROR. NULL-safe. */
FmiStatus fmi_refuse(const FmiInstance* instance, const char* function, const char* why);
/* A model's message: prefixed with the function running, when one is. */
void fmi_log_from_model(FmiInstance* instance, FmiStatus status, const char* category, const char* message);
int fmi_log_enabled(const FmiInstance* instance, const char* category);

/* The state check of every call: NULL-safe; when the instance's state is in `states`, the function
 * becomes the prefix of the model's messages; otherwise the refusal is logged. Inline, as the step
 * check below: every doStep passes both, and a call into another file costs what the check does. */
void fmi_log_state_refusal(const FmiInstance* instance, const char* function);
static inline int fmi_allowed(FmiInstance* instance, const char* function, int states) {
    if (instance == NULL) return 0;
    if (instance->state & states) {
        instance->calling = function;
        return 1;
    }
    fmi_log_state_refusal(instance, function);
    return 0;
}
int fmi_not_null(const FmiInstance* instance, const char* function, const void* pointer, const char* argument);

/* fmiXSetDebugLogging after its state check: no categories means all of them; every category is
 * checked before any is changed, so a refused call changes nothing. */
FmiStatus fmi_set_debug_logging(FmiInstance* instance, const char* function, int logging_on, size_t count,
                                const char* const categories[]);

/* Instantiation up to the model: `probe` holds the face, model, logger, environment, interface and
 * the name the host passed; the name, the face's own refusal `type_refusal` (NULL: none) and the GUID
 * (`token_name`: "GUID" or "instantiationToken") are checked in that order, the instance allocated,
 * the model created. NULL, logged, on a refusal or when memory is short. */
FmiInstance* fmi_instantiate(const FmiInstance* probe, const char* function, const char* type_refusal,
                             const char* token, const char* token_name, int logging_on);
void fmi_free_instance(FmiInstance* instance);
/* fmiXReset after its state check: the model's reset, then the instance's times and state as after
 * instantiation; a model that cannot reset leaves the instance in the error state. */
FmiStatus fmi_reset(FmiInstance* instance);

/* Whether a variable may be set in the instance's state: before initialization ends its inputs, its
 * exact start values and the approx ones (the rotors stay settable in Initialization Mode as when
 * they were exact); after, its inputs and tunable parameters. */
int fmi_settable(const FmiInstance* instance, FmiCausality causality, FmiVariability variability, FmiInitial initial);

/* fmiXSetupExperiment's / fmi3EnterInitializationMode's times: finite, stop after start; logged. */
int fmi_experiment_times_valid(const FmiInstance* instance, const char* function, double start, int stop_defined,
                               double stop);
/* A step's arguments under the communication-point rule (common/communication_point.h): a finite
 * positive step from the FMU's time (the master's point becomes the FMU's time), not past the stop
 * time; otherwise fmi_log_step_refusal names the culprit. */
int fmi_log_step_refusal(const FmiInstance* instance, const char* function, double point, double step_size);
static inline int fmi_step_valid(const FmiInstance* instance, const char* function, double point, double step_size) {
    if (step_size > 0.0 && isfinite(step_size) && communication_point_matches(instance->time, point, step_size) &&
        !(instance->stop_time_defined &&
          communication_step_passes_stop_time(point + step_size, instance->stop_time, step_size)))
        return 1;
    return fmi_log_step_refusal(instance, function, point, step_size);
}

/* A model's check_snapshot's verdict: `problem` NULL, the snapshot is one the model could have saved
 * (*initialized = snapshot_initialized, FMI_OK); otherwise the refusal, logged naming the function
 * running and the problem, FMI_ERROR. */
FmiStatus fmi_snapshot_verdict(FmiInstance* instance, const char* problem, int snapshot_initialized, int* initialized);

/* The FMU-state calls, after the face's state check. */
FmiStatus fmi_get_fmu_state(FmiInstance* instance, const char* function, void** state);
FmiStatus fmi_set_fmu_state(FmiInstance* instance, const char* function, const void* state);
FmiStatus fmi_free_fmu_state(FmiInstance* instance, const char* function, void** state);
FmiStatus fmi_serialized_fmu_state_size(FmiInstance* instance, const char* function, const void* state, size_t* size);
FmiStatus fmi_serialize_fmu_state(FmiInstance* instance, const char* function, const void* state, unsigned char* bytes,
                                  size_t size);
FmiStatus fmi_deserialize_fmu_state(FmiInstance* instance, const char* function, const unsigned char* bytes,
                                    size_t size, void** state);

#endif
