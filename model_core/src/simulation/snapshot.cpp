// The FMU state (snapshot) as one table of fields: encode, decode and check all walk kFields.
//
// A row names a member of SnapshotContent (a path of member pointers: its type and count follow from
// it), the words a refusal uses for it, when it is checked (always, or only in an initialized
// instance) and the check its values must pass. Its place in the bytes is computed from the rows
// before it: natural alignment, or more where a row asks (format 7 kept the tail padding of a nested
// struct). The rules that tie fields together or to the model (the interface the state was saved by,
// time against epoch, modes against the fidelity) follow the table, in check_snapshot_content().
//
// Format 7's byte layout is asserted field by field in tests/model_core/simulation/test_snapshot_layout.cpp.
#include "gimbal/simulation/snapshot.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "gimbal/simulation/parameter_building.hpp"
#include "gimbal/model/variable_groups.hpp"
#include "gimbal/switching_elements/element_registry.hpp"

namespace gimbal {
namespace {

static_assert(sizeof(int) == sizeof(std::int32_t), "Integer variables are stored as int");

// ---- Row types -------------------------------------------------------------------------------

enum class Wire : std::uint8_t { u8, i8, i32, i64, f64 };

template <typename>
constexpr bool kUnsupported = false;

template <typename E>
constexpr Wire wire_of() {
    if constexpr (std::is_enum_v<E>) return wire_of<std::underlying_type_t<E>>();
    else if constexpr (std::is_same_v<E, double>) return Wire::f64;
    else if constexpr (std::is_same_v<E, std::int64_t>) return Wire::i64;
    else if constexpr (std::is_same_v<E, std::int32_t>) return Wire::i32;
    else if constexpr (std::is_same_v<E, std::uint8_t>) return Wire::u8;
    else if constexpr (std::is_same_v<E, std::int8_t>) return Wire::i8;
    else static_assert(kUnsupported<E>, "a snapshot field is a fixed-width integer, an enum over one, or a double");
}

// Which rows a check walks: an uninitialized instance has no modes, counters, inputs or integrator.
enum class When : std::uint8_t { always, initialized };

enum class Rule : std::uint8_t {
    none,
    finite,  // doubles: finite, then optionally at least (or above) `bound`
    flag,    // 0 or 1
    count,   // 0 .. 2^53
    range,   // low .. high
};

// A rule of one element of a row (the Integer variables differ by variable), with its name.
struct ElementRule {
    const char* name;
    Rule rule;
    std::int64_t low, high;
};

struct Check {
    Rule rule = Rule::none;
    std::int64_t low = 0, high = 0;   // range
    double bound = 0.0;               // finite: values must be >= bound (> bound if strict) ...
    bool bounded = false, strict = false;
    const char* message = nullptr;    // ... or this is the reason; range: replaces "lies outside [low, high]"
    int index_base = 0;               // finite: the first element's number in "name[k] is not finite"
    const char* (*element_name)(std::size_t k) = nullptr;  // names each element in messages
    ElementRule (*element_rule)(std::size_t k) = nullptr;  // replaces rule, low, high and name per element
};

constexpr Check finite(int index_base = 0) {
    Check c;
    c.rule = Rule::finite;
    c.index_base = index_base;
    return c;
}
constexpr Check finite_at_least(int index_base, double bound, const char* message, bool strict = false) {
    Check c = finite(index_base);
    c.bounded = true;
    c.bound = bound;
    c.strict = strict;
    c.message = message;
    return c;
}
constexpr Check flag(const char* (*element_name)(std::size_t) = nullptr) {
    Check c;
    c.rule = Rule::flag;
    c.element_name = element_name;
    return c;
}
constexpr Check count() {
    Check c;
    c.rule = Rule::count;
    return c;
}
constexpr Check range(std::int64_t low, std::int64_t high, const char* message = nullptr) {
    Check c;
    c.rule = Rule::range;
    c.low = low;
    c.high = high;
    c.message = message;
    return c;
}
constexpr Check per_element(ElementRule (*rule)(std::size_t)) {
    Check c;
    c.element_rule = rule;
    return c;
}

struct Field {
    const char* key;   // the member path (tests, documentation)
    const char* name;  // in refusals
    Wire wire;
    std::size_t element_bytes;
    std::size_t count;
    std::size_t align;  // at least the natural alignment
    const void* (*locate)(const SnapshotContent&);
    When when;
    Check check;
};

// The address of a member reached through a path of member pointers.
template <typename T>
const void* address_of(const T& object) {
    return &object;
}
template <typename T, typename M, typename... Rest>
const void* address_of(const T& object, M T::*member, Rest... rest) {
    return address_of(object.*member, rest...);
}

template <typename T, typename... Path>
struct LeafOf {
    using type = T;
};
template <typename T, typename M, typename... Rest>
struct LeafOf<T, M T::*, Rest...> {
    using type = typename LeafOf<M, Rest...>::type;
};

template <auto... Path>
const void* locate(const SnapshotContent& content) {
    return address_of(content, Path...);
}

// A row for the member at Path: its type and count from the member's declaration.
template <auto... Path>
constexpr Field field(const char* key, const char* name, When when, Check check, std::size_t align = 1) {
    using Leaf = typename LeafOf<SnapshotContent, decltype(Path)...>::type;
    using Element = std::remove_all_extents_t<Leaf>;
    return Field{key,           name, wire_of<Element>(), sizeof(Element), sizeof(Leaf) / sizeof(Element),
                 align < sizeof(Element) ? sizeof(Element) : align, &locate<Path...>, when, check};
}

// ---- Per-element names and rules ---------------------------------------------------------------

const char* boolean_name(std::size_t k) { return kBooleanVariables[k].name; }

template <std::size_t N>
bool listed(const IntegerVariable (&list)[N], std::size_t k) {
    for (IntegerVariable vi : list)
        if (static_cast<std::size_t>(vi) == k) return true;
    return false;
}

// The Integer outputs a run can produce: the elements' mode outputs in their declared ranges
// (gimbal/switching_elements.def), counters. Parameters are validated with the model (snapshot_parameters).
ElementRule integer_variable_rule(std::size_t k) {
    struct ModeOutputRange {
        IntegerVariable output;
        std::int64_t lowest, highest;
    };
    static constexpr ModeOutputRange kModeOutputs[] = {
#define ELEMENT(identifier, instances, guards, element_switch, element_class)
#define MODE_OUTPUT(element, output, lowest, highest) {vi_##output, lowest, highest},
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
    };
    static constexpr IntegerVariable kSolverOutputs[] = {vi_solver_states, vi_solver_steps, vi_solver_rhs_evaluations,
                                                         vi_solver_jacobian_evaluations, vi_solver_method_switches};
    const char* name = kIntegerVariables[k].name;
    for (const ModeOutputRange& mode : kModeOutputs)
        if (static_cast<std::size_t>(mode.output) == k) return {name, Rule::range, mode.lowest, mode.highest};
    if (listed(kEventCounters, k) || listed(kSolverOutputs, k)) return {name, Rule::count, 0, 0};
    return {name, Rule::none, 0, 0};
}

// ---- The table ---------------------------------------------------------------------------------

using C = SnapshotContent;
using M = IntegratorMemory;
constexpr When kAlways = When::always;
constexpr When kInit = When::initialized;
constexpr const char* kSwitchRuleStep = "a saved step of the switch rule is negative";
constexpr const char* kInputJump = "the saved input jump is invalid";

constexpr Field kFields[] = {
    field<&C::reals>("reals", "Real variable", kAlways, finite()),
    field<&C::integers>("integers", "Integer variable", kAlways, per_element(integer_variable_rule)),
    field<&C::booleans>("booleans", "Boolean variable", kAlways, flag(boolean_name)),
    field<&C::initialized>("initialized", "initialized", kAlways, flag()),
    field<&C::integrator_running>("integrator_running", "integrator_running", kAlways, flag()),
    field<&C::at_rest>("at_rest", "at_rest", kAlways, flag()),
    field<&C::rtol_set>("rtol_set", "rtol_set", kAlways, flag()),
    field<&C::master_tolerance_defined>("master_tolerance_defined", "master_tolerance_defined", kAlways, flag()),
    field<&C::master_tolerance>("master_tolerance", "master tolerance", kAlways, finite()),
    field<&C::time>("time", "time", kAlways, finite()),
    field<&C::clock>("clock", "clock", kAlways, finite()),
    field<&C::state>("state", "state", kAlways, finite()),
    field<&C::modes, &Modes::gear_contact>("modes.gear_contact", "gear contact mode", kInit, range(-1, 1)),
    field<&C::modes, &Modes::motor_limited>("modes.motor_limited", "current limiter mode", kInit, range(-1, 1)),
    field<&C::modes, &Modes::voltage_clamped>("modes.voltage_clamped", "voltage clamp mode", kInit, range(-1, 1)),
    field<&C::modes, &Modes::friction>("modes.friction", "friction mode", kInit,
                                       range(static_cast<long>(FrictionMode::none),
                                             static_cast<long>(FrictionMode::at_max_negative))),
    // In what was the tail padding of Modes in format 9: no later field moves. One int per axis stop.
    field<&C::modes, &Modes::axis_stop>("modes.axis_stop", "axis stop mode", kInit, range(-1, 1)),
    field<&C::counters, &EventCounters::total>("counters.total", "event counter", kInit, count()),
    field<&C::counters, &EventCounters::backlash>("counters.backlash", "event counter", kInit, count()),
    field<&C::counters, &EventCounters::current_limit>("counters.current_limit", "event counter", kInit, count()),
    field<&C::counters, &EventCounters::stick_slip>("counters.stick_slip", "event counter", kInit, count()),
    field<&C::counters, &EventCounters::last_event_time>("counters.last_event_time", "last event time", kInit,
                                                         finite()),
    field<&C::statistics, &IntegratorStatistics::steps>("statistics.steps", "integrator statistic", kInit, count()),
    field<&C::statistics, &IntegratorStatistics::rhs_evaluations>("statistics.rhs_evaluations",
                                                                  "integrator statistic", kInit, count()),
    field<&C::statistics, &IntegratorStatistics::jacobian_evaluations>("statistics.jacobian_evaluations",
                                                                       "integrator statistic", kInit, count()),
    field<&C::statistics, &IntegratorStatistics::events>("statistics.events", "integrator statistic", kInit, count()),
    field<&C::statistics, &IntegratorStatistics::zeno_holds>("statistics.zeno_holds", "integrator statistic", kInit,
                                                             count()),
    field<&C::statistics, &IntegratorStatistics::method_switches>("statistics.method_switches",
                                                                  "integrator statistic", kInit, count()),
    field<&C::statistics, &IntegratorStatistics::rejected_steps>("statistics.rejected_steps", "integrator statistic",
                                                                 kInit, count()),
    field<&C::voltage>("voltage", "voltage", kInit, finite()),
    field<&C::commanded_voltage>("commanded_voltage", "commanded voltage", kInit, finite()),
    field<&C::voltage_rate>("voltage_rate", "voltage rate", kInit, finite()),
    field<&C::pending_voltage_rate>("pending_voltage_rate", "pending voltage rate", kAlways, finite()),
    field<&C::base>("base", "base motion", kInit, finite()),
    field<&C::arc_start_time>("arc_start_time", "arc start time", kInit, finite()),
    field<&C::epoch>("epoch", "epoch", kAlways, finite()),
    // The one-step integrators' memory (IntegratorMemory): its doubles are numbered as format 7 did.
    field<&C::integrator_memory, &M::step_size>("integrator_memory.step_size", "integrator memory", kInit,
                                                finite_at_least(0, 0.0, "the saved step size is negative")),
    field<&C::integrator_memory, &M::previous_error>(
        "integrator_memory.previous_error", "integrator memory", kInit,
        finite_at_least(1, 0.0, "the saved error estimate is not positive", true)),
    field<&C::integrator_memory, &M::stiff>("integrator_memory.stiff", "stiff", kInit, flag()),
    field<&C::integrator_memory, &M::stiff_votes>("integrator_memory.stiff_votes", "stiff votes", kInit, count()),
    field<&C::integrator_memory, &M::nonstiff_votes>("integrator_memory.nonstiff_votes", "non-stiff votes", kInit,
                                                     count()),
    field<&C::integrator_memory, &M::last_step_rejected>("integrator_memory.last_step_rejected", "last_step_rejected",
                                                         kInit, flag()),
    field<&C::integrator_memory, &M::chattering, &ChatteringMemory::last_event_time>(
        "integrator_memory.chattering.last_event_time", "integrator memory", kInit, finite(2)),
    field<&C::integrator_memory, &M::chattering, &ChatteringMemory::rapid_events>(
        "integrator_memory.chattering.rapid_events", "rapid events", kInit, count()),
    field<&C::integrator_memory, &M::chattering, &ChatteringMemory::dwell_until>(
        "integrator_memory.chattering.dwell_until", "integrator memory", kInit, finite(3)),
    field<&C::integrator_memory, &M::accuracy_step>("integrator_memory.accuracy_step", "integrator memory", kInit,
                                                    finite_at_least(4, 0.0, kSwitchRuleStep)),
    field<&C::integrator_memory, &M::accuracy_time>("integrator_memory.accuracy_time", "integrator memory", kInit,
                                                    finite(5)),
    field<&C::integrator_memory, &M::explicit_step>("integrator_memory.explicit_step", "integrator memory", kInit,
                                                    finite_at_least(6, 0.0, kSwitchRuleStep)),
    field<&C::integrator_memory, &M::stable_product>("integrator_memory.stable_product", "integrator memory", kInit,
                                                     finite_at_least(7, 0.0, kSwitchRuleStep)),
    field<&C::integrator_memory, &M::jump_time>("integrator_memory.jump_time", "integrator memory", kInit, finite(8)),
    field<&C::integrator_memory, &M::jump_step>("integrator_memory.jump_step", "integrator memory", kInit,
                                                finite_at_least(9, 0.0, kInputJump)),
    field<&C::integrator_memory, &M::steps_since_jump>("integrator_memory.steps_since_jump", "steps since the jump",
                                                       kInit,
                                                       range(-1, std::numeric_limits<std::int32_t>::max(), kInputJump)),
    // Format 7 ended the integrator memory on an 8-byte boundary (the struct's tail padding).
    field<&C::continuous_time>("continuous_time", "continuous_time", kAlways, flag(), 8),
    field<&C::decided_here>("decided_here", "decided_here", kAlways, flag()),
    field<&C::decided_side>("decided_side", "decided side", kAlways, range(-1, 1)),
    field<&C::reference_guards>("reference_guards", "reference guards", kAlways, finite()),
    field<&C::last_event_time>("last_event_time", "last event time", kAlways, finite()),
    field<&C::dwell_until>("dwell_until", "end of the chattering hold", kAlways, finite()),
    field<&C::rapid_events>("rapid_events", "rapid events", kAlways, count()),
    field<&C::zeno_holds>("zeno_holds", "chattering holds", kAlways, count()),
    // Format 11: current drive.
    field<&C::modes, &Modes::amplifier_saturated>("modes.amplifier_saturated", "amplifier saturation mode", kInit,
                                                  range(-1, 1)),
    field<&C::current_command>("current_command", "current command", kInit, finite()),
    field<&C::commanded_current>("commanded_current", "commanded current", kInit, finite()),
};
constexpr std::size_t kFieldCount = sizeof kFields / sizeof kFields[0];

// ---- The byte layout, from the table -----------------------------------------------------------

constexpr std::size_t kHeaderBytes = 8;  // magic, format

constexpr std::size_t align_up(std::size_t n, std::size_t alignment) {
    return (n + alignment - 1) / alignment * alignment;
}

struct Layout {
    std::size_t offset[kFieldCount] = {};
    std::size_t size = 0;
};

constexpr Layout compute_layout() {
    Layout layout;
    std::size_t at = kHeaderBytes;
    for (std::size_t row = 0; row < kFieldCount; ++row) {
        at = align_up(at, kFields[row].align);
        layout.offset[row] = at;
        at += kFields[row].element_bytes * kFields[row].count;
    }
    layout.size = align_up(at, 8);
    return layout;
}
constexpr Layout kLayout = compute_layout();

// ---- Checking ----------------------------------------------------------------------------------

// Counters beyond this are not the product of any run (2^53 steps would take centuries).
constexpr double kMaxCount = 9007199254740992.0;

// Collects the first reason a snapshot is refused.
struct SnapshotCheck {
    std::string reason;
    bool ok() const { return reason.empty(); }
    void fail(const std::string& why) {
        if (reason.empty()) reason = why;
    }
};

std::int64_t read_integer(Wire wire, const unsigned char* at) {
    switch (wire) {
        case Wire::u8: return *at;
        case Wire::i8: return static_cast<std::int8_t>(*at);
        case Wire::i32: {
            std::int32_t value;
            std::memcpy(&value, at, sizeof value);
            return value;
        }
        case Wire::i64:
        case Wire::f64: break;
    }
    std::int64_t value;
    std::memcpy(&value, at, sizeof value);
    return value;
}

void check_real(const Field& f, std::size_t k, double value, SnapshotCheck& check) {
    const Check& c = f.check;
    if (c.rule != Rule::finite) return;
    if (!std::isfinite(value)) {
        check.fail(std::string(f.name) + "[" + std::to_string(k + c.index_base) + "] is not finite");
    } else if (c.bounded && (c.strict ? !(value > c.bound) : !(value >= c.bound))) {
        check.fail(c.message);
    }
}

void check_integer(const Field& f, std::size_t k, std::int64_t value, SnapshotCheck& check) {
    const Check& c = f.check;
    ElementRule rule{f.name, c.rule, c.low, c.high};
    if (c.element_rule != nullptr) rule = c.element_rule(k);
    if (c.element_name != nullptr) rule.name = c.element_name(k);
    const std::string is = std::string(rule.name) + " = " + std::to_string(value);
    switch (rule.rule) {
        case Rule::flag:
            if (value != 0 && value != 1) check.fail(is + " is not a boolean");
            break;
        case Rule::count:
            if (value < 0 || static_cast<double>(value) > kMaxCount) check.fail(is + " is not a count");
            break;
        case Rule::range:
            if (value < rule.low || value > rule.high) {
                check.fail(c.message != nullptr ? std::string(c.message)
                                                : is + " lies outside [" + std::to_string(rule.low) + ", " +
                                                      std::to_string(rule.high) + "]");
            }
            break;
        case Rule::none:
        case Rule::finite: break;
    }
}

void check_field(const Field& f, const SnapshotContent& content, SnapshotCheck& check) {
    if (f.check.rule == Rule::none && f.check.element_rule == nullptr) return;
    const auto* at = static_cast<const unsigned char*>(f.locate(content));
    for (std::size_t k = 0; k < f.count && check.ok(); ++k, at += f.element_bytes) {
        if (f.wire == Wire::f64) {
            double value;
            std::memcpy(&value, at, sizeof value);
            check_real(f, k, value, check);
        } else {
            check_integer(f, k, read_integer(f.wire, at), check);
        }
    }
}

void check_fields(When when, const SnapshotContent& content, SnapshotCheck& check) {
    for (const Field& f : kFields)
        if (f.when == when && check.ok()) check_field(f, content, check);
}

// The parameters must be valid, and the modes and the state possible for the elements they define.
void check_against_model(const SnapshotContent& content, SnapshotCheck& check) {
    ModelParameters params;
    std::string error;
    if (!snapshot_parameters(content, params, error)) check.fail(error);
    if (check.ok()) {
        const std::string impossible = impossible_mode(params, content.modes);
        if (!impossible.empty()) check.fail(impossible);
    }
    for (int k = params.layout.size; k < kMaxStateSize && check.ok(); ++k)
        if (content.state[k] != 0.0)
            check.fail("the state has values beyond the model's " + std::to_string(params.layout.size) + " states");
}

}  // namespace

std::size_t snapshot_bytes() { return kLayout.size; }

void encode_snapshot(const SnapshotContent& content, void* buffer) {
    auto* bytes = static_cast<unsigned char*>(buffer);
    std::memset(bytes, 0, kLayout.size);  // no stray bytes in the gaps of a serialized state
    std::memcpy(bytes, &kSnapshotMagic, 4);
    std::memcpy(bytes + 4, &kSnapshotFormat, 4);
    for (std::size_t row = 0; row < kFieldCount; ++row)
        std::memcpy(bytes + kLayout.offset[row], kFields[row].locate(content), kFields[row].element_bytes * kFields[row].count);
}

bool decode_snapshot(const void* buffer, SnapshotContent& content) {
    const auto* bytes = static_cast<const unsigned char*>(buffer);
    std::memset(static_cast<void*>(&content), 0, sizeof content);
    for (std::size_t row = 0; row < kFieldCount; ++row) {
        // The content is not const: the row's address may be written.
        void* target = const_cast<void*>(kFields[row].locate(content));
        std::memcpy(target, bytes + kLayout.offset[row], kFields[row].element_bytes * kFields[row].count);
    }
    std::uint32_t magic, format;
    std::memcpy(&magic, bytes, 4);
    std::memcpy(&format, bytes + 4, 4);
    return magic == kSnapshotMagic && format == kSnapshotFormat;
}

std::string check_snapshot_content(const SnapshotContent& content, bool format_ok, bool continuous_time) {
    SnapshotCheck check;
    if (!format_ok)
        check.fail("it was not saved by this version of Gimbal2Axis (snapshot format " +
                   std::to_string(kSnapshotFormat) + ")");
    check_fields(When::always, content, check);
    if (check.ok() && (content.continuous_time != 0) != continuous_time)
        check.fail(std::string("it was saved by an instance of the ") +
                   (content.continuous_time ? "continuous-time (Model Exchange)" : "Co-Simulation") + " interface");
    if (check.ok() && content.initialized) {
        check_fields(When::initialized, content, check);
        if (check.ok() && (!(content.time >= content.epoch) || !(content.clock >= 0.0)))
            check.fail("the time lies before the start of the run");
        if (check.ok()) check_against_model(content, check);
    }
    return check.reason;
}

bool snapshot_parameters(const SnapshotContent& content, ModelParameters& params, std::string& error) {
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    bool booleans[kBooleanVariableCount];
    std::memcpy(reals, content.reals, sizeof reals);
    std::memcpy(integers, content.integers, sizeof integers);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) booleans[vr] = content.booleans[vr] != 0;
    return build_model_parameters(reals, integers, booleans, params, error) &&
           validate_start_state(reals, params, error);
}

std::size_t snapshot_field_count() { return kFieldCount; }

SnapshotFieldPlace snapshot_field_place(std::size_t row) {
    return {kFields[row].key, kLayout.offset[row], kFields[row].element_bytes * kFields[row].count};
}

}  // namespace gimbal
