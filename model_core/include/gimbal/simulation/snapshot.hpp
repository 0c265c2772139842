// An instance's FMU state (snapshot) as one table of fields (simulation/snapshot.cpp): every field's
// name, type, count, place in the serialized bytes and the check it must pass. Saving, checking and
// restoring all walk that table; adding a field is one row there (and where its value comes from and
// goes to: GimbalInstance::save_run / rebuild_run, instance_snapshot.cpp), with a new format number.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

// What a snapshot holds, typed. Plain integers and doubles only, flags as bytes: any byte pattern
// decodes without undefined behaviour, and check_snapshot_content() decides whether it is a state
// this model can be in. Its own layout in memory does not matter: the bytes are laid out by the table.
struct SnapshotContent {
    double reals[kRealVariableCount];
    std::int32_t integers[kIntegerVariableCount];
    std::uint8_t booleans[kBooleanVariableCount];
    std::uint8_t initialized;
    std::uint8_t integrator_running;
    std::uint8_t at_rest;
    std::uint8_t rtol_set;
    std::uint8_t master_tolerance_defined;
    double master_tolerance;
    double time;
    double clock;  // model time: the instance's own sum of steps since the start
    double state[kMaxStateSize];
    Modes modes;
    EventCounters counters;
    IntegratorStatistics statistics;
    double voltage[2];
    double commanded_voltage[2];
    double voltage_rate[2];
    double pending_voltage_rate[2];
    double base[15];        // attitude, rate, accel, v_a, a_a at the arc start
    double arc_start_time;  // model time
    double epoch;
    IntegratorMemory integrator_memory;
    // The continuous-time interface's event memory.
    std::uint8_t continuous_time;
    std::uint8_t decided_here;
    std::int8_t decided_side[GimbalHybridSystem::kIndicatorCount];
    double reference_guards[GimbalHybridSystem::kIndicatorCount];
    double last_event_time;
    double dwell_until;
    std::int32_t rapid_events;
    std::int64_t zeno_holds;
    // Format 11: current drive's running current commands (the amplifiers' modes are in `modes`).
    double current_command[2];
    double commanded_current[2];
};

// Serialized: a 4-byte magic ("G2AX"), the 4-byte format number, then the fields in table order, each
// at its natural alignment (a row may ask for more), the whole padded to 8 bytes; gaps are zero.
constexpr std::uint32_t kSnapshotMagic = 0x47324158;
// Format 8: format 7's fields with the longer variable tables of the disturbance elements (cables,
// cogging): the variable arrays grew, so a format-7 state is refused by its number, not misread.
// Format 9: format 8's fields with the Integer table grown by gear1.start and gear2.start.
// Format 10: format 9's fields with the elevation end stop: its variables (4 Real, 1 Integer, 1 Boolean)
// and its 2 event indicators lengthen the tables, and its mode sits in Modes' former tail padding.
// Format 11: format 10's fields with current drive: its variables (14 Real, 4 Integer, 2 Boolean), its 4
// event indicators and 2 more state slots lengthen the tables; the amplifiers' modes and the running
// current commands are rows at the end. (A format-10 state comes from an FMU with another GUID, which the
// FMU-state record's header refuses first.)
constexpr std::uint32_t kSnapshotFormat = 11;

std::size_t snapshot_bytes();
// The bytes of a content (every gap zero).
void encode_snapshot(const SnapshotContent& content, void* buffer);
// Any bytes decode; whether they are a possible state is check_snapshot_content's to say.
// Returns whether the magic and format number are this build's.
bool decode_snapshot(const void* buffer, SnapshotContent& content);

// The first reason a decoded snapshot is not a state this model can be in (empty: none). `format_ok`
// is decode_snapshot's answer; `continuous_time` is the interface of the instance it is meant for.
std::string check_snapshot_content(const SnapshotContent& content, bool format_ok, bool continuous_time);

// The model a snapshot's values define, validated as at initialization.
bool snapshot_parameters(const SnapshotContent& content, ModelParameters& params, std::string& error);

// One row of the table, for the layout test (tests/model_core/simulation/test_snapshot_layout.cpp): its member path and
// where it lies in the bytes.
struct SnapshotFieldPlace {
    const char* key;
    std::size_t offset;
    std::size_t bytes;
};
std::size_t snapshot_field_count();
SnapshotFieldPlace snapshot_field_place(std::size_t row);

}  // namespace gimbal
