/* The FMI instance layer (fmi_instance.h). */
#include "fmi_instance.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


/* ---------------------------------------------------------------- logging */

static int category_index(const FmiInstance* instance, const char* category) {
    for (int k = 0; k < instance->model->log_category_count; ++k)
        if (strcmp(category, instance->model->log_categories[k]) == 0) return k;
    return -1;
}

int fmi_log_enabled(const FmiInstance* instance, const char* category) {
    const int index = category_index(instance, category);
    return instance->logger != NULL && ((index >= 0 && instance->category_enabled[index]) ||
                                        instance->category_enabled[instance->model->log_category_count - 1]);
}

static void log_va(const FmiInstance* instance, FmiStatus status, const char* category, const char* format,
                   va_list args) {
    if (instance == NULL || instance->logger == NULL) return;
    if (status < FMI_DISCARD && !fmi_log_enabled(instance, category)) return;
    char text[1024];
    vsnprintf(text, sizeof text, format, args);
    if (!instance->face->logger_formats_message) {
        instance->face->deliver(instance, status, category, text);
        return;
    }
    char escaped[2 * sizeof text];
    size_t j = 0;
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; ++i) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    instance->face->deliver(instance, status, category, escaped);
}

void fmi_log(const FmiInstance* instance, FmiStatus status, const char* category, const char* format, ...) {
    va_list args;
    va_start(args, format);
    log_va(instance, status, category, format, args);
    va_end(args);
}

void fmi_log_error(const FmiInstance* instance, const char* format, ...) {
    va_list args;
    va_start(args, format);
    log_va(instance, FMI_ERROR, "logStatusError", format, args);
    va_end(args);
}

FmiStatus fmi_refuse(const FmiInstance* instance, const char* function, const char* why) {
    fmi_log_error(instance, "%s: %s", function, why);
    return FMI_ERROR;
}

void fmi_log_from_model(FmiInstance* instance, FmiStatus status, const char* category, const char* message) {
    if (instance->calling != NULL) fmi_log(instance, status, category, "%s: %s", instance->calling, message);
    else fmi_log(instance, status, category, "%s", message);
}

/* ---------------------------------------------------------------- states and arguments */

void fmi_log_state_refusal(const FmiInstance* instance, const char* function) {
    fmi_log_error(instance, "%s is not allowed in state '%s'", function, instance->face->state_name(instance->state));
}

int fmi_not_null(const FmiInstance* instance, const char* function, const void* pointer, const char* argument) {
    if (pointer != NULL) return 1;
    fmi_log_error(instance, "%s: argument %s is a null pointer", function, argument);
    return 0;
}

FmiStatus fmi_set_debug_logging(FmiInstance* instance, const char* function, int logging_on, size_t count,
                                const char* const categories[]) {
    if (!fmi_allowed(instance, function, instance == NULL ? 0 : instance->face->any_state)) return FMI_ERROR;
    if (count > 0 && !fmi_not_null(instance, function, categories, "categories")) return FMI_ERROR;
    int chosen[FMI_MAX_LOG_CATEGORIES] = {0};
    for (size_t i = 0; i < count; ++i) {
        const int index = categories[i] != NULL ? category_index(instance, categories[i]) : -1;
        if (index < 0) {
            fmi_log_error(instance, "%s: unknown log category '%s'", function,
                          categories[i] != NULL ? categories[i] : "(null)");
            return FMI_ERROR;
        }
        chosen[index] = 1;
    }
    for (int k = 0; k < instance->model->log_category_count; ++k)
        if (count == 0 || chosen[k]) instance->category_enabled[k] = logging_on ? 1 : 0;
    return FMI_OK;
}

/* ---------------------------------------------------------------- lifetime */

