// The variables the core reads and writes as groups: per body, per vector component, and the sets it
// walks (start state, base inputs, event counters). The order of a .def table gives the value
// references, and a table may be reordered or extended: so every group names its members instead of
// counting on from a first one (`vr_alpha + k` silently re-wires the physics when a line moves), and
// the static_asserts at the end refuse to compile when a group no longer holds exactly the variables
// its users assume.
#pragma once

#include <array>
#include <cstddef>

#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

using RealVector = std::array<RealVariable, 3>;  // the variables of components [1], [2], [3]

inline Vec3 read_vector(const double* values, const RealVector& vector) {
    return Vec3(values[vector[0]], values[vector[1]], values[vector[2]]);
}

// Indexed by BodyIndex, the order of the generalized coordinates q = [alpha, alpha_m, beta, beta_m].
inline constexpr RealVariable kBodyAngle[4] = {vr_alpha, vr_alpha_m, vr_beta, vr_beta_m};
inline constexpr RealVariable kBodyRate[4] = {vr_alpha_dot, vr_alpha_m_dot, vr_beta_dot, vr_beta_m_dot};
inline constexpr IntegerVariable kBodyStickSlip[4] = {vi_body1_stick_slip, vi_rotor1_stick_slip, vi_body2_stick_slip,
                                                      vi_rotor2_stick_slip};

struct InertiaVariables {
    RealVariable xx, yy, zz, xy, xz, yz;
};
struct DryFrictionVariables {
    RealVariable slip_torque, breakaway_torque, stick_speed, damping_factor;  // T_din, T_max, w_min, mu
};
struct BodyParameterVariables {
    const char* prefix;  // of every name below, and of the body's messages
    RealVariable mass;
    InertiaVariables inertia;
    RealVector centre_of_mass;
    RealVariable viscous_friction;
    DryFrictionVariables dry_friction;
};

inline constexpr BodyParameterVariables kBodyParameters[4] = {
    {"body1", vr_body1_m,
     {vr_body1_I_xx, vr_body1_I_yy, vr_body1_I_zz, vr_body1_I_xy, vr_body1_I_xz, vr_body1_I_yz},
     {vr_body1_d_bc_1, vr_body1_d_bc_2, vr_body1_d_bc_3}, vr_body1_c_visc,
     {vr_body1_T_din, vr_body1_T_max, vr_body1_w_min, vr_body1_mu}},
    {"rotor1", vr_rotor1_m,
     {vr_rotor1_I_xx, vr_rotor1_I_yy, vr_rotor1_I_zz, vr_rotor1_I_xy, vr_rotor1_I_xz, vr_rotor1_I_yz},
     {vr_rotor1_d_be_1, vr_rotor1_d_be_2, vr_rotor1_d_be_3}, vr_rotor1_c_visc,
     {vr_rotor1_T_din, vr_rotor1_T_max, vr_rotor1_w_min, vr_rotor1_mu}},
    {"body2", vr_body2_m,
     {vr_body2_I_xx, vr_body2_I_yy, vr_body2_I_zz, vr_body2_I_xy, vr_body2_I_xz, vr_body2_I_yz},
     {vr_body2_d_bd_1, vr_body2_d_bd_2, vr_body2_d_bd_3}, vr_body2_c_visc,
     {vr_body2_T_din, vr_body2_T_max, vr_body2_w_min, vr_body2_mu}},
    {"rotor2", vr_rotor2_m,
     {vr_rotor2_I_xx, vr_rotor2_I_yy, vr_rotor2_I_zz, vr_rotor2_I_xy, vr_rotor2_I_xz, vr_rotor2_I_yz},
     {vr_rotor2_d_bf_1, vr_rotor2_d_bf_2, vr_rotor2_d_bf_3}, vr_rotor2_c_visc,
     {vr_rotor2_T_din, vr_rotor2_T_max, vr_rotor2_w_min, vr_rotor2_mu}},
};

inline constexpr RealVector kBasePointB = {vr_base_d_ab_1, vr_base_d_ab_2, vr_base_d_ab_3};  // d_ab

// The fields of BaseMotion; the attitude in its order: delta (pitch), psi (yaw), gamma (roll).
struct BaseMotionVariables {
    RealVector attitude, attitude_rate, attitude_accel, velocity_a, acceleration_a;
};
inline constexpr BaseMotionVariables kBaseMotion = {
    {vr_base_delta, vr_base_psi, vr_base_gamma},
    {vr_base_delta_dot, vr_base_psi_dot, vr_base_gamma_dot},
    {vr_base_delta_ddot, vr_base_psi_ddot, vr_base_gamma_ddot},
    {vr_base_v_a_1, vr_base_v_a_2, vr_base_v_a_3},
    {vr_base_a_a_1, vr_base_a_a_2, vr_base_a_a_3},
};

