// Switching element: the backlash of one gear (docs/physics.md section 4.2, (2.75)-(2.81)). In the gap,
// or held at a stop while the free backlash rate X pushes into it; a gear with c_s = 0 is the pure dead
// zone theta_b = clamp(theta_d, +-eta). This module owns the gear's shaft coupling under every contact
// mode (rigid and compliant gears included: their shaft torque is the same pass), its contributions to
// the Jacobian, its guards and transitions.
//   parameters: ModelParameters::gear[axis] (gear<j>.N, k_s, c_s, eta), fidelity.gear[axis]
//   state slot: layout.backlash_slot[axis] (theta_b<j>)     mode: Modes::gear_contact[axis]
//   guards: 2 (indicators 0-3)                               counter: EventCounters::backlash[axis]
#pragma once

#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

// Gears whose damping is 0 are pure dead zones: theta_b follows theta_d inside the gap.
inline bool dead_zone_gear(const GearParameters& gear) { return gear.half_backlash > 0.0 && gear.damping == 0.0; }

// Force pass of the dynamics: the gear's deflection, its rate, the free backlash rate X, the backlash
// rate and the shaft torque T_E on the load (the rotor receives -T_E / N), written to `out`, from the
// expanded state out.full under the contact mode. Returns T_E.
inline double gear_coupling(const ModelParameters& params, const Modes& modes, int axis, Dynamics& out) {
    const GearParameters& gear = params.gear[axis];
    const int rotor = rotor_index(axis), load = load_index(axis);
    const Vec4& q = out.full.angle;
    const Vec4& qd = out.full.rate;
    const GearModel model = params.fidelity.gear[axis];
    const double deflection = model == GearModel::rigid ? 0.0 : gear_deflection(gear, q[rotor], q[load]);
    const double deflection_rate = model == GearModel::rigid ? 0.0 : gear_deflection(gear, qd[rotor], qd[load]);
    const double backlash = out.full.backlash[axis];
    const int contact = modes.gear_contact[axis];
    out.deflection[axis] = deflection;
    out.deflection_rate[axis] = deflection_rate;
    out.free_backlash_rate[axis] = 0.0;

    double shaft_torque = 0.0, backlash_rate = 0.0;
    if (model == GearModel::rigid) {
        // No shaft state: the rotor follows the load (coordinate_reduction).
    } else if (model == GearModel::compliant || gear.half_backlash == 0.0) {
        shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, 0.0, 0.0);
    } else if (dead_zone_gear(gear)) {
        // theta_b = clamp(theta_d, -eta, eta): it moves with theta_d inside the gap.
        out.free_backlash_rate[axis] = deflection_rate;
        if (contact == 0) {
            backlash_rate = deflection_rate;
        } else {
            shaft_torque = gear.stiffness * (deflection - contact * gear.half_backlash);
        }
    } else {
        const double x = free_backlash_rate(gear, deflection, deflection_rate, backlash);
        out.free_backlash_rate[axis] = x;
        if (contact == 0) {
            backlash_rate = x;  // and T_E = 0 exactly: (2.77) with dtheta_b = X cancels
        } else {
            shaft_torque = gear_shaft_torque(gear, deflection, deflection_rate, backlash, 0.0);
        }
    }
    out.shaft_torque[axis] = shaft_torque;
    out.backlash_rate[axis] = backlash_rate;
    return shaft_torque;
}

// Jacobian pass: d T_E / d(state) under the contact mode, added to the load's row of `force` and, as
// -T_E / N, to the rotor's (full coordinates, columns of JacobianColumn).
inline void add_gear_force_derivatives(const ModelParameters& params, const Modes& modes, int axis, Mat4x12& force) {
    const GearParameters& gear = params.gear[axis];
    const int rotor = rotor_index(axis), load = load_index(axis);
    const GearModel model = params.fidelity.gear[axis];
    const int contact = modes.gear_contact[axis];
    double stiffness = 0.0, damping = 0.0, backlash = 0.0;  // d T_E / d(theta_d, dtheta_d, theta_b)
    if (model == GearModel::compliant || (model == GearModel::backlash && gear.half_backlash == 0.0)) {
        stiffness = gear.stiffness, damping = gear.damping;
    } else if (model == GearModel::backlash && contact != 0) {
        stiffness = gear.stiffness;
        damping = dead_zone_gear(gear) ? 0.0 : gear.damping;
        backlash = dead_zone_gear(gear) ? 0.0 : -gear.stiffness;
    }
    Row12 torque = Row12::Zero();
    torque(rotor) = stiffness / gear.ratio;
    torque(load) = -stiffness;
    torque(kRateColumn + rotor) = damping / gear.ratio;
    torque(kRateColumn + load) = -damping;
    torque(kBacklashColumn + axis) = backlash;
    force.row(load) += torque;
    force.row(rotor) -= torque / gear.ratio;
}

// The row of d(dtheta_b/dt)/d(state) in the gap (q_full = T q_padded); false when theta_b has no
// dynamics of its own (no backlash state, at a stop, or eta = 0).
bool backlash_state_row(const ModelParameters& params, const Modes& modes, int axis, const Mat4& T, Row12& row);

class BacklashElement final : public SwitchingElement {
public:
    BacklashElement(int axis, int first_guard);
    explicit BacklashElement(const ElementSlot& slot) : BacklashElement(slot.instance, slot.first_guard) {}
    // A backlash gear's only.
    static bool present(const ModelParameters& params, const ElementSlot& slot) { return params.layout.backlash_slot[slot.instance] >= 0; }
    static constexpr DecisionStage kStage = DecisionStage::contact;
    static std::string impossible_mode(const ModelParameters& params, const Modes& modes, const ElementSlot& slot) {
        if (params.fidelity.gear[slot.instance] == GearModel::backlash || modes.gear_contact[slot.instance] == 0) return {};
        return "gear " + std::to_string(slot.instance + 1) + " has no backlash but a contact mode";
    }
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    bool changed(const Modes& before, const Modes& after) const override {
        return before.gear_contact[axis_] != after.gear_contact[axis_];
    }
    void count_change(EventCounters& counters) const override { ++counters.backlash[axis_]; }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    // The projection of theta_b for a compliant gear with damping: in the gap, or at a stop.
    int decide_compliant(const SwitchingContext& context, int current, double& backlash, const int* crossings) const;
    int axis_;
};

}  // namespace gimbal
