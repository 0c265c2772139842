/* FMU states of one instance: the record a state is kept in, its integrity check, and the registry
 * of the records this instance handed out. Host pointers are looked up here, never dereferenced:
 * an importer that passes garbage (an uninitialised fmi2FMUstate, a state where its address is
 * expected) gets a refusal instead of a crash. */
#ifndef GIMBAL_FMU_STATE_H
#define GIMBAL_FMU_STATE_H

#include <stddef.h>
#include <stdint.h>

/* The wrapper's own fields, followed by the core's snapshot bytes; serialized as is. Fixed-width
 * fields only, without padding, so that any byte pattern can be read and checked. */
typedef struct {
    uint32_t magic;
    uint32_t format_version;
    uint64_t size;     /* of the whole record */
    uint64_t checksum; /* of every byte after this field; filled in by serialization */
    char guid[64];
    int32_t state;
    int32_t stop_time_defined;
    int32_t last_step_status;
    int32_t reserved;
    double time;
    double stop_time;
    double last_successful_time;
} StateHeader;

#define STATE_MAGIC 0x46535441u      /* "FSTA": a state of the FMI 2.0 binary */
#define STATE_MAGIC_FMI3 0x33535441u /* "ATS3": a state of the FMI 3.0 binary */
#define STATE_FORMAT_VERSION 2u

/* Checksum of a serialized record: every 8-byte word goes through a bijective mix (MurmurHash3's
 * finalizer), so any change confined to one word - every single-bit flip - changes the result. */
uint64_t fmu_state_checksum(const unsigned char* record, size_t size);

/* A header with the record's identity (magic, format, size, GUID) and every other field zero. */
void fmu_state_header_init(StateHeader* header, uint32_t magic, size_t record_size, const char* guid);

/* A record's serialized bytes: a copy with its checksum filled in. */
void fmu_state_serialize(const unsigned char* record, size_t record_size, unsigned char* bytes);

/* NULL when the bytes are a record of this FMU (size, magic, format, GUID and checksum), otherwise
 * what is wrong with them. */
const char* fmu_state_integrity_problem(const unsigned char* bytes, size_t size, size_t expected_size,
                                        const char* guid, uint32_t magic);

/* What a record's wrapper fields may hold, by FMI version: the two wrappers check their records with
 * the same code (fmu_state_header_problem, fmu_state_model_problem) and differ only in these rules. */
typedef struct {
    int32_t saveable_states;     /* instance states an FMU state can be taken in, one bit each */
    int32_t initialized_states;  /* those in which the model is initialized */
    int32_t last_status_max;     /* last_step_status lies in [0, last_status_max], last_successful_time is
                                    finite; < 0: neither is recorded */
    int stop_time_bounds_time;   /* with a stop time defined, time <= stop time */
    int32_t model_exchange_states;  /* states only a Model Exchange instance takes (0: not told apart here) */
    int32_t cosimulation_states;    /* states only a Co-Simulation instance takes */
    const char* (*state_name)(int32_t state);
} FmuStateRules;

/* NULL when the wrapper's fields of a record are possible for an instance of the given interface;
 * otherwise what is wrong with them. */
const char* fmu_state_header_problem(const StateHeader* header, const FmuStateRules* rules, int model_exchange);

/* NULL when the record's instance state agrees with the core's snapshot being initialized (or not);
 * otherwise the contradiction, written to `text`. */
const char* fmu_state_model_problem(const StateHeader* header, const FmuStateRules* rules, int initialized,
                                    char* text, size_t text_size);

typedef struct {
    void** records;
    size_t count;
    size_t capacity;
} FmuStateRegistry;

/* Index of a record this instance handed out, or -1. */
long fmu_states_find(const FmuStateRegistry* registry, const void* record);
/* 0 when out of memory (the record is then not registered). */
int fmu_states_add(FmuStateRegistry* registry, void* record);
/* Frees the record and forgets it. */
void fmu_states_release(FmuStateRegistry* registry, long index);
void fmu_states_release_all(FmuStateRegistry* registry);

#endif