// Every base input: a fixed base requires each of them to be 0.
inline constexpr RealVariable kBaseInputs[15] = {
    vr_base_delta,      vr_base_psi,      vr_base_gamma,      vr_base_delta_dot, vr_base_psi_dot,
    vr_base_gamma_dot,  vr_base_delta_ddot, vr_base_psi_ddot, vr_base_gamma_ddot, vr_base_v_a_1,
    vr_base_v_a_2,      vr_base_v_a_3,    vr_base_a_a_1,      vr_base_a_a_2,     vr_base_a_a_3,
};

inline constexpr RealVector kPayloadAngularVelocity = {vr_los_omega_1, vr_los_omega_2, vr_los_omega_3};

// The outputs whose start values are the start state: validated, then loaded into the state vector.
inline constexpr RealVariable kStartState[12] = {
    vr_alpha,     vr_alpha_m,     vr_beta,     vr_beta_m,     vr_alpha_dot, vr_alpha_m_dot,
    vr_beta_dot,  vr_beta_m_dot,  vr_i_R1,     vr_i_R2,       vr_theta_b1,  vr_theta_b2,
};

// Counts of located mode changes: never negative.
inline constexpr IntegerVariable kEventCounters[7] = {
    vi_events_total,          vi_events_backlash1,  vi_events_backlash2,  vi_events_current_limit1,
    vi_events_current_limit2, vi_events_stick_slip, vi_events_zeno_guard,
};

// The continuous states of the Model Exchange interface, in the order of its state vector (and of
// <Derivatives>): the full state of section "State" in docs/physics.md and the energy accumulators,
// whatever the fidelity; kStateDerivatives[k] is der(kContinuousStates[k]).
// The current amplifiers' integrators come last (kAmplifierStates): appended, so that the 17 states
// before them keep their places.
inline constexpr int kContinuousStateCount = kMaxStateSize;
inline constexpr RealVariable kContinuousStates[kContinuousStateCount] = {
    vr_alpha,     vr_alpha_m,     vr_beta,     vr_beta_m,     vr_alpha_dot, vr_alpha_m_dot,
    vr_beta_dot,  vr_beta_m_dot,  vr_i_R1,     vr_i_R2,       vr_theta_b1,  vr_theta_b2,
    vr_energy_electrical_in, vr_energy_resistive, vr_energy_viscous, vr_energy_shaft_damping,
    vr_energy_dry_friction, vr_amplifier1_x_I, vr_amplifier2_x_I,
};
inline constexpr RealVariable kStateDerivatives[kContinuousStateCount] = {
    vr_der_alpha,     vr_der_alpha_m,     vr_der_beta,     vr_der_beta_m,     vr_der_alpha_dot, vr_der_alpha_m_dot,
    vr_der_beta_dot,  vr_der_beta_m_dot,  vr_der_i_R1,     vr_der_i_R2,       vr_der_theta_b1,  vr_der_theta_b2,
    vr_der_energy_electrical_in, vr_der_energy_resistive, vr_der_energy_viscous, vr_der_energy_shaft_damping,
    vr_der_energy_dry_friction, vr_der_amplifier1_x_I, vr_der_amplifier2_x_I,
};

