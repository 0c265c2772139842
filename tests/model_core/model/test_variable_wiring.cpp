// Every variable lands where its name says, whatever the order of the .def tables (issue 12): value
// references are only ever looked up here by name, and the field each name must reach is written by
// hand, so a reordered table that re-wires the core fails these checks.
//
// - parameters: each set to its own value, through build_model_parameters into ModelParameters;
// - start state and inputs: through GimbalInstance, against a reference run of the core built from
//   ModelParameters, the state vector and StepInputs field by field (no value references at all);
// - a fixed base refuses each base input by its name;
// - every variable a master may set reads back by name.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "check.hpp"
#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/simulation/gimbal_instance.hpp"
#include "gimbal/integrators/integrator.hpp"
#include "gimbal/simulation/parameter_building.hpp"

using namespace gimbal;

namespace {

template <class Variable>
Variable find_variable(const VariableInfo* table, unsigned count, const std::string& name) {
    for (unsigned v = 0; v < count; ++v)
        if (name == table[v].name) return static_cast<Variable>(v);
    std::fprintf(stderr, "no variable named %s: the test's names must be those of the .def tables\n", name.c_str());
    std::exit(1);
}
RealVariable real(const std::string& name) { return find_variable<RealVariable>(kRealVariables, kRealVariableCount, name); }
IntegerVariable integer(const std::string& name) {
    return find_variable<IntegerVariable>(kIntegerVariables, kIntegerVariableCount, name);
}
BooleanVariable boolean(const std::string& name) {
    return find_variable<BooleanVariable>(kBooleanVariables, kBooleanVariableCount, name);
}
bool is_real(const std::string& name) {
    for (unsigned v = 0; v < kRealVariableCount; ++v)
        if (name == kRealVariables[v].name) return true;
    return false;
}

void expect_equal(const std::string& what, double got, double expected) {
    if (got == expected) return;
    std::fprintf(stderr, "%s: got %.17g, expected %.17g\n", what.c_str(), got, expected);
    ++check::failures;
}

void expect_close(const std::string& what, double got, double expected, double scale) {
    if (std::fabs(got - expected) <= 1e-9 * (std::fabs(expected) + scale)) return;
    std::fprintf(stderr, "%s: got %.17g, expected %.17g\n", what.c_str(), got, expected);
    ++check::failures;
}

void expect(const std::string& what, bool ok) {
    if (ok) return;
    std::fprintf(stderr, "%s\n", what.c_str());
    ++check::failures;
}

struct Values {
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    bool flags[kBooleanVariableCount];
    Values() {
        for (unsigned v = 0; v < kRealVariableCount; ++v) reals[v] = kRealVariables[v].start;
        for (unsigned v = 0; v < kIntegerVariableCount; ++v) integers[v] = static_cast<int>(kIntegerVariables[v].start);
        for (unsigned v = 0; v < kBooleanVariableCount; ++v) flags[v] = kBooleanVariables[v].start != 0.0;
    }
};

// ---- Parameters ------------------------------------------------------------------------------------

using RealField = std::function<double(const ModelParameters&)>;
struct RealParameter {
    std::string name;
    double value;
    RealField field;
};

// Valid values, no two alike: products of inertia small against the moments (positive definite),
// moments meeting the triangle inequality, T_din < T_max, w_min > 0, R, L, i_L, U_L > 0.
std::vector<RealParameter> real_parameters() {
    struct Body {
        const char* name;
        const char* centre_of_mass;
        BodyIndex index;
        double m, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz, d[3], c_visc, T_din, T_max, w_min, mu;
    };
    const Body bodies[4] = {
        {"body1", "d_bc", kAzimuthBody, 8.01, 0.1201, 0.1002, 0.1503, 0.00204, -0.00105, 0.00156,
         {0.0107, -0.0058, -0.0809}, 0.0510, 0.0111, 0.0212, 0.00113, 0.0514},
        {"rotor1", "d_be", kAzimuthRotor, 0.301, 2.11e-5, 2.02e-5, 3.63e-5, 1.04e-7, -1.05e-7, 1.06e-7,
         {0.00107, 0.00208, -0.00309}, 1.1e-5, 0.00201, 0.00302, 0.0103, 0.0504},
        {"body2", "d_bd", kElevationBody, 5.02, 0.0507, 0.0405, 0.0606, 0.00117, 0.00058, -0.00089,
         {0.0031, 0.0202, 0.0153}, 0.0305, 0.0056, 0.0097, 0.00128, 0.0539},
        {"rotor2", "d_bf", kElevationRotor, 0.202, 3.05e-5, 1.56e-5, 1.57e-5, 2.1e-8, -2.2e-8, 2.3e-8,
         {-0.0011, 0.0012, 0.0013}, 1.2e-5, 0.0016, 0.0026, 0.0109, 0.0558},
    };
    std::vector<RealParameter> list;
    for (const Body& b : bodies) {
        const std::string p = std::string(b.name) + ".";
        const int k = b.index;
        auto inertia = [k](int row, int column) {
            return [k, row, column](const ModelParameters& m) { return m.multibody.bodies[k].inertia(row, column); };
        };
        list.push_back({p + "m", b.m, [k](const ModelParameters& m) { return m.multibody.bodies[k].mass; }});
        list.push_back({p + "I_xx", b.I_xx, inertia(0, 0)});
        list.push_back({p + "I_yy", b.I_yy, inertia(1, 1)});
        list.push_back({p + "I_zz", b.I_zz, inertia(2, 2)});
        list.push_back({p + "I_xy", b.I_xy, inertia(0, 1)});
        list.push_back({p + "I_xz", b.I_xz, inertia(0, 2)});
        list.push_back({p + "I_yz", b.I_yz, inertia(1, 2)});
        for (int c = 0; c < 3; ++c)
            list.push_back({p + b.centre_of_mass + "[" + std::to_string(c + 1) + "]", b.d[c],
                            [k, c](const ModelParameters& m) { return m.multibody.bodies[k].centre_of_mass[c]; }});
        list.push_back({p + "c_visc", b.c_visc, [k](const ModelParameters& m) { return m.viscous_friction[k]; }});
        list.push_back({p + "T_din", b.T_din, [k](const ModelParameters& m) { return m.dry_friction[k].slip_torque; }});
        list.push_back(
            {p + "T_max", b.T_max, [k](const ModelParameters& m) { return m.dry_friction[k].breakaway_torque; }});
        list.push_back({p + "w_min", b.w_min, [k](const ModelParameters& m) { return m.dry_friction[k].stick_speed; }});
        list.push_back({p + "mu", b.mu, [k](const ModelParameters& m) { return m.dry_friction[k].damping_factor; }});
    }
    const double d_ab[3] = {0.011, -0.012, 0.253};
    for (int c = 0; c < 3; ++c)
        list.push_back({"base.d_ab[" + std::to_string(c + 1) + "]", d_ab[c],
                        [c](const ModelParameters& m) { return m.multibody.d_ab[c]; }});
    list.push_back({"g", 9.79, [](const ModelParameters& m) { return m.multibody.gravity; }});

    struct Motor {
        double R, L, k_torque, k_emf, i_L, U_L;
    };
    const Motor motors[2] = {{2.01, 0.00203, 0.0601, 0.0602, 4.01, 24.1}, {2.52, 0.00153, 0.0404, 0.0408, 3.03, 23.9}};
    struct Gear {
        double N, k_s, c_s, eta;
    };
    const Gear gears[2] = {{80.5, 30100.0, 8.1, 0.000201}, {60.5, 20200.0, 5.2, 0.000202}};
    for (int j = 0; j < 2; ++j) {
        const std::string motor = "motor" + std::to_string(j + 1) + ".", gear = "gear" + std::to_string(j + 1) + ".";
        const Motor& mo = motors[j];
        const Gear& ge = gears[j];
        list.push_back({motor + "R", mo.R, [j](const ModelParameters& m) { return m.motor[j].resistance; }});
        list.push_back({motor + "L", mo.L, [j](const ModelParameters& m) { return m.motor[j].inductance; }});
        list.push_back(
            {motor + "k_torque", mo.k_torque, [j](const ModelParameters& m) { return m.motor[j].torque_constant; }});
        list.push_back({motor + "k_emf", mo.k_emf, [j](const ModelParameters& m) { return m.motor[j].back_emf_constant; }});
        list.push_back({motor + "i_L", mo.i_L, [j](const ModelParameters& m) { return m.motor[j].current_limit; }});
        list.push_back({motor + "U_L", mo.U_L, [j](const ModelParameters& m) { return m.motor[j].voltage_limit; }});
        list.push_back({gear + "N", ge.N, [j](const ModelParameters& m) { return m.gear[j].ratio; }});
        list.push_back({gear + "k_s", ge.k_s, [j](const ModelParameters& m) { return m.gear[j].stiffness; }});
        list.push_back({gear + "c_s", ge.c_s, [j](const ModelParameters& m) { return m.gear[j].damping; }});
        list.push_back({gear + "eta", ge.eta, [j](const ModelParameters& m) { return m.gear[j].half_backlash; }});
    }
    // The disturbance elements (multibody/disturbance_torques.hpp), per axis.
    struct Disturbance {
        double k, c, angle_0, T_cogging, cogging_phase;
    };
    const Disturbance disturbances[2] = {{2.31, 0.0231, 0.131, 0.00431, 0.331}, {1.42, 0.0142, -0.242, 0.00342, -1.142}};
    for (int j = 0; j < 2; ++j) {
        const std::string cable = "cable" + std::to_string(j + 1) + ".", motor = "motor" + std::to_string(j + 1) + ".";
        const Disturbance& d = disturbances[j];
        list.push_back({cable + "k", d.k, [j](const ModelParameters& m) { return m.disturbances.cable[j].stiffness; }});
        list.push_back({cable + "c", d.c, [j](const ModelParameters& m) { return m.disturbances.cable[j].damping; }});
        list.push_back(
            {cable + "angle_0", d.angle_0, [j](const ModelParameters& m) { return m.disturbances.cable[j].neutral_angle; }});
        list.push_back(
            {motor + "T_cogging", d.T_cogging, [j](const ModelParameters& m) { return m.disturbances.cogging[j].amplitude; }});
        list.push_back(
            {motor + "cogging_phase", d.cogging_phase, [j](const ModelParameters& m) { return m.disturbances.cogging[j].phase; }});
    }
    // The axis end stops (switching_elements/axis_stop.hpp), each AXIS_STOP row's variables into its slot.
    for (int s = 0; s < kAxisStopCount; ++s) {
        const AxisStopDeclaration& stop = kAxisStops[s];
        list.push_back({kRealVariables[stop.lower].name, -1.21 - 0.01 * s,
                        [s](const ModelParameters& m) { return m.axis_stop[s].lower; }});
        list.push_back({kRealVariables[stop.upper].name, 1.31 + 0.01 * s,
                        [s](const ModelParameters& m) { return m.axis_stop[s].upper; }});
        list.push_back({kRealVariables[stop.restitution].name, 0.61 + 0.01 * s,
                        [s](const ModelParameters& m) { return m.axis_stop[s].restitution; }});
        list.push_back({kRealVariables[stop.rest_rate].name, 0.0017 + 0.0001 * s,
                        [s](const ModelParameters& m) { return m.axis_stop[s].rest_rate; }});
    }
    // The current amplifiers (switching_elements/amplifier_saturation.hpp): gains given, not derived.
    for (int j = 0; j < 2; ++j) {
        const std::string amplifier = "amplifier" + std::to_string(j + 1) + ".";
        list.push_back({amplifier + "f_c", 1234.5 + j, [j](const ModelParameters& m) { return m.amplifier[j].bandwidth; }});
        list.push_back(
            {amplifier + "K_p", 7.25 + j, [j](const ModelParameters& m) { return m.amplifier[j].proportional_gain; }});
        list.push_back(
            {amplifier + "K_i", 31000.0 + j, [j](const ModelParameters& m) { return m.amplifier[j].integral_gain; }});
    }
    list.push_back({"solver.rtol", 1.1e-6, [](const ModelParameters& m) { return m.relative_tolerance; }});
    list.push_back({"solver.atol", 1.2e-8, [](const ModelParameters& m) { return m.absolute_tolerance; }});
    return list;
}

using IntegerField = std::function<long(const ModelParameters&)>;
const std::map<std::string, IntegerField>& integer_parameter_fields() {
    static const std::map<std::string, IntegerField> fields = {
        {"gear1.model", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.gear[0]); }},
        {"gear2.model", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.gear[1]); }},
        {"motor1.model", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.motor[0]); }},
        {"motor2.model", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.motor[1]); }},
        {"solver.method", [](const ModelParameters& m) { return static_cast<long>(m.method); }},
        {"solver.max_steps", [](const ModelParameters& m) { return m.max_steps; }},
        {"solver.substeps", [](const ModelParameters& m) { return static_cast<long>(m.substeps); }},
        {"motor1.cogging_periods", [](const ModelParameters& m) { return static_cast<long>(m.disturbances.cogging[0].periods); }},
        {"motor2.cogging_periods", [](const ModelParameters& m) { return static_cast<long>(m.disturbances.cogging[1].periods); }},
        {"gear1.start", [](const ModelParameters& m) { return static_cast<long>(m.gear_start[0]); }},
        {"gear2.start", [](const ModelParameters& m) { return static_cast<long>(m.gear_start[1]); }},
        {"motor1.drive", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.drive[0]); }},
        {"motor2.drive", [](const ModelParameters& m) { return static_cast<long>(m.fidelity.drive[1]); }},
    };
    return fields;
}

