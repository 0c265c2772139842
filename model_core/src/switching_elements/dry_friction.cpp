#include "gimbal/switching_elements/dry_friction.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace gimbal {
namespace {

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

void assign_coordinate_friction(ModelParameters& params) {
    const Fidelity& fidelity = params.fidelity;
    for (int body = 0; body < 4; ++body)
        params.coordinate_friction[body] = fidelity.dry_friction ? params.dry_friction[body] : DryFrictionParameters{};
    for (int axis = 0; axis < 2; ++axis) {
        params.rotor_friction_share[axis] = 0.0;
        if (fidelity.gear[axis] != GearModel::rigid || !fidelity.dry_friction) continue;
        const double ratio = std::fabs(params.gear[axis].ratio);
        const DryFrictionParameters& load = params.dry_friction[load_index(axis)];
        const DryFrictionParameters& rotor = params.dry_friction[rotor_index(axis)];
        DryFrictionParameters merged;
        merged.slip_torque = load.slip_torque + ratio * rotor.slip_torque;
        merged.breakaway_torque = load.breakaway_torque + ratio * rotor.breakaway_torque;
        merged.stick_speed = load.present() ? load.stick_speed : rotor.stick_speed / ratio;
        merged.damping_factor = load.present() ? load.damping_factor : rotor.damping_factor;
        params.coordinate_friction[load_index(axis)] = merged;
        params.coordinate_friction[rotor_index(axis)] = DryFrictionParameters{};
        if (merged.present())
            params.rotor_friction_share[axis] = ratio * rotor.breakaway_torque / merged.breakaway_torque;
    }
}

Vec4 other_torques(const Mat4& mass_matrix, const Vec4& applied_torque, const Modes& modes,
                   const DryFrictionParameters (&friction)[4]) {
    Mat4 modified = mass_matrix;
    Vec4 rhs = applied_torque;
    for (int k = 0; k < 4; ++k) {
        const FrictionMode mode = modes.friction[k];
        if (low_speed(mode)) {
            modified.col(k) = Vec4::Unit(k);
        } else if (mode == FrictionMode::slip_positive) {
            rhs[k] -= friction[k].slip_torque;
        } else if (mode == FrictionMode::slip_negative) {
            rhs[k] += friction[k].slip_torque;
        }
    }
    // Column replacement keeps the matrix invertible (its determinant is that of J's free block).
    return modified.partialPivLu().solve(rhs);
}

Mat4x12 hold_friction_derivatives(const ModelParameters& params, const Modes& modes, const Dynamics& d,
                                  const Mat4x12& applied, const Mat4 (&inertia_derivative)[4]) {
    Mat4x12 friction = Mat4x12::Zero();
    bool any_hold = false;
    for (int k = 0; k < 4; ++k) any_hold = any_hold || modes.friction[k] == FrictionMode::hold;
    if (!any_hold) return friction;
    Mat4 modified = d.reduced_mass;
    for (int k = 0; k < 4; ++k)
        if (low_speed(modes.friction[k])) modified.col(k) = Vec4::Unit(k);
    // T_outros = M^-1 applied, with M the mass matrix whose low-speed columns are unit vectors.
    Mat4x12 other_rhs = applied;
    for (int k = 0; k < 4; ++k) {
        Mat4 modified_derivative = inertia_derivative[k];
        for (int c = 0; c < 4; ++c)
            if (low_speed(modes.friction[c])) modified_derivative.col(c).setZero();
        other_rhs.col(k) -= modified_derivative * d.other_torque;
    }
    const Mat4x12 other = modified.partialPivLu().solve(other_rhs);
    for (int k = 0; k < 4; ++k) {
        if (modes.friction[k] != FrictionMode::hold) continue;
        friction.row(k) = -other.row(k);
        friction(k, kRateColumn + k) -= params.coordinate_friction[k].numerical_damping();
    }
    return friction;
}

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
    if (!changed(before, after)) return std::string();
    return switching::transition(friction_name(before.friction[body_]), friction_name(after.friction[body_]));
}

}  // namespace gimbal
