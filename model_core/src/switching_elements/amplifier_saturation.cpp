#include "gimbal/switching_elements/amplifier_saturation.hpp"

namespace gimbal {
namespace {

const char* output_name(int side) { return side > 0 ? "held at +U_L" : (side < 0 ? "held at -U_L" : "free"); }

}  // namespace

AmplifierSaturationElement::AmplifierSaturationElement(int axis, int first_guard)
    : SwitchingElement("motor" + std::to_string(axis + 1) + " amplifier", first_guard), axis_(axis) {}

// Free: u_unsat - U_L and u_unsat + U_L. Held at side s: u_unsat - s U_L, which crosses zero when the
// demand returns inside the limit.
void AmplifierSaturationElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    g[0] = g[1] = 1.0;
    if (!current_driven(context.params, axis_)) return;
    const double demand = context.dynamics.amplifier_demand[axis_];
    const double limit = context.params.motor[axis_].voltage_limit;
    const int side = modes.amplifier_saturated[axis_];
    if (side == 0) {
        g[0] = demand - limit;
        g[1] = demand + limit;
    } else {
        g[0] = demand - side * limit;
    }
}

// The demand does not depend on this element's own mode (x_I is a state, the quasi-static demand is the
// command's): decide from where it lies now, on either side; a guard exactly on zero by its crossing's
// direction, else the mode held.
void AmplifierSaturationElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double*,
                                        const int* crossings) const {
    if (!current_driven(context.params, axis_)) {
        modes.amplifier_saturated[axis_] = 0;
        return;
    }
    const int current = previous.amplifier_saturated[axis_];
    const double demand = context.dynamics.amplifier_demand[axis_];
    const double limit = context.params.motor[axis_].voltage_limit;
    const int crossing_plus = current == 0 || current == 1 ? crossing(crossings, 0) : 0;
    const int crossing_minus = current == 0 ? crossing(crossings, 1) : (current == -1 ? crossing(crossings, 0) : 0);
    const int above = crossing_plus != 0 ? crossing_plus : switching::sign(demand - limit);
    const int below = crossing_minus != 0 ? crossing_minus : switching::sign(demand + limit);
    int side = 0;
    if (above > 0 || (above == 0 && current == 1)) side = 1;
    else if (below < 0 || (below == 0 && current == -1)) side = -1;
    modes.amplifier_saturated[axis_] = side;
}

std::string AmplifierSaturationElement::describe(const Modes& before, const Modes& after) const {
    if (!changed(before, after)) return std::string();
    return switching::transition(output_name(before.amplifier_saturated[axis_]),
                                 output_name(after.amplifier_saturated[axis_]));
}

}  // namespace gimbal
