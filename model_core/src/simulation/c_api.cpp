// extern "C" face of the core (gimbal_c_api.h), for the probe library and the core's tests; the FMU's
// table over the core is fmu_model_table.cpp beside it. No C++ exception may cross into the host:
// every entry point runs its body through guarded(), which turns any exception into a status and a
// logged message (as cppfmu's entry points do).
#include "gimbal/gimbal_c_api.h"

#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "gimbal/simulation/entry_guard.hpp"
#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/simulation/linearization.hpp"

struct GimbalCore {
    GimbalCore(GimbalLogFunction log_function, void* context, gimbal::GimbalInstance::Logger logger,
               gimbal::GimbalInstance::LogFilter filter)
        : log(log_function), log_context(context), instance(std::move(logger), std::move(filter)) {}

    // Straight to the host's callback, no allocation: usable when memory has run out.
    void report(const char* what) const noexcept {
        if (log != nullptr) log(log_context, GIMBAL_ERROR, "logStatusError", what);
    }

    GimbalLogFunction log;
    void* log_context;
    gimbal::GimbalInstance instance;
};

namespace {

// Messages name no interface function: a caller that serves one prefixes it.
template <class Body>
GimbalStatus guarded(GimbalCore* core, Body&& body) noexcept {
    if (core == nullptr) return GIMBAL_ERROR;
    return gimbal::guarded_entry([core](const char* what) { core->report(what); }, body);
}
// The continuous-time entries need an initialized instance of that interface.
template <class Body>
GimbalStatus continuous(GimbalCore* core, Body&& body) noexcept {
    return guarded(core, [&] {
        if (!core->instance.continuous_time_interface() || !core->instance.initialized()) {
            core->log(core->log_context, GIMBAL_ERROR, "logStatusError",
                      "the instance is not an initialized instance of the continuous-time interface");
            return GIMBAL_ERROR;
        }
        return body();
    });
}


}  // namespace

