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
#include "gimbal/simulation/parameter_building.hpp"
#include "gimbal/simulation/step_inputs.hpp"
#include "gimbal/model/variable_groups.hpp"

namespace gimbal {

GimbalInstance::GimbalInstance(Logger logger, LogFilter filter)
    : logger_(std::move(logger)), log_filter_(std::move(filter)) {
    event_settings_.events_logged = [this] { return log_filter_("logEvents"); };
    reset();
}

void GimbalInstance::reset() {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) run_.reals[vr] = kRealVariables[vr].start;
    for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) run_.integers[vr] = static_cast<int>(kIntegerVariables[vr].start);
    for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) run_.booleans[vr] = kBooleanVariables[vr].start != 0.0;
    run_.integrator.reset();
    run_.system.reset();
    run_.integrator_running = false;
    run_.preview_current = false;
    run_.at_rest = false;
    run_.voltage_rate[0] = run_.voltage_rate[1] = 0.0;
    std::fill(run_.state, run_.state + kMaxStateSize, 0.0);
    run_.time = 0.0;
    run_.epoch = 0.0;
    run_.clock = 0.0;
    run_.master_tolerance_defined = false;
    run_.master_tolerance = 0.0;
    run_.rtol_set = false;
    run_.step_work.reset();
    run_.inputs_stale = run_.outputs_stale = true;
    run_.decided_here = false;
    std::fill(run_.reference_guards, run_.reference_guards + kIndicatorCount, 0.0);
    std::fill(run_.decided_side, run_.decided_side + kIndicatorCount, static_cast<std::int8_t>(0));
    run_.chattering = ChatteringMemory{};
    run_.zeno_holds = 0;
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
        run_.reals[variable] = values[k];
        input_set |= kRealVariables[variable].causality == Causality::input;
        if (variable == vr_solver_rtol) run_.rtol_set = true;
        // A new voltage starts a new ramp: its derivative must be given again.
        if (variable == vr_u_R1) run_.voltage_rate[0] = 0.0;
        if (variable == vr_u_R2) run_.voltage_rate[1] = 0.0;
    }
    run_.preview_current = false;
    if (input_set) {
        run_.inputs_stale = run_.outputs_stale = true;
        run_.decided_here = false;
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
    run_.voltage_rate[axis] = value;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_real(unsigned vr, double& value) {
    if (vr >= kRealVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Real variable");
    }
    if (!run_.system && kRealVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs(kRealVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    if (!run_.system && kRealVariables[vr].initial == Initial::approx) {
        // Before initialization a rotor reads where it will start (in mesh, or as given); its start
        // value stays what the host set.
        const GimbalStatus status = preview_outputs(kRealVariables[vr].name);
        if (status != GIMBAL_OK) return status;
        for (int k = 0; k < 4; ++k)
            if (kRotorStart[k] == vr) value = run_.preview_rotor_start[k];
        return GIMBAL_OK;
    }
    if (run_.system && run_.continuous_time && run_.outputs_stale) {
        const GimbalStatus status = publish_continuous_time_outputs();
        if (status != GIMBAL_OK) return status;
    }
    value = run_.reals[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_integer(unsigned vr, int value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    run_.integers[vr] = value;
    run_.preview_current = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_integer(unsigned vr, int& value) {
    if (vr >= kIntegerVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not an Integer variable");
    }
    if (!run_.system && kIntegerVariables[vr].initial == Initial::calculated) {
        const GimbalStatus status = preview_outputs(kIntegerVariables[vr].name);
        if (status != GIMBAL_OK) return status;
    }
    if (run_.system && run_.continuous_time && run_.outputs_stale) {
        const GimbalStatus status = publish_continuous_time_outputs();
        if (status != GIMBAL_OK) return status;
    }
    value = run_.integers[vr];
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_boolean(unsigned vr, bool value) {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Boolean variable");
    }
    run_.booleans[vr] = value;
    run_.preview_current = false;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_boolean(unsigned vr, bool& value) const {
    if (vr >= kBooleanVariableCount) {
        return refuse(GIMBAL_ERROR, "value reference " + std::to_string(vr) + " is not a Boolean variable");
    }
    value = run_.booleans[vr];
    return GIMBAL_OK;
}

StepInputs GimbalInstance::read_step_inputs(double step_start) const {
    return gimbal::read_step_inputs(model_.params, run_.reals, run_.voltage_rate, step_start);
}

// gear<j>.start (docs/physics.md section 3.3). By default a rotor angle or rate left at its start value 0
// follows its load: an FMI host that sets only alpha and beta gets relaxed gears, whether or not it
// also sets the rotors' untouched start values (importers differ in that, the values decide alike).
namespace {

// Whether a rotor's start value is used as given, under the model's gear<j>.start.
bool rotor_start_given(const InstanceModel& model, int axis, double value) {
    const GearStart rule = model.params.gear_start[axis];
    return rule == GearStart::as_given || (rule == GearStart::in_mesh_unless_given && value != 0.0);
}

}  // namespace

// In mesh, the shaft is neither twisted (theta_d = theta_b, the backlash state as given: centred by
// default) nor twisting (theta_d' = 0): T_E = 0 (section 4.2). A gear without backlash has theta_b = 0.
void GimbalInstance::rotor_in_mesh(int axis, double& angle, double& rate) const {
    const RealVariable backlash = axis == 0 ? vr_theta_b1 : vr_theta_b2;
    const double theta_b = model_.params.fidelity.gear[axis] == GearModel::backlash ? run_.reals[backlash] : 0.0;
    const int load = load_index(axis);
    const double ratio = model_.params.gear[axis].ratio;
    angle = ratio * (run_.reals[kBodyAngle[load]] + theta_b);
    rate = ratio * run_.reals[kBodyRate[load]];
}

void GimbalInstance::load_start_state() {
    const StateLayout& layout = model_.params.layout;
    std::fill(run_.state, run_.state + kMaxStateSize, 0.0);
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        run_.state[layout.angle_slot[body]] = run_.reals[kBodyAngle[body]];
        run_.state[layout.rate_slot[body]] = run_.reals[kBodyRate[body]];
    }
    const RealVariable currents[2] = {vr_i_R1, vr_i_R2}, backlash[2] = {vr_theta_b1, vr_theta_b2};
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) run_.state[layout.current_slot[axis]] = run_.reals[currents[axis]];
        if (layout.backlash_slot[axis] >= 0) run_.state[layout.backlash_slot[axis]] = run_.reals[backlash[axis]];
        const int rotor = rotor_index(axis);
        if (!layout.independent(rotor)) continue;  // a rigid gear: the rotor is N times its load anyway
        double mesh_angle = 0.0, mesh_rate = 0.0;
        rotor_in_mesh(axis, mesh_angle, mesh_rate);
        if (!rotor_start_given(model_, axis, run_.reals[kBodyAngle[rotor]])) run_.state[layout.angle_slot[rotor]] = mesh_angle;
        if (!rotor_start_given(model_, axis, run_.reals[kBodyRate[rotor]])) run_.state[layout.rate_slot[rotor]] = mesh_rate;
    }
}

// Said once, at initialization (not at the previews before it): a start value of a rotor that is not
// used, and a gear that starts twisted because its rotor's start values were given so.
void GimbalInstance::report_gear_starts() const {
    const StateLayout& layout = model_.params.layout;
    for (int axis = 0; axis < 2; ++axis) {
        const int rotor = rotor_index(axis), load = load_index(axis);
        const std::string gear = "gear" + std::to_string(axis + 1);
        const char* angle_name = kRealVariables[kBodyAngle[rotor]].name;
        const char* rate_name = kRealVariables[kBodyRate[rotor]].name;
        const double given_angle = run_.reals[kBodyAngle[rotor]], given_rate = run_.reals[kBodyRate[rotor]];
        std::ostringstream s;
        s.precision(6);
        if (!layout.independent(rotor)) {
            const double ratio = model_.params.gear[axis].ratio;
            const double angle = ratio * run_.reals[kBodyAngle[load]], rate = ratio * run_.reals[kBodyRate[load]];
            if ((rotor_start_given(model_, axis, given_angle) && given_angle != angle) ||
                (rotor_start_given(model_, axis, given_rate) && given_rate != rate)) {
                s << "rigid gear " << axis + 1 << ": the start values " << angle_name << " = " << given_angle << ", "
                  << rate_name << " = " << given_rate << " are not used: a rigid gear's rotor is " << gear
                  << ".N times its load, " << angle << " rad, " << rate << " rad/s";
                logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
            }
            continue;
        }
        double mesh_angle = 0.0, mesh_rate = 0.0;
        rotor_in_mesh(axis, mesh_angle, mesh_rate);
        if (model_.params.gear_start[axis] == GearStart::in_mesh) {
            const bool angle_dropped = given_angle != 0.0 && given_angle != mesh_angle;
            const bool rate_dropped = given_rate != 0.0 && given_rate != mesh_rate;
            if (angle_dropped || rate_dropped) {
                s << gear << ".start = in_mesh: the start value";
                if (angle_dropped) s << " " << angle_name << " = " << given_angle << " rad";
                if (angle_dropped && rate_dropped) s << " and";
                if (rate_dropped) s << " " << rate_name << " = " << given_rate << " rad/s";
                s << " not used; the rotor starts in mesh at " << mesh_angle << " rad, " << mesh_rate
                  << " rad/s (set " << gear << ".start = as_given to start from the given values)";
                logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
            }
            continue;
        }
        // The twist the shaft carries from the start: the deflection beyond the backlash play (the
        // shaft's end reaches the stop within c_s/k_s), and the rate of deflection.
        const double ratio = model_.params.gear[axis].ratio;
        const double rotor_angle = run_.state[layout.angle_slot[rotor]], rotor_rate = run_.state[layout.rate_slot[rotor]];
        const double load_angle = run_.reals[kBodyAngle[load]];
        const double deflection = rotor_angle / ratio - load_angle;
        const double deflection_rate = rotor_rate / ratio - run_.reals[kBodyRate[load]];
        const double play = model_.params.fidelity.gear[axis] == GearModel::backlash ? model_.params.gear[axis].half_backlash : 0.0;
        const double twist = deflection - std::clamp(deflection, -play, play);
        // Rounding of N (q_l + theta_b) / N - q_l is not a twist.
        const double resolution = 1e-12 * (1.0 + std::fabs(load_angle) + std::fabs(rotor_angle / ratio));
        const bool twisted = std::fabs(twist) > resolution;
        const bool twisting = std::fabs(deflection_rate) > 1e-12 * (1.0 + std::fabs(rotor_rate / ratio));
        if (!twisted && !twisting) continue;
        s << gear << " starts twisted: " << angle_name << " = " << rotor_angle << " rad";
        if (twisting) s << ", " << rate_name << " = " << rotor_rate << " rad/s";
        s << " against " << kRealVariables[kBodyAngle[load]].name << " = " << load_angle << " rad";
        if (twisting) s << ", " << kRealVariables[kBodyRate[load]].name << " = " << run_.reals[kBodyRate[load]] << " rad/s";
        if (twisted) {
            s << ": the shaft is twisted by " << twist << " rad";
            if (play > 0.0) s << " beyond the backlash (" << gear << ".eta = " << play << " rad)";
            s << ", a torque of " << model_.params.gear[axis].stiffness * twist << " N.m (" << gear << ".k_s times the twist)";
        }
        if (twisting) {
            s << (twisted ? "; " : ": ") << "the shaft twists at " << deflection_rate << " rad/s, a damping torque of "
              << model_.params.gear[axis].damping * deflection_rate << " N.m (" << gear << ".c_s times the rate)";
            if (!twisted && play > 0.0) s << " once the backlash closes";
        }
        if (model_.params.gear_start[axis] == GearStart::as_given)
            s << "; " << gear << ".start = as_given keeps the rotor's start values";
        else
            s << "; the rotor's start values were given (left at 0, they follow the load: " << mesh_angle << " rad, "
              << mesh_rate << " rad/s)";
        logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
    }
}

GimbalStatus GimbalInstance::check_fixed_base() const {
    if (!model_.params.fidelity.fixed_base) return GIMBAL_OK;
    for (RealVariable vr : kBaseInputs) {
        if (run_.reals[vr] != 0.0) {
            std::ostringstream s;
            s << kRealVariables[vr].name << " = " << run_.reals[vr]
              << " refused: base.fixed = true, so every base input must be 0";
            return refuse(GIMBAL_ERROR, s.str());
        }
    }
    return GIMBAL_OK;
}

bool GimbalInstance::build_parameters(ModelParameters& params, std::string& error) const {
    return build_model_parameters(run_.reals, run_.integers, run_.booleans, params, error) &&
           validate_start_state(run_.reals, params, error);
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
    settings.event_handling.events_logged = [this] { return log_filter_("logEvents"); };
    return HybridIntegrator::create(
        system, settings,
        [this](const std::string& message) {
            run_.last_integrator_error = message;
            logger_(GIMBAL_WARNING, "logSolver", message);
        },
        [this](const std::string& message) { logger_(GIMBAL_OK, "logEvents", message); });
}

void GimbalInstance::create_integrator() {
    run_.integrator = make_integrator(*run_.system, model_.params);
    run_.integrator_running = false;
}

void GimbalInstance::set_master_tolerance(bool defined, double tolerance) {
    run_.master_tolerance_defined = defined;
    run_.master_tolerance = defined ? tolerance : 0.0;
}

// The FMI standard gives the master's tolerance to the FMU's integrator; solver.rtol, when the user
// set it, says more precisely what this FMU should do.
void GimbalInstance::apply_master_tolerance() {
    if (!run_.master_tolerance_defined) return;
    std::ostringstream s;
    s.precision(17);
    if (run_.rtol_set) {
        if (run_.master_tolerance != run_.reals[vr_solver_rtol]) {
            s << "the master's tolerance = " << run_.master_tolerance << " is not used: solver.rtol = "
              << run_.reals[vr_solver_rtol] << " was set explicitly";
            logger_(GIMBAL_OK, "logSolver", s.str());
        }
        return;
    }
    if (!(run_.master_tolerance > 0.0 && run_.master_tolerance < 1.0)) {
        s << "the master's tolerance = " << run_.master_tolerance << " is ignored (a relative tolerance lies in "
          << "(0, 1)); solver.rtol keeps " << run_.reals[vr_solver_rtol];
        logger_(GIMBAL_WARNING, "logStatusWarning", s.str());
        return;
    }
    run_.reals[vr_solver_rtol] = run_.master_tolerance;
    s << "solver.rtol = " << run_.master_tolerance << ", the tolerance the master gave (set solver.rtol to override)";
    logger_(GIMBAL_OK, "logSolver", s.str());
}

GimbalStatus GimbalInstance::preview_outputs(const char* name) {
    if (run_.preview_current) return GIMBAL_OK;
    std::string error;
    ModelParameters params;
    if (!build_parameters(params, error)) {
        return refuse(GIMBAL_ERROR, std::string(name) +
                                        " cannot be computed from the current values: " + error);
    }
    // Built aside and committed only at the end: a failure (out of memory) leaves nothing half-made.
    ModelSwap swap(model_, make_instance_model(params));
    auto system = std::make_unique<GimbalHybridSystem>(model_.params);
    auto integrator = make_integrator(*system, model_.params);
    swap.commit();
    load_start_state();
    run_.epoch = run_.time;
    run_.clock = 0.0;
    system->hold_inputs_at_any_time(run_.continuous_time);
    system->set_inputs(read_step_inputs(0.0));
    system->update_modes(0.0, run_.state, nullptr);
    run_.system = std::move(system);
    run_.integrator = std::move(integrator);
    // Publishing writes the rotors' start into their variables: keep the host's start values there
    // (gear<j>.start reads them again), and the start the preview computed aside.
    double rotor_start_values[4];
    for (int k = 0; k < 4; ++k) rotor_start_values[k] = run_.reals[kRotorStart[k]];
    publish_outputs();
    for (int k = 0; k < 4; ++k) {
        run_.preview_rotor_start[k] = run_.reals[kRotorStart[k]];
        run_.reals[kRotorStart[k]] = rotor_start_values[k];
    }
    // The continuous-time interface may ask for the states and indicators during initialization.
    full_state_vector(model_.params, run_.system->dynamics_at(0.0, run_.state), run_.state, run_.preview_states);
    run_.system->event_indicators(0.0, run_.state, run_.preview_indicators);
    // The preview must not count as initialization: forget the integrator again.
    run_.integrator.reset();
    run_.system.reset();
    run_.preview_current = true;
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::initialize(double start_time) {
    const double rtol_before = run_.reals[vr_solver_rtol];
    apply_master_tolerance();
    std::string error;
    ModelParameters params;
    if (!build_parameters(params, error)) {
        run_.reals[vr_solver_rtol] = rtol_before;
        return refuse(GIMBAL_ERROR, error);
    }
    std::unique_ptr<GimbalHybridSystem> system;
    std::unique_ptr<HybridIntegrator> integrator;
    ModelSwap swap(model_, make_instance_model(params));
    try {
        system = std::make_unique<GimbalHybridSystem>(model_.params);
        integrator = make_integrator(*system, model_.params);
    } catch (...) {
        run_.reals[vr_solver_rtol] = rtol_before;
        throw;
    }
    const GimbalStatus base_status = check_fixed_base();
    if (base_status != GIMBAL_OK) {
        run_.reals[vr_solver_rtol] = rtol_before;
        return base_status;
    }
    swap.commit();
    load_start_state();
    run_.time = start_time;
    run_.epoch = start_time;
    run_.clock = 0.0;
    system->hold_inputs_at_any_time(run_.continuous_time);
    system->set_inputs(read_step_inputs(0.0));
    system->update_modes(0.0, run_.state, nullptr);
    EventCounters none;
    none.last_event_time = 0.0;
    system->restore(system->modes(), none);  // the initial choice of modes is not an event
    run_.system = std::move(system);
    run_.integrator = std::move(integrator);
    run_.integrator_running = false;
    run_.step_work.reset();
    // The continuous-time interface measures the first crossings against the guards of the start.
    run_.system->event_functions(0.0, run_.state, run_.reference_guards);
    std::fill(run_.decided_side, run_.decided_side + kIndicatorCount, static_cast<std::int8_t>(0));
    run_.inputs_stale = run_.decided_here = false;
    run_.chattering = ChatteringMemory{};
    run_.zeno_holds = 0;
    report_gear_starts();  // reads the rotors' start values: before publishing replaces them
    publish_outputs();
    run_.outputs_stale = false;
    return check_initial_outputs();
}

// The start's outputs, like a step's (check_published_outputs): inputs beyond what the model can
// represent (a carrier rate of 1e300 makes the kinetic energy overflow) are refused, not published.
GimbalStatus GimbalInstance::check_initial_outputs() {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::output || std::isfinite(run_.reals[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " = " << run_.reals[vr] << " at the start time " << run_.time
          << ": an input or parameter lies beyond what the model can represent";
        return refuse(GIMBAL_ERROR, s.str());
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::linearize(LinearModel& model) {
    if (!run_.system) return refuse(GIMBAL_ERROR, "linearize: the instance is not initialized (no operating point yet)");
    const double now = run_.clock;
    StepInputs inputs = read_step_inputs(now);
    inputs.voltage_rate[0] = inputs.voltage_rate[1] = 0.0;
    // The modes the next step would start in: inputs set since the last step may have switched some.
    GimbalHybridSystem selector(model_.params);
    selector.set_inputs(inputs);
    selector.restore(run_.system->modes(), run_.system->counters());
    double state[kMaxStateSize];
    std::copy(run_.state, run_.state + kMaxStateSize, state);
    selector.update_modes(now, state, nullptr);
    gimbal::linearize(model_.params, inputs, selector.modes(), now, state, model);
    return GIMBAL_OK;
}

}  // namespace gimbal
