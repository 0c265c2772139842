#include "gimbal/switching_elements/switching_elements.hpp"

#include <algorithm>

namespace gimbal {
namespace {

int sign(double value) { return value > 0.0 ? 1 : (value < 0.0 ? -1 : 0); }

// Contact rule of (2.81) at one side, shared by the limiter: at the stop, and not pulled back.
int select_contact(bool at_plus_stop, bool at_minus_stop, int pull_sign, int current) {
    if (at_plus_stop && (pull_sign > 0 || (pull_sign == 0 && current == 1))) return 1;
    if (at_minus_stop && (pull_sign < 0 || (pull_sign == 0 && current == -1))) return -1;
    return 0;
}

std::string transition(const char* from, const char* to) { return std::string(from) + " -> " + to; }

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

int SwitchingElement::side(double value, const int* crossings, int guard) const {
    const int crossed = crossing(crossings, guard);
    return crossed != 0 ? crossed : sign(value);
}

// ----------------------------------------------------------------------------------------------------
BacklashElement::BacklashElement(int axis, int first_guard)
    : SwitchingElement("gear" + std::to_string(axis + 1) + " backlash", first_guard), axis_(axis) {}

void BacklashElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    g[0] = g[1] = 1.0;
    const GearParameters& gear = context.params.gear[axis_];
    const double eta = gear.half_backlash;
    if (eta == 0.0) return;
    const Dynamics& d = context.dynamics;
    if (dead_zone_gear(gear)) {
        g[0] = d.deflection[axis_] - eta;
        g[1] = d.deflection[axis_] + eta;
    } else if (modes.gear_contact[axis_] == 0) {
        g[0] = d.full.backlash[axis_] - eta;  // reaching the + stop
        g[1] = d.full.backlash[axis_] + eta;  // reaching the - stop
    } else {
        g[0] = d.free_backlash_rate[axis_];   // X changing sign: pulled back into the gap
    }
}

void BacklashElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                             const int* crossings) const {
    const GearParameters& gear = context.params.gear[axis_];
    const Dynamics& d = context.dynamics;
    const double eta = gear.half_backlash;
    const int current = previous.gear_contact[axis_];
    double& backlash = state[context.params.layout.backlash_slot[axis_]];
    int contact = 0;
    if (eta == 0.0) {
        backlash = 0.0;
    } else if (dead_zone_gear(gear)) {
        const int above = side(d.deflection[axis_] - eta, crossings, 0);
        const int below = side(d.deflection[axis_] + eta, crossings, 1);
        if (above > 0 || (above == 0 && current == 1)) contact = 1;
        else if (below < 0 || (below == 0 && current == -1)) contact = -1;
        backlash = std::clamp(d.deflection[axis_], -eta, eta);
    } else {
        const bool in_gap = current == 0;
        const bool at_plus = !in_gap ? current == 1 : (side(backlash - eta, crossings, 0) >= 0);
        const bool at_minus = !in_gap ? current == -1 : (side(backlash + eta, crossings, 1) <= 0);
        const int pull = side(d.free_backlash_rate[axis_], crossings, in_gap ? -1 : 0);
        contact = select_contact(at_plus, at_minus, pull, current);
        // A located crossing of a stop from inside the gap is a contact: theta_b was moving outward,
        // whatever sign X has on the root state (with k_s/c_s ~ 1e10 rounding flips it).
        if (in_gap && crossing(crossings, 0) > 0) contact = 1;
        if (in_gap && crossing(crossings, 1) < 0) contact = -1;
        backlash = contact != 0 ? contact * eta : std::clamp(backlash, -eta, eta);
    }
    modes.gear_contact[axis_] = contact;
}

std::string BacklashElement::describe(const Modes& before, const Modes& after) const {
    if (before.gear_contact[axis_] == after.gear_contact[axis_]) return std::string();
    return transition(contact_name(before.gear_contact[axis_]), contact_name(after.gear_contact[axis_]));
}