extern "C" {

int gimbal_variable_info(GimbalType type, unsigned vr, GimbalVariableInfo* info) {
    const gimbal::VariableInfo* table = gimbal::kRealVariables;
    unsigned count = gimbal::kRealVariableCount;
    if (type == GIMBAL_INTEGER) table = gimbal::kIntegerVariables, count = gimbal::kIntegerVariableCount;
    if (type == GIMBAL_BOOLEAN) table = gimbal::kBooleanVariables, count = gimbal::kBooleanVariableCount;
    if (vr >= count || info == nullptr) return 0;
    const gimbal::VariableInfo& v = table[vr];
    info->name = v.name;
    info->causality = static_cast<GimbalCausality>(v.causality);
    info->variability = static_cast<GimbalVariability>(v.variability);
    info->initial = static_cast<GimbalInitial>(v.initial);
    info->declared_type = v.declared_type;
    return 1;
}

size_t gimbal_first_unsettable(GimbalType type, const unsigned* vr, size_t count, int initialized) {
    const gimbal::VariableInfo* table = gimbal::kRealVariables;
    unsigned variables = gimbal::kRealVariableCount;
    if (type == GIMBAL_INTEGER) table = gimbal::kIntegerVariables, variables = gimbal::kIntegerVariableCount;
    if (type == GIMBAL_BOOLEAN) table = gimbal::kBooleanVariables, variables = gimbal::kBooleanVariableCount;
    if (vr == nullptr) return 0;
    for (std::size_t k = 0; k < count; ++k) {
        if (vr[k] >= variables) return k;
        const gimbal::VariableInfo& v = table[vr[k]];
        const bool settable = v.causality == gimbal::Causality::input ||
                              (initialized ? v.causality == gimbal::Causality::parameter &&
                                                 v.variability == gimbal::Variability::tunable
                                           : v.initial == gimbal::Initial::exact || v.initial == gimbal::Initial::approx);
        if (!settable) return k;
    }
    return count;
}

GimbalCore* gimbal_core_create(GimbalLogFunction log, GimbalLogEnabledFunction enabled, void* log_context) {
    try {
        auto logger = [log, log_context](GimbalStatus status, const char* category, const std::string& message) {
            if (log != nullptr) log(log_context, status, category, message.c_str());
        };
        auto wants = [enabled, log_context](const char* category) {
            return enabled == nullptr || enabled(log_context, category) != 0;
        };
        return new GimbalCore{log, log_context, logger, wants};
    } catch (...) {
        if (log != nullptr) log(log_context, GIMBAL_ERROR, "logStatusError", "out of memory");
        return nullptr;
    }
}

void gimbal_core_destroy(GimbalCore* core) { delete core; }

GimbalStatus gimbal_core_reset(GimbalCore* core) {
    return guarded(core, [&] {
        core->instance.reset();
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_set_real(GimbalCore* core, unsigned vr, double value) {
    return guarded(core, [&] { return core->instance.set_real(vr, value); });
}

GimbalStatus gimbal_core_set_reals(GimbalCore* core, const unsigned* vr, size_t count, const double* values) {
    return guarded(core, [&] { return core->instance.set_reals(vr, count, values); });
}

GimbalStatus gimbal_core_get_real(GimbalCore* core, unsigned vr, double* value) {
    return guarded(core, [&] { return core->instance.get_real(vr, *value); });
}

GimbalStatus gimbal_core_set_input_derivative(GimbalCore* core, unsigned vr, int order, double value) {
    return guarded(core, [&] { return core->instance.set_input_derivative(vr, order, value); });
}

GimbalStatus gimbal_core_set_integer(GimbalCore* core, unsigned vr, int value) {
    return guarded(core, [&] { return core->instance.set_integer(vr, value); });
}

GimbalStatus gimbal_core_get_integer(GimbalCore* core, unsigned vr, int* value) {
    return guarded(core, [&] { return core->instance.get_integer(vr, *value); });
}

GimbalStatus gimbal_core_set_boolean(GimbalCore* core, unsigned vr, int value) {
    return guarded(core, [&] { return core->instance.set_boolean(vr, value != 0); });
}

GimbalStatus gimbal_core_get_boolean(GimbalCore* core, unsigned vr, int* value) {
    return guarded(core, [&] {
        bool flag = false;
        const GimbalStatus status = core->instance.get_boolean(vr, flag);
        *value = flag ? 1 : 0;
        return status;
    });
}

GimbalStatus gimbal_core_set_master_tolerance(GimbalCore* core, int defined, double tolerance) {
    return guarded(core, [&] {
        core->instance.set_master_tolerance(defined != 0, tolerance);
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_initialize(GimbalCore* core, double start_time) {
    return guarded(core, [&] { return core->instance.initialize(start_time); });
}

GimbalStatus gimbal_core_do_step(GimbalCore* core, double current_time, double step_size) {
    return guarded(core, [&] { return core->instance.do_step(current_time, step_size); });
}

GimbalStatus gimbal_core_do_step_until_mode_change(GimbalCore* core, double current_time, double step_size,
                                                   double* elapsed) {
    return guarded(core, [&] {
        double went = step_size;
        const GimbalStatus status = core->instance.do_step_with_early_return(current_time, step_size, went);
        if (elapsed != nullptr) *elapsed = went;
        return status;
    });
}

double gimbal_core_time(const GimbalCore* core) { return core != nullptr ? core->instance.time() : 0.0; }

size_t gimbal_core_snapshot_size(void) { return gimbal::GimbalInstance::snapshot_size(); }

GimbalStatus gimbal_core_save(GimbalCore* core, void* buffer) {
    return guarded(core, [&] {
        core->instance.save(buffer);
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_check_snapshot(GimbalCore* core, const void* buffer, int* initialized) {
    return guarded(core, [&] {
        bool flag = false;
        const GimbalStatus status = core->instance.check_snapshot(buffer, flag);
        *initialized = flag ? 1 : 0;
        return status;
    });
}

GimbalStatus gimbal_core_restore(GimbalCore* core, const void* buffer) {
    return guarded(core, [&] { return core->instance.restore(buffer); });
}

GimbalStatus gimbal_core_linearize(GimbalCore* core, GimbalLinearModel* model) {
    return guarded(core, [&] {
        if (model == nullptr) return GIMBAL_ERROR;
        static_assert(GIMBAL_LINEAR_MAX_STATES == gimbal::kLinearMaxStates && GIMBAL_LINEAR_INPUTS == gimbal::kLinearInputCount &&
                          GIMBAL_LINEAR_OUTPUTS == gimbal::kLinearOutputCount,
                      "the C view of the linear model has the core's sizes");
        gimbal::LinearModel linear;
        const GimbalStatus status = core->instance.linearize(linear);
        if (status != GIMBAL_OK) return status;
        *model = GimbalLinearModel{};
        model->state_count = linear.state_count;
        for (int k = 0; k < GIMBAL_LINEAR_MAX_STATES; ++k) model->state_vr[k] = linear.state_variable[k];
        for (int k = 0; k < GIMBAL_LINEAR_INPUTS; ++k) model->input_vr[k] = linear.input_variable[k];
        for (int k = 0; k < GIMBAL_LINEAR_OUTPUTS; ++k) model->output_vr[k] = gimbal::kLinearFirstOutput + k;
        std::memcpy(model->A, linear.A, sizeof model->A);
        std::memcpy(model->B, linear.B, sizeof model->B);
        std::memcpy(model->C, linear.C, sizeof model->C);
        std::memcpy(model->D, linear.D, sizeof model->D);
        for (int axis = 0; axis < 2; ++axis) {
            model->gear_contact[axis] = linear.modes.gear_contact[axis];
            model->motor_limited[axis] = linear.modes.motor_limited[axis];
            model->voltage_clamped[axis] = linear.modes.voltage_clamped[axis];
        }
        for (int body = 0; body < 4; ++body) model->friction[body] = static_cast<int>(linear.modes.friction[body]);
        model->elevation_stop = linear.modes.axis_stop[gimbal::axis_stop_of(gimbal::ElementKind::elevation_stop)];
        for (int axis = 0; axis < 2; ++axis) model->amplifier_saturated[axis] = linear.modes.amplifier_saturated[axis];
        model->time = core->instance.time();
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_use_continuous_time(GimbalCore* core) {
    return guarded(core, [&] {
        core->instance.use_continuous_time_interface();
        return GIMBAL_OK;
    });
}

unsigned gimbal_continuous_state_vr(int k) {
    static_assert(GIMBAL_CONTINUOUS_STATES == gimbal::kContinuousStateCount &&
                      GIMBAL_EVENT_INDICATORS == gimbal::GimbalHybridSystem::kIndicatorCount,
                  "the C view of the continuous-time interface has the core's sizes");
    return k >= 0 && k < GIMBAL_CONTINUOUS_STATES ? gimbal::kContinuousStates[k] : ~0u;
}

unsigned gimbal_state_derivative_vr(int k) {
    return k >= 0 && k < GIMBAL_CONTINUOUS_STATES ? gimbal::kStateDerivatives[k] : ~0u;
}


GimbalStatus gimbal_core_set_time(GimbalCore* core, double time) {
    return continuous(core, [&] { return core->instance.set_time(time); });
}

GimbalStatus gimbal_core_set_continuous_states(GimbalCore* core, const double* states) {
    return continuous(core, [&] { return core->instance.set_continuous_states(states); });
}

GimbalStatus gimbal_core_get_continuous_states(GimbalCore* core, double* states) {
    if (core != nullptr && !core->instance.initialized())
        return guarded(core, [&] { return core->instance.preview_continuous(states, nullptr); });
    return continuous(core, [&] {
        core->instance.get_continuous_states(states);
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_get_nominal_states(GimbalCore* core, double* nominals) {
    return guarded(core, [&] {
        core->instance.get_nominal_states(nominals);
        return GIMBAL_OK;
    });
}

GimbalStatus gimbal_core_get_derivatives(GimbalCore* core, double* derivatives) {
    return continuous(core, [&] { return core->instance.get_derivatives(derivatives); });
}

GimbalStatus gimbal_core_get_event_indicators(GimbalCore* core, double* indicators) {
    if (core != nullptr && !core->instance.initialized())
        return guarded(core, [&] { return core->instance.preview_continuous(nullptr, indicators); });
    return continuous(core, [&] { return core->instance.get_event_indicators(indicators); });
}

GimbalStatus gimbal_core_update_discrete_states(GimbalCore* core, GimbalDiscreteUpdate* update) {
    return continuous(core, [&] {
        gimbal::GimbalInstance::DiscreteUpdate result;
        const GimbalStatus status = core->instance.update_discrete_states(result);
        update->states_changed = result.states_changed ? 1 : 0;
        update->next_time_defined = result.next_time_defined ? 1 : 0;
        update->next_time = result.next_time;
        update->mode_changes = result.mode_changes;
        return status;
    });
}

GimbalStatus gimbal_core_directional_derivative(GimbalCore* core, const unsigned* unknowns, size_t unknown_count,
                                                const unsigned* knowns, size_t known_count, const double* seed,
                                                double* result) {
    return continuous(core, [&] {
        return core->instance.directional_derivative(unknowns, unknown_count, knowns, known_count, seed, result);
    });
}

}  // extern "C"
