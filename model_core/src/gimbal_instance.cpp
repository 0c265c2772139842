#include "gimbal/gimbal_instance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <type_traits>

#include "gimbal/parameter_validation.hpp"

namespace gimbal {
namespace {

// Whether the voltages at the start of a step continue the running ramps: then nothing jumps. A
// master's own arithmetic may differ from ours in the last bits, hence the tolerance.
bool continues(const StepInputs& running, const StepInputs& next, double time) {
    for (int axis = 0; axis < 2; ++axis) {
        if (running.voltage_rate[axis] == 0.0 && next.voltage_rate[axis] == 0.0) {
            if (running.voltage[axis] != next.voltage[axis]) return false;
            continue;
        }
        const double expected = ramped_voltage(running, axis, time);
        if (std::fabs(next.commanded_voltage[axis] - expected) > 1e-12 * std::max(1.0, std::fabs(expected)))
            return false;
    }
    return true;
}

bool same_base_motion(const BaseMotion& a, const BaseMotion& b) {
    return a.attitude == b.attitude && a.attitude_rate == b.attitude_rate && a.attitude_accel == b.attitude_accel &&
           a.velocity_a == b.velocity_a && a.acceleration_a == b.acceleration_a;
}

Vec3 vector_at(const double* values, unsigned first) { return Vec3(values[first], values[first + 1], values[first + 2]); }

constexpr std::uint32_t kSnapshotMagic = 0x47324158;  // "G2AX"
constexpr std::uint32_t kSnapshotVersion = 3;

struct Snapshot {
    std::uint32_t magic;
    std::uint32_t version;
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    bool booleans[kBooleanVariableCount];
    bool initialized;
    double time;
    double state[kMaxStateSize];
    Modes modes;
    EventCounters counters;
    IntegratorStatistics statistics;
    double voltage[2];
    double commanded_voltage[2];
    double voltage_rate[2];
    double pending_voltage_rate[2];
    double base[15];  // attitude, rate, accel, v_a, a_a at the arc start
    double arc_start_time;  // model time
    double epoch;
    bool integrator_running;
    bool at_rest;
    IntegratorMemory integrator_memory;
};
static_assert(std::is_trivially_copyable<Snapshot>::value, "snapshots are copied as bytes");

}  // namespace

GimbalInstance::GimbalInstance(Logger logger, LogFilter filter)
    : logger_(std::move(logger)), log_filter_(std::move(filter)) {
    reset();
}

void GimbalInstance::reset() {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals_[vr] = kRealVariables[vr].start;
    for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) integers_[vr] = static_cast<int>(kIntegerVariables[vr].start);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) booleans_[vr] = kBooleanVariables[vr].start != 0.0;
    integrator_.reset();
    system_.reset();
    integrator_running_ = false;
    preview_current_ = false;
    at_rest_ = false;
    voltage_rate_[0] = voltage_rate_[1] = 0.0;
    std::fill(state_, state_ + kMaxStateSize, 0.0);
    time_ = 0.0;
    epoch_ = 0.0;
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
    reals_[vr] = value;
    preview_current_ = false;
    // A new voltage starts a new ramp: its derivative must be given again.
    if (vr == vr_u_R1) voltage_rate_[0] = 0.0;
    if (vr == vr_u_R2) voltage_rate_[1] = 0.0;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_input_derivative(unsigned vr, int order, double value) {
    const int axis = vr == vr_u_R1 ? 0 : (vr == vr_u_R2 ? 1 : -1);
    if (axis < 0) {
        const char* name = vr < kRealVariableCount ? kRealVariables[vr].name : "(no Real variable)";
        return refuse(GIMBAL_ERROR, std::string("fmi2SetRealInputDerivatives: ") + name +
                                        " takes no derivative: only u_R1 and u_R2 do (the base inputs carry their own "
                                        "rates and accelerations)");
    }
    if (order != 1) {
        return refuse(GIMBAL_ERROR, "fmi2SetRealInputDerivatives: order " + std::to_string(order) + " for " +
                                        kRealVariables[vr].name + " refused: only first derivatives are used");
    }
    if (!std::isfinite(value)) {
        return refuse(GIMBAL_ERROR, std::string("fmi2SetRealInputDerivatives: the derivative of ") +
                                        kRealVariables[vr].name + " must be finite");
    }
    voltage_rate_[axis] = value;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_real(unsigned vr, double& value) {
    if (vr >= kRealVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2GetReal: value reference " + std::to_string(vr) + " is not a Real variable");
    }
    if (!system_ && kRealVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs("fmi2GetReal", kRealVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    value = reals_[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_integer(unsigned vr, int value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2SetInteger: value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    integers_[vr] = value;
    preview_current_ = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_integer(unsigned vr, int& value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2GetInteger: value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    if (!system_ && kIntegerVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs("fmi2GetInteger", kIntegerVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    value = integers_[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_boolean(unsigned vr, bool value) {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2SetBoolean: value reference " + std::to_string(vr) + " is not a Boolean variable");
    }
    booleans_[vr] = value;
    preview_current_ = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_boolean(unsigned vr, bool& value) const {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "fmi2GetBoolean: value reference " + std::to_string(vr) + " is not a Boolean variable");
    }
    value = booleans_[vr];
    return GIMBAL_OK;
}

StepInputs GimbalInstance::read_step_inputs(double step_start) const {
    StepInputs inputs;
    inputs.commanded_voltage[0] = reals_[vr_u_R1];
    inputs.commanded_voltage[1] = reals_[vr_u_R2];
    for (int axis = 0; axis < 2; ++axis) {
        inputs.voltage[axis] = clamp_voltage(params_.motor[axis], inputs.commanded_voltage[axis]);
        inputs.voltage_rate[axis] = voltage_rate_[axis];
    }
    inputs.base.attitude = vector_at(reals_, vr_base_delta);
    inputs.base.attitude_rate = vector_at(reals_, vr_base_delta_dot);
    inputs.base.attitude_accel = vector_at(reals_, vr_base_delta_ddot);
    inputs.base.velocity_a = vector_at(reals_, vr_base_v_a_1);
    inputs.base.acceleration_a = vector_at(reals_, vr_base_a_a_1);
    inputs.step_start_time = step_start;
    return inputs;
}

void GimbalInstance::publish_outputs() {
    const Modes& modes = system_->modes();
    const double now = model_time(time_);
    const Dynamics& dynamics = system_->dynamics_at(now, state_);
    const ModelOutputs out = outputs_from(params_, system_->inputs(), system_->base_kinematics_at_time(now), now, dynamics);
    for (int k = 0; k < 4; ++k) {
        reals_[vr_alpha + k] = out.full.angle[k];
        reals_[vr_alpha_dot + k] = out.full.rate[k];
    }
    reals_[vr_i_R1] = out.full.current[0];
    reals_[vr_i_R2] = out.full.current[1];
    reals_[vr_theta_b1] = out.full.backlash[0];
    reals_[vr_theta_b2] = out.full.backlash[1];
    reals_[vr_T_E1] = out.shaft_torque[0];
    reals_[vr_T_E2] = out.shaft_torque[1];
    for (int k = 0; k < 3; ++k) reals_[vr_los_omega_1 + k] = out.payload_angular_velocity[k];
    reals_[vr_energy_kinetic] = out.kinetic_energy;
    reals_[vr_energy_potential] = out.potential_energy;
    reals_[vr_energy_spring] = out.spring_energy;
    reals_[vr_energy_magnetic] = out.magnetic_energy;
    const bool accounting = params_.layout.energy_slot >= 0;
    const double* flows = state_ + (accounting ? params_.layout.energy_slot : 0);
    reals_[vr_energy_electrical_in] = accounting ? flows[kElectricalIn] : 0.0;
    reals_[vr_energy_resistive] = accounting ? flows[kResistive] : 0.0;
    reals_[vr_energy_viscous] = accounting ? flows[kViscous] : 0.0;
    reals_[vr_energy_shaft_damping] = accounting ? flows[kShaftDamping] : 0.0;
    reals_[vr_energy_dry_friction] = accounting ? flows[kDryFriction] : 0.0;

    integers_[vi_gear1_contact] = modes.gear_contact[0];
    integers_[vi_gear2_contact] = modes.gear_contact[1];
    integers_[vi_motor1_limited] = modes.motor_limited[0];
    integers_[vi_motor2_limited] = modes.motor_limited[1];
    for (int body = 0; body < 4; ++body)
        integers_[vi_body1_stick_slip + body] = friction_mode_indicator(modes.friction[body], out.full.rate[body]);
    const EventCounters& events = system_->counters();
    const IntegratorStatistics stats = integrator_->statistics();
    reals_[vr_events_last_time] = epoch_ + events.last_event_time;
    integers_[vi_events_total] = static_cast<int>(events.total);
    integers_[vi_events_backlash1] = static_cast<int>(events.backlash[0]);
    integers_[vi_events_backlash2] = static_cast<int>(events.backlash[1]);
    integers_[vi_events_current_limit1] = static_cast<int>(events.current_limit[0]);
    integers_[vi_events_current_limit2] = static_cast<int>(events.current_limit[1]);
    integers_[vi_events_stick_slip] = static_cast<int>(events.stick_slip);
    integers_[vi_events_zeno_guard] = static_cast<int>(stats.zeno_holds);
    integers_[vi_solver_states] = params_.layout.size;
    integers_[vi_solver_steps] = static_cast<int>(std::min<long>(stats.steps, 2147483647L));
    integers_[vi_solver_rhs_evaluations] = static_cast<int>(std::min<long>(stats.rhs_evaluations, 2147483647L));
    integers_[vi_solver_jacobian_evaluations] = static_cast<int>(std::min<long>(stats.jacobian_evaluations, 2147483647L));
    integers_[vi_solver_method_switches] = static_cast<int>(std::min<long>(stats.method_switches, 2147483647L));
}

void GimbalInstance::load_start_state() {
    const StateLayout& layout = params_.layout;
    std::fill(state_, state_ + kMaxStateSize, 0.0);
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        state_[layout.angle_slot[body]] = reals_[vr_alpha + body];
        state_[layout.rate_slot[body]] = reals_[vr_alpha_dot + body];
    }
    const RealVariable currents[2] = {vr_i_R1, vr_i_R2}, backlash[2] = {vr_theta_b1, vr_theta_b2};
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) state_[layout.current_slot[axis]] = reals_[currents[axis]];
        if (layout.backlash_slot[axis] >= 0) state_[layout.backlash_slot[axis]] = reals_[backlash[axis]];
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double ratio = params_.gear[axis].ratio;
        if (!layout.independent(rotor) && (reals_[vr_alpha + rotor] != ratio * reals_[vr_alpha + load] ||
                                           reals_[vr_alpha_dot + rotor] != ratio * reals_[vr_alpha_dot + load])) {
            logger_(GIMBAL_WARNING, "logStatusWarning",
                    std::string("rigid gear ") + std::to_string(axis + 1) + ": the start values of " +
                        kRealVariables[vr_alpha + rotor].name + " and its rate are replaced by N times the load's");
        }
    }
}

GimbalStatus GimbalInstance::check_fixed_base(const char* function) const {
    if (!params_.fidelity.fixed_base) return GIMBAL_OK;
    for (unsigned vr = vr_base_delta; vr <= vr_base_a_a_3; ++vr) {
        if (reals_[vr] != 0.0) {
            std::ostringstream s;
            s << function << ": " << kRealVariables[vr].name << " = " << reals_[vr]
              << " refused: base.fixed = true, so every base input must be 0";
            return refuse(GIMBAL_ERROR, s.str());
        }
    }
    return GIMBAL_OK;
}

bool GimbalInstance::build_parameters(ModelParameters& params, std::string& error) const {
    return build_model_parameters(reals_, integers_, booleans_, params, error) &&
           validate_start_state(reals_, params, error);
}

void GimbalInstance::create_integrator() {
    IntegratorSettings settings;
    settings.relative_tolerance = params_.relative_tolerance;
    settings.absolute_tolerance = params_.absolute_tolerance;
    settings.max_steps = params_.max_steps;
    settings.method = static_cast<IntegrationMethod>(params_.method);
    settings.events_logged = [this] { return log_filter_("logEvents"); };
    integrator_ = HybridIntegrator::create(
        *system_, settings,
        [this](const std::string& message) {
            last_integrator_error_ = message;
            logger_(GIMBAL_WARNING, "logSolver", message);
        },
        [this](const std::string& message) { logger_(GIMBAL_OK, "logEvents", message); });
    integrator_running_ = false;
}

GimbalStatus GimbalInstance::preview_outputs(const char* function, const char* name) {
    if (preview_current_) return GIMBAL_OK;
    std::string error;
    if (!build_parameters(params_, error)) {
        return refuse(GIMBAL_ERROR, std::string(function) + ": " + name +
                                        " cannot be computed from the current values: " + error);
    }
    load_start_state();
    epoch_ = time_;
    system_ = std::make_unique<GimbalHybridSystem>(params_);
    system_->set_inputs(read_step_inputs(0.0));
    system_->update_modes(0.0, state_, nullptr);
    create_integrator();
    publish_outputs();
    // The preview must not count as initialization: forget the integrator again.
    integrator_.reset();
    system_.reset();
    preview_current_ = true;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::initialize(double start_time) {
    std::string error;
    ModelParameters params;
    if (!build_parameters(params, error)) return refuse(GIMBAL_ERROR, error);
    params_ = params;
    const GimbalStatus base_status = check_fixed_base("fmi2ExitInitializationMode");
    if (base_status != GIMBAL_OK) return base_status;
    load_start_state();
    time_ = start_time;
    epoch_ = start_time;
    system_ = std::make_unique<GimbalHybridSystem>(params_);
    system_->set_inputs(read_step_inputs(0.0));
    system_->update_modes(0.0, state_, nullptr);
    EventCounters none;
    none.last_event_time = 0.0;
    system_->restore(system_->modes(), none);  // the initial choice of modes is not an event
    create_integrator();
    publish_outputs();
    return GIMBAL_OK;
}

std::size_t GimbalInstance::snapshot_size() { return sizeof(Snapshot); }

void GimbalInstance::save(void* buffer) {
    Snapshot snap;
    std::memset(static_cast<void*>(&snap), 0, sizeof snap);  // no stray padding bytes in a serialized state
    snap.magic = kSnapshotMagic;
    snap.version = kSnapshotVersion;
    std::copy(reals_, reals_ + kRealVariableCount, snap.reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, snap.integers);
    std::copy(booleans_, booleans_ + kBooleanVariableCount, snap.booleans);
    snap.initialized = integrator_ != nullptr;
    snap.time = time_;
    std::copy(state_, state_ + kMaxStateSize, snap.state);
    snap.pending_voltage_rate[0] = voltage_rate_[0];
    snap.pending_voltage_rate[1] = voltage_rate_[1];
    if (snap.initialized) {
        snap.modes = system_->modes();
        snap.counters = system_->counters();
        snap.statistics = integrator_->statistics();
        const StepInputs& in = system_->inputs();
        for (int axis = 0; axis < 2; ++axis) {
            snap.voltage[axis] = in.voltage[axis];
            snap.commanded_voltage[axis] = in.commanded_voltage[axis];
            snap.voltage_rate[axis] = in.voltage_rate[axis];
        }
        const Vec3* parts[5] = {&in.base.attitude, &in.base.attitude_rate, &in.base.attitude_accel,
                                &in.base.velocity_a, &in.base.acceleration_a};
        for (int p = 0; p < 5; ++p)
            for (int k = 0; k < 3; ++k) snap.base[3 * p + k] = (*parts[p])[k];
        snap.arc_start_time = in.step_start_time;
        snap.epoch = epoch_;
        snap.at_rest = at_rest_;
        if (integrator_->resumable()) {
            // The one-step methods carry only their step-size controller: the snapshot holds it, and a
            // restored copy continues exactly as this instance does.
            snap.integrator_running = integrator_running_;
            snap.integrator_memory = integrator_->memory();
        } else {
            // A multistep method's history does not fit in a snapshot: end the integration segment here,
            // so that this instance and a restored copy both restart the integrator at the next step.
            const IntegratorStatistics totals = integrator_->statistics();
            create_integrator();
            integrator_->set_statistics(totals);
            snap.integrator_running = false;
        }
    }
    std::memcpy(buffer, &snap, sizeof snap);
}

GimbalStatus GimbalInstance::restore(const void* buffer) {
    Snapshot snap;
    std::memcpy(&snap, buffer, sizeof snap);
    if (snap.magic != kSnapshotMagic || snap.version != kSnapshotVersion) {
        return refuse(GIMBAL_ERROR, "fmi2SetFMUstate: the state was not saved by this version of Gimbal2Axis");
    }
    std::copy(snap.reals, snap.reals + kRealVariableCount, reals_);
    std::copy(snap.integers, snap.integers + kIntegerVariableCount, integers_);
    std::copy(snap.booleans, snap.booleans + kBooleanVariableCount, booleans_);
    preview_current_ = false;
    integrator_.reset();
    system_.reset();
    time_ = snap.time;
    std::copy(snap.state, snap.state + kMaxStateSize, state_);
    voltage_rate_[0] = snap.pending_voltage_rate[0];
    voltage_rate_[1] = snap.pending_voltage_rate[1];
    if (!snap.initialized) return GIMBAL_OK;

    std::string error;
    if (!build_parameters(params_, error)) return refuse(GIMBAL_ERROR, "fmi2SetFMUstate: " + error);
    system_ = std::make_unique<GimbalHybridSystem>(params_);
    StepInputs in;
    for (int axis = 0; axis < 2; ++axis) {
        in.voltage[axis] = snap.voltage[axis];
        in.commanded_voltage[axis] = snap.commanded_voltage[axis];
        in.voltage_rate[axis] = snap.voltage_rate[axis];
    }
    Vec3* parts[5] = {&in.base.attitude, &in.base.attitude_rate, &in.base.attitude_accel, &in.base.velocity_a,
                      &in.base.acceleration_a};
    for (int p = 0; p < 5; ++p)
        for (int k = 0; k < 3; ++k) (*parts[p])[k] = snap.base[3 * p + k];
    in.step_start_time = snap.arc_start_time;
    epoch_ = snap.epoch;
    system_->set_inputs(in);
    system_->restore(snap.modes, snap.counters);
    create_integrator();
    if (snap.integrator_running && integrator_->resumable()) {
        if (!integrator_->resume(model_time(time_), state_, snap.integrator_memory)) {
            return refuse(GIMBAL_ERROR, "fmi2SetFMUstate: the integrator cannot continue from the saved state (" +
                                            last_integrator_error_ + ")");
        }
        integrator_running_ = true;
        at_rest_ = snap.at_rest;
    }
    integrator_->set_statistics(snap.statistics);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::do_step(double current_time, double step_size) {
    if (!integrator_) return refuse(GIMBAL_ERROR, "fmi2DoStep: the instance is not initialized");
    const GimbalStatus base_status = check_fixed_base("fmi2DoStep");
    if (base_status != GIMBAL_OK) return base_status;
    const double step_start = model_time(current_time);
    const double step_end = model_time(current_time + step_size);
    StepInputs inputs = read_step_inputs(step_start);
    const StepInputs& running = system_->inputs();
    // The right-hand side is continuous across the step boundary only if the held voltages are the same
    // and the base motion continues the running constant-acceleration arc; otherwise restart.
    const bool continuous = integrator_running_ && continues(running, inputs, step_start) &&
                            same_base_motion(inputs.base, running.base.advanced(step_start - running.step_start_time));
    double step_start_state[kMaxStateSize];
    std::copy(state_, state_ + kMaxStateSize, step_start_state);
    const Modes step_start_modes = system_->modes();
    const EventCounters step_start_counters = system_->counters();

    if (continuous && at_rest_ && inputs.voltage_rate[0] == 0.0 && inputs.voltage_rate[1] == 0.0) {
        time_ = current_time + step_size;  // outputs cannot change either
        return GIMBAL_OK;
    }
    at_rest_ = false;
    if (continuous) {
        // The right-hand side does not jump: keep the integrator's history, follow the new ramps.
        if (inputs.voltage_rate[0] != running.voltage_rate[0] || inputs.voltage_rate[1] != running.voltage_rate[1] ||
            inputs.commanded_voltage[0] != running.commanded_voltage[0] ||
            inputs.commanded_voltage[1] != running.commanded_voltage[1]) {
            inputs.base = running.base.advanced(step_start - running.step_start_time);
            system_->set_inputs(inputs);
            if (!integrator_->inputs_changed(step_start, state_)) {
                return refuse(GIMBAL_ERROR, "fmi2DoStep: the integrator could not take the new inputs (" +
                                                last_integrator_error_ + ")");
            }
        }
    } else {
        system_->set_inputs(inputs);
        // New inputs may cross a switching surface at once (e.g. the voltage reverses while limited).
        system_->update_modes(step_start, state_, nullptr);
        if (!integrator_->restart(step_start, state_)) {
            return refuse(GIMBAL_ERROR, "fmi2DoStep: the integrator could not be restarted");
        }
    }
    last_integrator_error_.clear();
    if (!integrator_->advance(step_end, state_)) {
        std::copy(step_start_state, step_start_state + kMaxStateSize, state_);
        system_->restore(step_start_modes, step_start_counters);
        integrator_running_ = false;
        std::ostringstream s;
        s.precision(17);
        s << "fmi2DoStep: integration from t = " << current_time << " over h = " << step_size << " failed ("
          << last_integrator_error_ << "); state rolled back to t = " << current_time;
        return refuse(GIMBAL_DISCARD, s.str());
    }
    integrator_running_ = true;
    voltage_rate_[0] = voltage_rate_[1] = 0.0;  // input derivatives hold for one step
    at_rest_ = system_->at_rest(step_end, state_);
    double previous_reals[kRealVariableCount];
    int previous_integers[kIntegerVariableCount];
    std::copy(reals_, reals_ + kRealVariableCount, previous_reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, previous_integers);
    time_ = current_time + step_size;
    publish_outputs();
    // Finite states can still give non-finite outputs from absurd inputs (a base velocity of 1e300
    // makes the kinetic energy overflow): refuse rather than hand out garbage.
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(reals_[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << "fmi2DoStep: " << kRealVariables[vr].name << " = " << reals_[vr] << " at t = " << time_
          << ": an input or parameter lies beyond what the model can represent; state rolled back to t = "
          << current_time;
        std::copy(step_start_state, step_start_state + kMaxStateSize, state_);
        system_->restore(step_start_modes, step_start_counters);
        std::copy(previous_reals, previous_reals + kRealVariableCount, reals_);
        std::copy(previous_integers, previous_integers + kIntegerVariableCount, integers_);
        integrator_running_ = false;
        time_ = current_time;
        return refuse(GIMBAL_ERROR, s.str());
    }
    return GIMBAL_OK;
}

}  // namespace gimbal
