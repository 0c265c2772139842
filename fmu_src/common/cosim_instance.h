/* What the small FMI 2.0 Co-Simulation FMUs (ship_motion/, controller/) share of an instance: the
 * host's logger and the instance's name, their two log categories, the states of the standard's
 * state machine, fmi2Instantiate's checks, and the checks of a call's state and of its pointer
 * arguments. Every refusal is logged naming the function and the culprit; nothing is written
 * anywhere else, and nothing here is global or mutable: all of it lives in the instance.
 *
 * Each FMU's Instance has a CosimInstance as its first member (cosim_instantiate allocates the
 * whole Instance and fills that member), so that the fmi2Component the host holds is both. */
#ifndef GIMBAL_COSIM_INSTANCE_H
#define GIMBAL_COSIM_INSTANCE_H

#include <stddef.h>

#include "fmi2Functions.h"

#if defined(__GNUC__)
#define COSIM_PRINTF_FORMAT(format_index, first_argument) __attribute__((format(printf, format_index, first_argument)))
#else
#define COSIM_PRINTF_FORMAT(format_index, first_argument)
#endif

/* Bits, so that a function's allowed states are one mask. */
typedef enum {
    STATE_INSTANTIATED = 1 << 0,
    STATE_INITIALIZATION = 1 << 1,
    STATE_STEP_COMPLETE = 1 << 2,
    STATE_TERMINATED = 1 << 3,
    STATE_ERROR = 1 << 4, /* a failed step the FMU cannot continue from */
} InstanceState;

/* The <LogCategories> of both model descriptions, in their order. */
enum { LOG_STATUS_ERROR, LOG_ALL, LOG_CATEGORY_COUNT };

typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char* instance_name; /* the instance's copy of fmi2Instantiate's instanceName */
    int category_enabled[LOG_CATEGORY_COUNT];
    InstanceState state;
} CosimInstance;

/* fmi2Instantiate up to the model: checks the callbacks (without a logger nothing could say why a
 * call is refused), the instance name, the type (Co-Simulation only) and the GUID against `fmu_guid`,
 * then allocates `instance_size` zeroed bytes whose first member is the CosimInstance, copies the
 * name and enables every category when `logging_on`. The state is STATE_INSTANTIATED. NULL, logged
 * when there is a logger, when a check fails or memory is short. */
void* cosim_instantiate(size_t instance_size, fmi2String instance_name, fmi2Type type, fmi2String guid,
                        const char* fmu_guid, const fmi2CallbackFunctions* functions, fmi2Boolean logging_on);

/* A copy of `text` the caller frees; NULL when memory is short. */
char* cosim_copy_text(const char* text);

/* Frees what cosim_instantiate allocated (the model's own allocations are the FMU's to free first). */
void cosim_free(CosimInstance* instance);

/* An error through the host's logger, category logStatusError, formatted as printf does. NULL-safe. */
void cosim_log_error(const CosimInstance* instance, const char* format, ...) COSIM_PRINTF_FORMAT(2, 3);

/* cosim_log_error, then fmi2Error: the end of a refused call. */
fmi2Status cosim_refuse(const CosimInstance* instance, const char* format, ...) COSIM_PRINTF_FORMAT(2, 3);

const char* cosim_state_name(InstanceState state);

/* NULL-safe: whether `function` may be called in the instance's state (`states`, a mask of
 * InstanceState); logged when not. */
int cosim_allowed(const CosimInstance* instance, const char* function, int states);

/* Whether the pointer argument `argument` of `function` is given; logged when it is NULL. */
int cosim_not_null(const CosimInstance* instance, const char* function, const void* pointer, const char* argument);

/* fmi2SetDebugLogging, in any state: no categories means all of them. Every category is checked
 * before any is changed, so that a refused call changes nothing. */
fmi2Status cosim_set_debug_logging(CosimInstance* instance, fmi2Boolean logging_on, size_t category_count,
                                   const fmi2String categories[]);

#endif
