// extern "C" face of the core. No C++ exception may cross into the host: each entry point catches.
#include "gimbal/gimbal_c_api.h"

#include <new>

#include "gimbal/gimbal_instance.hpp"

struct GimbalCore {
    GimbalCore(gimbal::GimbalInstance::Logger logger, gimbal::GimbalInstance::LogFilter filter)
        : instance(std::move(logger), std::move(filter)) {}
    gimbal::GimbalInstance instance;
};

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
    return 1;
}

GimbalCore* gimbal_core_create(GimbalLogFunction log, GimbalLogEnabledFunction enabled, void* log_context) {
    try {
        auto logger = [log, log_context](GimbalStatus status, const char* category, const std::string& message) {
            if (log != nullptr) log(log_context, status, category, message.c_str());
        };
        auto wants = [enabled, log_context](const char* category) {
            return enabled == nullptr || enabled(log_context, category) != 0;
        };
        return new (std::nothrow) GimbalCore{logger, wants};
    } catch (...) {
        return nullptr;
    }
}

void gimbal_core_destroy(GimbalCore* core) { delete core; }

void gimbal_core_reset(GimbalCore* core) { core->instance.reset(); }

GimbalStatus gimbal_core_set_real(GimbalCore* core, unsigned vr, double value) {
    return core->instance.set_real(vr, value);
}

GimbalStatus gimbal_core_get_real(GimbalCore* core, unsigned vr, double* value) {
    return core->instance.get_real(vr, *value);
}

GimbalStatus gimbal_core_set_input_derivative(GimbalCore* core, unsigned vr, int order, double value) {
    return core->instance.set_input_derivative(vr, order, value);
}

GimbalStatus gimbal_core_set_integer(GimbalCore* core, unsigned vr, int value) {
    return core->instance.set_integer(vr, value);
}

GimbalStatus gimbal_core_get_integer(GimbalCore* core, unsigned vr, int* value) {
    return core->instance.get_integer(vr, *value);
}

GimbalStatus gimbal_core_set_boolean(GimbalCore* core, unsigned vr, int value) {
    return core->instance.set_boolean(vr, value != 0);
}

GimbalStatus gimbal_core_get_boolean(GimbalCore* core, unsigned vr, int* value) {
    bool flag = false;
    const GimbalStatus status = core->instance.get_boolean(vr, flag);
    *value = flag ? 1 : 0;
    return status;
}

GimbalStatus gimbal_core_initialize(GimbalCore* core, double start_time) {
    try {
        return core->instance.initialize(start_time);
    } catch (const std::bad_alloc&) {
        return GIMBAL_ERROR;
    }
}

GimbalStatus gimbal_core_do_step(GimbalCore* core, double current_time, double step_size) {
    try {
        return core->instance.do_step(current_time, step_size);
    } catch (const std::bad_alloc&) {
        return GIMBAL_ERROR;
    }
}

double gimbal_core_time(const GimbalCore* core) { return core->instance.time(); }

size_t gimbal_core_snapshot_size(void) { return gimbal::GimbalInstance::snapshot_size(); }

GimbalStatus gimbal_core_save(GimbalCore* core, void* buffer) {
    core->instance.save(buffer);
    return GIMBAL_OK;
}

GimbalStatus gimbal_core_restore(GimbalCore* core, const void* buffer) {
    try {
        return core->instance.restore(buffer);
    } catch (const std::bad_alloc&) {
        return GIMBAL_ERROR;
    }
}

}  // extern "C"