// ---------------------------------------------------------------------------------------------------
// Compile-time checks of the groups against the tables themselves (names, causality, initial), read
// here from the same .def lines as kRealVariables.
namespace variable_table {

inline constexpr VariableInfo kReal[] = {
#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) \
    {name, Causality::causality, Variability::variability, Initial::initial, declared_type, unit, display_unit, start, \
     min, max, description},
#include "gimbal/real_variables.def"
};
inline constexpr VariableInfo kInteger[] = {
#include "gimbal/integer_variables.def"
#undef X
};

constexpr const char* name(RealVariable vr) { return kReal[vr].name; }
constexpr const char* name(IntegerVariable vi) { return kInteger[vi].name; }

constexpr std::size_t length(const char* text) {
    std::size_t n = 0;
    while (text[n] != '\0') ++n;
    return n;
}

constexpr bool starts_with(const char* text, const char* prefix) {
    for (; *prefix != '\0'; ++text, ++prefix)
        if (*text != *prefix) return false;
    return true;
}

// text == head + tail
constexpr bool joins(const char* text, const char* head, const char* tail) {
    return starts_with(text, head) && starts_with(text + length(head), tail) &&
           length(text) == length(head) + length(tail);
}

// "x[1]", "x[2]", "x[3]" of one vector x, in this order.
constexpr bool components_of_one_vector(const RealVector& vector) {
    const std::size_t n = length(name(vector[0]));
    for (int k = 0; k < 3; ++k) {
        const char* component = name(vector[k]);
        if (length(component) != n || n < 4 || component[n - 3] != '[' || component[n - 2] != '1' + k ||
            component[n - 1] != ']')
            return false;
        for (std::size_t c = 0; c + 3 < n; ++c)
            if (component[c] != name(vector[0])[c]) return false;
    }
    return true;
}

// The group lists, once each, exactly the variables of `table` for which `is_member` holds.
template <class Variable, std::size_t N, std::size_t M, class Rule>
constexpr bool holds_exactly(const Variable (&group)[N], const VariableInfo (&table)[M], Rule is_member) {
    std::size_t members = 0;
    for (std::size_t v = 0; v < M; ++v)
        if (is_member(table[v])) ++members;
    if (members != N) return false;
    for (std::size_t i = 0; i < N; ++i) {
        if (group[i] >= M || !is_member(table[group[i]])) return false;
        for (std::size_t j = 0; j < i; ++j)
            if (group[j] == group[i]) return false;
    }
    return true;
}

template <std::size_t N>
constexpr bool contains(const RealVariable (&group)[N], const RealVector& vector) {
    for (RealVariable component : vector) {
        bool found = false;
        for (RealVariable member : group) found = found || member == component;
        if (!found) return false;
    }
    return true;
}

constexpr bool body_parameters_named(const BodyParameterVariables& body) {
    const char* p = body.prefix;
    const InertiaVariables& i = body.inertia;
    const DryFrictionVariables& f = body.dry_friction;
    return joins(name(body.mass), p, ".m") && joins(name(i.xx), p, ".I_xx") && joins(name(i.yy), p, ".I_yy") &&
           joins(name(i.zz), p, ".I_zz") && joins(name(i.xy), p, ".I_xy") && joins(name(i.xz), p, ".I_xz") &&
           joins(name(i.yz), p, ".I_yz") && starts_with(name(body.centre_of_mass[0]), p) &&
           starts_with(name(body.centre_of_mass[0]) + length(p), ".d_b") &&
           components_of_one_vector(body.centre_of_mass) && joins(name(body.viscous_friction), p, ".c_visc") &&
           joins(name(f.slip_torque), p, ".T_din") && joins(name(f.breakaway_torque), p, ".T_max") &&
           joins(name(f.stick_speed), p, ".w_min") && joins(name(f.damping_factor), p, ".mu");
}

// Every Real parameter of the body is in its group: a new one must be wired, not forgotten.
constexpr bool body_parameters_complete(const BodyParameterVariables& body) {
    const RealVariable members[] = {body.mass,
                                    body.inertia.xx,
                                    body.inertia.yy,
                                    body.inertia.zz,
                                    body.inertia.xy,
                                    body.inertia.xz,
                                    body.inertia.yz,
                                    body.centre_of_mass[0],
                                    body.centre_of_mass[1],
                                    body.centre_of_mass[2],
                                    body.viscous_friction,
                                    body.dry_friction.slip_torque,
                                    body.dry_friction.breakaway_torque,
                                    body.dry_friction.stick_speed,
                                    body.dry_friction.damping_factor};
    const char* p = body.prefix;
    return holds_exactly(members, kReal, [p](const VariableInfo& v) {
        return v.causality == Causality::parameter && starts_with(v.name, p) && v.name[length(p)] == '.';
    });
}

constexpr bool bodies_consistent() {
    const char* prefixes[4] = {"body1", "rotor1", "body2", "rotor2"};  // BodyIndex order
    for (int k = 0; k < 4; ++k) {
        if (!joins(kBodyParameters[k].prefix, prefixes[k], "") || !body_parameters_named(kBodyParameters[k]) ||
            !body_parameters_complete(kBodyParameters[k]) || !joins(name(kBodyRate[k]), name(kBodyAngle[k]), "_dot") ||
            !joins(name(kBodyStickSlip[k]), prefixes[k], ".stick_slip"))
            return false;
    }
    return true;
}

}  // namespace variable_table

static_assert(kAzimuthBody == 0 && kAzimuthRotor == 1 && kElevationBody == 2 && kElevationRotor == 3 &&
                  rotor_index(0) == kAzimuthRotor && load_index(0) == kAzimuthBody &&
                  rotor_index(1) == kElevationRotor && load_index(1) == kElevationBody,
              "the per-body groups are indexed by BodyIndex, in q order: body1, rotor1, body2, rotor2");
static_assert(variable_table::bodies_consistent(),
              "kBodyParameters[k] holds every Real parameter named <body k>.*, each in the field of its name, and "
              "kBodyRate[k] / kBodyStickSlip[k] belong to the same body k as kBodyAngle[k] / kBodyParameters[k]");

static_assert(variable_table::components_of_one_vector(kBasePointB) &&
                  variable_table::joins(variable_table::name(kBasePointB[0]), "base.d_ab", "[1]"),
              "kBasePointB is base.d_ab[1..3] in component order");
