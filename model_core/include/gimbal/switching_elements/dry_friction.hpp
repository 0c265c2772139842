// Switching element: dry friction with stick-slip on one coordinate (docs/physics.md section 4.4,
// (2.98)-(2.106)). Decided in two passes: the speed regime (slipping, or a stick candidate below w_min)
// for all bodies first, because the other torques of (2.106) depend on which bodies are at low speed;
// then, at low speed, stuck or breaking away. This module owns the friction per coordinate (a rigid
// axis merges its rotor's into the load's), the friction torques of the dynamics, their Jacobian
// contribution, the guards, the transitions and the FMU's stick-slip indicator.
//   parameters: ModelParameters::dry_friction[body] (<body>.T_din, T_max, w_min, mu), fidelity.dry_friction
//   state slot: none                                      mode: Modes::friction[body]
//   guards: 6 (indicators 12-35)                           counter: EventCounters::stick_slip
#pragma once

#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

// ModelParameters::coordinate_friction and rotor_friction_share from dry_friction and the fidelity
// (docs/physics.md section 6, rigid gear): a rigid axis has no unique static split of friction between
// rotor and load; one element on the load axis carries both, the rotor's reflected through N.
void assign_coordinate_friction(ModelParameters& params);

// Solves (2.106) with the columns of the low-speed coordinates replaced by unit vectors: T_outros.
Vec4 other_torques(const Mat4& mass_matrix, const Vec4& applied_torque, const Modes& modes,
                   const DryFrictionParameters (&friction)[4]);

// Force pass of the dynamics: T_outros (for low-speed coordinates) and the friction torque T_as of
// every padded coordinate under its mode, written to `out`, from the padded mass matrix and the
// applied torques without friction.
inline void friction_torques(const ModelParameters& params, const Modes& modes, const Mat4& reduced_mass,
                             const Vec4& applied, const Vec4& qd, Dynamics& out) {
    bool any_low_speed = false;
    for (int k = 0; k < 4; ++k) any_low_speed = any_low_speed || low_speed(modes.friction[k]);
    out.other_torque =
        any_low_speed ? other_torques(reduced_mass, applied, modes, params.coordinate_friction) : Vec4::Zero();
    for (int k = 0; k < 4; ++k) {
        const DryFrictionParameters& friction = params.coordinate_friction[k];
        double torque = 0.0;
        switch (modes.friction[k]) {
            case FrictionMode::none: break;
            case FrictionMode::slip_positive: torque = -friction.slip_torque; break;
            case FrictionMode::slip_negative: torque = friction.slip_torque; break;
            case FrictionMode::hold: torque = -out.other_torque[k] - friction.numerical_damping() * qd[k]; break;
            case FrictionMode::at_max_positive: torque = friction.breakaway_torque; break;
            case FrictionMode::at_max_negative: torque = -friction.breakaway_torque; break;
        }
        out.friction_torque[k] = torque;
    }
}

// Jacobian pass: a held coordinate's friction cancels the other torques (2.101), which depend on the
// state too. `applied`: d(applied torques)/d(state) in padded coordinates; `inertia_derivative[k]`:
// d(padded J)/dq_k. Returns d T_as / d(state) (zero rows for coordinates not held).
Mat4x12 hold_friction_derivatives(const ModelParameters& params, const Modes& modes, const Dynamics& dynamics,
                                  const Mat4x12& applied, const Mat4 (&inertia_derivative)[4]);

// Friction mode as the FMU reports it: 0 stuck, +-1 breaking away, +-2 slipping (sign = motion).
int friction_mode_indicator(FrictionMode mode, double rate);

class DryFrictionElement final : public SwitchingElement {
public:
    DryFrictionElement(int body, int first_guard);
    explicit DryFrictionElement(const ElementSlot& slot) : DryFrictionElement(slot.instance, slot.first_guard) {}
    // A coordinate with dry friction only.
    static bool present(const ModelParameters& params, const ElementSlot& slot) { return params.coordinate_friction[slot.instance].present(); }
    static constexpr DecisionStage kStage = DecisionStage::friction;
    static std::string impossible_mode(const ModelParameters& params, const Modes& modes, const ElementSlot& slot) {
        if (params.fidelity.dry_friction || modes.friction[slot.instance] == FrictionMode::none) return {};
        return "a friction mode is set but dry friction is off";
    }
    static constexpr int kGuards = 6;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    // The speed regime; decide_torque completes the decision with the dynamics of the new regimes.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    void decide_torque(const SwitchingContext& context, const Modes& previous, Modes& modes,
                       const int* crossings) const;
    // At low speed the torque's decision reads the other torques under the modes and the state chosen so far.
    bool settles_on_dynamics(const Modes& modes) const override { return low_speed(modes.friction[body_]); }
    void settle(const SwitchingContext& context, const Modes& previous, Modes& modes, double*,
                const int* crossings) const override {
        decide_torque(context, previous, modes, crossings);
    }
    bool changed(const Modes& before, const Modes& after) const override {
        return before.friction[body_] != after.friction[body_];
    }
    void count_change(EventCounters& counters) const override { ++counters.stick_slip; }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    int body_;
};

}  // namespace gimbal