using BooleanField = std::function<bool(const ModelParameters&)>;
std::map<std::string, BooleanField> listed_boolean_fields() {
    std::map<std::string, BooleanField> fields = {
        {"energy_accounting", [](const ModelParameters& m) { return m.energy_accounting; }},
        {"dry_friction", [](const ModelParameters& m) { return m.fidelity.dry_friction; }},
        {"base.fixed", [](const ModelParameters& m) { return m.fidelity.fixed_base; }},
        {"amplifier1.back_emf_feedforward", [](const ModelParameters& m) { return m.amplifier[0].back_emf_feedforward; }},
        {"amplifier2.back_emf_feedforward", [](const ModelParameters& m) { return m.amplifier[1].back_emf_feedforward; }},
    };
    // Each axis stop's switch, its ELEMENT row's.
    for (int s = 0; s < kAxisStopCount; ++s)
        fields[declaration_of(kAxisStops[s].element).element_switch] = [s](const ModelParameters& m) {
            return m.axis_stop[s].present;
        };
    return fields;
}
const std::map<std::string, BooleanField>& boolean_parameter_fields() {
    static const std::map<std::string, BooleanField> fields = listed_boolean_fields();
    return fields;
}

// The lists above must cover every parameter of the tables, or a new one would go unchecked.
void check_parameter_lists_complete(const std::vector<RealParameter>& reals) {
    std::set<std::string> listed;
    std::set<double> values;
    for (const RealParameter& p : reals) {
        expect("parameter " + p.name + " is listed twice", listed.insert(p.name).second);
        expect("the value of " + p.name + " is not distinct", values.insert(p.value).second);
    }
    for (unsigned v = 0; v < kRealVariableCount; ++v)
        if (kRealVariables[v].causality == Causality::parameter)
            expect(std::string("Real parameter ") + kRealVariables[v].name + " has no expected field in this test",
                   listed.count(kRealVariables[v].name) == 1);
    for (unsigned v = 0; v < kIntegerVariableCount; ++v)
        if (kIntegerVariables[v].causality == Causality::parameter)
            expect(std::string("Integer parameter ") + kIntegerVariables[v].name + " has no expected field in this test",
                   integer_parameter_fields().count(kIntegerVariables[v].name) == 1);
    for (unsigned v = 0; v < kBooleanVariableCount; ++v)
        if (kBooleanVariables[v].causality == Causality::parameter)
            expect(std::string("Boolean parameter ") + kBooleanVariables[v].name + " has no expected field in this test",
                   boolean_parameter_fields().count(kBooleanVariables[v].name) == 1);
}

