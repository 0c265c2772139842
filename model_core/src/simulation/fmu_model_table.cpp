// The gimbal FMU's table for the FMI faces (fmu_src/fmi_layer/fmu_model.h), filled over the core itself
// (GimbalInstance), beside the core's C interface (c_api.cpp): a host's call goes through the face of
// its FMI version and the faces' shared part (fmu_model.c) to a function here, which calls the core;
// the status is one type all the way (gimbal/gimbal_status.h, the layer's FmiStatus). Compiled into the
// FMU's binaries only (fmu_src/CMakeLists.txt), not into gimbal_core: the one file of the core that
// knows the FMI layer. Every function here is called from C: each catches everything (guarded).
//
// The variables: a Real (FMI 3.0 Float64) the core's Real of the same value reference, all of a call at
// once (the core checks and sets a call's inputs together); an Integer (FMI 3.0 Int32, an Enumeration
// Int64) or Boolean one by one; FMI 3.0's `time` and scalar event indicators follow the Booleans
// (GIMBAL_FMI3_* of gimbal_c_api.h, which the model description generator numbers by too).
#include <cmath>
#include <string>

extern "C" {
#include "fmi_layer/fmu_model.h"
#include "gimbal_guid.h"
}
#include "gimbal/gimbal_c_api.h"
#include "gimbal/simulation/entry_guard.hpp"
#include "gimbal/simulation/gimbal_instance.hpp"

