#include "gimbal/probe_api.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "gimbal/multibody/rigid_body.hpp"

namespace {

gimbal::Vec3 vec3(const double* v) { return gimbal::Vec3(v[0], v[1], v[2]); }

// Keeps the first error the core logs: the reason a probe call failed.
struct ErrorLog {
    std::string first_error;
    static void log(void* context, GimbalStatus status, const char*, const char* message) {
        auto* self = static_cast<ErrorLog*>(context);
        if (status >= GIMBAL_DISCARD && self->first_error.empty()) self->first_error = message;
    }
};

int fail(char* message, size_t size, const std::string& why) {
    if (message != nullptr && size > 0) std::snprintf(message, size, "%s", why.c_str());
    return 1;
}

std::string variable_name(int type, unsigned vr) {
    GimbalVariableInfo info;
    return gimbal_variable_info(static_cast<GimbalType>(type), vr, &info) ? info.name : "value reference " + std::to_string(vr);
}

GimbalStatus apply(GimbalCore* core, const GimbalProbeSetting& setting) {
    switch (setting.type) {
        case GIMBAL_REAL: return gimbal_core_set_real(core, setting.vr, setting.value);
        case GIMBAL_INTEGER: return gimbal_core_set_integer(core, setting.vr, static_cast<int>(setting.value));
        case GIMBAL_BOOLEAN: return gimbal_core_set_boolean(core, setting.vr, setting.value != 0.0);
        default: return GIMBAL_ERROR;
    }
}

}  // namespace

extern "C" int gimbal_probe_variable(int type, unsigned vr, const char** name, int* causality) {
    GimbalVariableInfo info;
    if (type < GIMBAL_REAL || type > GIMBAL_BOOLEAN || !gimbal_variable_info(static_cast<GimbalType>(type), vr, &info))
        return 0;
    if (name != nullptr) *name = info.name;
    if (causality != nullptr) *causality = info.causality;
    return 1;
}

extern "C" size_t gimbal_probe_snapshot_size(void) { return gimbal_core_snapshot_size(); }

extern "C" void gimbal_probe_linear_model_layout(int* max_states, int* inputs, int* outputs, size_t* size) {
    if (max_states != nullptr) *max_states = GIMBAL_LINEAR_MAX_STATES;
    if (inputs != nullptr) *inputs = GIMBAL_LINEAR_INPUTS;
    if (outputs != nullptr) *outputs = GIMBAL_LINEAR_OUTPUTS;
    if (size != nullptr) *size = sizeof(GimbalLinearModel);
}

extern "C" int gimbal_probe_linearize(const GimbalProbeSetting* settings, size_t setting_count, const void* snapshot,
                                      size_t snapshot_size, GimbalLinearModel* model, char* message,
                                      size_t message_size) {
    if (model == nullptr || (settings == nullptr && setting_count > 0)) return fail(message, message_size, "null argument");
    ErrorLog errors;
    std::unique_ptr<GimbalCore, void (*)(GimbalCore*)> core(gimbal_core_create(&ErrorLog::log, nullptr, &errors),
                                                            gimbal_core_destroy);
    if (!core) return fail(message, message_size, "out of memory");
    if (snapshot != nullptr) {
        if (snapshot_size != gimbal_core_snapshot_size())
            return fail(message, message_size,
                        "the snapshot has " + std::to_string(snapshot_size) + " bytes where this build's have " +
                            std::to_string(gimbal_core_snapshot_size()) + ": it comes from another version");
        int initialized = 0;
        if (gimbal_core_check_snapshot(core.get(), snapshot, &initialized) != GIMBAL_OK)
            return fail(message, message_size, errors.first_error);
        if (!initialized) return fail(message, message_size, "the snapshot is of an instance not yet initialized");
        if (gimbal_core_restore(core.get(), snapshot) != GIMBAL_OK) return fail(message, message_size, errors.first_error);
    }
    for (size_t k = 0; k < setting_count; ++k) {
        const GimbalProbeSetting& setting = settings[k];
        GimbalVariableInfo info;
        if (setting.type < GIMBAL_REAL || setting.type > GIMBAL_BOOLEAN ||
            !gimbal_variable_info(static_cast<GimbalType>(setting.type), setting.vr, &info))
            return fail(message, message_size, "setting " + std::to_string(k) + " names no variable");
        if (info.causality == GIMBAL_OUTPUT && info.initial != GIMBAL_INITIAL_EXACT && info.initial != GIMBAL_INITIAL_APPROX)
            return fail(message, message_size,
                        std::string(info.name) + " is a computed output: it has no start value to set");
        if (setting.type != GIMBAL_REAL &&
            !(std::nearbyint(setting.value) == setting.value && std::fabs(setting.value) <= 2147483647.0))
            return fail(message, message_size,
                        std::string(info.name) + " is " + (setting.type == GIMBAL_INTEGER ? "an Integer" : "a Boolean") +
                            ": " + std::to_string(setting.value) + " is not a whole number");
        if (snapshot != nullptr && info.causality != GIMBAL_INPUT)
            return fail(message, message_size,
                        std::string(info.name) + " is not an input: at a snapshot's operating point only inputs can change");
        if (apply(core.get(), setting) != GIMBAL_OK)
            return fail(message, message_size, variable_name(setting.type, setting.vr) + ": " + errors.first_error);
    }
    if (snapshot == nullptr && gimbal_core_initialize(core.get(), 0.0) != GIMBAL_OK)
        return fail(message, message_size, errors.first_error);
    if (gimbal_core_linearize(core.get(), model) != GIMBAL_OK) return fail(message, message_size, errors.first_error);
    return 0;
}

extern "C" int gimbal_probe_mass_matrix_and_bias(const GimbalProbeRigidBodyInput* input, double J_row_major[16],
                                                 double f[4]) {
    if (input == nullptr || J_row_major == nullptr || f == nullptr) return 1;
    gimbal::MultibodyModel model;
    for (int k = 0; k < 4; ++k) {
        const double* i = input->inertia[k];
        gimbal::RigidBody& body = model.bodies[k];
        body.mass = input->mass[k];
        body.inertia << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
        body.centre_of_mass = vec3(input->com[k]);
    }
    model.d_ab = vec3(input->d_ab);
    model.gravity = input->g;

    gimbal::BaseMotion base;
    base.attitude = vec3(input->attitude);
    base.attitude_rate = vec3(input->attitude_rate);
    base.attitude_accel = vec3(input->attitude_accel);
    base.velocity_a = vec3(input->v_a);
    base.acceleration_a = vec3(input->a_a);
    const gimbal::BaseKinematics kinematics = gimbal::evaluate_base_kinematics(base, model.gravity);

    const gimbal::Vec4 q(input->q[0], input->q[1], input->q[2], input->q[3]);
    const gimbal::Vec4 qd(input->qd[0], input->qd[1], input->qd[2], input->qd[3]);
    gimbal::Mat4 mass_matrix;
    gimbal::Vec4 bias;
    gimbal::compute_mass_matrix_and_bias(model, kinematics, q, qd, mass_matrix, bias);
    for (int r = 0; r < 4; ++r) {
        f[r] = bias[r];
        for (int c = 0; c < 4; ++c) J_row_major[4 * r + c] = mass_matrix(r, c);
    }
    return 0;
}