bool build(const Values& values, ModelParameters& params, const std::string& label) {
    std::string error;
    const bool ok = build_model_parameters(values.reals, values.integers, values.flags, params, error);
    expect(label + ": build_model_parameters refused valid values: " + error, ok);
    return ok;
}

void check_real_parameters(const std::vector<RealParameter>& reals) {
    Values values;
    for (const RealParameter& p : reals) values.reals[real(p.name)] = p.value;
    ModelParameters params;
    if (!build(values, params, "Real parameters")) return;
    for (const RealParameter& p : reals) expect_equal(p.name, p.field(params), p.value);
    for (int k = 0; k < 4; ++k)
        expect("the inertia tensor of body " + std::to_string(k) + " is symmetric",
               params.multibody.bodies[k].inertia == params.multibody.bodies[k].inertia.transpose());
}

void check_integer_parameters() {
    // Models and start rules fit in {0, 1, 2} (gears) and {0, 1} (motors): no single setting tells them all apart, but
    // every pair differs in one of these two.
    const std::map<std::string, int> settings[2] = {
        {{"gear1.model", 2}, {"gear2.model", 1}, {"motor1.model", 0}, {"motor2.model", 1}, {"solver.method", 6},
         {"solver.max_steps", 12345}, {"solver.substeps", 3}, {"motor1.cogging_periods", 24},
         {"motor2.cogging_periods", 18}, {"gear1.start", 0}, {"gear2.start", 2}, {"motor1.drive", 1},
         {"motor2.drive", 0}},
        {{"gear1.model", 0}, {"gear2.model", 2}, {"motor1.model", 1}, {"motor2.model", 0}, {"solver.method", 2},
         {"solver.max_steps", 777}, {"solver.substeps", 250}, {"motor1.cogging_periods", 7},
         {"motor2.cogging_periods", 11}, {"gear1.start", 2}, {"gear2.start", 1}, {"motor1.drive", 0},
         {"motor2.drive", 1}},
    };
    for (const auto& setting : settings) {
        Values values;
        for (const auto& [name, value] : setting) values.integers[integer(name)] = value;
        ModelParameters params;
        if (!build(values, params, "Integer parameters")) continue;
        for (const auto& [name, value] : setting)
            expect_equal(name, static_cast<double>(integer_parameter_fields().at(name)(params)), value);
    }
}

