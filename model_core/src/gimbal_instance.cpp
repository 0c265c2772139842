#include "gimbal/gimbal_instance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>

#include "gimbal/parameter_validation.hpp"
#include "gimbal/snapshot.hpp"
#include "gimbal/variable_groups.hpp"

namespace gimbal {
namespace {

// The real-time method's bounds (solver.method = 7, docs/real_time.md): chosen by measurement.
constexpr int kRealTimeEventIterations = 10;        // Illinois iterations per located mode change
constexpr int kRealTimeModeChangesPerSubstep = 8;   // located mode changes per substep, on average
constexpr double kRealTimeContactResolution = 1.0;  // largest omega h of a gear's contact oscillation

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

// A base motion as the 15 numbers of a snapshot: attitude, rate, acceleration, v_a, a_a.
void write_base_motion(const BaseMotion& base, double* values) {
    const Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                            &base.acceleration_a};
    for (int p = 0; p < 5; ++p)
        for (int k = 0; k < 3; ++k) values[3 * p + k] = (*parts[p])[k];
}

BaseMotion read_base_motion(const double* values) {
    BaseMotion base;
    Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                      &base.acceleration_a};
    for (int p = 0; p < 5; ++p)
        for (int k = 0; k < 3; ++k) (*parts[p])[k] = values[3 * p + k];
    return base;
}

bool same_base_motion(const BaseMotion& a, const BaseMotion& b) {
    return a.attitude == b.attitude && a.attitude_rate == b.attitude_rate && a.attitude_accel == b.attitude_accel &&
           a.velocity_a == b.velocity_a && a.acceleration_a == b.acceleration_a;
}

// The hybrid system keeps a reference to the instance's parameters, so new ones go in place before
// it is built; this puts the previous ones back unless the new run is committed.
class ParameterSwap {
public:
    ParameterSwap(ModelParameters& current, const ModelParameters& next) : current_(current), previous_(current) {
        current_ = next;
    }
    ~ParameterSwap() {
        if (!committed_) current_ = previous_;
    }
    void commit() { committed_ = true; }

private:
    ModelParameters& current_;
    ModelParameters previous_;
    bool committed_ = false;
};

}  // namespace

GimbalInstance::GimbalInstance(Logger logger, LogFilter filter)
    : logger_(std::move(logger)), log_filter_(std::move(filter)) {
    event_settings_.events_logged = [this] { return log_filter_("logEvents"); };
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
    clock_ = 0.0;
    master_tolerance_defined_ = false;
    master_tolerance_ = 0.0;
    rtol_set_ = false;
    steps_over_budget_ = 0;
    inputs_stale_ = outputs_stale_ = true;
    decided_here_ = false;
    std::fill(reference_guards_, reference_guards_ + kIndicatorCount, 0.0);
    std::fill(decided_side_, decided_side_ + kIndicatorCount, static_cast<std::int8_t>(0));
    chattering_ = ChatteringMemory{};
    zeno_holds_ = 0;
}

GimbalStatus GimbalInstance::refuse(GimbalStatus status, const std::string& message) const {
    logger_(status, status == GIMBAL_DISCARD ? "logStatusDiscard" : "logStatusError", message);
    return status;
}

GimbalStatus GimbalInstance::set_real(unsigned vr, double value) { return set_reals(&vr, 1, &value); }

