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

void GimbalInstance::map_integrated_states() {
    const StateLayout& layout = params_.layout;
    int slot_of[kStateCount];
    for (int body = 0; body < 4; ++body) {
        slot_of[body] = layout.angle_slot[body];
        slot_of[kRates + body] = layout.rate_slot[body];
    }
    for (int axis = 0; axis < 2; ++axis) {
        slot_of[kCurrents + axis] = layout.current_slot[axis];
        slot_of[kBacklash + axis] = layout.backlash_slot[axis];
    }
    for (int k = 0; k < kEnergyFlowCount; ++k) slot_of[kStateSize + k] = layout.energy_slot >= 0 ? layout.energy_slot + k : -1;
    integrated_count_ = 0;
    for (int k = 0; k < kStateCount; ++k) {
        if (slot_of[k] < 0) continue;
        integrated_state_[integrated_count_] = k;
        integrated_slot_[integrated_count_++] = slot_of[k];
    }
}

void GimbalInstance::refresh_held_inputs() {
    if (!inputs_stale_) return;
    StepInputs inputs = read_step_inputs(clock_);
    inputs.voltage_rate[0] = inputs.voltage_rate[1] = 0.0;  // no input derivatives in this interface
    system_->set_inputs(inputs);
    inputs_stale_ = false;
}

GimbalStatus GimbalInstance::set_time(double time) {
    if (!std::isfinite(time)) return refuse(GIMBAL_ERROR, "the time must be finite");
    if (time < epoch_) {
        std::ostringstream s;
        s.precision(17);
        s << "time = " << time << " lies before the start time " << epoch_;
        return refuse(GIMBAL_ERROR, s.str());
    }
    if (time != time_) {
        time_ = time;
        clock_ = time - epoch_;
        outputs_stale_ = true;
        decided_here_ = false;
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
    for (int k = 0; k < integrated_count_; ++k) state_[integrated_slot_[k]] = states[integrated_state_[k]];
    outputs_stale_ = true;
    decided_here_ = false;
    return GIMBAL_OK;
}

void GimbalInstance::get_continuous_states(double* states) {
    refresh_held_inputs();
    full_state_vector(params_, system_->dynamics_at(clock_, state_), state_, states);
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
            initialized() ? params_.gear[axis].half_backlash : reals_[half_backlash_values[axis]];
        if (half_backlash > 0.0) nominals[kBacklash + axis] = half_backlash;
    }
}