void check_boolean_parameters() {
    // Each flag once alone true and once alone false: any two flags differ in one of the settings.
    for (const auto& [odd_one, field] : boolean_parameter_fields()) {
        (void)field;
        for (bool odd_value : {true, false}) {
            Values values;
            for (const auto& [name, other_field] : boolean_parameter_fields())
                values.flags[boolean(name)] = name == odd_one ? odd_value : !odd_value;
            ModelParameters params;
            if (!build(values, params, "Boolean parameters")) continue;
            for (const auto& [name, f] : boolean_parameter_fields())
                expect(name + " does not hold the value set for it (" + odd_one + " = " + (odd_value ? "true" : "false") +
                           ", the others opposite)",
                       f(params) == (name == odd_one ? odd_value : !odd_value));
        }
    }
}

// ---- Start state and inputs -------------------------------------------------------------------------

// Full fidelity: every one of these is a state.
struct StartValue {
    const char* name;
    double value;
    std::function<int(const StateLayout&)> slot;
};
const std::vector<StartValue>& start_values() {
    // Near mesh (alpha_m ~ N alpha), inside the backlash, below the current limits. The rates are such
    // that the four stick-slip indicators tell every two bodies apart (checked below).
    static const std::vector<StartValue> values = {
        {"alpha", 0.31, [](const StateLayout& l) { return l.angle_slot[kAzimuthBody]; }},
        {"alpha_m", 24.959, [](const StateLayout& l) { return l.angle_slot[kAzimuthRotor]; }},
        {"beta", -0.22, [](const StateLayout& l) { return l.angle_slot[kElevationBody]; }},
        {"beta_m", -13.313, [](const StateLayout& l) { return l.angle_slot[kElevationRotor]; }},
        {"alpha_dot", 0.05, [](const StateLayout& l) { return l.rate_slot[kAzimuthBody]; }},
        {"alpha_m_dot", -1.5, [](const StateLayout& l) { return l.rate_slot[kAzimuthRotor]; }},
        {"beta_dot", 0.0004, [](const StateLayout& l) { return l.rate_slot[kElevationBody]; }},
        {"beta_m_dot", 0.5, [](const StateLayout& l) { return l.rate_slot[kElevationRotor]; }},
        {"i_R1", 0.7, [](const StateLayout& l) { return l.current_slot[0]; }},
        {"i_R2", -0.45, [](const StateLayout& l) { return l.current_slot[1]; }},
        {"theta_b1", 0.6e-4, [](const StateLayout& l) { return l.backlash_slot[0]; }},
        {"theta_b2", -0.9e-4, [](const StateLayout& l) { return l.backlash_slot[1]; }},
    };
    return values;
}

