// The FMU state's bytes (snapshot format 11: format 7's layout over the present variable tables, with the
// elevation stop's mode in what was Modes' tail padding, and format 11's current-drive rows appended) field by
// field: the table of gimbal/simulation/snapshot.hpp must lay every field where format 7 put it. Format 7 was a C++ struct copied as bytes; that struct is kept
// here as the reference (Format7), and every row's offset and size is compared with its member's.
// Then: content survives encode/decode bit for bit, and single faults are refused naming the field.
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "check.hpp"
#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/simulation/snapshot.hpp"
#include "gimbal/model/variable_groups.hpp"

namespace {

using namespace gimbal;

// Modes as format 7-10 laid them out (the current amplifiers' modes, format 11, are a row at the end).
struct Modes10 {
    int gear_contact[2];
    int motor_limited[2];
    int voltage_clamped[2];
    FrictionMode friction[4];
    int axis_stop[kAxisStopCount];  // one per AXIS_STOP row, as the reals are one per Real variable
};

struct Format7 {
    std::uint32_t magic;
    std::uint32_t version;
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
    double clock;
    double state[kMaxStateSize];
    Modes10 modes;
    EventCounters counters;
    IntegratorStatistics statistics;
    double voltage[2];
    double commanded_voltage[2];
    double voltage_rate[2];
    double pending_voltage_rate[2];
    double base[15];
    double arc_start_time;
    double epoch;
    IntegratorMemory integrator_memory;
    std::uint8_t continuous_time;
    std::uint8_t decided_here;
    std::int8_t decided_side[GimbalHybridSystem::kIndicatorCount];
    double reference_guards[GimbalHybridSystem::kIndicatorCount];
    double last_event_time;
    double dwell_until;
    std::int32_t rapid_events;
    std::int64_t zeno_holds;
    // Format 11.
    std::int32_t amplifier_saturated[2];
    double current_command[2];
    double commanded_current[2];
};

struct Place {
    const char* key;
    std::size_t offset, bytes;
};
#define PLACE(member) Place{#member, offsetof(Format7, member), sizeof(Format7::member)}
#define PLACE_IN(member, sub) Place{#member "." #sub, offsetof(Format7, member) + offsetof(decltype(Format7::member), sub), \
                                    sizeof(decltype(Format7::member)::sub)}

const Place kFormat7[] = {
    PLACE(reals), PLACE(integers), PLACE(booleans), PLACE(initialized), PLACE(integrator_running), PLACE(at_rest),
    PLACE(rtol_set), PLACE(master_tolerance_defined), PLACE(master_tolerance), PLACE(time), PLACE(clock), PLACE(state),
    PLACE_IN(modes, gear_contact), PLACE_IN(modes, motor_limited), PLACE_IN(modes, voltage_clamped),
    PLACE_IN(modes, friction), PLACE_IN(modes, axis_stop), PLACE_IN(counters, total), PLACE_IN(counters, backlash),
    PLACE_IN(counters, current_limit), PLACE_IN(counters, stick_slip), PLACE_IN(counters, last_event_time),
    PLACE_IN(statistics, steps), PLACE_IN(statistics, rhs_evaluations), PLACE_IN(statistics, jacobian_evaluations),
    PLACE_IN(statistics, events), PLACE_IN(statistics, zeno_holds), PLACE_IN(statistics, method_switches),
    PLACE_IN(statistics, rejected_steps), PLACE(voltage), PLACE(commanded_voltage), PLACE(voltage_rate),
    PLACE(pending_voltage_rate), PLACE(base), PLACE(arc_start_time), PLACE(epoch),
    PLACE_IN(integrator_memory, step_size), PLACE_IN(integrator_memory, previous_error),
    PLACE_IN(integrator_memory, stiff), PLACE_IN(integrator_memory, stiff_votes),
    PLACE_IN(integrator_memory, nonstiff_votes), PLACE_IN(integrator_memory, last_step_rejected),
    Place{"integrator_memory.chattering.last_event_time",
          offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, chattering) +
              offsetof(ChatteringMemory, last_event_time),
          sizeof(double)},
    Place{"integrator_memory.chattering.rapid_events",
          offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, chattering) +
              offsetof(ChatteringMemory, rapid_events),
          sizeof(int)},
    Place{"integrator_memory.chattering.dwell_until",
          offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, chattering) +
              offsetof(ChatteringMemory, dwell_until),
          sizeof(double)},
    PLACE_IN(integrator_memory, accuracy_step), PLACE_IN(integrator_memory, accuracy_time),
    PLACE_IN(integrator_memory, explicit_step), PLACE_IN(integrator_memory, stable_product),
    PLACE_IN(integrator_memory, jump_time), PLACE_IN(integrator_memory, jump_step),
    PLACE_IN(integrator_memory, steps_since_jump), PLACE(continuous_time), PLACE(decided_here), PLACE(decided_side),
    PLACE(reference_guards), PLACE(last_event_time), PLACE(dwell_until), PLACE(rapid_events), PLACE(zeno_holds),
    Place{"modes.amplifier_saturated", offsetof(Format7, amplifier_saturated), sizeof(Format7::amplifier_saturated)},
    PLACE(current_command), PLACE(commanded_current),
};

