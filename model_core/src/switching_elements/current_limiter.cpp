#include "gimbal/switching_elements/current_limiter.hpp"

#include <algorithm>

namespace gimbal {
namespace {

const char* limit_name(int side) { return side > 0 ? "held at +i_L" : (side < 0 ? "held at -i_L" : "free"); }

}  // namespace

bool current_state_row(const ModelParameters& params, const Modes& modes, int axis, const Mat4& T, Row12& row) {
    if (params.layout.current_slot[axis] < 0 || modes.motor_limited[axis] != 0) return false;
    const MotorParameters& motor = params.motor[axis];
    row = Row12::Zero();
    if (current_driven(params, axis)) {
        const AmplifierSlopes slopes = amplifier_slopes(params, modes, axis);
        row.segment<4>(kRateColumn) =
            (slopes.rotor_rate - motor.back_emf_constant) / motor.inductance * T.row(rotor_index(axis));
        row(kCurrentColumn + axis) = (slopes.current - motor.resistance) / motor.inductance;
        return true;
    }
    row.segment<4>(kRateColumn) = -motor.back_emf_constant / motor.inductance * T.row(rotor_index(axis));
    row(kCurrentColumn + axis) = -motor.resistance / motor.inductance;
    return true;
}

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
    const int current = previous.motor_limited[axis_];
    const int current_slot = context.params.layout.current_slot[axis_];
    modes.motor_limited[axis_] = current_slot >= 0
                                     ? decide_inductive(context, current, state[current_slot], crossings)
                                     : decide_quasi_static(context, current, crossings);
}

// The inductive current is continuous: held until the free circuit turns back from the limit.
int CurrentLimiterElement::decide_inductive(const SwitchingContext& context, int current, double& state_current,
                                            const int* crossings) const {
    const double limit = context.params.motor[axis_].current_limit;
    const double steady = context.dynamics.steady_current[axis_];
    const double free_current = state_current;
    const bool at_plus = current == 1 || (current == 0 && side(free_current - limit, crossings, 0) >= 0);
    const bool at_minus = current == -1 || (current == 0 && side(free_current + limit, crossings, 1) <= 0);
    int push = 0;
    if (at_plus) push = side(steady - limit, crossings, current == 1 ? 0 : -1);
    if (at_minus && !at_plus) push = side(steady + limit, crossings, current == -1 ? 0 : -1);
    const int limited = switching::select_contact(at_plus, at_minus, push, current);
    state_current = limited != 0 ? limited * limit : std::clamp(state_current, -limit, limit);
    return limited;
}

// A quasi-static motor's current is the steady current, which jumps with the voltage: decide from
// where it lies now, on either side, not only whether the old limit still holds.
int CurrentLimiterElement::decide_quasi_static(const SwitchingContext& context, int current,
                                               const int* crossings) const {
    const double limit = context.params.motor[axis_].current_limit;
    const double steady = context.dynamics.steady_current[axis_];
    const int crossing_plus = current == 0 || current == 1 ? crossing(crossings, 0) : 0;
    const int crossing_minus = current == 0 ? crossing(crossings, 1) : (current == -1 ? crossing(crossings, 0) : 0);
    const int above = crossing_plus != 0 ? crossing_plus : switching::sign(steady - limit);
    const int below = crossing_minus != 0 ? crossing_minus : switching::sign(steady + limit);
    if (above > 0 || (above == 0 && current == 1)) return 1;
    if (below < 0 || (below == 0 && current == -1)) return -1;
    return 0;
}

std::string CurrentLimiterElement::describe(const Modes& before, const Modes& after) const {
    if (!changed(before, after)) return std::string();
    return switching::transition(limit_name(before.motor_limited[axis_]), limit_name(after.motor_limited[axis_]));
}

}  // namespace gimbal
