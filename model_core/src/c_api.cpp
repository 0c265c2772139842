// extern "C" face of the core. No C++ exception may cross into the host: each entry point catches.
#include "gimbal/gimbal_c_api.h"

#include <new>

#include "gimbal/gimbal_instance.hpp"

struct GimbalCore {
    gimbal::GimbalInstance instance;
};

extern "C" {

unsigned gimbal_real_variable_count(void) { return gimbal::kRealVariableCount; }

int gimbal_real_variable_info(unsigned vr, GimbalVariableInfo* info) {
    if (vr >= gimbal::kRealVariableCount || info == nullptr) return 0;
    const gimbal::RealVariableInfo& v = gimbal::kRealVariables[vr];
    info->name = v.name;
    info->causality = static_cast<GimbalCausality>(v.causality);
    info->variability = static_cast<GimbalVariability>(v.variability);
    info->initial = static_cast<GimbalInitial>(v.initial);
    return 1;
}

GimbalCore* gimbal_core_create(GimbalLogFunction log, void* log_context) {
    try {
        auto logger = [log, log_context](GimbalStatus status, const char* category, const std::string& message) {
            if (log != nullptr) log(log_context, status, category, message.c_str());
        };
        return new (std::nothrow) GimbalCore{gimbal::GimbalInstance(logger)};
    } catch (...) {
        return nullptr;
    }
}

void gimbal_core_destroy(GimbalCore* core) { delete core; }

void gimbal_core_reset(GimbalCore* core) { core->instance.reset(); }

GimbalStatus gimbal_core_set_real(GimbalCore* core, unsigned vr, double value) {
    return core->instance.set_real(vr, value);
}

GimbalStatus gimbal_core_get_real(const GimbalCore* core, unsigned vr, double* value) {
    return core->instance.get_real(vr, *value);
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

}  // extern "C"