void test_layout_is_format_7() {
    CHECK(kSnapshotFormat == 11);
    CHECK(snapshot_bytes() == sizeof(Format7));
    CHECK(GimbalInstance::snapshot_size() == sizeof(Format7));
    const std::size_t rows = sizeof kFormat7 / sizeof kFormat7[0];
    CHECK(snapshot_field_count() == rows);
    for (std::size_t row = 0; row < rows && row < snapshot_field_count(); ++row) {
        const SnapshotFieldPlace place = snapshot_field_place(row);
        const bool same = std::string(place.key) == kFormat7[row].key && place.offset == kFormat7[row].offset &&
                          place.bytes == kFormat7[row].bytes;
        if (!same)
            std::fprintf(stderr, "  row %zu: %s at %zu (%zu bytes), format 7: %s at %zu (%zu bytes)\n", row, place.key,
                         place.offset, place.bytes, kFormat7[row].key, kFormat7[row].offset, kFormat7[row].bytes);
        CHECK(same);
    }
}

// Every byte of every field set: encode, then read as format 7 did (the struct over the bytes).
void test_bytes_are_format_7() {
    SnapshotContent content;
    auto* raw = reinterpret_cast<unsigned char*>(&content);
    for (std::size_t k = 0; k < sizeof content; ++k) raw[k] = static_cast<unsigned char>(37 * k + 11);
    std::vector<unsigned char> bytes(snapshot_bytes());
    encode_snapshot(content, bytes.data());
    Format7 legacy;
    std::memcpy(&legacy, bytes.data(), sizeof legacy);
    CHECK(legacy.magic == kSnapshotMagic && legacy.version == kSnapshotFormat);
    CHECK(std::memcmp(legacy.reals, content.reals, sizeof legacy.reals) == 0);
    CHECK(std::memcmp(legacy.integers, content.integers, sizeof legacy.integers) == 0);
    CHECK(std::memcmp(legacy.decided_side, content.decided_side, sizeof legacy.decided_side) == 0);
    CHECK(std::memcmp(legacy.modes.friction, content.modes.friction, sizeof legacy.modes.friction) == 0);
    CHECK(legacy.integrator_memory.steps_since_jump == content.integrator_memory.steps_since_jump);
    CHECK(legacy.integrator_memory.chattering.rapid_events == content.integrator_memory.chattering.rapid_events);
    CHECK(legacy.counters.stick_slip == content.counters.stick_slip);
    CHECK(legacy.zeno_holds == content.zeno_holds && legacy.at_rest == content.at_rest);
    // Gaps are zero: the bytes of a state do not depend on what memory held before.
    const std::size_t gaps[][2] = {{offsetof(Format7, master_tolerance_defined) + 1, offsetof(Format7, master_tolerance)},
                                   {offsetof(Format7, modes) + sizeof(Modes10), offsetof(Format7, counters)},
                                   {offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, chattering) +
                                        offsetof(ChatteringMemory, rapid_events) + sizeof(int),
                                    offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, chattering) +
                                        offsetof(ChatteringMemory, dwell_until)},
                                   {offsetof(Format7, integrator_memory) + offsetof(IntegratorMemory, steps_since_jump) +
                                        sizeof(int),
                                    offsetof(Format7, continuous_time)},
                                   {offsetof(Format7, rapid_events) + sizeof(std::int32_t), offsetof(Format7, zeno_holds)}};
    for (const auto& gap : gaps)
        for (std::size_t k = gap[0]; k < gap[1]; ++k) CHECK(bytes[k] == 0);
    // And back, bit for bit.
    SnapshotContent decoded;
    CHECK(decode_snapshot(bytes.data(), decoded));
    std::vector<unsigned char> again(snapshot_bytes());
    encode_snapshot(decoded, again.data());
    CHECK(again == bytes);
}

