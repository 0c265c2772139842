// Switching element: the hard stops of one axis (docs/physics.md section 5.5), one element per AXIS_STOP row
// of gimbal/switching_elements.def (the elevation stop: beta). The stopped coordinate q_s is limited to
// [lower, upper]. Reaching a stop, its rate relative to the housing reverses by Newton's impact law with the
// coefficient of restitution e, through an impulse of the stop on the stopped body (and its reaction on the
// body it is mounted on) that the mass matrix spreads over the coordinates it couples; a rebound slower
// than rest_rate ends the bounces (Zeno): the body then rests on the stop, held there by the stop's
// reaction while the other torques push it in, released when they pull away.
//   parameters: ModelParameters::axis_stop[stop] (the row's switch, lower, upper, e, w_rest: for the
//               elevation stop elevation_stop, elevation_stop.beta_min, beta_max, e, w_rest)
//   state slot: none (it jumps q_s's rate, and the rates the mass matrix couples to it)
//   mode: Modes::axis_stop[stop] (output: the row's contact)   guards: 2 (switching_elements.def)
//   counter: none (a rest and a release count in the total; a bounce changes no mode)
#pragma once

#include <string>

#include "gimbal/model/variables.hpp"
#include "gimbal/switching_elements/switching_element.hpp"

namespace gimbal {

// An AXIS_STOP row: the element kind it is, the coordinate it stops (a BodyIndex, q order) and its variables.
struct AxisStopDeclaration {
    ElementKind element;
    int coordinate;
    RealVariable lower, upper, restitution, rest_rate;
    IntegerVariable contact;
};

inline constexpr AxisStopDeclaration kAxisStops[kAxisStopCount] = {
#define AXIS_STOP(element, coordinate, lower, upper, restitution, rest_rate, contact) \
    {ElementKind::element, coordinate, vr_##lower, vr_##upper, vr_##restitution, vr_##rest_rate, vi_##contact},
#define ELEMENT(identifier, instances, guards, element_switch, element_class)
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
#undef AXIS_STOP
};

// The axis stop of an element kind (its index in kAxisStops), or -1.
constexpr int axis_stop_of(ElementKind kind) {
    for (int stop = 0; stop < kAxisStopCount; ++stop)
        if (kAxisStops[stop].element == kind) return stop;
    return -1;
}

// "elevation stop": the element's identifier in words.
std::string axis_stop_name(int stop);

namespace axis_stop_detail {
// Two or more stops resting at once (rare): the joint solve of hold_at_axis_stops and its derivatives.
void hold_together(const int* resting, int count, Dynamics& out);
void hold_together_derivatives(const int* resting, int count, const Mat4& reduced_mass, Mat4x12& acceleration);
// The rates' change at an impact on `coordinate` that changes its rate by `jump` while the stops `resting`
// hold theirs: impulses on the impacting and the held coordinates, through the mass matrix.
Vec4 impact_while_held(int coordinate, double jump, const int* resting, int count, const Mat4& reduced_mass);
}  // namespace axis_stop_detail

// Force pass, after the accelerations: while a body rests on a stop, the stop's reaction is the torque that
// keeps its coordinate's acceleration at 0, applied through the mass matrix (M qdd = F + e_s torque). Free,
// or without a stop: no term. Several stops resting at once hold their coordinates together.
inline void hold_at_axis_stops(const Modes& modes, Dynamics& out) {
    int resting[kAxisStopCount];
    int count = 0;
    for (int stop = 0; stop < kAxisStopCount; ++stop) {
        out.stop_torque[stop] = 0.0;
        if (modes.axis_stop[stop] != 0) resting[count++] = stop;
    }
    if (count == 0) return;
    if (count > 1) return axis_stop_detail::hold_together(resting, count, out);
    const int s = kAxisStops[resting[0]].coordinate;
    const Vec4 response = solve_mass_matrix(out.reduced_mass, Vec4(Vec4::Unit(s)));
    const double torque = -out.acceleration[s] / response[s];
    out.acceleration += torque * response;
    out.acceleration[s] = 0.0;
    out.stop_torque[resting[0]] = torque;
}

// Jacobian pass of the same constraint: with the torque a function of the state, d(qdd)/dx is the free one
// less M^-1 e_s times its own row of q_s over (M^-1)_ss, so that q_s's row is 0.
inline void hold_at_axis_stops_derivatives(const Modes& modes, const Mat4& reduced_mass, Mat4x12& acceleration) {
    int resting[kAxisStopCount];
    int count = 0;
    for (int stop = 0; stop < kAxisStopCount; ++stop)
        if (modes.axis_stop[stop] != 0) resting[count++] = stop;
    if (count == 0) return;
    if (count > 1) return axis_stop_detail::hold_together_derivatives(resting, count, reduced_mass, acceleration);
    const int s = kAxisStops[resting[0]].coordinate;
    const Vec4 response = solve_mass_matrix(reduced_mass, Vec4(Vec4::Unit(s)));
    const Row12 free_row = acceleration.row(s);
    acceleration -= (response / response[s]) * free_row;
    acceleration.row(s).setZero();
}

class AxisStopElement final : public SwitchingElement {
public:
    explicit AxisStopElement(const ElementSlot& slot);
    static bool present(const ModelParameters& params, const ElementSlot& slot) {
        return params.axis_stop[axis_stop_of(slot.kind)].present;
    }
    static constexpr DecisionStage kStage = DecisionStage::impact;
    static std::string impossible_mode(const ModelParameters& params, const Modes& modes, const ElementSlot& slot);
    static constexpr int kGuards = 2;
    int guard_count() const override { return kGuards; }
    void guards(const SwitchingContext& context, const Modes& modes, double* values) const override;
    // Free: an impact (q_s on or past a stop, moving into it) projects q_s onto the stop and applies the
    // impulse of Newton's law; resting: released where the stop's reaction crossed zero.
    void decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    // After an impact, with the dynamics evaluated at the state it left: a body on a stop with no rate
    // rests there if the other torques push it in, and leaves from just inside it if they do not.
    void settle(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                const int* crossings) const override;
    bool changed(const Modes& before, const Modes& after) const override {
        return before.axis_stop[stop_] != after.axis_stop[stop_];
    }
    std::string describe(const Modes& before, const Modes& after) const override;

private:
    std::string side_name(int side) const;
    // The impact's jump of q_s's rate to `rebound`, and the rates the mass matrix couples to it.
    void apply_impulse(const SwitchingContext& context, const Modes& modes, double* state, double rebound) const;

    int stop_;        // in kAxisStops and the per-stop arrays
    int coordinate_;  // the stopped coordinate
};

}  // namespace gimbal