static_assert(variable_table::joins(variable_table::name(kBaseMotion.attitude[0]), "base.delta", "") &&
                  variable_table::joins(variable_table::name(kBaseMotion.attitude[1]), "base.psi", "") &&
                  variable_table::joins(variable_table::name(kBaseMotion.attitude[2]), "base.gamma", ""),
              "BaseMotion::attitude is (delta, psi, gamma)");
static_assert([] {
    for (int k = 0; k < 3; ++k)
        if (!variable_table::joins(variable_table::name(kBaseMotion.attitude_rate[k]),
                                   variable_table::name(kBaseMotion.attitude[k]), "_dot") ||
            !variable_table::joins(variable_table::name(kBaseMotion.attitude_accel[k]),
                                   variable_table::name(kBaseMotion.attitude[k]), "_ddot"))
            return false;
    return true;
}(), "kBaseMotion's attitude rate and acceleration are those of its attitude, component by component");
static_assert(variable_table::components_of_one_vector(kBaseMotion.velocity_a) &&
                  variable_table::joins(variable_table::name(kBaseMotion.velocity_a[0]), "base.v_a", "[1]") &&
                  variable_table::components_of_one_vector(kBaseMotion.acceleration_a) &&
                  variable_table::joins(variable_table::name(kBaseMotion.acceleration_a[0]), "base.a_a", "[1]"),
              "kBaseMotion's velocity_a and acceleration_a are base.v_a[1..3] and base.a_a[1..3] in component order");
static_assert(variable_table::holds_exactly(kBaseInputs, variable_table::kReal,
                                            [](const VariableInfo& v) {
                                                return v.causality == Causality::input &&
                                                       variable_table::starts_with(v.name, "base.");
                                            }) &&
                  variable_table::contains(kBaseInputs, kBaseMotion.attitude) &&
                  variable_table::contains(kBaseInputs, kBaseMotion.attitude_rate) &&
                  variable_table::contains(kBaseInputs, kBaseMotion.attitude_accel) &&
                  variable_table::contains(kBaseInputs, kBaseMotion.velocity_a) &&
                  variable_table::contains(kBaseInputs, kBaseMotion.acceleration_a),
              "kBaseInputs is every Real input named base.*, and kBaseMotion reads exactly these");
static_assert(variable_table::components_of_one_vector(kPayloadAngularVelocity) &&
                  variable_table::joins(variable_table::name(kPayloadAngularVelocity[0]), "los.omega", "[1]"),
              "kPayloadAngularVelocity is los.omega[1..3] in component order");
static_assert(variable_table::holds_exactly(kStartState, variable_table::kReal,
                                            [](const VariableInfo& v) {
                                                return v.causality == Causality::output &&
                                                       (v.initial == Initial::exact || v.initial == Initial::approx);
                                            }),
              "kStartState is every output whose start value is used (initial = exact, or approx: the rotors, "
              "which may start in mesh instead): the start state");
// The rotor angles and rates: the start values a compliant gear's start rule (gear<j>.start) may replace
// by the values in mesh with the loads, hence initial = approx.
inline constexpr RealVariable kRotorStart[4] = {vr_alpha_m, vr_alpha_m_dot, vr_beta_m, vr_beta_m_dot};
static_assert(variable_table::holds_exactly(kRotorStart, variable_table::kReal,
                                            [](const VariableInfo& v) { return v.initial == Initial::approx; }),
              "kRotorStart is every variable with initial = approx: the rotor angles and rates");
static_assert([] {
    for (int k = 0; k < kContinuousStateCount; ++k) {
        const char* state = variable_table::name(kContinuousStates[k]);
        const char* derivative = variable_table::name(kStateDerivatives[k]);
        if (!variable_table::starts_with(derivative, "der(") || !variable_table::starts_with(derivative + 4, state) ||
            variable_table::length(derivative) != variable_table::length(state) + 5 ||
            derivative[variable_table::length(derivative) - 1] != ')')
            return false;
        if (k < 12 && kContinuousStates[k] != kStartState[k]) return false;
    }
    return true;
}(), "kStateDerivatives[k] is der(kContinuousStates[k]), and the first 12 states are the start state in its order");
static_assert(variable_table::holds_exactly(kStateDerivatives, variable_table::kReal,
                                            [](const VariableInfo& v) { return v.causality == Causality::local; }),
              "kStateDerivatives is every local variable: the derivatives are the only ones");
static_assert(variable_table::holds_exactly(kEventCounters, variable_table::kInteger,
                                            [](const VariableInfo& v) {
                                                return variable_table::starts_with(v.name, "events.");
                                            }),
              "kEventCounters is every Integer variable named events.*: the counters a snapshot must hold as counts");

}  // namespace gimbal