struct InputValue {
    const char* name;
    double value;
    std::function<void(StepInputs&, double)> set;
};
const std::vector<InputValue>& input_values() {
    static const std::vector<InputValue> values = {
        {"u_R1", 3.1, [](StepInputs& in, double v) { in.commanded_voltage[0] = in.voltage[0] = v; }},
        {"u_R2", -2.7, [](StepInputs& in, double v) { in.commanded_voltage[1] = in.voltage[1] = v; }},
        {"base.delta", 0.021, [](StepInputs& in, double v) { in.base.attitude[0] = v; }},
        {"base.psi", 0.13, [](StepInputs& in, double v) { in.base.attitude[1] = v; }},
        {"base.gamma", -0.034, [](StepInputs& in, double v) { in.base.attitude[2] = v; }},
        {"base.delta_dot", 0.041, [](StepInputs& in, double v) { in.base.attitude_rate[0] = v; }},
        {"base.psi_dot", -0.052, [](StepInputs& in, double v) { in.base.attitude_rate[1] = v; }},
        {"base.gamma_dot", 0.063, [](StepInputs& in, double v) { in.base.attitude_rate[2] = v; }},
        {"base.delta_ddot", -0.11, [](StepInputs& in, double v) { in.base.attitude_accel[0] = v; }},
        {"base.psi_ddot", 0.12, [](StepInputs& in, double v) { in.base.attitude_accel[1] = v; }},
        {"base.gamma_ddot", 0.17, [](StepInputs& in, double v) { in.base.attitude_accel[2] = v; }},
        {"base.v_a[1]", 0.5, [](StepInputs& in, double v) { in.base.velocity_a[0] = v; }},
        {"base.v_a[2]", -0.6, [](StepInputs& in, double v) { in.base.velocity_a[1] = v; }},
        {"base.v_a[3]", 0.07, [](StepInputs& in, double v) { in.base.velocity_a[2] = v; }},
        {"base.a_a[1]", 0.21, [](StepInputs& in, double v) { in.base.acceleration_a[0] = v; }},
        {"base.a_a[2]", -0.32, [](StepInputs& in, double v) { in.base.acceleration_a[1] = v; }},
        {"base.a_a[3]", 0.43, [](StepInputs& in, double v) { in.base.acceleration_a[2] = v; }},
    };
    return values;
}

