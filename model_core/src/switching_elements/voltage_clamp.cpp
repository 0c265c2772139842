#include "gimbal/switching_elements/voltage_clamp.hpp"

namespace gimbal {
namespace {

const char* clamp_name(int side) { return side > 0 ? "at +U_L" : (side < 0 ? "at -U_L" : "following the ramp"); }

}  // namespace

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
    if (!changed(before, after)) return std::string();
    return switching::transition(clamp_name(before.voltage_clamped[axis_]), clamp_name(after.voltage_clamped[axis_]));
}

}  // namespace gimbal
