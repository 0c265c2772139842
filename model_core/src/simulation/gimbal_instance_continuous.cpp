// The continuous-time face of an instance (what FMI calls Model Exchange): the host owns time, the
// continuous states and the integration; the instance evaluates derivatives, event indicators and
// outputs at the point the host sets, and decides the modes where the host reports an event.
//
// The modes are decided by the same switching elements, with the same crossing directions and the
// same settling of guards that sit exactly on zero as the integrators of the Co-Simulation step use,
// so that a host that locates events accurately meets the same mode sequence. A host that locates
// them late (a fixed-step method) gets the state projected back onto the constraint of the new mode
// (a gear at its stop, a current at its limit): no state leaves its bounds after an event update.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "gimbal/hybrid_system/event_handling.hpp"
#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/simulation/instance_outputs.hpp"

namespace gimbal {
namespace {

bool crossed(double before, double after) {
    return before != 0.0 && (after == 0.0 || (before > 0.0) != (after > 0.0));
}

// How far ahead a guard sitting exactly on zero is looked at to see where it goes: short against the
// fastest time constant the parameters allow (L/R and c_s/k_s down to 1e-8 s in the hard cases).
constexpr double kDepartureLookahead = 1e-12;

}  // namespace

IntegratedStates integrated_states_of(const StateLayout& layout) {
    int slot_of[kContinuousStateCount];
    for (int body = 0; body < 4; ++body) {
        slot_of[body] = layout.angle_slot[body];
        slot_of[kRates + body] = layout.rate_slot[body];
    }
    for (int axis = 0; axis < 2; ++axis) {
        slot_of[kCurrents + axis] = layout.current_slot[axis];
        slot_of[kBacklash + axis] = layout.backlash_slot[axis];
    }
    for (int k = 0; k < kEnergyFlowCount; ++k) slot_of[kStateSize + k] = layout.energy_slot >= 0 ? layout.energy_slot + k : -1;
    for (int axis = 0; axis < 2; ++axis) slot_of[kAmplifierStates + axis] = layout.amplifier_slot[axis];
    IntegratedStates integrated;
    for (int k = 0; k < kContinuousStateCount; ++k) {
        if (slot_of[k] < 0) continue;
        integrated.state[integrated.count] = k;
        integrated.slot[integrated.count++] = slot_of[k];
    }
    return integrated;
}

InstanceModel make_instance_model(const ModelParameters& params) {
    InstanceModel model;
    model.params = params;
    model.integrated = integrated_states_of(params.layout);
    return model;
}

void GimbalInstance::refresh_held_inputs() {
    if (!run_.inputs_stale) return;
    StepInputs inputs = read_step_inputs(run_.clock);
    inputs.voltage_rate[0] = inputs.voltage_rate[1] = 0.0;  // no input derivatives in this interface
    run_.system->set_inputs(inputs);
    run_.inputs_stale = false;
}

GimbalStatus GimbalInstance::set_time(double time) {
    if (!std::isfinite(time)) return refuse(GIMBAL_ERROR, "the time must be finite");
    if (time < run_.epoch) {
        std::ostringstream s;
        s.precision(17);
        s << "time = " << time << " lies before the start time " << run_.epoch;
        return refuse(GIMBAL_ERROR, s.str());
    }
    if (time != run_.time) {
        run_.time = time;
        run_.clock = time - run_.epoch;
        run_.outputs_stale = true;
        run_.decided_here = false;
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::set_continuous_states(const double* states) {
    // One pass over the host's values, branch-free: this runs at every right-hand side of the host.
    bool finite = true;
    for (int k = 0; k < kStateCount; ++k) finite &= std::isfinite(states[k]);
    if (!finite) {
        for (int k = 0; k < kStateCount; ++k) {
            if (std::isfinite(states[k])) continue;
            std::ostringstream s;
            s << "continuous state " << k << " (" << kRealVariables[kContinuousStates[k]].name << ") = " << states[k]
              << " refused: states must be finite";
            return refuse(GIMBAL_ERROR, s.str());
        }
    }
    // The states this fidelity integrates take the host's values; the others follow from them.
    const IntegratedStates& integrated = model_.integrated;
    for (int k = 0; k < integrated.count; ++k) run_.state[integrated.slot[k]] = states[integrated.state[k]];
    run_.outputs_stale = true;
    run_.decided_here = false;
    return GIMBAL_OK;
}

void GimbalInstance::get_continuous_states(double* states) {
    refresh_held_inputs();
    full_state_vector(model_.params, run_.system->dynamics_at(run_.clock, run_.state), run_.state, states);
}

void GimbalInstance::get_nominal_states(double* nominals) const {
    std::fill(nominals, nominals + kStateCount, 1.0);
    // The play is small against a radian: its own size is the scale its error is measured on.
    // From the built parameters, as everything else; before initialization there are none yet (the
    // host may ask in Instantiated mode), and the values as set are what the build will copy:
    // gear<j>.eta is a fixed parameter, read unchanged into GearParameters::half_backlash.
    const RealVariable half_backlash_values[2] = {vr_gear1_eta, vr_gear2_eta};
    for (int axis = 0; axis < 2; ++axis) {
        const double half_backlash =
            initialized() ? model_.params.gear[axis].half_backlash : run_.reals[half_backlash_values[axis]];
        if (half_backlash > 0.0) nominals[kBacklash + axis] = half_backlash;
    }
}

GimbalStatus GimbalInstance::preview_continuous(double* states, double* indicators) {
    if (run_.system) return refuse(GIMBAL_ERROR, "the instance is initialized: ask for the current point instead");
    const GimbalStatus status = preview_outputs(states != nullptr ? "the continuous states" : "the event indicators");
    if (status != GIMBAL_OK) return status;
    if (states != nullptr) std::copy(run_.preview_states, run_.preview_states + kStateCount, states);
    if (indicators != nullptr) std::copy(run_.preview_indicators, run_.preview_indicators + kIndicatorCount, indicators);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_derivatives(double* derivatives) {
    refresh_held_inputs();
    const double now = run_.clock;
    const Dynamics& dynamics = run_.system->dynamics_at(now, run_.state);
    double integrated[kMaxStateSize];
    if (!state_derivative(model_.params, dynamics, integrated)) {
        std::ostringstream s;
        s.precision(17);
        s << "the derivatives are not finite at t = " << run_.time
          << ": the states or inputs set lie beyond what the model can represent";
        return refuse(GIMBAL_ERROR, s.str());
    }
    full_state_derivative(model_.params, run_.system->modes(), dynamics, integrated, derivatives);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_event_indicators(double* indicators) {
    refresh_held_inputs();
    const double now = run_.clock;
    if (now < run_.chattering.dwell_until) {
        // The chattering guard holds the modes: the indicators keep the values of its start, so that
        // the host sees no crossing before the time event that ends the hold.
        std::fill(indicators, indicators + kIndicatorCount, 1.0);
        for (int k = 0; k < run_.system->event_count(); ++k)
            indicators[run_.system->indicator_of_guard(k)] = run_.reference_guards[k];
        return GIMBAL_OK;
    }
    double guards[kIndicatorCount];
    run_.system->event_functions(now, run_.state, guards);
    std::fill(indicators, indicators + kIndicatorCount, 1.0);
    for (int k = 0; k < run_.system->event_count(); ++k) {
        double value = guards[k];
        if (!std::isfinite(value)) {
            std::ostringstream s;
            s.precision(17);
            s << "event indicator " << run_.system->indicator_of_guard(k) << " is not finite at t = " << run_.time
              << ": the states or inputs set lie beyond what the model can represent";
            return refuse(GIMBAL_ERROR, s.str());
        }
        // A guard exactly on zero where the modes were decided has the side it was decided for.
        if (value == 0.0 && run_.decided_side[k] != 0) value = run_.decided_side[k] * std::numeric_limits<double>::min();
        indicators[run_.system->indicator_of_guard(k)] = value;
    }
    return GIMBAL_OK;
}

// The guards left exactly on zero, settled as the integrators settle them after a located event;
// what they settle to is where the next crossing is measured from. Returns the mode changes made.
int GimbalInstance::settle_guards(double now, int n, const int* directions, const HybridIntegrator::MessageSink& sink) {
    double derivative[kMaxStateSize];
    double raw[kIndicatorCount];
    int settled_changes = 0;
    const double lookahead = kDepartureLookahead * std::max(1.0, std::fabs(now));
    const bool evaluated = run_.guard_settling.settle(
        now, run_.state, model_.params.layout.size, n, lookahead, directions, derivative, run_.reference_guards, settled_changes,
        [this](double t, const double* x, double* dx) { return run_.system->derivative(t, x, dx); },
        [this, n, &raw](double t, const double* x, double* g) {
            run_.system->event_functions(t, x, g);
            if (g == run_.reference_guards) std::copy(g, g + n, raw);
            return true;
        },
        [this, now, &sink](const int* settle_directions) {
            return switch_modes(*run_.system, now, run_.state, settle_directions, event_settings_, sink, run_.time);
        });
    for (int k = 0; k < n; ++k) {
        const double reference = run_.reference_guards[k];
        run_.decided_side[k] = static_cast<std::int8_t>(evaluated && raw[k] == 0.0 ? (reference > 0.0) - (reference < 0.0) : 0);
    }
    // A failed evaluation (non-finite derivatives) is reported by the next fmi2GetDerivatives.
    return settled_changes;
}

GimbalStatus GimbalInstance::update_discrete_states(DiscreteUpdate& update) {
    update = DiscreteUpdate{};
    refresh_held_inputs();
    const double now = run_.clock;
    const bool holding = run_.chattering.holding();
    if (holding && now < run_.chattering.dwell_until) {
        update.next_time_defined = true;
        update.next_time = run_.epoch + run_.chattering.dwell_until;
        return GIMBAL_OK;
    }
    // A repeated call at the point just decided (a host that iterates once more) changes nothing: a
    // second decision without the crossing directions could undo what they decided.
    if (run_.decided_here && !holding) return GIMBAL_OK;

    const int n = run_.system->event_count();
    double guards[kIndicatorCount];
    run_.system->event_functions(now, run_.state, guards);
    int directions[kIndicatorCount] = {};
    if (holding) {
        // The hold ends here: the modes are chosen again from the signs, as after an input change.
        run_.chattering.dwell_until = -1e300;
    } else {
        for (int k = 0; k < n; ++k)
            if (crossed(run_.reference_guards[k], guards[k])) directions[k] = guards[k] > run_.reference_guards[k] ? 1 : -1;
    }
    double before[kMaxStateSize];
    std::copy(run_.state, run_.state + kMaxStateSize, before);
    const HybridIntegrator::MessageSink sink = [this](const std::string& message) { log_event(message); };
    int changes = switch_modes(*run_.system, now, run_.state, directions, event_settings_, sink, run_.time);
    changes += settle_guards(now, n, directions, sink);

    if (changes > 0 && record_mode_change(run_.chattering, event_settings_, now, 0.0, sink, run_.epoch)) ++run_.zeno_holds;
    update.mode_changes = changes;
    update.states_changed = !std::equal(run_.state, run_.state + model_.params.layout.size, before);
    update.next_time_defined = run_.chattering.holding();
    update.next_time = run_.epoch + run_.chattering.dwell_until;
    run_.decided_here = true;
    run_.outputs_stale = true;
    return GIMBAL_OK;
}

// The knowns of a directional derivative: a state's seed goes to its index among the 17, an input's
// to the list of inputs moved (refused: anything else).
GimbalStatus GimbalInstance::seed_knowns(const unsigned* knowns, std::size_t known_count, const double* seed,
                                         double* state_seed, std::vector<std::pair<unsigned, double>>& input_seed) const {
    for (std::size_t j = 0; j < known_count; ++j) {
        const unsigned vr = knowns[j];
        const auto state = std::find(kContinuousStates, kContinuousStates + kStateCount, vr);
        if (state != kContinuousStates + kStateCount) {
            state_seed[state - kContinuousStates] += seed[j];
        } else if (vr < kRealVariableCount && kRealVariables[vr].causality == Causality::input) {
            if (seed[j] != 0.0) input_seed.emplace_back(vr, seed[j]);
        } else {
            return refuse(GIMBAL_ERROR, std::string("known ") + std::to_string(j) + ": " +
                                            (vr < kRealVariableCount ? kRealVariables[vr].name : "(no Real variable)") +
                                            " is neither a continuous state nor an input");
        }
    }
    return GIMBAL_OK;
}

// The row of the analytic Jacobian that answers each unknown, or -1: the derivatives of the states
// this fidelity integrates, but for the energy accumulators (their rows are not in the Jacobian).
GimbalStatus GimbalInstance::jacobian_rows(const unsigned* unknowns, std::size_t unknown_count,
                                           std::vector<int>& jacobian_row, bool& all_rows_analytic) const {
    all_rows_analytic = true;
    for (std::size_t i = 0; i < unknown_count; ++i) {
        const unsigned vr = unknowns[i];
        const auto derivative = std::find(kStateDerivatives, kStateDerivatives + kStateCount, vr);
        if (derivative == kStateDerivatives + kStateCount &&
            !(vr < kRealVariableCount && kRealVariables[vr].causality == Causality::output))
            return refuse(GIMBAL_ERROR, std::string("unknown ") + std::to_string(i) + ": " +
                                            (vr < kRealVariableCount ? kRealVariables[vr].name : "(no Real variable)") +
                                            " is neither a state derivative nor an output");
        if (derivative != kStateDerivatives + kStateCount) {
            const int state = static_cast<int>(derivative - kStateDerivatives);
            for (int k = 0; k < model_.integrated.count; ++k)
                if (model_.integrated.state[k] == state && (state < kStateSize || state >= kAmplifierStates))
                    jacobian_row[i] = model_.integrated.slot[k];
        }
        all_rows_analytic &= jacobian_row[i] >= 0;
    }
    return GIMBAL_OK;
}

// The state part of the derivatives' rows from the Jacobian the implicit integrators use (analytic
// where the model is stiff), into result; `used` says whether there was any.
GimbalStatus GimbalInstance::jacobian_part(const std::vector<int>& jacobian_row, const double* state_seed,
                                           double* result, bool& used) {
    const int n = model_.params.layout.size;
    double jacobian[kMaxStateSize * kMaxStateSize];
    double slot_seed[kMaxStateSize] = {};
    bool any_state_seed = false;
    for (int k = 0; k < model_.integrated.count; ++k) {
        slot_seed[model_.integrated.slot[k]] = state_seed[model_.integrated.state[k]];
        any_state_seed |= state_seed[model_.integrated.state[k]] != 0.0;
    }
    used = any_state_seed && std::any_of(jacobian_row.begin(), jacobian_row.end(), [](int r) { return r >= 0; });
    if (!used) return GIMBAL_OK;
    run_.system->jacobian(run_.clock, run_.state, jacobian);
    for (std::size_t i = 0; i < jacobian_row.size(); ++i) {
        if (jacobian_row[i] < 0) continue;
        double sum = 0.0;
        for (int column = 0; column < n; ++column) sum += jacobian[jacobian_row[i] + column * n] * slot_seed[column];
        if (!std::isfinite(sum)) {
            std::ostringstream s;
            s.precision(17);
            s << "the Jacobian is not finite at t = " << run_.time
              << ": the states or inputs set lie beyond what the model can represent";
            return refuse(GIMBAL_ERROR, s.str());
        }
        result[i] = sum;
    }
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::directional_derivative(const unsigned* unknowns, std::size_t unknown_count,
                                                    const unsigned* knowns, std::size_t known_count, const double* seed,
                                                    double* result) {
    // What each known and unknown is: a state (its index among the 17) or an input; a derivative (its
    // index) or an output.
    double state_seed[kStateCount] = {};
    std::vector<std::pair<unsigned, double>> input_seed;
    GimbalStatus status = seed_knowns(knowns, known_count, seed, state_seed, input_seed);
    if (status != GIMBAL_OK) return status;
    std::vector<int> jacobian_row(unknown_count, -1);
    bool all_rows_analytic = true;
    status = jacobian_rows(unknowns, unknown_count, jacobian_row, all_rows_analytic);
    if (status != GIMBAL_OK) return status;
    std::fill(result, result + unknown_count, 0.0);
    refresh_held_inputs();

    // The state part of the derivatives' rows from the Jacobian; everything else by a central
    // difference within the modes in force.
    bool use_jacobian = false;
    status = jacobian_part(jacobian_row, state_seed, result, use_jacobian);
    if (status != GIMBAL_OK) return status;
    // The rest: the input part of the analytic rows, and the whole of the other unknowns.
    std::vector<double> difference[2] = {std::vector<double>(unknown_count), std::vector<double>(unknown_count)};
    if (!all_rows_analytic || !use_jacobian) {
        status = central_difference(unknowns, unknown_count, state_seed, input_seed, difference[0].data());
        if (status != GIMBAL_OK) return status;
        for (std::size_t i = 0; i < unknown_count; ++i)
            if (jacobian_row[i] < 0 || !use_jacobian) result[i] = difference[0][i];
    }
    if (use_jacobian && !input_seed.empty()) {
        const double no_state_seed[kStateCount] = {};
        status = central_difference(unknowns, unknown_count, no_state_seed, input_seed, difference[1].data());
        if (status != GIMBAL_OK) return status;
        for (std::size_t i = 0; i < unknown_count; ++i)
            if (jacobian_row[i] >= 0) result[i] += difference[1][i];
    }
    return GIMBAL_OK;
}

// The step of a central difference: the cube root of the rounding error relative to the values
// moved, the balance of truncation and rounding. False when nothing is moved.
bool GimbalInstance::difference_step(const double* state_seed,
                                     const std::vector<std::pair<unsigned, double>>& input_seed, double& step) {
    double states[kStateCount];
    get_continuous_states(states);
    double size = 0.0, scale = 1.0;
    for (int k = 0; k < kStateCount; ++k)
        if (state_seed[k] != 0.0) size = std::max(size, std::fabs(state_seed[k])), scale = std::max(scale, std::fabs(states[k]));
    for (const auto& [vr, value] : input_seed)
        if (value != 0.0) size = std::max(size, std::fabs(value)), scale = std::max(scale, std::fabs(run_.reals[vr]));
    if (size == 0.0) return false;
    step = 6e-6 * scale / size;
    return true;
}

GimbalStatus GimbalInstance::central_difference(const unsigned* unknowns, std::size_t unknown_count,
                                                const double* state_seed,
                                                const std::vector<std::pair<unsigned, double>>& input_seed,
                                                double* result) {
    std::fill(result, result + unknown_count, 0.0);
    // Two evaluations whatever the number of knowns and unknowns.
    double step = 0.0;
    if (!difference_step(state_seed, input_seed, step)) return GIMBAL_OK;

    double saved_state[kMaxStateSize];
    std::copy(run_.state, run_.state + kMaxStateSize, saved_state);
    std::vector<double> saved_reals(run_.reals, run_.reals + kRealVariableCount);
    std::vector<int> saved_integers(run_.integers, run_.integers + kIntegerVariableCount);
    const bool saved_outputs_stale = run_.outputs_stale, saved_decided = run_.decided_here;
    std::vector<double> values[2] = {std::vector<double>(unknown_count), std::vector<double>(unknown_count)};
    GimbalStatus status = GIMBAL_OK;
    for (int side = 0; side < 2 && status == GIMBAL_OK; ++side) {
        const double h = side == 0 ? step : -step;
        std::copy(saved_state, saved_state + kMaxStateSize, run_.state);
        for (int k = 0; k < model_.integrated.count; ++k)
            run_.state[model_.integrated.slot[k]] += h * state_seed[model_.integrated.state[k]];
        std::copy(saved_reals.begin(), saved_reals.end(), run_.reals);
        for (const auto& [vr, value] : input_seed) run_.reals[vr] += h * value;
        run_.inputs_stale = true;
        double derivatives[kStateCount];
        status = get_derivatives(derivatives);
        if (status == GIMBAL_OK) status = publish_continuous_time_outputs();
        for (std::size_t i = 0; i < unknown_count; ++i) {
            const auto d = std::find(kStateDerivatives, kStateDerivatives + kStateCount, unknowns[i]);
            values[side][i] = d != kStateDerivatives + kStateCount ? derivatives[d - kStateDerivatives] : run_.reals[unknowns[i]];
        }
    }
    std::copy(saved_state, saved_state + kMaxStateSize, run_.state);
    std::copy(saved_reals.begin(), saved_reals.end(), run_.reals);
    std::copy(saved_integers.begin(), saved_integers.end(), run_.integers);
    run_.inputs_stale = true;
    run_.outputs_stale = saved_outputs_stale;
    run_.decided_here = saved_decided;
    if (status != GIMBAL_OK) return status;
    for (std::size_t i = 0; i < unknown_count; ++i) result[i] = (values[0][i] - values[1][i]) / (2.0 * step);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::publish_continuous_time_outputs() {
    refresh_held_inputs();
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    std::copy(run_.reals, run_.reals + kRealVariableCount, reals);
    std::copy(run_.integers, run_.integers + kIntegerVariableCount, integers);
    publish_outputs();
    clamp_published_to_bounds(model_.params, run_.reals);
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (std::isfinite(run_.reals[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " is not finite at t = " << run_.time
          << ": the states or inputs set lie beyond what the model can represent";
        std::copy(reals, reals + kRealVariableCount, run_.reals);
        std::copy(integers, integers + kIntegerVariableCount, run_.integers);
        return refuse(GIMBAL_ERROR, s.str());
    }
    run_.outputs_stale = false;
    return GIMBAL_OK;
}

}  // namespace gimbal