// Every Real parameter distinct, full fidelity, energy accounting on (its flows are outputs too).
Values full_fidelity_values(const std::vector<RealParameter>& reals) {
    Values values;
    for (const RealParameter& p : reals) values.reals[real(p.name)] = p.value;
    values.reals[real("solver.rtol")] = 1e-10;
    values.reals[real("solver.atol")] = 1e-12;
    for (const char* name : {"gear1.model", "gear2.model"}) values.integers[integer(name)] = 2;
    for (const char* name : {"motor1.model", "motor2.model"}) values.integers[integer(name)] = 1;
    values.flags[boolean("dry_friction")] = true;
    values.flags[boolean("energy_accounting")] = true;
    values.flags[boolean("base.fixed")] = false;
    return values;
}

// The outputs the core computes, by output name, from the fields they are made of.
using Outputs = std::map<std::string, double>;
Outputs outputs_by_name(const ModelParameters& params, GimbalHybridSystem& system, double time, const double* state) {
    const ModelOutputs out =
        outputs_from(params, system.inputs(), system.base_kinematics_at_time(time), time, system.dynamics_at(time, state));
    const Modes& modes = system.modes();
    const double* flows = state + params.layout.energy_slot;
    Outputs o = {
        {"alpha", out.full.angle[kAzimuthBody]},
        {"alpha_m", out.full.angle[kAzimuthRotor]},
        {"beta", out.full.angle[kElevationBody]},
        {"beta_m", out.full.angle[kElevationRotor]},
        {"alpha_dot", out.full.rate[kAzimuthBody]},
        {"alpha_m_dot", out.full.rate[kAzimuthRotor]},
        {"beta_dot", out.full.rate[kElevationBody]},
        {"beta_m_dot", out.full.rate[kElevationRotor]},
        {"i_R1", out.full.current[0]},
        {"i_R2", out.full.current[1]},
        {"theta_b1", out.full.backlash[0]},
        {"theta_b2", out.full.backlash[1]},
        {"T_E1", out.shaft_torque[0]},
        {"T_E2", out.shaft_torque[1]},
        {"los.omega[1]", out.payload_angular_velocity[0]},
        {"los.omega[2]", out.payload_angular_velocity[1]},
        {"los.omega[3]", out.payload_angular_velocity[2]},
        {"energy.kinetic", out.kinetic_energy},
        {"energy.potential", out.potential_energy},
        {"energy.spring", out.spring_energy},
        {"energy.magnetic", out.magnetic_energy},
        {"energy.cable", out.cable_energy},
        {"energy.cogging", out.cogging_energy},
        {"energy.electrical_in", flows[kElectricalIn]},
        {"energy.resistive", flows[kResistive]},
        {"energy.viscous", flows[kViscous]},
        {"energy.shaft_damping", flows[kShaftDamping]},
        {"energy.dry_friction", flows[kDryFriction]},
        {"gear1.contact", modes.gear_contact[0]},
        {"gear2.contact", modes.gear_contact[1]},
        {"motor1.limited", modes.motor_limited[0]},
        {"motor2.limited", modes.motor_limited[1]},
    };
    const char* stick_slip[4] = {"body1.stick_slip", "rotor1.stick_slip", "body2.stick_slip", "rotor2.stick_slip"};
    const BodyIndex bodies[4] = {kAzimuthBody, kAzimuthRotor, kElevationBody, kElevationRotor};
    for (int b = 0; b < 4; ++b)
        o[stick_slip[b]] = friction_mode_indicator(modes.friction[bodies[b]], out.full.rate[bodies[b]]);
    return o;
}

constexpr double kStep = 2e-3;