// ----------------------------------------------------------------------------------------------------
VoltageClampElement::VoltageClampElement(int axis, int first_guard)
    : SwitchingElement("motor" + std::to_string(axis + 1) + " voltage clamp", first_guard), axis_(axis) {}

void VoltageClampElement::guards(const SwitchingContext& context, const Modes&, double* values) const {
    double* g = values + first_guard();
    g[0] = g[1] = 1.0;
    if (context.inputs.voltage_rate[axis_] == 0.0) return;
    const double ramp = ramped_voltage(context.inputs, axis_, context.time);
    const double limit = context.params.motor[axis_].voltage_limit;
    g[0] = ramp - limit;
    g[1] = ramp + limit;
}

void VoltageClampElement::decide(const SwitchingContext& context, const Modes&, Modes& modes, double*,
                                 const int* crossings) const {
    int clamped = 0;
    if (context.inputs.voltage_rate[axis_] != 0.0) {
        const double ramp = ramped_voltage(context.inputs, axis_, context.time);
        const double limit = context.params.motor[axis_].voltage_limit;
        if (side(ramp - limit, crossings, 0) >= 0) clamped = 1;
        else if (side(ramp + limit, crossings, 1) <= 0) clamped = -1;
    }
    modes.voltage_clamped[axis_] = clamped;
}

std::string VoltageClampElement::describe(const Modes& before, const Modes& after) const {
    if (before.voltage_clamped[axis_] == after.voltage_clamped[axis_]) return std::string();
    return transition(clamp_name(before.voltage_clamped[axis_]), clamp_name(after.voltage_clamped[axis_]));
}

// ----------------------------------------------------------------------------------------------------
CurrentLimiterElement::CurrentLimiterElement(int axis, int first_guard)
    : SwitchingElement("motor" + std::to_string(axis + 1) + " current limiter", first_guard), axis_(axis) {}

void CurrentLimiterElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    g[0] = g[1] = 1.0;
    const Dynamics& d = context.dynamics;
    const double limit = context.params.motor[axis_].current_limit;
    const int limited = modes.motor_limited[axis_];
    // A quasi-static motor's current is the steady current itself: the same functions apply.
    const double free_current =
        context.params.layout.current_slot[axis_] >= 0 ? d.full.current[axis_] : d.steady_current[axis_];
    if (limited == 0) {
        g[0] = free_current - limit;
        g[1] = free_current + limit;
    } else {
        g[0] = d.steady_current[axis_] - limited * limit;  // the free circuit turning back from the limit
    }
}

void CurrentLimiterElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes,
                                   double* state, const int* crossings) const {
    const Dynamics& d = context.dynamics;
    const double limit = context.params.motor[axis_].current_limit;
    const int current = previous.motor_limited[axis_];
    const int current_slot = context.params.layout.current_slot[axis_];
    const double steady = d.steady_current[axis_];
    int limited;
    if (current_slot >= 0) {
        // The inductive current is continuous: held until the free circuit turns back from the limit.
        const double free_current = state[current_slot];
        const bool at_plus = current == 1 || (current == 0 && side(free_current - limit, crossings, 0) >= 0);
        const bool at_minus = current == -1 || (current == 0 && side(free_current + limit, crossings, 1) <= 0);
        int push = 0;
        if (at_plus) push = side(steady - limit, crossings, current == 1 ? 0 : -1);
        if (at_minus && !at_plus) push = side(steady + limit, crossings, current == -1 ? 0 : -1);
        limited = select_contact(at_plus, at_minus, push, current);
        state[current_slot] = limited != 0 ? limited * limit : std::clamp(state[current_slot], -limit, limit);
    } else {
        // A quasi-static motor's current is the steady current, which jumps with the voltage: decide
        // from where it lies now, on either side, not only whether the old limit still holds.
        const int crossing_plus = current == 0 || current == 1 ? crossing(crossings, 0) : 0;
        const int crossing_minus = current == 0 ? crossing(crossings, 1) : (current == -1 ? crossing(crossings, 0) : 0);
        const int above = crossing_plus != 0 ? crossing_plus : sign(steady - limit);
        const int below = crossing_minus != 0 ? crossing_minus : sign(steady + limit);
        if (above > 0 || (above == 0 && current == 1)) limited = 1;
        else if (below < 0 || (below == 0 && current == -1)) limited = -1;
        else limited = 0;
    }
    modes.motor_limited[axis_] = limited;
}