namespace {

static_assert(int{GIMBAL_INPUT} == int{FMI_INPUT} && int{GIMBAL_PARAMETER} == int{FMI_PARAMETER} &&
                  int{GIMBAL_TUNABLE} == int{FMI_TUNABLE} && int{GIMBAL_INITIAL_EXACT} == int{FMI_INITIAL_EXACT} &&
                  int{GIMBAL_INITIAL_APPROX} == int{FMI_INITIAL_APPROX},
              "the core's variable attributes are the layer's");

constexpr unsigned kIntegerBase = GIMBAL_FMI3_INTEGER_BASE;
constexpr unsigned kBooleanBase = GIMBAL_FMI3_BOOLEAN_BASE;
constexpr unsigned kTime = GIMBAL_FMI3_TIME;
constexpr unsigned kFirstEventIndicator = GIMBAL_FMI3_FIRST_EVENT_INDICATOR;

// The <LogCategories> of both model descriptions, in their order.
const char* const kLogCategories[] = {"logEvents", "logSolver", "logStatusWarning", "logStatusDiscard",
                                      "logStatusError", "logAll"};

// An instance's model: the core, whose messages go to the instance (prefixed with the function running).
struct Model {
    explicit Model(FmiInstance* instance)
        : host(instance),
          core([instance](GimbalStatus status, const char* category, const std::string& message) {
              fmi_log_from_model(instance, status, category, message.c_str());
          },
               [instance](const char* category) { return fmi_log_enabled(instance, category) != 0; }) {}
    FmiInstance* host;
    gimbal::GimbalInstance core;
};

gimbal::GimbalInstance& core_of(const FmiInstance* instance) { return static_cast<Model*>(instance->model_data)->core; }

// Straight to the host's logger, no allocation: usable when memory has run out.
void report(FmiInstance* instance, const char* what) noexcept {
    fmi_log_from_model(instance, GIMBAL_ERROR, "logStatusError", what);
}

// The body's status; any exception a GIMBAL_ERROR logged to the instance.
template <class Body>
GimbalStatus guarded(FmiInstance* instance, Body&& body) noexcept {
    return gimbal::guarded_entry([instance](const char* what) { report(instance, what); }, body);
}

// Model Exchange's equations need an initialized instance (the faces have checked the interface).
template <class Body>
GimbalStatus continuous(FmiInstance* instance, Body&& body) noexcept {
    return guarded(instance, [&] {
        const gimbal::GimbalInstance& core = core_of(instance);
        if (!core.continuous_time_interface() || !core.initialized()) {
            report(instance, "the instance is not an initialized instance of the continuous-time interface");
            return GIMBAL_ERROR;
        }
        return body(core_of(instance));
    });
}

// ---------------------------------------------------------------- the core's lifetime and snapshots

// A Model Exchange instance's core evaluates the equations at the host's points instead of stepping.
void* create(FmiInstance* instance) {
    try {
        auto* model = new Model(instance);
        if (instance->model_exchange) model->core.use_continuous_time_interface();
        return model;
    } catch (...) {
        report(instance, "out of memory");
        return nullptr;
    }
}

void destroy(void* model) { delete static_cast<Model*>(model); }

GimbalStatus reset(void* model) {
    auto* m = static_cast<Model*>(model);
    return guarded(m->host, [&] {
        m->core.reset();
        return GIMBAL_OK;
    });
}

size_t snapshot_size() { return gimbal::GimbalInstance::snapshot_size(); }

GimbalStatus save(void* model, unsigned char* snapshot) {
    auto* m = static_cast<Model*>(model);
    return guarded(m->host, [&] {
        m->core.save(snapshot);
        return GIMBAL_OK;
    });
}

GimbalStatus check_snapshot(void* model, const unsigned char* snapshot, int* initialized) {
    auto* m = static_cast<Model*>(model);
    return guarded(m->host, [&] {
        bool flag = false;
        const GimbalStatus status = m->core.check_snapshot(snapshot, flag);
        *initialized = flag ? 1 : 0;
        return status;
    });
}

GimbalStatus restore(void* model, const unsigned char* snapshot) {
    auto* m = static_cast<Model*>(model);
    return guarded(m->host, [&] { return m->core.restore(snapshot); });
}

// ---------------------------------------------------------------- Reals (FMI 3.0: Float64)

// The layer's settable rule over the core's variable table.
bool variable_settable(const FmiInstance* instance, const GimbalVariableInfo& info) {
    return fmi_settable(instance, static_cast<FmiCausality>(info.causality), static_cast<FmiVariability>(info.variability),
                        static_cast<FmiInitial>(info.initial)) != 0;
}

// A call's Reals: settable ones found in one pass through the core's table (the master's inputs at
// every step), the first refused then named; the core checks every value before it applies any (all or
// nothing) and names a non-finite one.
GimbalStatus set_reals_named(FmiInstance* instance, const char* function, const char* type, const unsigned vr[],
                             size_t nvr, const double values[]) {
    const int initialized = !(instance->state & instance->face->before_initialized_states);
    for (size_t i = gimbal_first_unsettable(GIMBAL_REAL, vr, nvr, initialized); i < nvr; ++i) {
        GimbalVariableInfo info;
        if (!gimbal_variable_info(GIMBAL_REAL, vr[i], &info)) {
            fmi_log_error(instance, "%s: value reference %u is not a %s", function, vr[i], type);
            return GIMBAL_ERROR;
        }
        if (!variable_settable(instance, info)) {
            fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, info.name,
                          instance->face->state_name(instance->state));
            return GIMBAL_ERROR;
        }
    }
    return guarded(instance, [&] { return core_of(instance).set_reals(vr, nvr, values); });
}

GimbalStatus set_reals(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                       const double values[]) {
    return set_reals_named(instance, function, "Real variable", vr, nvr, values);
}

GimbalStatus set_float64(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                         const double values[]) {
    return set_reals_named(instance, function, "Float64 variable that can be set", vr, nvr, values);
}

// The core names a reference it has no Real of.
GimbalStatus get_reals(FmiInstance* instance, const char*, const unsigned vr[], size_t nvr, double values[]) {
    return guarded(instance, [&] {
        GimbalStatus worst = GIMBAL_OK;
        for (size_t i = 0; i < nvr && worst <= GIMBAL_WARNING; ++i) {
            const GimbalStatus status = core_of(instance).get_real(vr[i], values[i]);
            if (status > worst) worst = status;
        }
        return worst;
    });
}

bool is_event_indicator(unsigned vr) {
    return vr >= kFirstEventIndicator && vr < kFirstEventIndicator + GIMBAL_EVENT_INDICATORS;
}