FmiInstance* fmi_instantiate(const FmiInstance* probe, const char* function, const char* type_refusal,
                             const char* token, const char* token_name, int logging_on) {
    if (probe->logger == NULL) return NULL; /* nowhere to say why */
    const char* guid = probe->model->guid;
    const char* name = probe->name;
    if (name == NULL || name[0] == '\0') {
        fmi_log_error(probe, "%s: instanceName must be a non-empty string", function);
        return NULL;
    }
    if (type_refusal != NULL) {
        fmi_log_error(probe, "%s: %s", function, type_refusal);
        return NULL;
    }
    if (token == NULL || strcmp(token, guid) != 0) {
        fmi_log_error(probe, "%s: %s '%s' does not match this FMU's '%s'", function, token_name,
                      token != NULL ? token : "(null)", guid);
        return NULL;
    }
    FmiInstance* instance = (FmiInstance*)calloc(1, probe->model->instance_size);
    char* copy = (char*)malloc(strlen(name) + 1);
    if (instance == NULL || copy == NULL) {
        free(instance);
        free(copy);
        fmi_log_error(probe, "%s: out of memory", function);
        return NULL;
    }
    strcpy(copy, name);
    *instance = *probe;
    instance->name = copy;
    for (int k = 0; k < instance->model->log_category_count; ++k) instance->category_enabled[k] = logging_on ? 1 : 0;
    instance->calling = function;
    instance->model_data = instance->model->create(instance);
    if (instance->model_data == NULL) {
        fmi_log_error(instance, "%s: out of memory", function);
        free(copy);
        free(instance);
        return NULL;
    }
    instance->state = instance->face->instantiated_state;
    return instance;
}

void fmi_free_instance(FmiInstance* instance) {
    if (instance == NULL) return;
    fmu_states_release_all(&instance->states);
    instance->model->destroy(instance->model_data);
    free(instance->name);
    free(instance);
}

FmiStatus fmi_reset(FmiInstance* instance) {
    const FmiStatus status = instance->model->reset(instance->model_data);
    if (status > FMI_WARNING) {
        instance->state = instance->face->error_state;
        return status;
    }
    instance->time = 0.0;
    instance->stop_time_defined = 0;
    instance->last_successful_time = 0.0;
    instance->last_step_status = FMI_OK;
    instance->state = instance->face->instantiated_state;
    return FMI_OK;
}

/* ---------------------------------------------------------------- rules */

int fmi_settable(const FmiInstance* instance, FmiCausality causality, FmiVariability variability, FmiInitial initial) {
    if (instance->state & instance->face->before_initialized_states)
        return causality == FMI_INPUT || initial == FMI_INITIAL_EXACT || initial == FMI_INITIAL_APPROX;
    return causality == FMI_INPUT || (causality == FMI_PARAMETER && variability == FMI_TUNABLE);
}

int fmi_experiment_times_valid(const FmiInstance* instance, const char* function, double start, int stop_defined,
                               double stop) {
    if (isfinite(start) && (!stop_defined || (isfinite(stop) && stop >= start))) return 1;
    fmi_log_error(instance, "%s: startTime = %g, stopTime = %g: times must be finite and stopTime >= startTime",
                  function, start, stop);
    return 0;
}

int fmi_log_step_refusal(const FmiInstance* instance, const char* function, double point, double step_size) {
    if (!(step_size > 0.0) || !isfinite(step_size))
        fmi_log_error(instance, "%s: communicationStepSize = %g must be finite and > 0", function, step_size);
    else if (!communication_point_matches(instance->time, point, step_size))
        fmi_log_error(instance, "%s: currentCommunicationPoint = %.17g does not match the FMU's time %.17g", function,
                      point, instance->time);
    else
        fmi_log_error(instance, "%s: step to t = %.17g passes the stopTime %.17g", function, point + step_size,
                      instance->stop_time);
    return 0;
}

/* ---------------------------------------------------------------- FMU states */

static size_t record_size(const FmiInstance* instance) {
    return sizeof(StateHeader) + instance->model->snapshot_size();
}

