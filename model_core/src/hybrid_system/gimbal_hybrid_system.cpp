#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"

#include <algorithm>

namespace gimbal {
GimbalHybridSystem::GimbalHybridSystem(const ModelParameters& params) : params_(params), elements_(params) {}

const BaseKinematics& GimbalHybridSystem::base_at(double time) {
    // The integrator asks for the same instant several times (right-hand side, events, Jacobian), and
    // a fixed or non-rotating base never changes: evaluate its trigonometry once.
    if (!base_cached_ || (time != base_time_ && !base_constant_)) {
        if (params_.fidelity.fixed_base) {
            base_ = base_kinematics_at(params_, inputs_, time);
        } else if (inputs_held_) {
            base_ = evaluate_base_kinematics(inputs_.base, arc_start_trig_, params_.multibody.gravity);
        } else {
            const BaseMotion motion = inputs_.base.advanced(time - inputs_.step_start_time);
            const AttitudeTrig trig = attitude_trig_near(arc_start_trig_, inputs_.base.attitude, motion.attitude);
            base_ = evaluate_base_kinematics(motion, trig, params_.multibody.gravity);
        }
        base_time_ = time;
        base_cached_ = true;
    }
    return base_;
}

void GimbalHybridSystem::set_inputs(const StepInputs& inputs) {
    inputs_ = inputs;
    base_cached_ = false;
    cache_valid_ = false;
    const BaseMotion& b = inputs.base;
    arc_start_trig_ = attitude_trig(b.attitude);
    // Held inputs do not move with time either: evaluated once per set.
    base_constant_ = params_.fidelity.fixed_base || inputs_held_ ||
                     (b.attitude_rate.isZero(0.0) && b.attitude_accel.isZero(0.0) && b.acceleration_a.isZero(0.0));
}

bool GimbalHybridSystem::at_rest(double time, const double* state) {
    if (!base_constant_ || inputs_.voltage_rate[0] != 0.0 || inputs_.voltage_rate[1] != 0.0) return false;
    for (int body = 0; body < 4; ++body)  // the cheap test first: anything moving is not at rest
        if (params_.layout.independent(body) && state[params_.layout.rate_slot[body]] != 0.0) return false;
    double rate[kMaxStateSize];
    if (!derivative(time, state, rate)) return false;
    for (int k = 0; k < params_.layout.size; ++k) {
        // Energy accumulators only integrate flows: they stay put when the flows are 0.
        if (rate[k] != 0.0) return false;
    }
    return true;
}

bool GimbalHybridSystem::time_dependent() const {
    return !base_constant_ || elements_.time_dependent(inputs_, modes_);
}

const Dynamics& GimbalHybridSystem::dynamics_at(double time, const double* state) {
    const int n = params_.layout.size;
    if (!cache_valid_ || time != cache_time_ || !std::equal(state, state + n, cache_state_)) {
        evaluate_dynamics(params_, inputs_, base_at(time), time, state, modes_, cache_);
        cache_time_ = time;
        std::copy(state, state + n, cache_state_);
        cache_valid_ = true;
    }
    return cache_;
}

int GimbalHybridSystem::kinematic_pairs(int* position, int* velocity) const {
    int pairs = 0;
    for (int body = 0; body < 4; ++body) {
        if (!params_.layout.independent(body)) continue;
        position[pairs] = params_.layout.angle_slot[body];
        velocity[pairs++] = params_.layout.rate_slot[body];
    }
    return pairs;
}

bool GimbalHybridSystem::derivative(double time, const double* state, double* derivative) {
    // A restart asks again for the point where the mode decision just evaluated the dynamics.
    return state_derivative(params_, dynamics_at(time, state), derivative);
}

bool GimbalHybridSystem::jacobian(double time, const double* state, double* column_major) {
    const Dynamics& dynamics = dynamics_at(time, state);
    evaluate_jacobian(params_, modes_, base_at(time), dynamics, column_major);
    return true;
}

int GimbalHybridSystem::relaxing_states(RelaxingState* out) const {
    const StateLayout& layout = params_.layout;
    if (layout.energy_slot >= 0) return 0;
    int count = 0;
    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params_.gear[axis];
        const int backlash = layout.backlash_slot[axis];
        const int rotor = layout.angle_slot[rotor_index(axis)], load = layout.angle_slot[load_index(axis)];
        if (backlash < 0 || rotor < 0 || load < 0 || modes_.gear_contact[axis] != 0) continue;
        if (params_.fidelity.gear[axis] != GearModel::backlash || !(gear.half_backlash > 0.0) || !(gear.damping > 0.0))
            continue;
        out[count++] = RelaxingState{backlash, gear.stiffness / gear.damping, rotor, gear.ratio, load};
    }
    return count;
}

void GimbalHybridSystem::event_functions(double time, const double* state, double* values) {
    const SwitchingContext context{params_, inputs_, dynamics_at(time, state), time};
    elements_.guards(context, modes_, values);
}

void GimbalHybridSystem::event_indicators(double time, const double* state, double* values) {
    std::fill(values, values + kIndicatorCount, 1.0);
    double guards[kIndicatorCount];
    event_functions(time, state, guards);
    for (int k = 0; k < event_count(); ++k) values[elements_.indicator_of_guard(k)] = guards[k];
}

int GimbalHybridSystem::update_modes(double time, double* state, const int* directions) {
    const Modes previous = modes_;
    previous_modes_ = previous;
    const int n = params_.layout.size;
    double state_before[kMaxStateSize];
    std::copy(state, state + n, state_before);
    Dynamics d = dynamics_at(time, state);
    cache_valid_ = false;  // new modes, and perhaps a projected state
    const BaseKinematics base = base_at(time);
    const SwitchingContext context{params_, inputs_, d, time};
    elements_.decide(context, previous, modes_, state, directions,
                     [&] { evaluate_dynamics(params_, inputs_, base, time, state, modes_, d); });

    const int changes = elements_.count_changes(previous, modes_, counters_);
    counters_.total += changes;
    if (changes > 0) counters_.last_event_time = time;
    // Unchanged modes and state: the dynamics just evaluated are those of this point.
    if (changes == 0 && std::equal(state, state + n, state_before)) {
        cache_ = d;
        cache_time_ = time;
        std::copy(state, state + n, cache_state_);
        cache_valid_ = true;
    }
    return changes;
}

std::string GimbalHybridSystem::describe_last_changes() const { return elements_.describe(previous_modes_, modes_); }

}  // namespace gimbal
