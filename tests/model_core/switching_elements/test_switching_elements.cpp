// The switching elements one by one (model_core/*/switching_elements/): each element's guards, mode
// decision, state projection, transition text and force / Jacobian contributions, on the default
// model at a chosen state; then the registration (element_registry). A new element adds its section
// here (docs/architecture.md, "Adding a switching element").
#include <cmath>
#include <string>

#include "check.hpp"
#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/simulation/parameter_building.hpp"
#include "gimbal/switching_elements/element_registry.hpp"

using namespace gimbal;

namespace {

ModelParameters default_parameters(bool inductive = true) {
    static double reals[kRealVariableCount];
    static int integers[kIntegerVariableCount];
    static bool flags[kBooleanVariableCount];
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals[vr] = kRealVariables[vr].start;
    for (unsigned vi = 0; vi < kIntegerVariableCount; ++vi) integers[vi] = static_cast<int>(kIntegerVariables[vi].start);
    for (unsigned vb = 0; vb < kBooleanVariableCount; ++vb) flags[vb] = kBooleanVariables[vb].start != 0.0;
    if (!inductive) integers[vi_motor1_model] = integers[vi_motor2_model] = 0;
    ModelParameters params;
    std::string error;
    if (!build_model_parameters(reals, integers, flags, params, error)) std::fprintf(stderr, "%s\n", error.c_str());
    return params;
}

// The dynamics at (time, state) under `modes`, fixed base.
Dynamics dynamics_at(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                     const double* state) {
    Dynamics d;
    evaluate_dynamics(params, inputs, base_kinematics_at(params, inputs, time), time, state, modes, d);
    return d;
}

void test_gear_backlash() {
    const ModelParameters params = default_parameters();
    const double eta = params.gear[0].half_backlash;
    CHECK(eta > 0.0 && !dead_zone_gear(params.gear[0]));
    const StepInputs inputs;
    Modes modes;
    double state[kMaxStateSize] = {};
    state[params.layout.backlash_slot[0]] = 1.5 * eta;  // beyond the + stop, in the gap mode
    const Dynamics d = dynamics_at(params, inputs, modes, 0.0, state);
    const SwitchingContext context{params, inputs, d, 0.0};
    const BacklashElement element(0, 0);
    double guards[2];
    element.guards(context, modes, guards);
    CHECK_NEAR(guards[0], 0.5 * eta, 1e-18);  // theta_b - eta
    CHECK_NEAR(guards[1], 2.5 * eta, 1e-18);  // theta_b + eta
    // Crossing the + stop upward: contact, theta_b projected onto the stop.
    const int crossings[2] = {1, 0};
    Modes decided = modes;
    element.decide(context, modes, decided, state, crossings);
    CHECK(decided.gear_contact[0] == 1);
    CHECK(state[params.layout.backlash_slot[0]] == eta);
    CHECK(element.changed(modes, decided));
    CHECK(element.describe(modes, decided) == "gap -> +eta stop");
    EventCounters counters;
    element.count_change(counters);
    CHECK(counters.backlash[0] == 1 && counters.backlash[1] == 0);
    // At a stop the shaft is a spring-damper on theta_d - theta_b: d T_E / d theta_b = -k_s on the load.
    Mat4x12 force = Mat4x12::Zero();
    add_gear_force_derivatives(params, decided, 0, force);
    CHECK(force(load_index(0), kBacklashColumn) == -params.gear[0].stiffness);
    CHECK(force(load_index(0), load_index(0)) == -params.gear[0].stiffness);
    Row12 row;
    CHECK(!backlash_state_row(params, decided, 0, coordinate_reduction(params), row));  // held: no dynamics
    CHECK(backlash_state_row(params, modes, 0, coordinate_reduction(params), row));     // in the gap
    CHECK_NEAR(row(kBacklashColumn), -params.gear[0].stiffness / params.gear[0].damping, 0.0);
}

void test_voltage_clamp() {
    const ModelParameters params = default_parameters();
    const double limit = params.motor[0].voltage_limit;
    StepInputs inputs;
    inputs.commanded_voltage[0] = inputs.voltage[0] = 0.5 * limit;
    inputs.voltage_rate[0] = limit;  // reaches +U_L at t = 0.5
    Modes modes;
    double state[kMaxStateSize] = {};
    const Dynamics d = dynamics_at(params, inputs, modes, 0.75, state);
    const SwitchingContext context{params, inputs, d, 0.75};
    const VoltageClampElement element(0, 0);
    double guards[2];
    element.guards(context, modes, guards);
    CHECK_NEAR(guards[0], 0.25 * limit, 1e-12);
    CHECK_NEAR(applied_voltage(params, inputs, modes, 0, 0.75), 1.25 * limit, 1e-12);  // following the ramp
    Modes decided = modes;
    element.decide(context, modes, decided, state, nullptr);
    CHECK(decided.voltage_clamped[0] == 1);
    CHECK(applied_voltage(params, inputs, decided, 0, 0.75) == limit);
    CHECK(element.describe(modes, decided) == "following the ramp -> at +U_L");
    // A held voltage (no derivative) is clamped once per step, not by this element.
    inputs.voltage_rate[0] = 0.0;
    element.decide(context, modes, decided, state, nullptr);
    CHECK(decided.voltage_clamped[0] == 0);
}

void test_current_limiter() {
    const ModelParameters params = default_parameters();
    const double limit = params.motor[0].current_limit;
    const int slot = params.layout.current_slot[0];
    StepInputs inputs;
    Modes modes;
    double state[kMaxStateSize] = {};
    state[slot] = 1.2 * limit;
    // The free circuit keeps pushing: the steady current beyond the limit.
    inputs.voltage[0] = inputs.commanded_voltage[0] = 2.0 * limit * params.motor[0].resistance;
    const Dynamics d = dynamics_at(params, inputs, modes, 0.0, state);
    CHECK(d.steady_current[0] > limit);
    const SwitchingContext context{params, inputs, d, 0.0};
    const CurrentLimiterElement element(0, 0);
    double guards[2];
    element.guards(context, modes, guards);
    CHECK_NEAR(guards[0], 0.2 * limit, 1e-12);
    Modes decided = modes;
    element.decide(context, modes, decided, state, nullptr);
    CHECK(decided.motor_limited[0] == 1);
    CHECK(state[slot] == limit);
    CHECK(element.describe(modes, decided) == "free -> held at +i_L");
    // Held: the current is no state of the dynamics, and the motor torque no function of it.
    Mat4x12 force = Mat4x12::Zero();
    add_motor_force_derivatives(params, decided, 0, force);
    CHECK(force.isZero(0.0));
    Row12 row;
    CHECK(!current_state_row(params, decided, 0, coordinate_reduction(params), row));
    add_motor_force_derivatives(params, modes, 0, force);
    CHECK(force(rotor_index(0), kCurrentColumn) == params.motor[0].torque_constant);
    // Quasi-static: the current is the steady current, decided from where it lies now.
    const ModelParameters quasi_static = default_parameters(false);
    const Dynamics dq = dynamics_at(quasi_static, inputs, modes, 0.0, state);
    const SwitchingContext quasi_context{quasi_static, inputs, dq, 0.0};
    Modes quasi_decided = modes;
    element.decide(quasi_context, modes, quasi_decided, state, nullptr);
    CHECK(quasi_decided.motor_limited[0] == 1);
}

void test_dry_friction() {
    const ModelParameters params = default_parameters();
    int body = -1;
    for (int k = 0; k < 4 && body < 0; ++k)
        if (params.coordinate_friction[k].present()) body = k;
    CHECK(body >= 0);
    if (body < 0) return;
    const DryFrictionParameters& friction = params.coordinate_friction[body];
    const StepInputs inputs;
    Modes modes;
    modes.friction[body] = FrictionMode::slip_positive;
    double state[kMaxStateSize] = {};
    state[params.layout.rate_slot[body]] = 0.5 * friction.stick_speed;  // below w_min
    const Dynamics d = dynamics_at(params, inputs, modes, 0.0, state);
    CHECK(d.friction_torque[body] == -friction.slip_torque);
    const SwitchingContext context{params, inputs, d, 0.0};
    const DryFrictionElement element(body, 0);
    double guards[6];
    element.guards(context, modes, guards);
    CHECK_NEAR(guards[0], -0.5 * friction.stick_speed, 1e-18);
    CHECK(guards[2] == 1.0 && guards[5] == 1.0);  // the torque guards only at low speed
    const int crossings[6] = {-1, 0, 0, 0, 0, 0};
    Modes decided = modes;
    element.decide(context, modes, decided, state, crossings);
    CHECK(decided.friction[body] == FrictionMode::hold);  // a stick candidate
    const Dynamics held = dynamics_at(params, inputs, decided, 0.0, state);
    const SwitchingContext held_context{params, inputs, held, 0.0};
    element.decide_torque(held_context, modes, decided, crossings);
    CHECK(low_speed(decided.friction[body]));
    CHECK(element.describe(modes, decided).rfind("slipping + -> ", 0) == 0);
    CHECK(friction_mode_indicator(FrictionMode::slip_positive, 0.0) == 2);
    EventCounters counters;
    element.count_change(counters);
    CHECK(counters.stick_slip == 1);
}

void test_registry() {
    const ModelParameters params = default_parameters();
    const SwitchingElementSet elements(params);
    int friction_bodies = 0;
    for (int k = 0; k < 4; ++k) friction_bodies += params.coordinate_friction[k].present() ? 1 : 0;
    int backlash_gears = 0;
    for (int axis = 0; axis < 2; ++axis) backlash_gears += params.layout.backlash_slot[axis] >= 0 ? 1 : 0;
    CHECK(elements.guard_count() == 2 * backlash_gears + 4 + 4 + 6 * friction_bodies);
    // Each guard has its own fixed indicator, in increasing order, within the FMU's indicators.
    for (int k = 0; k < elements.guard_count(); ++k) {
        CHECK(elements.indicator_of_guard(k) >= 0 && elements.indicator_of_guard(k) < kEventIndicatorCount);
        if (k > 0) CHECK(elements.indicator_of_guard(k) > elements.indicator_of_guard(k - 1));
    }
    // Modes that differ in two elements: two changes, each in its counter, both described.
    Modes before, after;
    after.gear_contact[1] = -1;
    after.motor_limited[0] = 1;
    EventCounters counters;
    CHECK(elements.count_changes(before, after, counters) == 2);
    CHECK(counters.backlash[1] == 1 && counters.current_limit[0] == 1);
    CHECK(elements.describe(before, after) == "gear2 backlash: gap -> -eta stop; motor1 current limiter: free -> held at +i_L");
}

}  // namespace

