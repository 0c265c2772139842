#include "gimbal/gimbal_hybrid_system.hpp"

#include <algorithm>
#include <sstream>

namespace gimbal {
namespace {

constexpr int gear_slot(int axis) { return GimbalHybridSystem::kGearSlots * axis; }
constexpr int motor_slot(int axis) { return 2 * GimbalHybridSystem::kGearSlots + GimbalHybridSystem::kMotorSlots * axis; }
constexpr int friction_slot(int body) {
    return 2 * GimbalHybridSystem::kGearSlots + 2 * GimbalHybridSystem::kMotorSlots +
           GimbalHybridSystem::kFrictionSlots * body;
}

bool same_modes(const Modes& a, const Modes& b) {
    for (int axis = 0; axis < 2; ++axis)
        if (a.gear_contact[axis] != b.gear_contact[axis] || a.motor_limited[axis] != b.motor_limited[axis] ||
            a.voltage_clamped[axis] != b.voltage_clamped[axis])
            return false;
    for (int body = 0; body < 4; ++body)
        if (a.friction[body] != b.friction[body]) return false;
    return true;
}

int sign(double value) { return value > 0.0 ? 1 : (value < 0.0 ? -1 : 0); }

// Sign of an event function at a mode decision. Right after a located crossing the function may sit
// exactly on zero or a rounding error short of it: the crossing direction then decides.
int side(double value, const int* directions, int slot) {
    if (directions != nullptr && slot >= 0 && directions[slot] != 0) return directions[slot];
    return sign(value);
}

// Contact rule of (2.81) at one side: at the stop, and not pulled back into the gap.
int select_contact(bool at_plus_stop, bool at_minus_stop, int pull_sign, int current) {
    if (at_plus_stop && (pull_sign > 0 || (pull_sign == 0 && current == 1))) return 1;
    if (at_minus_stop && (pull_sign < 0 || (pull_sign == 0 && current == -1))) return -1;
    return 0;
}

}  // namespace

int friction_mode_indicator(FrictionMode mode, double rate) {
    switch (mode) {
        case FrictionMode::slip_positive: return 2;
        case FrictionMode::slip_negative: return -2;
        case FrictionMode::hold: return 0;
        case FrictionMode::at_max_positive: return -1;  // friction pushes +: the body is driven -
        case FrictionMode::at_max_negative: return 1;
        case FrictionMode::none: break;
    }
    return rate >= 0.0 ? 2 : -2;
}

const BaseKinematics& GimbalHybridSystem::base_at(double time) {
    // The integrator asks for the same instant several times (right-hand side, events, Jacobian), and
    // a fixed or non-rotating base never changes: evaluate its trigonometry once.
    if (!base_cached_ || (time != base_time_ && !base_constant_)) {
        base_ = base_kinematics_at(params_, inputs_, time);
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
    base_constant_ = params_.fidelity.fixed_base ||
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
    return !base_constant_ || (inputs_.voltage_rate[0] != 0.0 && modes_.voltage_clamped[0] == 0) ||
           (inputs_.voltage_rate[1] != 0.0 && modes_.voltage_clamped[1] == 0);
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

bool GimbalHybridSystem::derivative(double time, const double* state, double* derivative) {
    const int n = params_.layout.size;
    evaluate_dynamics(params_, inputs_, base_at(time), time, state, modes_, cache_);
    cache_time_ = time;
    std::copy(state, state + n, cache_state_);
    cache_valid_ = true;
    return state_derivative(params_, cache_, derivative);
}

bool GimbalHybridSystem::jacobian(double time, const double* state, double* column_major) {
    const Dynamics& dynamics = dynamics_at(time, state);
    evaluate_jacobian(params_, modes_, base_at(time), dynamics, column_major);
    return true;
}

void GimbalHybridSystem::event_functions(double time, const double* state, double* values) {
    std::fill(values, values + kEventCount, 1.0);
    const Dynamics& d = dynamics_at(time, state);

    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params_.gear[axis];
        double* g = values + gear_slot(axis);
        const double eta = gear.half_backlash;
        if (params_.fidelity.gear[axis] != GearModel::backlash || eta == 0.0) continue;
        if (dead_zone_gear(gear)) {
            g[0] = d.deflection[axis] - eta;
            g[1] = d.deflection[axis] + eta;
        } else if (modes_.gear_contact[axis] == 0) {
            g[0] = d.full.backlash[axis] - eta;
            g[1] = d.full.backlash[axis] + eta;
        } else {
            g[0] = d.free_backlash_rate[axis];
        }
    }
    for (int axis = 0; axis < 2; ++axis) {
        const double limit = params_.motor[axis].current_limit;
        double* g = values + motor_slot(axis);
        const int limited = modes_.motor_limited[axis];
        // A quasi-static motor's current is the steady current itself: the same functions apply.
        const double free_current =
            params_.layout.current_slot[axis] >= 0 ? d.full.current[axis] : d.steady_current[axis];
        if (limited == 0) {
            g[0] = free_current - limit;
            g[1] = free_current + limit;
        } else {
            g[0] = d.steady_current[axis] - limited * limit;
        }
        // A ramped voltage (input derivatives) reaching the clamp of (2.142-2.145).
        if (inputs_.voltage_rate[axis] != 0.0) {
            const double ramp = ramped_voltage(inputs_, axis, time);
            g[2] = ramp - params_.motor[axis].voltage_limit;
            g[3] = ramp + params_.motor[axis].voltage_limit;
        }
    }
    for (int body = 0; body < 4; ++body) {
        const DryFrictionParameters& friction = params_.coordinate_friction[body];
        if (!friction.present()) continue;
        double* g = values + friction_slot(body);
        const double rate = d.full.rate[body];
        g[0] = rate - friction.stick_speed;
        g[1] = rate + friction.stick_speed;
        if (low_speed(modes_.friction[body])) {
            const double other = d.other_torque[body];
            const double hold = -other - friction.numerical_damping() * rate;
            g[2] = other - friction.breakaway_torque;
            g[3] = other + friction.breakaway_torque;
            g[4] = hold - friction.breakaway_torque;
            g[5] = hold + friction.breakaway_torque;
        }
    }
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

    for (int axis = 0; axis < 2; ++axis) {
        const GearParameters& gear = params_.gear[axis];
        const double eta = gear.half_backlash;
        const int slot = gear_slot(axis);
        const int current = previous.gear_contact[axis];
        const int backlash_slot = params_.layout.backlash_slot[axis];
        int contact = 0;
        if (backlash_slot < 0) {
            modes_.gear_contact[axis] = 0;
            continue;
        }
        double& backlash = state[backlash_slot];
        if (eta == 0.0) {
            backlash = 0.0;
        } else if (dead_zone_gear(gear)) {
            const int above = side(d.deflection[axis] - eta, directions, slot);
            const int below = side(d.deflection[axis] + eta, directions, slot + 1);
            if (above > 0 || (above == 0 && current == 1)) contact = 1;
            else if (below < 0 || (below == 0 && current == -1)) contact = -1;
            backlash = std::clamp(d.deflection[axis], -eta, eta);
        } else {
            const bool in_gap = current == 0;
            const bool at_plus = !in_gap ? current == 1 : (side(backlash - eta, directions, slot) >= 0);
            const bool at_minus = !in_gap ? current == -1 : (side(backlash + eta, directions, slot + 1) <= 0);
            const int pull = side(d.free_backlash_rate[axis], directions, in_gap ? -1 : slot);
            contact = select_contact(at_plus, at_minus, pull, current);
            // A located crossing of a stop from inside the gap is a contact: theta_b was moving outward,
            // whatever sign X has on the root state (with k_s/c_s ~ 1e10 rounding flips it).
            if (in_gap && directions != nullptr && directions[slot] > 0) contact = 1;
            if (in_gap && directions != nullptr && directions[slot + 1] < 0) contact = -1;
            backlash = contact != 0 ? contact * eta : std::clamp(backlash, -eta, eta);
        }
        modes_.gear_contact[axis] = contact;
    }

    for (int axis = 0; axis < 2; ++axis) {
        const double limit = params_.motor[axis].current_limit;
        const int slot = motor_slot(axis);
        // The clamp first: the limiter's steady current depends on the voltage.
        int clamped = 0;
        if (inputs_.voltage_rate[axis] != 0.0) {
            const double ramp = ramped_voltage(inputs_, axis, time);
            const double voltage_limit = params_.motor[axis].voltage_limit;
            if (side(ramp - voltage_limit, directions, slot + 2) >= 0) clamped = 1;
            else if (side(ramp + voltage_limit, directions, slot + 3) <= 0) clamped = -1;
        }
        if (clamped != modes_.voltage_clamped[axis]) {
            modes_.voltage_clamped[axis] = clamped;
            evaluate_dynamics(params_, inputs_, base, time, state, modes_, d);
        }
        const int current = previous.motor_limited[axis];
        const int current_slot = params_.layout.current_slot[axis];
        const double free_current = current_slot >= 0 ? state[current_slot] : d.steady_current[axis];
        const bool at_plus = current == 1 || (current == 0 && side(free_current - limit, directions, slot) >= 0);
        const bool at_minus = current == -1 || (current == 0 && side(free_current + limit, directions, slot + 1) <= 0);
        int push = 0;
        if (at_plus) push = side(d.steady_current[axis] - limit, directions, current == 1 ? slot : -1);
        if (at_minus && !at_plus) push = side(d.steady_current[axis] + limit, directions, current == -1 ? slot : -1);
        int limited = select_contact(at_plus, at_minus, push, current);
        if (current_slot < 0) {
            // A quasi-static motor's current is the steady current itself, which jumps with the voltage:
            // decide from where it lies now, on either side, not only whether the old limit still holds.
            const double steady = d.steady_current[axis];
            int crossing_plus = 0, crossing_minus = 0;
            if (directions != nullptr) {
                if (current == 0) crossing_plus = directions[slot], crossing_minus = directions[slot + 1];
                if (current == 1) crossing_plus = directions[slot];
                if (current == -1) crossing_minus = directions[slot];
            }
            const int above = crossing_plus != 0 ? crossing_plus : sign(steady - limit);
            const int below = crossing_minus != 0 ? crossing_minus : sign(steady + limit);
            if (above > 0 || (above == 0 && current == 1)) limited = 1;
            else if (below < 0 || (below == 0 && current == -1)) limited = -1;
            else limited = 0;
        }
        modes_.motor_limited[axis] = limited;
        if (current_slot >= 0)
            state[current_slot] = limited != 0 ? limited * limit : std::clamp(state[current_slot], -limit, limit);
    }

    // Low-speed set first: the other torques depend on which bodies are held, not on how.
    for (int body = 0; body < 4; ++body) {
        const DryFrictionParameters& friction = params_.coordinate_friction[body];
        if (!friction.present()) {
            modes_.friction[body] = FrictionMode::none;
            continue;
        }
        const int slot = friction_slot(body);
        const double rate = d.full.rate[body];
        const int above = side(rate - friction.stick_speed, directions, slot);
        const int below = side(rate + friction.stick_speed, directions, slot + 1);
        if (above >= 0) modes_.friction[body] = FrictionMode::slip_positive;
        else if (below <= 0) modes_.friction[body] = FrictionMode::slip_negative;
        else if (!low_speed(previous.friction[body])) modes_.friction[body] = FrictionMode::hold;
        else modes_.friction[body] = previous.friction[body];
    }
    // The other torques of the low-speed bodies depend on the modes and the state chosen so far.
    bool any_low_speed = false;
    for (int body = 0; body < 4; ++body) any_low_speed = any_low_speed || low_speed(modes_.friction[body]);
    if (any_low_speed && (!same_modes(modes_, previous) || !std::equal(state, state + n, state_before)))
        evaluate_dynamics(params_, inputs_, base, time, state, modes_, d);
    for (int body = 0; body < 4; ++body) {
        if (!low_speed(modes_.friction[body])) continue;
        const DryFrictionParameters& friction = params_.coordinate_friction[body];
        // Event slots 2..5 carried these functions only if the body was already at low speed.
        const int slot = low_speed(previous.friction[body]) ? friction_slot(body) : -1000;
        const double other = d.other_torque[body];
        const double hold = -other - friction.numerical_damping() * d.full.rate[body];
        const double limit = friction.breakaway_torque;
        FrictionMode mode = FrictionMode::hold;
        // (2.99): break away when |T_outros| >= T_max (a tie breaks away); (2.102): clip the hold torque.
        if (side(other - limit, directions, slot + 2) >= 0) mode = FrictionMode::at_max_negative;
        else if (side(other + limit, directions, slot + 3) <= 0) mode = FrictionMode::at_max_positive;
        else if (side(hold - limit, directions, slot + 4) > 0) mode = FrictionMode::at_max_positive;
        else if (side(hold + limit, directions, slot + 5) < 0) mode = FrictionMode::at_max_negative;
        modes_.friction[body] = mode;
    }

    int changes = 0;
    for (int axis = 0; axis < 2; ++axis) {
        if (modes_.voltage_clamped[axis] != previous.voltage_clamped[axis]) ++changes;
        if (modes_.gear_contact[axis] != previous.gear_contact[axis]) ++counters_.backlash[axis], ++changes;
        if (modes_.motor_limited[axis] != previous.motor_limited[axis]) ++counters_.current_limit[axis], ++changes;
    }
    for (int body = 0; body < 4; ++body)
        if (modes_.friction[body] != previous.friction[body]) ++counters_.stick_slip, ++changes;
    counters_.total += changes;
    if (changes > 0) counters_.last_event_time = time;
    return changes;
}

namespace {

const char* contact_name(int side) { return side > 0 ? "+eta stop" : (side < 0 ? "-eta stop" : "gap"); }
const char* limit_name(int side) { return side > 0 ? "held at +i_L" : (side < 0 ? "held at -i_L" : "free"); }
const char* clamp_name(int side) { return side > 0 ? "at +U_L" : (side < 0 ? "at -U_L" : "following the ramp"); }
const char* friction_name(FrictionMode mode) {
    switch (mode) {
        case FrictionMode::none: return "none";
        case FrictionMode::slip_positive: return "slipping +";
        case FrictionMode::slip_negative: return "slipping -";
        case FrictionMode::hold: return "stuck";
        case FrictionMode::at_max_positive: return "breaking away (+T_max)";
        case FrictionMode::at_max_negative: return "breaking away (-T_max)";
    }
    return "?";
}
const char* const kBodyNames[4] = {"body1", "rotor1", "body2", "rotor2"};

}  // namespace

std::string GimbalHybridSystem::describe_last_changes() const {
    std::ostringstream s;
    const char* separator = "";
    auto change = [&](const std::string& element, const char* from, const char* to) {
        s << separator << element << ": " << from << " -> " << to;
        separator = "; ";
    };
    for (int axis = 0; axis < 2; ++axis) {
        const std::string number = std::to_string(axis + 1);
        if (previous_modes_.gear_contact[axis] != modes_.gear_contact[axis])
            change("gear" + number + " backlash", contact_name(previous_modes_.gear_contact[axis]),
                   contact_name(modes_.gear_contact[axis]));
        if (previous_modes_.voltage_clamped[axis] != modes_.voltage_clamped[axis])
            change("motor" + number + " voltage clamp", clamp_name(previous_modes_.voltage_clamped[axis]),
                   clamp_name(modes_.voltage_clamped[axis]));
        if (previous_modes_.motor_limited[axis] != modes_.motor_limited[axis])
            change("motor" + number + " current limiter", limit_name(previous_modes_.motor_limited[axis]),
                   limit_name(modes_.motor_limited[axis]));
    }
    for (int body = 0; body < 4; ++body)
        if (previous_modes_.friction[body] != modes_.friction[body])
            change(std::string(kBodyNames[body]) + " dry friction", friction_name(previous_modes_.friction[body]),
                   friction_name(modes_.friction[body]));
    return s.str();
}

}  // namespace gimbal