GimbalStatus GimbalInstance::set_reals(const unsigned* vr, std::size_t count, const double* values) {
    // All checks first: a refused call sets nothing.
    for (std::size_t k = 0; k < count; ++k) {
        if (vr[k] >= kRealVariableCount)
            return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr[k]) + " is not a Real variable");
        if (!std::isfinite(values[k])) {
            std::ostringstream s;
            s << kRealVariables[vr[k]].name << " = " << values[k] << " refused: values must be finite";
            return refuse(GIMBAL_ERROR, s.str());
        }
    }
    bool input_set = false;
    for (std::size_t k = 0; k < count; ++k) {
        const unsigned variable = vr[k];
        reals_[variable] = values[k];
        input_set |= kRealVariables[variable].causality == Causality::input;
        if (variable == vr_solver_rtol) rtol_set_ = true;
        // A new voltage starts a new ramp: its derivative must be given again.
        if (variable == vr_u_R1) voltage_rate_[0] = 0.0;
        if (variable == vr_u_R2) voltage_rate_[1] = 0.0;
    }
    preview_current_ = false;
    if (input_set) {
        inputs_stale_ = outputs_stale_ = true;
        decided_here_ = false;
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_input_derivative(unsigned vr, int order, double value) {
    const int axis = vr == vr_u_R1 ? 0 : (vr == vr_u_R2 ? 1 : -1);
    if (axis < 0) {
        const char* name = vr < kRealVariableCount ? kRealVariables[vr].name : "(no Real variable)";
        return refuse(GIMBAL_ERROR, std::string(name) +
                                        " takes no derivative: only u_R1 and u_R2 do (the base inputs carry their own "
                                        "rates and accelerations)");
    }
    if (order != 1) {
        return refuse(GIMBAL_ERROR, "order " + std::to_string(order) + " for " +
                                        kRealVariables[vr].name + " refused: only first derivatives are used");
    }
    if (!std::isfinite(value)) {
        return refuse(GIMBAL_ERROR, std::string("the derivative of ") +
                                        kRealVariables[vr].name + " must be finite");
    }
    voltage_rate_[axis] = value;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_real(unsigned vr, double& value) {
    if (vr >= kRealVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Real variable");
    }
    if (!system_ && kRealVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs(kRealVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    if (system_ && continuous_time_ && outputs_stale_) {
        const GimbalStatus status = publish_continuous_time_outputs();
        if (status != GIMBAL_OK) return status;
    }
    value = reals_[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_integer(unsigned vr, int value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    integers_[vr] = value;
    preview_current_ = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_integer(unsigned vr, int& value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    if (!system_ && kIntegerVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs(kIntegerVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    if (system_ && continuous_time_ && outputs_stale_) {
        const GimbalStatus status = publish_continuous_time_outputs();
        if (status != GIMBAL_OK) return status;
    }
    value = integers_[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_boolean(unsigned vr, bool value) {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Boolean variable");
    }
    booleans_[vr] = value;
    preview_current_ = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_boolean(unsigned vr, bool& value) const {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Boolean variable");
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
    inputs.base.attitude = read_vector(reals_, kBaseMotion.attitude);
    inputs.base.attitude_rate = read_vector(reals_, kBaseMotion.attitude_rate);
    inputs.base.attitude_accel = read_vector(reals_, kBaseMotion.attitude_accel);
    inputs.base.velocity_a = read_vector(reals_, kBaseMotion.velocity_a);
    inputs.base.acceleration_a = read_vector(reals_, kBaseMotion.acceleration_a);
    inputs.step_start_time = step_start;
    return inputs;
}

void GimbalInstance::publish_outputs() {
    const Modes& modes = system_->modes();
    const double now = clock_;
    const Dynamics& dynamics = system_->dynamics_at(now, state_);
    const ModelOutputs out = outputs_from(params_, system_->inputs(), system_->base_kinematics_at_time(now), now, dynamics);
    for (int k = 0; k < 4; ++k) {
        reals_[kBodyAngle[k]] = out.full.angle[k];
        reals_[kBodyRate[k]] = out.full.rate[k];
    }
    reals_[vr_i_R1] = out.full.current[0];
    reals_[vr_i_R2] = out.full.current[1];
    reals_[vr_theta_b1] = out.full.backlash[0];
    reals_[vr_theta_b2] = out.full.backlash[1];
    reals_[vr_T_E1] = out.shaft_torque[0];
    reals_[vr_T_E2] = out.shaft_torque[1];
    for (int k = 0; k < 3; ++k) reals_[kPayloadAngularVelocity[k]] = out.payload_angular_velocity[k];
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
    double integrated[kMaxStateSize], derivative[kContinuousStateCount];
    if (state_derivative(params_, dynamics, integrated)) {
        full_state_derivative(dynamics, integrated, derivative);
        for (int k = 0; k < kContinuousStateCount; ++k) reals_[kStateDerivatives[k]] = derivative[k];
    } else {
        for (int k = 0; k < kContinuousStateCount; ++k)
            reals_[kStateDerivatives[k]] = std::numeric_limits<double>::quiet_NaN();
    }

    integers_[vi_gear1_contact] = modes.gear_contact[0];
    integers_[vi_gear2_contact] = modes.gear_contact[1];
    integers_[vi_motor1_limited] = modes.motor_limited[0];
    integers_[vi_motor2_limited] = modes.motor_limited[1];
    for (int body = 0; body < 4; ++body)
        integers_[kBodyStickSlip[body]] = friction_mode_indicator(modes.friction[body], out.full.rate[body]);
    const EventCounters& events = system_->counters();
    const IntegratorStatistics stats = integrator_->statistics();
    reals_[vr_events_last_time] = epoch_ + events.last_event_time;
    integers_[vi_events_total] = static_cast<int>(events.total);
    integers_[vi_events_backlash1] = static_cast<int>(events.backlash[0]);
    integers_[vi_events_backlash2] = static_cast<int>(events.backlash[1]);
    integers_[vi_events_current_limit1] = static_cast<int>(events.current_limit[0]);
    integers_[vi_events_current_limit2] = static_cast<int>(events.current_limit[1]);
    integers_[vi_events_stick_slip] = static_cast<int>(events.stick_slip);
    integers_[vi_events_zeno_guard] = static_cast<int>(std::min<std::int64_t>(stats.zeno_holds + zeno_holds_, 2147483647));
    integers_[vi_solver_states] = params_.layout.size;
    integers_[vi_solver_steps] = static_cast<int>(std::min<std::int64_t>(stats.steps, 2147483647));
    integers_[vi_solver_rhs_evaluations] = static_cast<int>(std::min<std::int64_t>(stats.rhs_evaluations, 2147483647));
    integers_[vi_solver_jacobian_evaluations] = static_cast<int>(std::min<std::int64_t>(stats.jacobian_evaluations, 2147483647));
    integers_[vi_solver_method_switches] = static_cast<int>(std::min<std::int64_t>(stats.method_switches, 2147483647));
}

void GimbalInstance::load_start_state() {
    const StateLayout& layout = params_.layout;
    std::fill(state_, state_ + kMaxStateSize, 0.0);
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        state_[layout.angle_slot[body]] = reals_[kBodyAngle[body]];
        state_[layout.rate_slot[body]] = reals_[kBodyRate[body]];
    }
    const RealVariable currents[2] = {vr_i_R1, vr_i_R2}, backlash[2] = {vr_theta_b1, vr_theta_b2};
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) state_[layout.current_slot[axis]] = reals_[currents[axis]];
        if (layout.backlash_slot[axis] >= 0) state_[layout.backlash_slot[axis]] = reals_[backlash[axis]];
        const int rotor = rotor_index(axis), load = load_index(axis);
        const double ratio = params_.gear[axis].ratio;
        if (!layout.independent(rotor) && (reals_[kBodyAngle[rotor]] != ratio * reals_[kBodyAngle[load]] ||
                                           reals_[kBodyRate[rotor]] != ratio * reals_[kBodyRate[load]])) {
            logger_(GIMBAL_WARNING, "logStatusWarning",
                    std::string("rigid gear ") + std::to_string(axis + 1) + ": the start values of " +
                        kRealVariables[kBodyAngle[rotor]].name + " and its rate are replaced by N times the load's");
        }
    }
}

GimbalStatus GimbalInstance::check_fixed_base() const {
    if (!params_.fidelity.fixed_base) return GIMBAL_OK;
    for (RealVariable vr : kBaseInputs) {
        if (reals_[vr] != 0.0) {
            std::ostringstream s;
            s << kRealVariables[vr].name << " = " << reals_[vr]
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

std::unique_ptr<HybridIntegrator> GimbalInstance::make_integrator(GimbalHybridSystem& system,
                                                                  const ModelParameters& params) {
    IntegratorSettings settings;
    settings.relative_tolerance = params.relative_tolerance;
    settings.absolute_tolerance = params.absolute_tolerance;
    settings.max_steps = params.max_steps;
    settings.method = static_cast<IntegrationMethod>(params.method);
    if (settings.method == IntegrationMethod::real_time) {
        settings.substeps = params.substeps;
        settings.event_iterations = kRealTimeEventIterations;
        settings.mode_changes_per_step = kRealTimeModeChangesPerSubstep * params.substeps;
    }
    settings.events_logged = [this] { return log_filter_("logEvents"); };
    return HybridIntegrator::create(
        system, settings,
        [this](const std::string& message) {
            last_integrator_error_ = message;
            logger_(GIMBAL_WARNING, "logSolver", message);
        },
        [this](const std::string& message) { logger_(GIMBAL_OK, "logEvents", message); });
}

void GimbalInstance::create_integrator() {
    integrator_ = make_integrator(*system_, params_);
    integrator_running_ = false;
}

void GimbalInstance::set_master_tolerance(bool defined, double tolerance) {
    master_tolerance_defined_ = defined;
    master_tolerance_ = defined ? tolerance : 0.0;
}

// The FMI standard gives the master's tolerance to the FMU's integrator; solver.rtol, when the user
// set it, says more precisely what this FMU should do.
void GimbalInstance::apply_master_tolerance() {
    if (!master_tolerance_defined_) return;
    std::ostringstream s;
    s.precision(17);
    if (rtol_set_) {
        if (master_tolerance_ != reals_[vr_solver_rtol]) {
            s << "the master's tolerance = " << master_tolerance_ << " is not used: solver.rtol = "
              << reals_[vr_solver_rtol] << " was set explicitly";
            logger_(GIMBAL_OK, "logSolver", s.str());
        }
        return;
    }
    if (!(master_tolerance_ > 0.0 && master_tolerance_ < 1.0)) {
        s << "the master's tolerance = " << master_tolerance_ << " is ignored (a relative tolerance lies in "
          << "(0, 1)); solver.rtol keeps " << reals_[vr_solver_rtol];
        logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
        return;
    }
    reals_[vr_solver_rtol] = master_tolerance_;
    s << "solver.rtol = " << master_tolerance_ << ", the tolerance the master gave (set solver.rtol to override)";
    logger_(GIMBAL_OK, "logSolver", s.str());
}

GimbalStatus GimbalInstance::preview_outputs(const char* name) {
    if (preview_current_) return GIMBAL_OK;
    std::string error;
    ModelParameters params;
    if (!build_parameters(params, error)) {
        return refuse(GIMBAL_ERROR, std::string(name) +
                                        " cannot be computed from the current values: " + error);
    }
    // Built aside and committed only at the end: a failure (out of memory) leaves nothing half-made.
    ParameterSwap swap(params_, params);
    auto system = std::make_unique<GimbalHybridSystem>(params_);
    auto integrator = make_integrator(*system, params_);
    swap.commit();
    map_integrated_states();
    load_start_state();
    epoch_ = time_;
    clock_ = 0.0;
    system->hold_inputs_at_any_time(continuous_time_);
    system->set_inputs(read_step_inputs(0.0));
    system->update_modes(0.0, state_, nullptr);
    system_ = std::move(system);
    integrator_ = std::move(integrator);
    publish_outputs();
    // The continuous-time interface may ask for the states and indicators during initialization.
    full_state_vector(system_->dynamics_at(0.0, state_), preview_states_);
    system_->event_indicators(0.0, state_, preview_indicators_);
    // The preview must not count as initialization: forget the integrator again.
    integrator_.reset();
    system_.reset();
    preview_current_ = true;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::initialize(double start_time) {
    const double rtol_before = reals_[vr_solver_rtol];
    apply_master_tolerance();
    std::string error;
    ModelParameters params;
    if (!build_parameters(params, error)) {
        reals_[vr_solver_rtol] = rtol_before;
        return refuse(GIMBAL_ERROR, error);
    }
    std::unique_ptr<GimbalHybridSystem> system;
    std::unique_ptr<HybridIntegrator> integrator;
    ParameterSwap swap(params_, params);
    try {
        system = std::make_unique<GimbalHybridSystem>(params_);
        integrator = make_integrator(*system, params_);
    } catch (...) {
        reals_[vr_solver_rtol] = rtol_before;
        throw;
    }
    const GimbalStatus base_status = check_fixed_base();
    if (base_status != GIMBAL_OK) {
        reals_[vr_solver_rtol] = rtol_before;
        return base_status;
    }
    swap.commit();
    map_integrated_states();
    load_start_state();
    time_ = start_time;
    epoch_ = start_time;
    clock_ = 0.0;
    system->hold_inputs_at_any_time(continuous_time_);
    system->set_inputs(read_step_inputs(0.0));
    system->update_modes(0.0, state_, nullptr);
    EventCounters none;
    none.last_event_time = 0.0;
    system->restore(system->modes(), none);  // the initial choice of modes is not an event
    system_ = std::move(system);
    integrator_ = std::move(integrator);
    integrator_running_ = false;
    steps_over_budget_ = 0;
    // The continuous-time interface measures the first crossings against the guards of the start.
    system_->event_functions(0.0, state_, reference_guards_);
    std::fill(decided_side_, decided_side_ + kIndicatorCount, static_cast<std::int8_t>(0));
    inputs_stale_ = decided_here_ = false;
    chattering_ = ChatteringMemory{};
    zeno_holds_ = 0;
    publish_outputs();
    outputs_stale_ = false;
    return GIMBAL_OK;
}

std::size_t GimbalInstance::snapshot_size() { return snapshot_bytes(); }

void GimbalInstance::save(void* buffer) {
    SnapshotContent snap;
    std::memset(static_cast<void*>(&snap), 0, sizeof snap);
    std::copy(reals_, reals_ + kRealVariableCount, snap.reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, snap.integers);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) snap.booleans[vr] = booleans_[vr] ? 1 : 0;
    snap.initialized = integrator_ != nullptr;
    snap.rtol_set = rtol_set_;
    snap.master_tolerance_defined = master_tolerance_defined_;
    snap.master_tolerance = master_tolerance_;
    snap.time = time_;
    snap.clock = clock_;
    std::copy(state_, state_ + kMaxStateSize, snap.state);
    snap.pending_voltage_rate[0] = voltage_rate_[0];
    snap.pending_voltage_rate[1] = voltage_rate_[1];
    snap.epoch = epoch_;
    snap.integrator_memory = IntegratorMemory{};
    snap.continuous_time = continuous_time_;
    snap.decided_here = decided_here_;
    std::copy(decided_side_, decided_side_ + kIndicatorCount, snap.decided_side);
    std::copy(reference_guards_, reference_guards_ + kIndicatorCount, snap.reference_guards);
    snap.last_event_time = chattering_.last_event_time;
    snap.dwell_until = chattering_.dwell_until;
    snap.rapid_events = chattering_.rapid_events;
    snap.zeno_holds = zeno_holds_;
    if (snap.initialized) save_run(snap);
    encode_snapshot(snap, buffer);
}

// The parts of a snapshot only an initialized instance has: modes, counters, the running inputs and
// the integrator.
void GimbalInstance::save_run(SnapshotContent& snap) {
    snap.modes = system_->modes();
    snap.counters = system_->counters();
    snap.statistics = integrator_->statistics();
    const StepInputs& in = system_->inputs();
    for (int axis = 0; axis < 2; ++axis) {
        snap.voltage[axis] = in.voltage[axis];
        snap.commanded_voltage[axis] = in.commanded_voltage[axis];
        snap.voltage_rate[axis] = in.voltage_rate[axis];
    }
    write_base_motion(in.base, snap.base);
    snap.arc_start_time = in.step_start_time;
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

GimbalStatus GimbalInstance::read_snapshot(const void* buffer, SnapshotContent& snap) const {
    const bool format_ok = decode_snapshot(buffer, snap);
    const std::string reason = check_snapshot_content(snap, format_ok, continuous_time_);
    if (!reason.empty()) return refuse(GIMBAL_ERROR, "the FMU state is refused: " + reason);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::check_snapshot(const void* buffer, bool& initialized) const {
    SnapshotContent snap;
    const GimbalStatus status = read_snapshot(buffer, snap);
    if (status != GIMBAL_OK) return status;
    initialized = snap.initialized != 0;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::restore(const void* buffer) {
    SnapshotContent snap;
    const GimbalStatus checked = read_snapshot(buffer, snap);
    if (checked != GIMBAL_OK) return checked;
    const bool initialized = snap.initialized != 0;

    // Everything is built aside first: a refusal (or running out of memory) leaves the instance as it was.
    std::unique_ptr<GimbalHybridSystem> system;
    std::unique_ptr<HybridIntegrator> integrator;
    ParameterSwap swap(params_, params_);
    if (initialized) {
        const GimbalStatus built = rebuild_run(snap, system, integrator);
        if (built != GIMBAL_OK) return built;
    }

    std::copy(snap.reals, snap.reals + kRealVariableCount, reals_);
    std::copy(snap.integers, snap.integers + kIntegerVariableCount, integers_);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) booleans_[vr] = snap.booleans[vr] != 0;
    preview_current_ = false;
    rtol_set_ = snap.rtol_set != 0;
    master_tolerance_defined_ = snap.master_tolerance_defined != 0;
    master_tolerance_ = snap.master_tolerance;
    time_ = snap.time;
    epoch_ = snap.epoch;
    clock_ = snap.clock;
    std::copy(snap.state, snap.state + kMaxStateSize, state_);
    voltage_rate_[0] = snap.pending_voltage_rate[0];
    voltage_rate_[1] = snap.pending_voltage_rate[1];
    decided_here_ = snap.decided_here != 0;
    std::copy(snap.decided_side, snap.decided_side + kIndicatorCount, decided_side_);
    std::copy(snap.reference_guards, snap.reference_guards + kIndicatorCount, reference_guards_);
    chattering_.last_event_time = snap.last_event_time;
    chattering_.dwell_until = snap.dwell_until;
    chattering_.rapid_events = snap.rapid_events;
    zeno_holds_ = snap.zeno_holds;
    inputs_stale_ = outputs_stale_ = true;
    integrator_running_ = initialized && snap.integrator_running && integrator->resumable();
    at_rest_ = integrator_running_ && snap.at_rest;
    swap.commit();
    if (initialized) map_integrated_states();
    system_ = std::move(system);
    integrator_ = std::move(integrator);
    return GIMBAL_OK;
}

// The hybrid system and the integrator of a checked snapshot's run, its parameters put in place (the
// caller's ParameterSwap puts the previous ones back unless it commits).
GimbalStatus GimbalInstance::rebuild_run(const SnapshotContent& snap, std::unique_ptr<GimbalHybridSystem>& system,
                                         std::unique_ptr<HybridIntegrator>& integrator) {
    ModelParameters params;
    std::string error;
    if (!snapshot_parameters(snap, params, error)) return refuse(GIMBAL_ERROR, error);
    params_ = params;
    system = std::make_unique<GimbalHybridSystem>(params_);
    system->hold_inputs_at_any_time(continuous_time_);
    StepInputs in;
    for (int axis = 0; axis < 2; ++axis) {
        in.voltage[axis] = snap.voltage[axis];
        in.commanded_voltage[axis] = snap.commanded_voltage[axis];
        in.voltage_rate[axis] = snap.voltage_rate[axis];
    }
    in.base = read_base_motion(snap.base);
    in.step_start_time = snap.arc_start_time;
    system->set_inputs(in);
    system->restore(snap.modes, snap.counters);
    integrator = make_integrator(*system, params_);
    if (snap.integrator_running && integrator->resumable() &&
        !integrator->resume(snap.clock, snap.state, snap.integrator_memory)) {
        return refuse(GIMBAL_ERROR, "the integrator cannot continue from the saved state (" +
                                        last_integrator_error_ + ")");
    }
    integrator->set_statistics(snap.statistics);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::do_step(double current_time, double step_size) {
    double reached = 0.0;
    return advance_step(current_time, step_size, nullptr, reached);
}

GimbalStatus GimbalInstance::do_step_until_mode_change(double current_time, double step_size, double& reached) {
    return advance_step(current_time, step_size, &reached, reached);
}

GimbalStatus GimbalInstance::advance_step(double current_time, double step_size, double* early, double& reached) {
    if (!integrator_) return refuse(GIMBAL_ERROR, "the instance is not initialized");
    if (continuous_time_) return refuse(GIMBAL_ERROR, "the instance serves the continuous-time interface");
    StepStart start;
    std::copy(state_, state_ + kMaxStateSize, start.state);
    start.modes = system_->modes();
    start.counters = system_->counters();
    start.work = integrator_->statistics();
    start.time = time_;
    start.clock = clock_;
    GimbalStatus status;
    try {
        status = integrate_step(current_time, step_size, start, early);
    } catch (...) {
        // A C++ exception (out of memory while formatting a message, say) must not leave a half-taken step.
        roll_back(start);
        throw;
    }
    reached = time_;
    if (status != GIMBAL_OK) return status;
    return report_step_work(step_size, start.work, start.counters);
}

void GimbalInstance::roll_back(const StepStart& start) {
    std::copy(start.state, start.state + kMaxStateSize, state_);
    system_->restore(start.modes, start.counters);
    if (start.outputs_saved) {
        std::copy(start.reals, start.reals + kRealVariableCount, reals_);
        std::copy(start.integers, start.integers + kIntegerVariableCount, integers_);
    }
    time_ = start.time;
    clock_ = start.clock;
    integrator_running_ = false;
    at_rest_ = false;
}

// A step that costs far more than the model usually needs is reported once in a while (the first
// time, then at the 2nd, 4th, 8th, ... such step) with what most likely makes it expensive.
GimbalStatus GimbalInstance::report_step_work(double step_size, const IntegratorStatistics& before,
                                              const EventCounters& events_before) {
    const IntegratorStatistics after = integrator_->statistics();
    const std::int64_t rhs = after.rhs_evaluations - before.rhs_evaluations;
    if (rhs <= kStepWorkBudget) return GIMBAL_OK;
    ++steps_over_budget_;
    if ((steps_over_budget_ & (steps_over_budget_ - 1)) != 0) return GIMBAL_WARNING;
    const std::int64_t steps = after.steps - before.steps, rejected = after.rejected_steps - before.rejected_steps;
    const std::int64_t events = system_->counters().total - events_before.total;
    const auto method = static_cast<IntegrationMethod>(params_.method);
    std::ostringstream s;
    s.precision(6);
    s << "the step to t = " << time_ << " (h = " << step_size << ") took " << rhs
      << " right-hand-side evaluations (budget " << kStepWorkBudget << "), " << steps << " steps, " << rejected
      << " rejected, " << events << " mode changes";
    if (events > steps / 4) {
        s << ". Likely cause: the switching elements change mode " << events
          << " times in one step (backlash impacts of a stiff gear, stick-slip or limiter chatter)";
    } else if (method == IntegrationMethod::dormand_prince || method == IntegrationMethod::explicit_runge_kutta) {
        s << ". Likely cause: the problem is stiff (a stiff gear k_s, a small motor inductance L) and solver.method = "
          << params_.method << " is explicit: its steps are held by stability, not accuracy; solver.method = 4 or 6 "
          << "handles stiffness";
    } else if (rejected > steps / 2) {
        s << ". Likely cause: most steps are rejected (discontinuities the integrator has to resolve)";
    } else {
        s << ". Likely cause: solver.rtol = " << params_.relative_tolerance << " and solver.atol = "
          << params_.absolute_tolerance << " ask for more accuracy than the step affords";
    }
    if (steps_over_budget_ > 1) s << " [" << steps_over_budget_ << " steps over budget so far]";
    logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
    return GIMBAL_WARNING;
}

// Fixed L-stable steps damp an oscillation they do not resolve instead of following it; at a gear's
// contact that turns bounces into sticking and, with the contact's onset located only to the
// substep's precision, feeds energy in (docs/real_time.md has the measurements). The contact
// oscillation of each compliant gear, the load against the rotor reflected through N^2, must be
// resolved by the substeps: omega h <= kRealTimeContactResolution.
GimbalStatus GimbalInstance::check_real_time_resolution(double step_size) {
    const double substep = step_size / params_.substeps;
    const Dynamics& dynamics = system_->dynamics_at(clock_, state_);
    double contact_frequency[2] = {0.0, 0.0};
    double needed = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params_.gear[axis];
        if (params_.fidelity.gear[axis] == GearModel::rigid || gear.stiffness == 0.0) continue;
        const double load_inertia = dynamics.reduced_mass(load_index(axis), load_index(axis));
        const double rotor_inertia = dynamics.reduced_mass(rotor_index(axis), rotor_index(axis));
        contact_frequency[axis] =
            std::sqrt(gear.stiffness * (1.0 / load_inertia + 1.0 / (gear.ratio * gear.ratio * rotor_inertia)));
        if (contact_frequency[axis] * substep > kRealTimeContactResolution)
            needed = std::max(needed, std::ceil(contact_frequency[axis] * step_size / kRealTimeContactResolution));
    }
    if (needed == 0.0) return GIMBAL_OK;  // every doStep: nothing formatted
    std::ostringstream s;
    s.precision(4);
    s << "the real-time method cannot resolve ";
    const char* separator = "";
    for (int axis = 0; axis < 2; ++axis) {
        if (!(contact_frequency[axis] * substep > kRealTimeContactResolution)) continue;
        s << separator << "gear" << axis + 1 << "'s contact oscillation (" << contact_frequency[axis]
          << " rad/s at k_s = " << params_.gear[axis].stiffness
          << " N.m/rad: omega h = " << contact_frequency[axis] * substep << ")";
        separator = "; ";
    }
    s << " with substeps of " << substep << " s (omega h at most " << kRealTimeContactResolution
      << "): set solver.substeps >= " << static_cast<long long>(needed)
      << " for this communication step, or make a gear rigid (gear<k>.model = 0) if the scene does not need its shaft";
    return refuse(GIMBAL_ERROR, s.str());
}

GimbalStatus GimbalInstance::integrate_step(double current_time, double step_size, StepStart& start, double* early) {

    const GimbalStatus base_status = check_fixed_base();
    if (base_status != GIMBAL_OK) return base_status;
    if (params_.method == static_cast<int>(IntegrationMethod::real_time)) {
        const GimbalStatus resolution = check_real_time_resolution(step_size);
        if (resolution != GIMBAL_OK) return resolution;
    }
    // From the instance's own clock (the host's current_time was checked against its time by the
    // interface): any start time gives the same model times, bit for bit.
    const double step_start = clock_;
    const double step_end = clock_ + step_size;
    StepInputs inputs = read_step_inputs(step_start);
    const StepInputs& running = system_->inputs();
    // The right-hand side is continuous across the step boundary only if the held voltages are the same
    // and the base motion continues the running constant-acceleration arc; otherwise restart.
    const bool continuous = integrator_running_ && continues(running, inputs, step_start) &&
                            same_base_motion(inputs.base, running.base.advanced(step_start - running.step_start_time));
    if (continuous && at_rest_ && inputs.voltage_rate[0] == 0.0 && inputs.voltage_rate[1] == 0.0) {
        clock_ = step_end;
        time_ = epoch_ + clock_;  // outputs cannot change either
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
                return refuse(GIMBAL_ERROR, "the integrator could not take the new inputs (" +
                                                last_integrator_error_ + ")");
            }
        }
    } else {
        system_->set_inputs(inputs);
        // New inputs may cross a switching surface at once (e.g. the voltage reverses while limited).
        system_->update_modes(step_start, state_, nullptr);
        if (!integrator_->restart(step_start, state_)) {
            return refuse(GIMBAL_ERROR, "the integrator could not be restarted");
        }
    }
    last_integrator_error_.clear();
    double reached_model_time = step_end;
    const bool advanced = early != nullptr ? integrator_->advance_until_mode_change(step_end, state_, reached_model_time)
                                           : integrator_->advance(step_end, state_);
    if (!advanced) {
        roll_back(start);
        std::ostringstream s;
        s.precision(17);
        s << "integration from t = " << current_time << " over h = " << step_size << " failed ("
          << last_integrator_error_ << "); state rolled back to t = " << current_time;
        return refuse(GIMBAL_DISCARD, s.str());
    }
    integrator_running_ = true;
    const bool ended_early = early != nullptr && reached_model_time < step_end;
    // Only now is there anything to undo in the published values (a step at rest publishes nothing).
    std::copy(reals_, reals_ + kRealVariableCount, start.reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, start.integers);
    start.outputs_saved = true;
    if (ended_early) {
        // The inputs as the step carried them to where it ended: a master that sets nothing new
        // continues the same carrier arc and voltage ramps from here.
        const StepInputs& running = system_->inputs();
        const BaseMotion base = running.base.advanced(reached_model_time - running.step_start_time);
        const Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                                &base.acceleration_a};
        const RealVector* vectors[5] = {&kBaseMotion.attitude, &kBaseMotion.attitude_rate, &kBaseMotion.attitude_accel,
                                        &kBaseMotion.velocity_a, &kBaseMotion.acceleration_a};
        if (!params_.fidelity.fixed_base)
            for (int p = 0; p < 5; ++p)
                for (int k = 0; k < 3; ++k) reals_[(*vectors[p])[k]] = (*parts[p])[k];
        const RealVariable voltages[2] = {vr_u_R1, vr_u_R2};
        for (int axis = 0; axis < 2; ++axis)
            if (running.voltage_rate[axis] != 0.0) reals_[voltages[axis]] = ramped_voltage(running, axis, reached_model_time);
        clock_ = reached_model_time;
        time_ = epoch_ + clock_;
        at_rest_ = false;
    } else {
        voltage_rate_[0] = voltage_rate_[1] = 0.0;  // input derivatives hold for one step
        at_rest_ = system_->at_rest(step_end, state_);
        clock_ = step_end;
        time_ = epoch_ + clock_;
    }
    publish_outputs();
    // Finite states can still give non-finite outputs from absurd inputs (a base velocity of 1e300
    // makes the kinetic energy overflow): refuse rather than hand out garbage.
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(reals_[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " = " << reals_[vr] << " at t = " << time_
          << ": an input or parameter lies beyond what the model can represent; state rolled back to t = "
          << current_time;
        roll_back(start);
        return refuse(GIMBAL_ERROR, s.str());
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::linearize(LinearModel& model) {
    if (!system_) return refuse(GIMBAL_ERROR, "linearize: the instance is not initialized (no operating point yet)");
    const double now = clock_;
    StepInputs inputs = read_step_inputs(now);
    inputs.voltage_rate[0] = inputs.voltage_rate[1] = 0.0;
    // The modes the next step would start in: inputs set since the last step may have switched some.
    GimbalHybridSystem selector(params_);
    selector.set_inputs(inputs);
    selector.restore(system_->modes(), system_->counters());
    double state[kMaxStateSize];
    std::copy(state_, state_ + kMaxStateSize, state);
    selector.update_modes(now, state, nullptr);
    gimbal::linearize(params_, inputs, selector.modes(), now, state, model);
    return GIMBAL_OK;
}

}  // namespace gimbal