static int records_step_status(const FmiInstance* instance) { return instance->face->state_rules.last_status_max >= 0; }

/* A registered record of this instance, or NULL with the refusal logged. */
static unsigned char* own_state(const FmiInstance* instance, const char* function, const void* state) {
    const char* argument = instance->face->fmu_state_argument;
    if (!fmi_not_null(instance, function, state, argument)) return NULL;
    if (fmu_states_find(&instance->states, state) < 0) {
        fmi_log_error(instance,
                      "%s: %s %p is not an FMU state of instance '%s' (not handed out by its %s or %s, or already "
                      "freed)",
                      function, argument, state, instance->name, instance->face->get_fmu_state,
                      instance->face->deserialize_fmu_state);
        return NULL;
    }
    return (unsigned char*)state;
}

/* The wrapper's fields of a record range-checked, the model's snapshot checked by the model: a record
 * this FMU could not have saved is refused with the reason. */
static int valid_record(FmiInstance* instance, const char* function, const unsigned char* record) {
    const FmuStateRules* rules = &instance->face->state_rules;
    StateHeader header;
    memcpy(&header, record, sizeof header);
    char text[160];
    const char* problem = fmu_state_header_problem(&header, rules, instance->model_exchange);
    if (problem == NULL) {
        int initialized = 0;
        if (instance->model->check_snapshot(instance->model_data, record + sizeof header, &initialized) > FMI_WARNING)
            return 0;
        problem = fmu_state_model_problem(&header, rules, initialized, text, sizeof text);
    }
    if (problem != NULL) {
        fmi_log_error(instance, "%s: the FMU state is refused: %s", function, problem);
        return 0;
    }
    return 1;
}

FmiStatus fmi_snapshot_verdict(FmiInstance* instance, const char* problem, int snapshot_initialized, int* initialized) {
    if (problem == NULL) {
        *initialized = snapshot_initialized;
        return FMI_OK;
    }
    char text[256];
    snprintf(text, sizeof text, "the FMU state is refused: %s", problem);
    fmi_log_from_model(instance, FMI_ERROR, "logStatusError", text);
    return FMI_ERROR;
}

FmiStatus fmi_get_fmu_state(FmiInstance* instance, const char* function, void** state) {
    if (!fmi_not_null(instance, function, state, instance->face->fmu_state_argument)) return FMI_ERROR;
    /* Overwrite the host's previous state when it hands back one of ours, as the standard allows.
     * Anything else (FMI4j passes an uninitialised pointer) is not ours to touch: take a new record. */
    unsigned char* record = fmu_states_find(&instance->states, *state) >= 0 ? (unsigned char*)*state : NULL;
    const int fresh = record == NULL;
    const size_t size = record_size(instance);
    if (fresh) {
        record = (unsigned char*)calloc(1, size);
        if (record == NULL || !fmu_states_add(&instance->states, record)) {
            free(record);
            fmi_log_error(instance, "%s: out of memory", function);
            return FMI_ERROR;
        }
    }
    StateHeader header;
    fmu_state_header_init(&header, instance->face->state_magic, size, instance->model->guid);
    header.state = (int32_t)instance->state;
    header.time = instance->time;
    header.stop_time = instance->stop_time;
    header.stop_time_defined = instance->stop_time_defined;
    if (records_step_status(instance)) {
        header.last_successful_time = instance->last_successful_time;
        header.last_step_status = (int32_t)instance->last_step_status;
    }
    if (instance->model->save(instance->model_data, record + sizeof header) > FMI_WARNING) {
        if (fresh) fmu_states_release(&instance->states, fmu_states_find(&instance->states, record));
        return FMI_ERROR;
    }
    memcpy(record, &header, sizeof header);
    *state = record;
    return FMI_OK;
}

