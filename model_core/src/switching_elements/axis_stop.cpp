#include "gimbal/switching_elements/axis_stop.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <Eigen/LU>

namespace gimbal {
namespace {

// A limit's name within its stop: "elevation_stop.beta_max" -> "beta_max".
std::string limit_name(RealVariable limit) {
    const char* name = kRealVariables[limit].name;
    const char* dot = std::strchr(name, '.');
    return dot != nullptr ? dot + 1 : name;
}

using StopMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kAxisStopCount, kAxisStopCount>;

// M^-1 e_s for each resting stop's coordinate (columns), and their rows among them ((M^-1)_SS).
void stop_responses(const int* resting, int count, const Mat4& reduced_mass, Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, kAxisStopCount>& responses,
                    StopMatrix& coupling) {
    responses.resize(4, count);
    coupling.resize(count, count);
    for (int j = 0; j < count; ++j)
        responses.col(j) = solve_mass_matrix(reduced_mass, Vec4(Vec4::Unit(kAxisStops[resting[j]].coordinate)));
    for (int i = 0; i < count; ++i)
        for (int j = 0; j < count; ++j) coupling(i, j) = responses(kAxisStops[resting[i]].coordinate, j);
}

}  // namespace

std::string axis_stop_name(int stop) {
    std::string name = declaration_of(kAxisStops[stop].element).identifier;
    std::replace(name.begin(), name.end(), '_', ' ');
    return name;
}

namespace axis_stop_detail {

void hold_together(const int* resting, int count, Dynamics& out) {
    Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, kAxisStopCount> responses;
    StopMatrix coupling;
    stop_responses(resting, count, out.reduced_mass, responses, coupling);
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kAxisStopCount, 1> stopped(count);
    for (int i = 0; i < count; ++i) stopped[i] = -out.acceleration[kAxisStops[resting[i]].coordinate];
    const auto torques = coupling.partialPivLu().solve(stopped).eval();
    out.acceleration += responses * torques;
    for (int i = 0; i < count; ++i) {
        out.acceleration[kAxisStops[resting[i]].coordinate] = 0.0;
        out.stop_torque[resting[i]] = torques[i];
    }
}

void hold_together_derivatives(const int* resting, int count, const Mat4& reduced_mass, Mat4x12& acceleration) {
    Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, kAxisStopCount> responses;
    StopMatrix coupling;
    stop_responses(resting, count, reduced_mass, responses, coupling);
    Eigen::Matrix<double, Eigen::Dynamic, 12, Eigen::RowMajor, kAxisStopCount, 12> free_rows(count, 12);
    for (int i = 0; i < count; ++i) free_rows.row(i) = acceleration.row(kAxisStops[resting[i]].coordinate);
    acceleration -= responses * coupling.partialPivLu().solve(free_rows);
    for (int i = 0; i < count; ++i) acceleration.row(kAxisStops[resting[i]].coordinate).setZero();
}

Vec4 impact_while_held(int coordinate, double jump, const int* resting, int count, const Mat4& reduced_mass) {
    int coordinates[kAxisStopCount + 1];
    coordinates[0] = coordinate;
    for (int i = 0; i < count; ++i) coordinates[i + 1] = kAxisStops[resting[i]].coordinate;
    const int n = count + 1;
    Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, kAxisStopCount + 1> responses(4, n);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kAxisStopCount + 1, kAxisStopCount + 1> coupling(n, n);
    for (int j = 0; j < n; ++j) responses.col(j) = solve_mass_matrix(reduced_mass, Vec4(Vec4::Unit(coordinates[j])));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) coupling(i, j) = responses(coordinates[i], j);
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kAxisStopCount + 1, 1> change = decltype(change)::Zero(n);
    change[0] = jump;
    return responses * coupling.partialPivLu().solve(change);
}

}  // namespace axis_stop_detail

AxisStopElement::AxisStopElement(const ElementSlot& slot)
    : SwitchingElement(axis_stop_name(axis_stop_of(slot.kind)), slot.first_guard),
      stop_(axis_stop_of(slot.kind)),
      coordinate_(kAxisStops[axis_stop_of(slot.kind)].coordinate) {}

std::string AxisStopElement::impossible_mode(const ModelParameters& params, const Modes& modes,
                                             const ElementSlot& slot) {
    const int stop = axis_stop_of(slot.kind);
    if (params.axis_stop[stop].present || modes.axis_stop[stop] == 0) return {};
    const ElementDeclaration& declared = declaration_of(slot.kind);
    return std::string("the ") + declared.identifier + " mode is set but the stop is off (" + declared.element_switch +
           " = false)";
}

std::string AxisStopElement::side_name(int side) const {
    if (side == 0) return "free";
    return "resting on " + limit_name(side > 0 ? kAxisStops[stop_].upper : kAxisStops[stop_].lower);
}

void AxisStopElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    const AxisStopParameters& stop = context.params.axis_stop[stop_];
    const Dynamics& d = context.dynamics;
    g[0] = g[1] = 1.0;
    const int resting = modes.axis_stop[stop_];
    if (resting == 0) {
        g[0] = stop.upper - d.full.angle[coordinate_];  // reaching the upper stop
        g[1] = d.full.angle[coordinate_] - stop.lower;  // reaching the lower stop
    } else if (resting > 0) {
        g[0] = -d.stop_torque[stop_];  // the stop pushes down while the body presses up into it
    } else {
        g[1] = d.stop_torque[stop_];
    }
}

void AxisStopElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                             const int* crossings) const {
    const AxisStopParameters& stop = context.params.axis_stop[stop_];
    const StateLayout& layout = context.params.layout;
    const Dynamics& d = context.dynamics;
    const int resting = previous.axis_stop[stop_];
    if (resting != 0) {
        const int guard = resting > 0 ? 0 : 1;
        const double reaction = resting > 0 ? -d.stop_torque[stop_] : d.stop_torque[stop_];
        modes.axis_stop[stop_] = side(reaction, crossings, guard) < 0 ? 0 : resting;
        // Released, the body leaves from one rounding unit inside the stop: the free guard of the stop it
        // leaves then starts on its inner side. On the stop itself it would stay exactly 0 for a while
        // (q_s moves by a t^2 / 2 from rest), which ARKODE's root finder refuses as a root "at and very
        // near" its start.
        if (modes.axis_stop[stop_] == 0) {
            double& angle = state[layout.angle_slot[coordinate_]];
            angle = std::nextafter(resting > 0 ? stop.upper : stop.lower, resting > 0 ? -HUGE_VAL : HUGE_VAL);
        }
        return;
    }
    modes.axis_stop[stop_] = 0;
    double& angle = state[layout.angle_slot[coordinate_]];
    const double rate = state[layout.rate_slot[coordinate_]];
    int hit = 0;
    if (side(stop.upper - angle, crossings, 0) <= 0 && rate > 0.0) hit = 1;
    else if (side(angle - stop.lower, crossings, 1) <= 0 && rate < 0.0) hit = -1;
    if (hit == 0) return;
    angle = hit > 0 ? stop.upper : stop.lower;
    // Newton's law on the relative rate: q_s_dot+ = -e q_s_dot-, unless the rebound is too slow to leave
    // (the Zeno limit of the bounces): then q_s_dot+ = 0.
    const double rebound = stop.restitution * std::fabs(rate) >= stop.rest_rate ? -stop.restitution * rate : 0.0;
    apply_impulse(context, modes, state, rebound);
}

// The impulse P on e_s changes the rates by M^-1 e_s P: the coordinates the mass matrix couples to q_s (the
// housing, a rigid gear's rotor through its reflected inertia) take their share; a compliant gear's rotor
// is held only by its spring, which carries no impulse, and the backlash and the currents do not jump.
// Another body resting on its stop meanwhile keeps its rate (0): that stop's impulse acts too.
void AxisStopElement::apply_impulse(const SwitchingContext& context, const Modes& modes, double* state,
                                    double rebound) const {
    const StateLayout& layout = context.params.layout;
    const Mat4& reduced_mass = context.dynamics.reduced_mass;
    double& rate = state[layout.rate_slot[coordinate_]];
    int held[kAxisStopCount];
    int held_count = 0;
    bool is_held[4] = {false, false, false, false};
    for (int other = 0; other < kAxisStopCount; ++other) {
        if (other == stop_ || modes.axis_stop[other] == 0) continue;
        held[held_count++] = other;
        is_held[kAxisStops[other].coordinate] = true;
    }
    if (held_count > 0) {
        const Vec4 change =
            axis_stop_detail::impact_while_held(coordinate_, rebound - rate, held, held_count, reduced_mass);
        for (int body = 0; body < 4; ++body)
            if (layout.independent(body) && body != coordinate_ && !is_held[body])
                state[layout.rate_slot[body]] += change[body];
        rate = rebound;
        return;
    }
    const Vec4 response = solve_mass_matrix(reduced_mass, Vec4(Vec4::Unit(coordinate_)));
    const double impulse = (rebound - rate) / response[coordinate_];
    for (int body = 0; body < 4; ++body)
        if (layout.independent(body) && body != coordinate_) state[layout.rate_slot[body]] += impulse * response[body];
    rate = rebound;
}

void AxisStopElement::settle(const SwitchingContext& context, const Modes& previous, Modes& modes, double* state,
                             const int*) const {
    if (previous.axis_stop[stop_] != 0 || modes.axis_stop[stop_] != 0) return;  // not just released
    const AxisStopParameters& stop = context.params.axis_stop[stop_];
    const StateLayout& layout = context.params.layout;
    if (state[layout.rate_slot[coordinate_]] != 0.0) return;
    double& angle = state[layout.angle_slot[coordinate_]];
    const int on = angle == stop.upper ? 1 : (angle == stop.lower ? -1 : 0);
    if (on == 0) return;
    const double pushed = context.dynamics.acceleration[coordinate_];
    if (on * pushed > 0.0) {
        modes.axis_stop[stop_] = on;
    } else {
        // Stopped dead on it (a plastic impact) while the torques pull it away: it leaves at once, from one
        // rounding unit inside, as after a release.
        angle = std::nextafter(angle, on > 0 ? -HUGE_VAL : HUGE_VAL);
    }
}

std::string AxisStopElement::describe(const Modes& before, const Modes& after) const {
    if (!changed(before, after)) return std::string();
    return switching::transition(side_name(before.axis_stop[stop_]).c_str(), side_name(after.axis_stop[stop_]).c_str());
}

}  // namespace gimbal
