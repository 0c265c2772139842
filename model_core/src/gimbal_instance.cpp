#include "gimbal/gimbal_instance.hpp"

#include <cmath>
#include <sstream>

#include "gimbal/parameter_validation.hpp"

namespace gimbal {
namespace {

bool same_base_motion(const BaseMotion& a, const BaseMotion& b) {
    return a.attitude == b.attitude && a.attitude_rate == b.attitude_rate && a.attitude_accel == b.attitude_accel &&
           a.velocity_a == b.velocity_a && a.acceleration_a == b.acceleration_a;
}

Vec3 vector_at(const double* values, unsigned first) { return Vec3(values[first], values[first + 1], values[first + 2]); }

}  // namespace

GimbalInstance::GimbalInstance(Logger logger) : logger_(std::move(logger)) { reset(); }

void GimbalInstance::reset() {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) values_[vr] = kRealVariables[vr].start;
    integrator_.reset();
    integrator_running_ = false;
    state_.setZero();
    time_ = 0.0;
}

GimbalStatus GimbalInstance::refuse(GimbalStatus status, const std::string& message) const {
    logger_(status, status == GIMBAL_DISCARD ? "logStatusDiscard" : "logStatusError", message);
    return status;
}

GimbalStatus GimbalInstance::set_real(unsigned vr, double value) {
    if (vr >= kRealVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2SetReal: value reference " + std::to_string(vr) + " is not a Real variable");
    }
    if (!std::isfinite(value)) {
        std::ostringstream s;
        s << "fmi2SetReal: " << kRealVariables[vr].name << " = " << value << " refused: values must be finite";
        return refuse(GIMBAL_ERROR, s.str());
    }
    values_[vr] = value;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_real(unsigned vr, double& value) const {
    if (vr >= kRealVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2GetReal: value reference " + std::to_string(vr) + " is not a Real variable");
    }
    value = values_[vr];
    return GIMBAL_OK;
}

StepInputs GimbalInstance::read_step_inputs(double step_start) const {
    StepInputs inputs;
    inputs.voltage[0] = clamp_voltage(params_.motor[0], values_[vr_u_R1]);
    inputs.voltage[1] = clamp_voltage(params_.motor[1], values_[vr_u_R2]);
    inputs.base.attitude = vector_at(values_, vr_base_delta);
    inputs.base.attitude_rate = vector_at(values_, vr_base_delta_dot);
    inputs.base.attitude_accel = vector_at(values_, vr_base_delta_ddot);
    inputs.base.velocity_a = vector_at(values_, vr_base_v_a_1);
    inputs.base.acceleration_a = vector_at(values_, vr_base_a_a_1);
    inputs.step_start_time = step_start;
    return inputs;
}

void GimbalInstance::publish_outputs(const StepInputs& inputs) {
    for (int k = 0; k < kStateSize; ++k) values_[vr_alpha + k] = state_[k];
    const ModelOutputs out = evaluate_outputs(params_, inputs, time_, state_);
    values_[vr_T_E1] = out.shaft_torque[0];
    values_[vr_T_E2] = out.shaft_torque[1];
    for (int k = 0; k < 3; ++k) values_[vr_los_omega_1 + k] = out.payload_angular_velocity[k];
    values_[vr_energy_kinetic] = out.kinetic_energy;
    values_[vr_energy_potential] = out.potential_energy;
    values_[vr_energy_spring] = out.spring_energy;
}

GimbalStatus GimbalInstance::initialize(double start_time) {
    std::string error;
    ModelParameters params;
    if (!build_model_parameters(values_, params, error) || !validate_start_state(values_, params, error)) {
        return refuse(GIMBAL_ERROR, error);
    }
    params_ = params;
    for (int k = 0; k < kStateSize; ++k) state_[k] = values_[vr_alpha + k];
    time_ = start_time;
    integrator_ = std::make_unique<CvodeIntegrator>(
        params_, [this](const std::string& message) { logger_(GIMBAL_WARNING, "logSolver", message); });
    integrator_running_ = false;
    publish_outputs(read_step_inputs(time_));
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::do_step(double current_time, double step_size) {
    if (!integrator_) return refuse(GIMBAL_ERROR, "fmi2DoStep: the instance is not initialized");
    const StepInputs inputs = read_step_inputs(current_time);
    // The right-hand side is continuous across the step boundary only if the held voltages are the same
    // and the base motion continues the previous step's constant-acceleration arc; otherwise restart.
    const bool continuous = integrator_running_ && inputs.voltage[0] == previous_inputs_.voltage[0] &&
                            inputs.voltage[1] == previous_inputs_.voltage[1] &&
                            same_base_motion(inputs.base, previous_inputs_.base.advanced(previous_step_size_));
    const StateVector step_start_state = state_;
    if (!continuous && !integrator_->restart(current_time, state_)) {
        return refuse(GIMBAL_ERROR, "fmi2DoStep: the integrator could not be restarted");
    }
    StepInputs held = inputs;
    if (continuous) held.step_start_time = previous_inputs_.step_start_time, held.base = previous_inputs_.base;
    if (!integrator_->advance(held, current_time + step_size, state_)) {
        state_ = step_start_state;
        integrator_running_ = false;
        std::ostringstream s;
        s << "fmi2DoStep: integration from t = " << current_time << " over h = " << step_size
          << " failed; state rolled back to t = " << current_time;
        return refuse(GIMBAL_DISCARD, s.str());
    }
    previous_inputs_ = held;
    previous_step_size_ = current_time + step_size - held.step_start_time;
    integrator_running_ = true;
    time_ = current_time + step_size;
    publish_outputs(held);
    return GIMBAL_OK;
}

}  // namespace gimbal