GimbalStatus GimbalInstance::preview_continuous(double* states, double* indicators) {
    if (system_) return refuse(GIMBAL_ERROR, "the instance is initialized: ask for the current point instead");
    const GimbalStatus status = preview_outputs(states != nullptr ? "the continuous states" : "the event indicators");
    if (status != GIMBAL_OK) return status;
    if (states != nullptr) std::copy(preview_states_, preview_states_ + kStateCount, states);
    if (indicators != nullptr) std::copy(preview_indicators_, preview_indicators_ + kIndicatorCount, indicators);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_derivatives(double* derivatives) {
    refresh_held_inputs();
    const double now = clock_;
    const Dynamics& dynamics = system_->dynamics_at(now, state_);
    double integrated[kMaxStateSize];
    if (!state_derivative(params_, dynamics, integrated)) {
        std::ostringstream s;
        s.precision(17);
        s << "the derivatives are not finite at t = " << time_
          << ": the states or inputs set lie beyond what the model can represent";
        return refuse(GIMBAL_ERROR, s.str());
    }
    full_state_derivative(params_, system_->modes(), dynamics, integrated, derivatives);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::get_event_indicators(double* indicators) {
    refresh_held_inputs();
    const double now = clock_;
    if (now < chattering_.dwell_until) {
        // The chattering guard holds the modes: the indicators keep the values of its start, so that
        // the host sees no crossing before the time event that ends the hold.
        std::fill(indicators, indicators + kIndicatorCount, 1.0);
        for (int k = 0; k < system_->event_count(); ++k)
            indicators[system_->indicator_of_guard(k)] = reference_guards_[k];
        return GIMBAL_OK;
    }
    double guards[kIndicatorCount];
    system_->event_functions(now, state_, guards);
    std::fill(indicators, indicators + kIndicatorCount, 1.0);
    for (int k = 0; k < system_->event_count(); ++k) {
        double value = guards[k];
        if (!std::isfinite(value)) {
            std::ostringstream s;
            s.precision(17);
            s << "event indicator " << system_->indicator_of_guard(k) << " is not finite at t = " << time_
              << ": the states or inputs set lie beyond what the model can represent";
            return refuse(GIMBAL_ERROR, s.str());
        }
        // A guard exactly on zero where the modes were decided has the side it was decided for.
        if (value == 0.0 && decided_side_[k] != 0) value = decided_side_[k] * std::numeric_limits<double>::min();
        indicators[system_->indicator_of_guard(k)] = value;
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
    const bool evaluated = guard_settling_.settle(
        now, state_, params_.layout.size, n, lookahead, directions, derivative, reference_guards_, settled_changes,
        [this](double t, const double* x, double* dx) { return system_->derivative(t, x, dx); },
        [this, n, &raw](double t, const double* x, double* g) {
            system_->event_functions(t, x, g);
            if (g == reference_guards_) std::copy(g, g + n, raw);
            return true;
        },
        [this, now, &sink](const int* settle_directions) {
            return switch_modes(*system_, now, state_, settle_directions, event_settings_, sink, time_);
        });
    for (int k = 0; k < n; ++k)
        decided_side_[k] = static_cast<std::int8_t>(evaluated && raw[k] == 0.0 ? (reference_guards_[k] > 0.0) - (reference_guards_[k] < 0.0) : 0);
    // A failed evaluation (non-finite derivatives) is reported by the next fmi2GetDerivatives.
    return settled_changes;
}

GimbalStatus GimbalInstance::update_discrete_states(DiscreteUpdate& update) {
    update = DiscreteUpdate{};
    refresh_held_inputs();
    const double now = clock_;
    const bool holding = chattering_.holding();
    if (holding && now < chattering_.dwell_until) {
        update.next_time_defined = true;
        update.next_time = epoch_ + chattering_.dwell_until;
        return GIMBAL_OK;
    }
    // A repeated call at the point just decided (a host that iterates once more) changes nothing: a
    // second decision without the crossing directions could undo what they decided.
    if (decided_here_ && !holding) return GIMBAL_OK;

    const int n = system_->event_count();
    double guards[kIndicatorCount];
    system_->event_functions(now, state_, guards);
    int directions[kIndicatorCount] = {};
    if (holding) {
        // The hold ends here: the modes are chosen again from the signs, as after an input change.
        chattering_.dwell_until = -1e300;
    } else {
        for (int k = 0; k < n; ++k)
            if (crossed(reference_guards_[k], guards[k])) directions[k] = guards[k] > reference_guards_[k] ? 1 : -1;
    }
    double before[kMaxStateSize];
    std::copy(state_, state_ + kMaxStateSize, before);
    const HybridIntegrator::MessageSink sink = [this](const std::string& message) { log_event(message); };
    int changes = switch_modes(*system_, now, state_, directions, event_settings_, sink, time_);
    changes += settle_guards(now, n, directions, sink);

    if (changes > 0 && record_mode_change(chattering_, event_settings_, now, 0.0, sink, epoch_)) ++zeno_holds_;
    update.mode_changes = changes;
    update.states_changed = !std::equal(state_, state_ + params_.layout.size, before);
    update.next_time_defined = chattering_.holding();
    update.next_time = epoch_ + chattering_.dwell_until;
    decided_here_ = true;
    outputs_stale_ = true;
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
            for (int k = 0; k < integrated_count_; ++k)
                if (integrated_state_[k] == state && state < kStateSize) jacobian_row[i] = integrated_slot_[k];
        }
        all_rows_analytic &= jacobian_row[i] >= 0;
    }
    return GIMBAL_OK;
}

// The state part of the derivatives' rows from the Jacobian the implicit integrators use (analytic
// where the model is stiff), into result; `used` says whether there was any.
GimbalStatus GimbalInstance::jacobian_part(const std::vector<int>& jacobian_row, const double* state_seed,
                                           double* result, bool& used) {
    const int n = params_.layout.size;
    double jacobian[kMaxStateSize * kMaxStateSize];
    double slot_seed[kMaxStateSize] = {};
    bool any_state_seed = false;
    for (int k = 0; k < integrated_count_; ++k) {
        slot_seed[integrated_slot_[k]] = state_seed[integrated_state_[k]];
        any_state_seed |= state_seed[integrated_state_[k]] != 0.0;
    }
    used = any_state_seed && std::any_of(jacobian_row.begin(), jacobian_row.end(), [](int r) { return r >= 0; });
    if (!used) return GIMBAL_OK;
    system_->jacobian(clock_, state_, jacobian);
    for (std::size_t i = 0; i < jacobian_row.size(); ++i) {
        if (jacobian_row[i] < 0) continue;
        double sum = 0.0;
        for (int column = 0; column < n; ++column) sum += jacobian[jacobian_row[i] + column * n] * slot_seed[column];
        if (!std::isfinite(sum)) {
            std::ostringstream s;
            s.precision(17);
            s << "the Jacobian is not finite at t = " << time_
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
        if (value != 0.0) size = std::max(size, std::fabs(value)), scale = std::max(scale, std::fabs(reals_[vr]));
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
    std::copy(state_, state_ + kMaxStateSize, saved_state);
    std::vector<double> saved_reals(reals_, reals_ + kRealVariableCount);
    std::vector<int> saved_integers(integers_, integers_ + kIntegerVariableCount);
    const bool saved_outputs_stale = outputs_stale_, saved_decided = decided_here_;
    std::vector<double> values[2] = {std::vector<double>(unknown_count), std::vector<double>(unknown_count)};
    GimbalStatus status = GIMBAL_OK;
    for (int side = 0; side < 2 && status == GIMBAL_OK; ++side) {
        const double h = side == 0 ? step : -step;
        std::copy(saved_state, saved_state + kMaxStateSize, state_);
        for (int k = 0; k < integrated_count_; ++k)
            state_[integrated_slot_[k]] += h * state_seed[integrated_state_[k]];
        std::copy(saved_reals.begin(), saved_reals.end(), reals_);
        for (const auto& [vr, value] : input_seed) reals_[vr] += h * value;
        inputs_stale_ = true;
        double derivatives[kStateCount];
        status = get_derivatives(derivatives);
        if (status == GIMBAL_OK) status = publish_continuous_time_outputs();
        for (std::size_t i = 0; i < unknown_count; ++i) {
            const auto d = std::find(kStateDerivatives, kStateDerivatives + kStateCount, unknowns[i]);
            values[side][i] = d != kStateDerivatives + kStateCount ? derivatives[d - kStateDerivatives] : reals_[unknowns[i]];
        }
    }
    std::copy(saved_state, saved_state + kMaxStateSize, state_);
    std::copy(saved_reals.begin(), saved_reals.end(), reals_);
    std::copy(saved_integers.begin(), saved_integers.end(), integers_);
    inputs_stale_ = true;
    outputs_stale_ = saved_outputs_stale;
    decided_here_ = saved_decided;
    if (status != GIMBAL_OK) return status;
    for (std::size_t i = 0; i < unknown_count; ++i) result[i] = (values[0][i] - values[1][i]) / (2.0 * step);
    return GIMBAL_OK;
}

GimbalStatus GimbalInstance::publish_continuous_time_outputs() {
    refresh_held_inputs();
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    std::copy(reals_, reals_ + kRealVariableCount, reals);
    std::copy(integers_, integers_ + kIntegerVariableCount, integers);
    publish_outputs();
    clamp_published_to_bounds(params_, reals_);
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (std::isfinite(reals_[vr])) continue;
        std::ostringstream s;
        s.precision(17);
        s << kRealVariables[vr].name << " is not finite at t = " << time_
          << ": the states or inputs set lie beyond what the model can represent";
        std::copy(reals, reals + kRealVariableCount, reals_);
        std::copy(integers, integers + kIntegerVariableCount, integers_);
        return refuse(GIMBAL_ERROR, s.str());
    }
    outputs_stale_ = false;
    return GIMBAL_OK;
}

}  // namespace gimbal