// What the instance must report after initialization and after one step, computed without any value
// reference: the start state placed by layout slot, the inputs by StepInputs field.
struct Reference {
    Outputs initial, stepped;
};
Reference reference_run(const Values& parameters, const StepInputs& inputs) {
    Reference r;
    ModelParameters params;
    if (!build(parameters, params, "reference")) return r;
    GimbalHybridSystem system(params);
    double state[kMaxStateSize] = {};
    for (const StartValue& s : start_values()) state[s.slot(params.layout)] = s.value;
    system.set_inputs(inputs);
    system.update_modes(0.0, state, nullptr);
    r.initial = outputs_by_name(params, system, 0.0, state);

    IntegratorSettings settings;
    settings.method = static_cast<IntegrationMethod>(params.method);
    settings.relative_tolerance = params.relative_tolerance;
    settings.absolute_tolerance = params.absolute_tolerance;
    settings.max_steps = params.max_steps;
    std::string error;
    auto integrator = HybridIntegrator::create(
        system, settings, [&](const std::string& message) { error = message; }, [](const std::string&) {});
    const bool advanced = integrator->restart(0.0, state) && integrator->advance(kStep, state);
    expect("reference run failed: " + error, advanced);
    r.stepped = outputs_by_name(params, system, kStep, state);
    return r;
}

StepInputs named_inputs() {
    StepInputs inputs;
    for (const InputValue& i : input_values()) i.set(inputs, i.value);
    return inputs;
}

struct Log {
    std::vector<std::string> messages;
    GimbalInstance::Logger logger() {
        return [this](GimbalStatus, const char*, const std::string& message) { messages.push_back(message); };
    }
    std::string all() const {
        std::string text;
        for (const std::string& m : messages) text += "  " + m + "\n";
        return text;
    }
};

void set_all(GimbalInstance& instance, const Values& values) {
    for (unsigned v = 0; v < kRealVariableCount; ++v)
        if (kRealVariables[v].causality == Causality::parameter) instance.set_real(v, values.reals[v]);
    for (unsigned v = 0; v < kIntegerVariableCount; ++v)
        if (kIntegerVariables[v].causality == Causality::parameter) instance.set_integer(v, values.integers[v]);
    for (unsigned v = 0; v < kBooleanVariableCount; ++v) instance.set_boolean(v, values.flags[v]);
}

void compare_outputs(GimbalInstance& instance, const Outputs& expected, const std::string& when) {
    for (const auto& [name, value] : expected) {
        double got = 0.0;
        bool read = false;
        if (is_real(name)) {
            read = instance.get_real(real(name), got) == GIMBAL_OK;
        } else {
            int i = 0;
            read = instance.get_integer(integer(name), i) == GIMBAL_OK;
            got = i;
        }
        expect(when + ": " + name + " cannot be read", read);
        // The same computation in the same order: equal but for a different restart history.
        expect_close(when + ": " + name, got, value, 1e-12);
    }
}

void check_start_state_and_inputs(const std::vector<RealParameter>& reals) {
    const Values parameters = full_fidelity_values(reals);
    const Reference reference = reference_run(parameters, named_inputs());

    // The comparison sees every input and every start value: without it, the reference differs.
    auto differs = [&](const Reference& other) {
        for (const auto& [name, value] : reference.stepped)
            if (std::fabs(other.stepped.at(name) - value) > 1e-6 * (std::fabs(value) + 1e-9)) return true;
        return false;
    };
    for (const InputValue& i : input_values()) {
        StepInputs without = named_inputs();
        i.set(without, 0.0);
        expect(std::string("the outputs compared do not depend on ") + i.name, differs(reference_run(parameters, without)));
    }

    Log log;
    GimbalInstance instance(log.logger(), [](const char*) { return true; });
    set_all(instance, parameters);
    for (const StartValue& s : start_values()) instance.set_real(real(s.name), s.value);
    for (const InputValue& i : input_values()) instance.set_real(real(i.name), i.value);
    const bool initialized = instance.initialize(0.0) == GIMBAL_OK;
    expect("initialization failed:\n" + log.all(), initialized);
    if (!initialized) return;
    for (const StartValue& s : start_values()) {
        double got = 0.0;
        instance.get_real(real(s.name), got);
        expect_equal(std::string("start value of ") + s.name + " after initialization", got, s.value);
    }
    compare_outputs(instance, reference.initial, "after initialization");
    const bool stepped = instance.do_step(0.0, kStep) == GIMBAL_OK;
    expect("the step failed:\n" + log.all(), stepped);
    if (stepped) compare_outputs(instance, reference.stepped, "after one step");

    const char* indicators[4] = {"body1.stick_slip", "rotor1.stick_slip", "body2.stick_slip", "rotor2.stick_slip"};
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < a; ++b)
            expect(std::string("the start values do not tell ") + indicators[a] + " from " + indicators[b],
                   reference.initial.at(indicators[a]) != reference.initial.at(indicators[b]) ||
                       reference.stepped.at(indicators[a]) != reference.stepped.at(indicators[b]));
}

