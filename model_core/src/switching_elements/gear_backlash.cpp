#include "gimbal/switching_elements/gear_backlash.hpp"

#include <algorithm>

namespace gimbal {
namespace {

const char* contact_name(int side) { return side > 0 ? "+eta stop" : (side < 0 ? "-eta stop" : "gap"); }

}  // namespace

bool backlash_state_row(const ModelParameters& params, const Modes& modes, int axis, const Mat4& T, Row12& row) {
    const GearParameters& gear = params.gear[axis];
    if (params.layout.backlash_slot[axis] < 0 || modes.gear_contact[axis] != 0 || gear.half_backlash <= 0.0)
        return false;
    const int rotor = rotor_index(axis), load = load_index(axis);
    // theta_d = (e_r / N - e_l) q_full = (e_r / N - e_l) T q_padded, likewise its rate.
    const Eigen::Matrix<double, 1, 4> deflection = (Vec4::Unit(rotor) / gear.ratio - Vec4::Unit(load)).transpose() * T;
    row = Row12::Zero();
    row.segment<4>(kRateColumn) = deflection;
    if (!dead_zone_gear(gear)) {
        const double rate = gear.stiffness / gear.damping;
        row.segment<4>(kAngleColumn) = rate * deflection;
        row(kBacklashColumn + axis) = -rate;
    }
    return true;
}

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
        contact = decide_compliant(context, current, backlash, crossings);
    }
    modes.gear_contact[axis_] = contact;
}

int BacklashElement::decide_compliant(const SwitchingContext& context, int current, double& backlash,
                                      const int* crossings) const {
    const double eta = context.params.gear[axis_].half_backlash;
    const bool in_gap = current == 0;
    const bool at_plus = !in_gap ? current == 1 : (side(backlash - eta, crossings, 0) >= 0);
    const bool at_minus = !in_gap ? current == -1 : (side(backlash + eta, crossings, 1) <= 0);
    const int pull = side(context.dynamics.free_backlash_rate[axis_], crossings, in_gap ? -1 : 0);
    int contact = switching::select_contact(at_plus, at_minus, pull, current);
    // A located crossing of a stop from inside the gap is a contact: theta_b was moving outward,
    // whatever sign X has on the root state (with k_s/c_s ~ 1e10 rounding flips it).
    if (in_gap && crossing(crossings, 0) > 0) contact = 1;
    if (in_gap && crossing(crossings, 1) < 0) contact = -1;
    backlash = contact != 0 ? contact * eta : std::clamp(backlash, -eta, eta);
    return contact;
}

std::string BacklashElement::describe(const Modes& before, const Modes& after) const {
    if (!changed(before, after)) return std::string();
    return switching::transition(contact_name(before.gear_contact[axis_]), contact_name(after.gear_contact[axis_]));
}

}  // namespace gimbal
