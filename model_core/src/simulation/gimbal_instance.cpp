#include "gimbal/simulation/gimbal_instance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>

#include "gimbal/simulation/instance_outputs.hpp"
#include "gimbal/simulation/parameter_swap.hpp"
#include "gimbal/simulation/parameter_validation.hpp"
#include "gimbal/simulation/step_inputs.hpp"
#include "gimbal/model/variable_groups.hpp"

namespace gimbal {

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
    step_work_.reset();
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
    return gimbal::read_step_inputs(params_, reals_, voltage_rate_, step_start);
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
    full_state_vector(params_, system_->dynamics_at(0.0, state_), state_, preview_states_);
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
    step_work_.reset();
    // The continuous-time interface measures the first crossings against the guards of the start.
    system_->event_functions(0.0, state_, reference_guards_);
    std::fill(decided_side_, decided_side_ + kIndicatorCount, static_cast<std::int8_t>(0));
    inputs_stale_ = decided_here_ = false;
    chattering_ = ChatteringMemory{};
    zeno_holds_ = 0;
    publish_outputs();
    outputs_stale_ = false;
    return check_initial_outputs();
}

// The start's outputs, like a step's (check_published_outputs): inputs beyond what the model can
// represent (a carrier rate of 1e300 makes the kinetic energy overflow) are refused, not published.
GimbalStatus GimbalInstance::check_initial_outputs() {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(reals_[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " = " << reals_[vr] << " at the start time " << time_
          << ": an input or parameter lies beyond what the model can represent";
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