// An axis stop's hold (axis_stop.hpp): the reaction that keeps the stopped coordinate's acceleration at 0
// is a torque on that coordinate alone (M (qdd_held - qdd_free) = e_s torque); the joint solve of several
// resting stops, given one, is the single stop's hold, and so is its Jacobian projection.
void test_axis_stop_hold() {
    const ModelParameters params = default_parameters();
    const StepInputs inputs;
    double state[kMaxStateSize] = {};
    state[params.layout.angle_slot[kAxisStops[0].coordinate]] = 0.3;
    state[params.layout.rate_slot[kAzimuthBody]] = 0.2;
    Modes free_modes, resting;
    resting.axis_stop[0] = 1;
    const Dynamics free = dynamics_at(params, inputs, free_modes, 0.0, state);
    const Dynamics held = dynamics_at(params, inputs, resting, 0.0, state);
    const int s = kAxisStops[0].coordinate;
    CHECK(free.stop_torque[0] == 0.0 && held.stop_torque[0] != 0.0 && held.acceleration[s] == 0.0);
    const Vec4 reaction = held.reduced_mass * (held.acceleration - free.acceleration);
    for (int k = 0; k < 4; ++k)
        CHECK(std::fabs(reaction[k] - (k == s ? held.stop_torque[0] : 0.0)) <= 1e-9 * std::fabs(held.stop_torque[0]));

    Dynamics joint = free;
    const int stops[1] = {0};
    axis_stop_detail::hold_together(stops, 1, joint);
    CHECK(joint.acceleration[s] == 0.0);
    CHECK(std::fabs(joint.stop_torque[0] - held.stop_torque[0]) <= 1e-12 * std::fabs(held.stop_torque[0]));
    CHECK((joint.acceleration - held.acceleration).cwiseAbs().maxCoeff() <= 1e-12 * held.acceleration.cwiseAbs().maxCoeff());

    Mat4x12 derivative;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 12; ++c) derivative(r, c) = std::sin(1.0 + r + 4.0 * c);
    Mat4x12 single = derivative, together = derivative;
    hold_at_axis_stops_derivatives(resting, free.reduced_mass, single);
    axis_stop_detail::hold_together_derivatives(stops, 1, free.reduced_mass, together);
    CHECK(single.row(s).isZero(0.0) && together.row(s).isZero(0.0));
    CHECK((single - together).cwiseAbs().maxCoeff() <= 1e-12 * derivative.cwiseAbs().maxCoeff());
    Mat4x12 untouched = derivative;
    hold_at_axis_stops_derivatives(free_modes, free.reduced_mass, untouched);
    CHECK(untouched == derivative);
}