FmiStatus fmi_set_fmu_state(FmiInstance* instance, const char* function, const void* state) {
    /* A registered record was made by GetFMUState or checked whole by DeserializeFMUState; it is
     * checked once more, and the model's restore checks its snapshot before committing anything. */
    const unsigned char* record = own_state(instance, function, state);
    if (record == NULL || !valid_record(instance, function, record)) return FMI_ERROR;
    StateHeader header;
    memcpy(&header, record, sizeof header);
    /* A refused snapshot leaves the model as it was: so does the instance. */
    const FmiStatus status = instance->model->restore(instance->model_data, record + sizeof header);
    if (status > FMI_WARNING) return status;
    instance->state = header.state;
    instance->time = header.time;
    instance->stop_time = header.stop_time;
    instance->stop_time_defined = header.stop_time_defined;
    if (records_step_status(instance)) {
        instance->last_successful_time = header.last_successful_time;
        instance->last_step_status = header.last_step_status;
    }
    return FMI_OK;
}

FmiStatus fmi_free_fmu_state(FmiInstance* instance, const char* function, void** state) {
    if (state == NULL) return FMI_OK;
    /* The Reference-FMUs' fmusim passes the state itself instead of its address: recognised before
     * anything behind the pointer is read. */
    if (fmu_states_find(&instance->states, state) >= 0) {
        fmi_log_error(instance, "%s: the argument is an FMU state, not the address of one (pass &state); nothing was freed",
                      function);
        return FMI_ERROR;
    }
    if (*state == NULL) return FMI_OK;
    const long index = fmu_states_find(&instance->states, *state);
    if (index < 0) {
        fmi_log_error(instance,
                      "%s: *%s = %p is not an FMU state of instance '%s' (never handed out, or already freed); "
                      "nothing was freed",
                      function, instance->face->fmu_state_argument, *state, instance->name);
        return FMI_ERROR;
    }
    fmu_states_release(&instance->states, index);
    *state = NULL;
    return FMI_OK;
}

FmiStatus fmi_serialized_fmu_state_size(FmiInstance* instance, const char* function, const void* state, size_t* size) {
    if (own_state(instance, function, state) == NULL || !fmi_not_null(instance, function, size, "size")) return FMI_ERROR;
    *size = record_size(instance);
    return FMI_OK;
}

FmiStatus fmi_serialize_fmu_state(FmiInstance* instance, const char* function, const void* state, unsigned char* bytes,
                                  size_t size) {
    const unsigned char* record = own_state(instance, function, state);
    if (record == NULL || !fmi_not_null(instance, function, bytes, "serializedState")) return FMI_ERROR;
    if (size < record_size(instance)) {
        fmi_log_error(instance, "%s: size %zu is below the %zu bytes needed", function, size, record_size(instance));
        return FMI_ERROR;
    }
    fmu_state_serialize(record, record_size(instance), bytes);
    return FMI_OK;
}

FmiStatus fmi_deserialize_fmu_state(FmiInstance* instance, const char* function, const unsigned char* bytes,
                                    size_t size, void** state) {
    if (!fmi_not_null(instance, function, bytes, "serializedState") ||
        !fmi_not_null(instance, function, state, instance->face->fmu_state_argument))
        return FMI_ERROR;
    const char* guid = instance->model->guid;
    const char* problem =
        fmu_state_integrity_problem(bytes, size, record_size(instance), guid, instance->face->state_magic);
    if (problem != NULL) {
        fmi_log_error(instance,
                      "%s: the %zu bytes are refused: %s (an FMU state of this FMU, GUID %s, has %zu bytes)",
                      function, size, problem, guid, record_size(instance));
        return FMI_ERROR;
    }
    if (!valid_record(instance, function, bytes)) return FMI_ERROR;
    void* record = malloc(size);
    if (record == NULL || !fmu_states_add(&instance->states, record)) {
        free(record);
        fmi_log_error(instance, "%s: out of memory", function);
        return FMI_ERROR;
    }
    memcpy(record, bytes, size);
    *state = record;
    return FMI_OK;
}