std::string CurrentLimiterElement::describe(const Modes& before, const Modes& after) const {
    if (before.motor_limited[axis_] == after.motor_limited[axis_]) return std::string();
    return transition(limit_name(before.motor_limited[axis_]), limit_name(after.motor_limited[axis_]));
}

// ----------------------------------------------------------------------------------------------------
DryFrictionElement::DryFrictionElement(int body, int first_guard)
    : SwitchingElement(std::string(kBodyNames[body]) + " dry friction", first_guard), body_(body) {}

void DryFrictionElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    std::fill(g, g + 6, 1.0);
    const DryFrictionParameters& friction = context.params.coordinate_friction[body_];
    const Dynamics& d = context.dynamics;
    const double rate = d.full.rate[body_];
    g[0] = rate - friction.stick_speed;
    g[1] = rate + friction.stick_speed;
    if (low_speed(modes.friction[body_])) {
        const double other = d.other_torque[body_];
        const double hold = -other - friction.numerical_damping() * rate;
        g[2] = other - friction.breakaway_torque;  // (2.99) breakaway
        g[3] = other + friction.breakaway_torque;
        g[4] = hold - friction.breakaway_torque;   // (2.102) the hold torque reaching its clip
        g[5] = hold + friction.breakaway_torque;
    }
}

void DryFrictionElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double*,
                                const int* crossings) const {
    const DryFrictionParameters& friction = context.params.coordinate_friction[body_];
    const double rate = context.dynamics.full.rate[body_];
    const int above = side(rate - friction.stick_speed, crossings, 0);
    const int below = side(rate + friction.stick_speed, crossings, 1);
    if (above >= 0) modes.friction[body_] = FrictionMode::slip_positive;
    else if (below <= 0) modes.friction[body_] = FrictionMode::slip_negative;
    else if (!low_speed(previous.friction[body_])) modes.friction[body_] = FrictionMode::hold;
    else modes.friction[body_] = previous.friction[body_];
}

void DryFrictionElement::decide_torque(const SwitchingContext& context, const Modes& previous, Modes& modes,
                                       const int* crossings) const {
    if (!low_speed(modes.friction[body_])) return;
    const DryFrictionParameters& friction = context.params.coordinate_friction[body_];
    const Dynamics& d = context.dynamics;
    // Guards 2..5 carried these functions only if the body was already at low speed.
    const bool tracked = low_speed(previous.friction[body_]);
    const double other = d.other_torque[body_];
    const double hold = -other - friction.numerical_damping() * d.full.rate[body_];
    const double limit = friction.breakaway_torque;
    FrictionMode mode = FrictionMode::hold;
    // (2.99): break away when |T_outros| >= T_max (a tie breaks away); (2.102): clip the hold torque.
    if (side(other - limit, crossings, tracked ? 2 : -1) >= 0) mode = FrictionMode::at_max_negative;
    else if (side(other + limit, crossings, tracked ? 3 : -1) <= 0) mode = FrictionMode::at_max_positive;
    else if (side(hold - limit, crossings, tracked ? 4 : -1) > 0) mode = FrictionMode::at_max_positive;
    else if (side(hold + limit, crossings, tracked ? 5 : -1) < 0) mode = FrictionMode::at_max_negative;
    modes.friction[body_] = mode;
}

std::string DryFrictionElement::describe(const Modes& before, const Modes& after) const {
    if (before.friction[body_] == after.friction[body_]) return std::string();
    return transition(friction_name(before.friction[body_]), friction_name(after.friction[body_]));
}

}  // namespace gimbal
