#include "fmu_state.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(sizeof(StateHeader) == 128, "the state header has no padding");

static uint64_t mix(uint64_t h) {
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

uint64_t fmu_state_checksum(const unsigned char* record, size_t size) {
    const size_t first = offsetof(StateHeader, checksum) + sizeof(uint64_t);
    uint64_t h = mix((uint64_t)size);
    size_t i = first;
    for (; i + 8 <= size; i += 8) {
        uint64_t word;
        memcpy(&word, record + i, 8);
        h = mix(h ^ word);
    }
    if (i < size) {
        uint64_t word = 0;
        memcpy(&word, record + i, size - i);
        h = mix(h ^ word);
    }
    return h;
}

void fmu_state_header_init(StateHeader* header, uint32_t magic, size_t record_size, const char* guid) {
    memset(header, 0, sizeof *header);
    header->magic = magic;
    header->format_version = STATE_FORMAT_VERSION;
    header->size = record_size;
    strncpy(header->guid, guid, sizeof header->guid - 1);
}

void fmu_state_serialize(const unsigned char* record, size_t record_size, unsigned char* bytes) {
    memcpy(bytes, record, record_size);
    const uint64_t checksum = fmu_state_checksum(bytes, record_size);
    memcpy(bytes + offsetof(StateHeader, checksum), &checksum, sizeof checksum);
}

const char* fmu_state_integrity_problem(const unsigned char* bytes, size_t size, size_t expected_size,
                                        const char* guid, uint32_t magic) {
    if (size != expected_size) return "its size is not that of this FMU's states";
    StateHeader header;
    memcpy(&header, bytes, sizeof header);
    if (header.magic == (magic == STATE_MAGIC ? STATE_MAGIC_FMI3 : STATE_MAGIC))
        return "it is a state of this FMU's other FMI version";
    if (header.magic != magic) return "it does not start like an FMU state of this FMU";
    if (header.format_version != STATE_FORMAT_VERSION) return "it was saved by another version of this FMU";
    if (header.size != expected_size) return "its recorded size does not match";
    if (memchr(header.guid, '\0', sizeof header.guid) == NULL || strcmp(header.guid, guid) != 0)
        return "it was saved by an FMU with another GUID";
    if (header.checksum != fmu_state_checksum(bytes, size)) return "its checksum does not match: the bytes were altered";
    return NULL;
}

/* The instance state a record was saved in: one state, and one an FMU state can be taken in. */
static const char* instance_state_problem(int32_t state, const FmuStateRules* rules) {
    if ((state & rules->saveable_states) == 0 || (state & (state - 1)) != 0)
        return "its instance state is not one an FMU state can be taken in";
    return NULL;
}

/* ... and one an instance of this interface can be in. */
static const char* interface_problem(int32_t state, const FmuStateRules* rules, int model_exchange) {
    if ((state & rules->model_exchange_states) && !model_exchange) return "it was saved by a Model Exchange instance";
    if ((state & rules->cosimulation_states) && model_exchange) return "it was saved by a Co-Simulation instance";
    return NULL;
}

/* The flag, the step status and the times. */
static const char* recorded_values_problem(const StateHeader* header, const FmuStateRules* rules) {
    const int recorded = rules->last_status_max >= 0;
    if (header->stop_time_defined != 0 && header->stop_time_defined != 1) return "its stop-time flag is not a boolean";
    if (recorded && (header->last_step_status < 0 || header->last_step_status > rules->last_status_max))
        return "its last step status is not an fmi2Status";
    if (!isfinite(header->time) || !isfinite(header->stop_time) || (recorded && !isfinite(header->last_successful_time)))
        return "its times are not finite";
    if (rules->stop_time_bounds_time && header->stop_time_defined && header->time > header->stop_time)
        return "its time lies beyond its stop time";
    return NULL;
}

const char* fmu_state_header_problem(const StateHeader* header, const FmuStateRules* rules, int model_exchange) {
    const char* problem = instance_state_problem(header->state, rules);
    if (problem == NULL) problem = recorded_values_problem(header, rules);
    if (problem == NULL) problem = interface_problem(header->state, rules, model_exchange);
    return problem;
}

const char* fmu_state_model_problem(const StateHeader* header, const FmuStateRules* rules, int initialized,
                                    char* text, size_t text_size) {
    const int running = (header->state & rules->initialized_states) != 0;
    if (running == (initialized != 0)) return NULL;
    snprintf(text, text_size, "its instance state '%s' contradicts its %s model", rules->state_name(header->state),
             initialized ? "initialized" : "uninitialized");
    return text;
}

long fmu_states_find(const FmuStateRegistry* registry, const void* record) {
    if (record == NULL) return -1;
    for (size_t k = 0; k < registry->count; ++k)
        if (registry->records[k] == record) return (long)k;
    return -1;
}

int fmu_states_add(FmuStateRegistry* registry, void* record) {
    if (registry->count == registry->capacity) {
        const size_t capacity = registry->capacity == 0 ? 8 : 2 * registry->capacity;
        void** grown = (void**)realloc(registry->records, capacity * sizeof *grown);
        if (grown == NULL) return 0;
        registry->records = grown;
        registry->capacity = capacity;
    }
    registry->records[registry->count++] = record;
    return 1;
}

void fmu_states_release(FmuStateRegistry* registry, long index) {
    free(registry->records[index]);
    registry->records[index] = registry->records[--registry->count];
}

void fmu_states_release_all(FmuStateRegistry* registry) {
    for (size_t k = 0; k < registry->count; ++k) free(registry->records[k]);
    free(registry->records);
    registry->records = NULL;
    registry->count = registry->capacity = 0;
}