GimbalStatus float64_value(FmiInstance* instance, const char* function, unsigned vr, double& value) {
    GimbalVariableInfo info;
    if (vr >= kIntegerBase || !gimbal_variable_info(GIMBAL_REAL, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not a Float64 variable", function, vr);
        return GIMBAL_ERROR;
    }
    return core_of(instance).get_real(vr, value);
}

// The event indicators of a Model Exchange instance: before initialization those of the start values.
GimbalStatus read_event_indicators(FmiInstance* instance, double indicators[]) {
    gimbal::GimbalInstance& core = core_of(instance);
    if (!core.initialized()) return guarded(instance, [&] { return core.preview_continuous(nullptr, indicators); });
    return continuous(instance, [&](gimbal::GimbalInstance& c) { return c.get_event_indicators(indicators); });
}

// The core computes the event indicators all at once: read once per call (`read`). Co-Simulation
// locates the events itself: no indicator is exposed (each reads 1).
GimbalStatus event_indicator(FmiInstance* instance, unsigned vr, double indicators[], bool& read, double& value) {
    if (!read) {
        for (int z = 0; z < GIMBAL_EVENT_INDICATORS; ++z) indicators[z] = 1.0;
        if (instance->model_exchange) {
            const GimbalStatus status = read_event_indicators(instance, indicators);
            if (status > GIMBAL_WARNING) return status;
        }
        read = true;
    }
    value = indicators[vr - kFirstEventIndicator];
    return GIMBAL_OK;
}

// The Reals, `time` and the event indicators.
GimbalStatus get_float64(FmiInstance* instance, const char* function, const unsigned vr[], size_t nvr,
                         double values[]) {
    return guarded(instance, [&] {
        double indicators[GIMBAL_EVENT_INDICATORS];
        bool indicators_read = false;
        GimbalStatus worst = GIMBAL_OK;
        for (size_t k = 0; k < nvr && worst <= GIMBAL_WARNING; ++k) {
            GimbalStatus status = GIMBAL_OK;
            if (vr[k] == kTime)
                values[k] = instance->time;
            else if (is_event_indicator(vr[k]))
                status = event_indicator(instance, vr[k], indicators, indicators_read, values[k]);
            else
                status = float64_value(instance, function, vr[k], values[k]);
            if (status > worst) worst = status;
        }
        return worst;
    });
}

// ---------------------------------------------------------------- Integers (FMI 3.0: Int32, and Int64 for
// the Enumerations) and Booleans, one by one

// A settable variable of the type; else logged, 0.
int settable(FmiInstance* instance, const char* function, GimbalType type, unsigned vr) {
    GimbalVariableInfo info;
    if (!gimbal_variable_info(type, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not a variable of its type", function, vr);
        return 0;
    }
    if (variable_settable(instance, info)) return 1;
    fmi_log_error(instance, "%s: %s cannot be set in state '%s'", function, info.name,
                  instance->face->state_name(instance->state));
    return 0;
}

GimbalStatus get_integer(FmiInstance* instance, const char*, unsigned vr, void* value) {
    return guarded(instance, [&] { return core_of(instance).get_integer(vr, *static_cast<int*>(value)); });
}

// The core checks the value when it is set, naming the variable.
int integer_settable(FmiInstance* instance, const char* function, unsigned vr, const void*) {
    return settable(instance, function, GIMBAL_INTEGER, vr);
}

GimbalStatus set_integer(FmiInstance* instance, const char*, unsigned vr, const void* value) {
    return guarded(instance, [&] { return core_of(instance).set_integer(vr, *static_cast<const int*>(value)); });
}

int integer_known(unsigned vr) {
    GimbalVariableInfo info;
    return gimbal_variable_info(GIMBAL_INTEGER, vr, &info);
}

// FMI 3.0 tells the Enumerations (Int64) from the other Integers (Int32): a call of the other type is
// refused naming the variable and the type it is.
bool of_kind(FmiInstance* instance, const char* function, unsigned vr, bool enumeration) {
    GimbalVariableInfo info;
    if (!gimbal_variable_info(GIMBAL_INTEGER, vr, &info)) {
        fmi_log_error(instance, "%s: value reference %u is not an Integer variable", function, vr);
        return false;
    }
    if ((info.declared_type[0] != '\0') == enumeration) return true;
    fmi_log_error(instance, "%s: %s is %s", function, info.name,
                  enumeration ? "an Int32 variable" : "an Enumeration (fmi3GetInt64/fmi3SetInt64)");
    return false;
}

GimbalStatus get_int32(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    return of_kind(instance, function, vr, false) ? get_integer(instance, function, vr, value) : GIMBAL_ERROR;
}
int int32_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    return of_kind(instance, function, vr, false) && integer_settable(instance, function, vr, value);
}
GimbalStatus get_enumeration(FmiInstance* instance, const char* function, unsigned vr, void* value) {
    return of_kind(instance, function, vr, true) ? get_integer(instance, function, vr, value) : GIMBAL_ERROR;
}
int enumeration_settable(FmiInstance* instance, const char* function, unsigned vr, const void* value) {
    return of_kind(instance, function, vr, true) && integer_settable(instance, function, vr, value);
}

GimbalStatus get_boolean(FmiInstance* instance, const char*, unsigned vr, void* value) {
    return guarded(instance, [&] {
        bool flag = false;
        const GimbalStatus status = core_of(instance).get_boolean(vr, flag);
        *static_cast<int*>(value) = flag ? 1 : 0;
        return status;
    });
}

int boolean_settable(FmiInstance* instance, const char* function, unsigned vr, const void*) {
    return settable(instance, function, GIMBAL_BOOLEAN, vr);
}

GimbalStatus set_boolean(FmiInstance* instance, const char*, unsigned vr, const void* value) {
    return guarded(instance, [&] { return core_of(instance).set_boolean(vr, *static_cast<const int*>(value) != 0); });
}

int boolean_known(unsigned vr) {
    GimbalVariableInfo info;
    return gimbal_variable_info(GIMBAL_BOOLEAN, vr, &info);
}

// ---------------------------------------------------------------- initialization and the step

// The core names the tolerance it refuses.
GimbalStatus tolerance(FmiInstance* instance, const char*, int defined, double value) {
    return guarded(instance, [&] {
        core_of(instance).set_master_tolerance(defined != 0, value);
        return GIMBAL_OK;
    });
}

GimbalStatus exit_initialization(FmiInstance* instance, const char* function) {
    const GimbalStatus status = guarded(instance, [&] { return core_of(instance).initialize(instance->time); });
    if (status <= GIMBAL_WARNING) return status;
    fmi_log_error(instance, "%s: initialization refused; fix the values above and retry", function);
    return GIMBAL_ERROR;  // still in initialization mode: the master may correct and retry
}

// With early return allowed, the step ends right after the first mode change inside it: the importer
// sees the event where it happens (and handles it in Event Mode if it uses that).
GimbalStatus do_step(FmiInstance* instance, const char*, double point, double step, int* ended_early) {
    double elapsed = step;  // how far the step went: all of it, or to the first mode change
    const GimbalStatus status = guarded(instance, [&] {
        gimbal::GimbalInstance& core = core_of(instance);
        return instance->early_return_allowed ? core.do_step_with_early_return(point, step, elapsed)
                                              : core.do_step(point, step);
    });
    if (status > GIMBAL_WARNING) {
        instance->state = status == GIMBAL_DISCARD ? instance->face->step_failed_state : instance->face->error_state;
        return status;
    }
    *ended_early = instance->early_return_allowed && elapsed < step;
    instance->time = *ended_early ? point + elapsed : point + step;
    return status;
}

// ---------------------------------------------------------------- derivatives

// The `index`-th unknown or known (`role`) of a Co-Simulation instance's directional derivative: a Real
// variable of the given causality, whose description it writes to `info`; else logged, false.
bool directional_variable(FmiInstance* instance, const char* function, const char* role, size_t index, unsigned vr,
                          GimbalCausality causality, GimbalVariableInfo& info) {
    const char* kind = causality == GIMBAL_OUTPUT ? "output" : "input";
    if (!gimbal_variable_info(GIMBAL_REAL, vr, &info)) {
        fmi_log_error(instance, "%s: %s %zu: value reference %u is not a real-valued variable", function, role, index, vr);
        return false;
    }
    if (info.causality == causality) return true;
    fmi_log_error(instance, "%s: %s %s is not an %s: in Co-Simulation the %ss are the %ss", function, role, info.name,
                  kind, role, kind);
    return false;
}

// Model Exchange: unknowns are state derivatives or outputs, knowns states or inputs (FMI 2.0, section
// 3.2.1); the core checks which, and names a variable that is neither.
//
// Co-Simulation, at a communication point (FMI 2.0, section 4.2.1 with 3.2.1): the unknowns are outputs
// and the knowns inputs; a Co-Simulation FMU exposes no states. The outputs are computed by the step and
// held until the next one: setting an input changes no output before the next step, which is why
// ModelStructure declares every output with dependencies="". The partial derivatives at the current
// point are therefore exactly zero; what is computed here is the check of the arguments. The
// linearization of the continuous model itself (A, B, C, D, with the direct feedthrough of e.g. a
// quasi-static motor's current) is a different quantity.
GimbalStatus directional_derivative(FmiInstance* instance, const char* function, const unsigned unknowns[],
                                    size_t unknown_count, const unsigned knowns[], size_t known_count,
                                    const double seed[], double sensitivity[]) {
    if (instance->model_exchange) {
        for (size_t j = 0; j < known_count; ++j) {
            if (std::isfinite(seed[j])) continue;
            fmi_log_error(instance, "%s: the seed of known %zu must be finite", function, j);
            return GIMBAL_ERROR;
        }
        return continuous(instance, [&](gimbal::GimbalInstance& core) {
            return core.directional_derivative(unknowns, unknown_count, knowns, known_count, seed, sensitivity);
        });
    }
    GimbalVariableInfo info;
    for (size_t i = 0; i < unknown_count; ++i)
        if (!directional_variable(instance, function, "unknown", i, unknowns[i], GIMBAL_OUTPUT, info))
            return GIMBAL_ERROR;
    for (size_t j = 0; j < known_count; ++j) {
        if (!directional_variable(instance, function, "known", j, knowns[j], GIMBAL_INPUT, info)) return GIMBAL_ERROR;
        if (!std::isfinite(seed[j])) {
            fmi_log_error(instance, "%s: the seed of %s must be finite", function, info.name);
            return GIMBAL_ERROR;
        }
    }
    for (size_t i = 0; i < unknown_count; ++i) sensitivity[i] = 0.0;
    return GIMBAL_OK;
}

// The core names the input and the order it refuses.
GimbalStatus set_input_derivative(FmiInstance* instance, const char*, unsigned vr, int order, double value) {
    return guarded(instance, [&] { return core_of(instance).set_input_derivative(vr, order, value); });
}

// ---------------------------------------------------------------- Model Exchange

GimbalStatus set_time(FmiInstance* instance, double time) {
    return continuous(instance, [&](gimbal::GimbalInstance& core) { return core.set_time(time); });
}

GimbalStatus set_continuous_states(FmiInstance* instance, const double states[]) {
    return continuous(instance, [&](gimbal::GimbalInstance& core) { return core.set_continuous_states(states); });
}

GimbalStatus get_derivatives(FmiInstance* instance, double derivatives[]) {
    return continuous(instance, [&](gimbal::GimbalInstance& core) { return core.get_derivatives(derivatives); });
}

// Before initialization: those of the start values (FMI's initialization mode).
GimbalStatus get_continuous_states(FmiInstance* instance, double states[]) {
    gimbal::GimbalInstance& core = core_of(instance);
    if (!core.initialized()) return guarded(instance, [&] { return core.preview_continuous(states, nullptr); });
    return continuous(instance, [&](gimbal::GimbalInstance& c) {
        c.get_continuous_states(states);
        return GIMBAL_OK;
    });
}

GimbalStatus get_nominals(FmiInstance* instance, double nominals[]) {
    return guarded(instance, [&] {
        core_of(instance).get_nominal_states(nominals);
        return GIMBAL_OK;
    });
}

GimbalStatus update_discrete_states(FmiInstance* instance, FmuDiscreteUpdate* update) {
    return continuous(instance, [&](gimbal::GimbalInstance& core) {
        gimbal::GimbalInstance::DiscreteUpdate result;
        const GimbalStatus status = core.update_discrete_states(result);
        if (status > GIMBAL_WARNING) return status;
        update->states_changed = result.states_changed ? 1 : 0;
        update->next_time_defined = result.next_time_defined ? 1 : 0;
        update->next_time = result.next_time;
        return status;
    });
}

// ---------------------------------------------------------------- the tables

// The variables of one type, accessed one by one.
constexpr FmuVariables one_by_one(unsigned count, FmiStatus (*get)(FmiInstance*, const char*, unsigned, void*),
                                  int (*can_set)(FmiInstance*, const char*, unsigned, const void*),
                                  FmiStatus (*set)(FmiInstance*, const char*, unsigned, const void*),
                                  int (*known)(unsigned)) {
    FmuVariables variables{};
    variables.count = count;
    variables.get = get;
    variables.settable = can_set;
    variables.set = set;
    variables.known = known;
    return variables;
}

// The variables of one type, a call's all at once.
constexpr FmuVariables all_at_once(
    unsigned count, FmiStatus (*get_all)(FmiInstance*, const char*, const unsigned[], size_t, double[]),
    FmiStatus (*set_all)(FmiInstance*, const char*, const unsigned[], size_t, const double[])) {
    FmuVariables variables{};
    variables.count = count;
    variables.get_all = get_all;
    variables.set_all = set_all;
    return variables;
}

// Every value reference below the next type's FMI 3.0 base may be one of the type's.
constexpr FmuVariables kReals = all_at_once(kIntegerBase, get_reals, set_reals);
constexpr FmuVariables kIntegers =
    one_by_one(kBooleanBase - kIntegerBase, get_integer, integer_settable, set_integer, integer_known);
constexpr FmuVariables kBooleans = one_by_one(kTime - kBooleanBase, get_boolean, boolean_settable, set_boolean,
                                              boolean_known);

// FMI 3.0's: the Float64 include `time` and the event indicators, the Enumerations are Int64.
constexpr Fmi3Variables fmi3_variables() {
    Fmi3Variables fmi3{};
    fmi3.float64 = all_at_once(kFirstEventIndicator + GIMBAL_EVENT_INDICATORS, get_float64, set_float64);
    fmi3.int32 = one_by_one(kBooleanBase - kIntegerBase, get_int32, int32_settable, set_integer, integer_known);
    fmi3.int64 = one_by_one(kBooleanBase - kIntegerBase, get_enumeration, enumeration_settable, set_integer,
                            integer_known);
    fmi3.boolean = kBooleans;
    fmi3.int32_base = kIntegerBase;
    fmi3.int64_base = kIntegerBase;
    fmi3.boolean_base = kBooleanBase;
    fmi3.time = kTime;
    return fmi3;
}
constexpr Fmi3Variables kFmi3Variables = fmi3_variables();

constexpr FmuModelExchange model_exchange() {
    FmuModelExchange equations{};
    equations.continuous_states = GIMBAL_CONTINUOUS_STATES;
    equations.event_indicators = GIMBAL_EVENT_INDICATORS;
    equations.set_time = set_time;
    equations.set_continuous_states = set_continuous_states;
    equations.get_derivatives = get_derivatives;
    equations.get_event_indicators = read_event_indicators;
    equations.get_continuous_states = get_continuous_states;
    equations.get_nominals = get_nominals;
    equations.update_discrete_states = update_discrete_states;
    return equations;
}
constexpr FmuModelExchange kModelExchange = model_exchange();

constexpr FmuModel table() {
    FmuModel model{};
    model.layer = {GIMBAL_GUID, sizeof(FmiInstance), kLogCategories,
                   static_cast<int>(sizeof kLogCategories / sizeof kLogCategories[0]), create, destroy, reset,
                   snapshot_size, save, check_snapshot, restore};
    model.get_states = GET_STATES;
    model.set_states = SET_STATES;
    model.terminate_states = RUNNING_STATES;
    model.status_states = STATUS_STATES;
    model.real = kReals;
    model.integer = kIntegers;
    model.boolean = kBooleans;
    model.fmi3 = &kFmi3Variables;
    model.tolerance = tolerance;
    model.exit_initialization = exit_initialization;
    model.do_step = do_step;
    model.directional_derivative = directional_derivative;
    model.set_input_derivative = set_input_derivative;
    model.model_exchange = &kModelExchange;
    model.has_event_mode = 1;
    model.fmi2_fmu_state = 1;
    return model;
}

}  // namespace

// The table the faces read (fmu_model.h), constant-initialized: no code runs when the library loads.
extern "C" const FmuModel kFmuModel = table();