// A fixed base takes no base motion: each base input, set alone, is refused by its own name.
void check_fixed_base_names_each_input(const std::vector<RealParameter>& reals) {
    Values parameters = full_fidelity_values(reals);
    parameters.flags[boolean("base.fixed")] = true;
    for (const InputValue& i : input_values()) {
        if (std::string(i.name).rfind("base.", 0) != 0) continue;
        Log log;
        GimbalInstance instance(log.logger(), [](const char*) { return true; });
        set_all(instance, parameters);
        instance.set_real(real(i.name), 1e-3);
        const bool refused = instance.initialize(0.0) == GIMBAL_ERROR;
        expect(std::string("base.fixed = true accepts ") + i.name + " = 1e-3", refused);
        expect(std::string("the refusal of ") + i.name + " does not name it:\n" + log.all(),
               refused && !log.messages.empty() &&
                   log.messages.back().find(std::string(i.name) + " = ") != std::string::npos);
    }
}

// Every input and every start value of the tables is in the lists above, or it would go unchecked.
void check_state_and_input_lists_complete() {
    std::set<std::string> inputs, states;
    for (const InputValue& i : input_values()) inputs.insert(i.name);
    for (const StartValue& s : start_values()) states.insert(s.name);
    for (unsigned v = 0; v < kRealVariableCount; ++v) {
        const VariableInfo& info = kRealVariables[v];
        // The current commands act in current drive only (this test runs voltage drive): their wiring is
        // tests/model_core/model/test_current_drive.cpp's (the closed loop follows them to 1e-6).
        if (info.causality == Causality::input && v != vr_i_R1_cmd && v != vr_i_R2_cmd)
            expect(std::string("input ") + info.name + " has no expected StepInputs field in this test",
                   inputs.count(info.name) == 1);
        if (info.causality == Causality::output && info.initial == Initial::exact)
            expect(std::string("start value ") + info.name + " has no expected state slot in this test",
                   states.count(info.name) == 1);
    }
}

// ---- Set and get by name ------------------------------------------------------------------------------

// Every variable a master may set (parameters, inputs, outputs with a start value) reads back the value
// set under its name, no two sharing storage. Calculated outputs cannot be set: they are compared with
// the core's computation above.
void check_round_trip_by_name() {
    Log log;
    GimbalInstance instance(log.logger(), [](const char*) { return true; });
    std::map<std::string, double> reals;
    std::map<std::string, int> integers;
    for (unsigned v = 0; v < kRealVariableCount; ++v) {
        const VariableInfo& info = kRealVariables[v];
        if ((info.causality == Causality::output || info.causality == Causality::local) && info.initial != Initial::exact)
            continue;
        reals[info.name] = 0.5 + 0.25 * static_cast<double>(reals.size());
    }
    for (unsigned v = 0; v < kIntegerVariableCount; ++v)
        if (kIntegerVariables[v].causality == Causality::parameter)
            integers[kIntegerVariables[v].name] = 101 + static_cast<int>(integers.size());
    for (const auto& [name, value] : reals) expect(name + " cannot be set", instance.set_real(real(name), value) == GIMBAL_OK);
    for (const auto& [name, value] : integers)
        expect(name + " cannot be set", instance.set_integer(integer(name), value) == GIMBAL_OK);
    for (const auto& [name, value] : reals) {
        double got = 0.0;
        expect(name + " cannot be read", instance.get_real(real(name), got) == GIMBAL_OK);
        expect_equal(name + " read back", got, value);
    }
    for (const auto& [name, value] : integers) {
        int got = 0;
        expect(name + " cannot be read", instance.get_integer(integer(name), got) == GIMBAL_OK);
        expect_equal(name + " read back", got, value);
    }
    for (const auto& [odd_one, field] : boolean_parameter_fields()) {
        (void)field;
        for (const auto& [name, f] : boolean_parameter_fields()) instance.set_boolean(boolean(name), name == odd_one);
        for (const auto& [name, f] : boolean_parameter_fields()) {
            bool got = false;
            instance.get_boolean(boolean(name), got);
            expect(name + " does not read back the value set (" + odd_one + " alone true)", got == (name == odd_one));
        }
    }
}

}  // namespace

int main() {
    const std::vector<RealParameter> reals = real_parameters();
    check_parameter_lists_complete(reals);
    check_real_parameters(reals);
    check_integer_parameters();
    check_boolean_parameters();
    check_state_and_input_lists_complete();
    check_start_state_and_inputs(reals);
    check_fixed_base_names_each_input(reals);
    check_round_trip_by_name();
    return check_report("variable_wiring");
}