// A restored state's modes against the elements the parameters define (impossible_mode, each class's
// rule): a mode of an element the model lacks is refused, naming it; the model's own modes are not.
void test_impossible_modes() {
    ModelParameters params = default_parameters();
    Modes modes;
    CHECK(impossible_mode(params, modes).empty());
    modes.gear_contact[0] = 1;
    modes.friction[2] = FrictionMode::hold;
    CHECK(impossible_mode(params, modes).empty());  // backlash gears and dry friction by default
    modes.axis_stop[0] = -1;
    CHECK(impossible_mode(params, modes) == "the elevation_stop mode is set but the stop is off (elevation_stop = false)");
    params.axis_stop[0].present = true;
    CHECK(impossible_mode(params, modes).empty());
    modes.amplifier_saturated[1] = 1;
    CHECK(impossible_mode(params, modes) == "motor 2 is in voltage drive but has an amplifier saturation mode");
    params.fidelity.drive[1] = DriveMode::current;
    CHECK(impossible_mode(params, modes).empty());
    params.fidelity.dry_friction = false;
    CHECK(impossible_mode(params, modes) == "a friction mode is set but dry friction is off");
    params.fidelity.gear[0] = GearModel::rigid;
    CHECK(impossible_mode(params, modes) == "gear 1 has no backlash but a contact mode");
}

int main() {
    test_gear_backlash();
    test_voltage_clamp();
    test_current_limiter();
    test_dry_friction();
    test_axis_stop_hold();
    test_impossible_modes();
    test_registry();
    return check_report("switching_elements");
}
