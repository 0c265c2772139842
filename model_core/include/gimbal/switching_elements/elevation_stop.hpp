// Switching element: the hard stops of the elevation axis (docs/physics.md section 5.5). The payload's
// elevation beta is limited to [lower, upper]. Reaching a stop, its rate relative to the azimuth housing
// reverses by Newton's impact law with the coefficient of restitution e, through an impulse of the stop
// on the payload (and its reaction on the housing) that the mass matrix spreads over the coordinates it
// couples; a rebound slower than rest_rate ends the bounces (Zeno): the payload then rests on the stop,
// held there by the stop's reaction while the other torques push it in, released when they pull away.
//   parameters: ModelParameters::elevation_stop (elevation_stop, elevation_stop.beta_min, beta_max, e,
//               w_rest)
//   state slot: none (it jumps beta_dot, and the rates the mass matrix couples to it)
//   mode: Modes::elevation_stop                  guards: 2 (switching_elements.def)
//   counter: none (a rest and a release count in the total; a bounce changes no mode)
#pragma once

#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

// Force pass, after the accelerations: while the payload rests on a stop, the stop's reaction is the
// torque that keeps beta's acceleration at 0, applied through the mass matrix (M qdd = F + e_beta
// torque). Free, or without a stop: no term.
inline void hold_at_elevation_stop(const Modes& modes, Dynamics& out) {
    out.stop_torque = 0.0;
    if (modes.elevation_stop == 0) return;
    const Vec4 response = solve_mass_matrix(out.reduced_mass, Vec4(Vec4::Unit(kElevation)));
    const double torque = -out.acceleration[kElevation] / response[kElevation];
    out.acceleration += torque * response;
    out.acceleration[kElevation] = 0.0;
    out.stop_torque = torque;
}

// Jacobian pass of the same constraint: with the torque a function of the state, d(qdd)/dx is the free
// one less M^-1 e_beta times its own beta row over (M^-1)_beta,beta, so that beta's row is 0.
inline void hold_at_elevation_stop_derivatives(const Modes& modes, const Mat4& reduced_mass, Mat4x12& acceleration) {
    if (modes.elevation_stop == 0) return;
    const Vec4 response = solve_mass_matrix(reduced_mass, Vec4(Vec4::Unit(kElevation)));
    const Row12 free_row = acceleration.row(kElevation);
    acceleration -= (response / response[kElevation]) * free_row;
    acceleration.row(kElevation).setZero();
}

class ElevationStopElement final : public SwitchingElement {
public:
    ElevationStopElement(int index, int first_guard);
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    // Free: an impact (beta on or past a stop, moving into it) projects beta onto the stop and applies
    // the impulse of Newton's law; resting: released where the stop's reaction crossed zero.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    // After an impact, with the dynamics evaluated at the state it left: a payload on a stop with no
    // rate rests there if the other torques push it in, and leaves from just inside it if they do not.
    void decide_rest(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state) const;
    bool changed(const Modes& before, const Modes& after) const override {
        return before.elevation_stop != after.elevation_stop;
    }
    std::string describe(const Modes& before, const Modes& after) const override;
};

}  // namespace gimbal