std::string refusal(const SnapshotContent& content) { return check_snapshot_content(content, true, false); }

void test_single_faults_name_the_field() {
    GimbalInstance instance([](GimbalStatus, const char*, const std::string&) {}, [](const char*) { return false; });
    CHECK(instance.initialize(0.0) == GIMBAL_OK);
    std::vector<unsigned char> bytes(snapshot_bytes());
    instance.save(bytes.data());
    SnapshotContent good;
    CHECK(decode_snapshot(bytes.data(), good));
    CHECK(refusal(good).empty());
    struct Fault {
        void (*apply)(SnapshotContent&);
        std::string reason;
    };
    const Fault faults[] = {
        {[](SnapshotContent& c) { c.reals[3] = std::numeric_limits<double>::quiet_NaN(); }, "Real variable[3] is not finite"},
        {[](SnapshotContent& c) { c.booleans[0] = 3; }, std::string(kBooleanVariables[0].name) + " = 3 is not a boolean"},
        {[](SnapshotContent& c) { c.integers[vi_gear2_contact] = 4; }, "gear2.contact = 4 lies outside [-1, 1]"},
        {[](SnapshotContent& c) { c.integers[vi_events_total] = -1; }, "events.total = -1 is not a count"},
        {[](SnapshotContent& c) { c.at_rest = 2; }, "at_rest = 2 is not a boolean"},
        {[](SnapshotContent& c) { c.modes.friction[2] = static_cast<FrictionMode>(9); }, "friction mode = 9 lies outside [0, 5]"},
        {[](SnapshotContent& c) { c.statistics.events = -5; }, "integrator statistic = -5 is not a count"},
        {[](SnapshotContent& c) { c.integrator_memory.previous_error = 0.0; }, "the saved error estimate is not positive"},
        {[](SnapshotContent& c) { c.integrator_memory.chattering.dwell_until = INFINITY; }, "integrator memory[3] is not finite"},
        {[](SnapshotContent& c) { c.integrator_memory.steps_since_jump = -2; }, "the saved input jump is invalid"},
        {[](SnapshotContent& c) { c.integrator_memory.stable_product = -1.0; }, "a saved step of the switch rule is negative"},
        {[](SnapshotContent& c) { c.decided_side[5] = -3; }, "decided side = -3 lies outside [-1, 1]"},
        {[](SnapshotContent& c) { c.zeno_holds = -1; }, "chattering holds = -1 is not a count"},
        {[](SnapshotContent& c) { c.time = -1.0; }, "the time lies before the start of the run"},
        {[](SnapshotContent& c) { c.state[kMaxStateSize - 1] = 1.0; }, "the state has values beyond the model's"},
        {[](SnapshotContent& c) { c.continuous_time = 1; },
         "it was saved by an instance of the continuous-time (Model Exchange) interface"},
    };
    for (const Fault& fault : faults) {
        SnapshotContent bad = good;
        fault.apply(bad);
        const std::string reason = refusal(bad);
        if (reason.compare(0, fault.reason.size(), fault.reason) != 0)
            std::fprintf(stderr, "  refused with '%s', expected '%s'\n", reason.c_str(), fault.reason.c_str());
        CHECK(reason.compare(0, fault.reason.size(), fault.reason) == 0);
    }
    CHECK(check_snapshot_content(good, false, false) ==
          "it was not saved by this version of Gimbal2Axis (snapshot format 11)");
    // An uninitialized instance's snapshot has no run: its modes are not looked at.
    GimbalInstance fresh([](GimbalStatus, const char*, const std::string&) {}, [](const char*) { return false; });
    fresh.save(bytes.data());
    SnapshotContent idle;
    CHECK(decode_snapshot(bytes.data(), idle));
    idle.modes.gear_contact[0] = 7;
    CHECK(refusal(idle).empty());
}

}  // namespace

int main() {
    test_layout_is_format_7();
    test_bytes_are_format_7();
    test_single_faults_name_the_field();
    return check_report("snapshot_layout");
}
