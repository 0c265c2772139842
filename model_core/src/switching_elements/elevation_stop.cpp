#include "gimbal/switching_elements/elevation_stop.hpp"

#include <cmath>

namespace gimbal {
namespace {

const char* stop_name(int side) { return side > 0 ? "resting on beta_max" : (side < 0 ? "resting on beta_min" : "free"); }

}  // namespace

ElevationStopElement::ElevationStopElement(int index, int first_guard)
    : SwitchingElement("elevation stop", first_guard) {
    (void)index;  // one elevation axis
}

void ElevationStopElement::guards(const SwitchingContext& context, const Modes& modes, double* values) const {
    double* g = values + first_guard();
    const ElevationStopParameters& stop = context.params.elevation_stop;
    const Dynamics& d = context.dynamics;
    g[0] = g[1] = 1.0;
    if (modes.elevation_stop == 0) {
        g[0] = stop.upper - d.full.angle[kElevation];  // reaching beta_max
        g[1] = d.full.angle[kElevation] - stop.lower;  // reaching beta_min
    } else if (modes.elevation_stop > 0) {
        g[0] = -d.stop_torque;  // the stop pushes down while the payload presses up into it
    } else {
        g[1] = d.stop_torque;
    }
}

void ElevationStopElement::decide(const SwitchingContext& context, const Modes& previous, Modes& modes,
                                  double* state, const int* crossings) const {
    const ElevationStopParameters& stop = context.params.elevation_stop;
    const StateLayout& layout = context.params.layout;
    const Dynamics& d = context.dynamics;
    const int resting = previous.elevation_stop;
    if (resting != 0) {
        const int guard = resting > 0 ? 0 : 1;
        const double reaction = resting > 0 ? -d.stop_torque : d.stop_torque;
        modes.elevation_stop = side(reaction, crossings, guard) < 0 ? 0 : resting;
        // Released, the payload leaves from one rounding unit inside the stop: the free guard of the stop
        // it leaves then starts on its inner side. On the stop itself it would stay exactly 0 for a while
        // (beta moves by a t^2 / 2 from rest), which ARKODE's root finder refuses as a root "at and very
        // near" its start.
        if (modes.elevation_stop == 0) {
            double& beta = state[context.params.layout.angle_slot[kElevation]];
            beta = std::nextafter(resting > 0 ? stop.upper : stop.lower, resting > 0 ? -HUGE_VAL : HUGE_VAL);
        }
        return;
    }
    modes.elevation_stop = 0;
    double& beta = state[layout.angle_slot[kElevation]];
    const double rate = state[layout.rate_slot[kElevation]];
    int hit = 0;
    if (side(stop.upper - beta, crossings, 0) <= 0 && rate > 0.0) hit = 1;
    else if (side(beta - stop.lower, crossings, 1) <= 0 && rate < 0.0) hit = -1;
    if (hit == 0) return;
    beta = hit > 0 ? stop.upper : stop.lower;
    // Newton's law on the relative rate: beta_dot+ = -e beta_dot-, unless the rebound is too slow to
    // leave (the Zeno limit of the bounces): then beta_dot+ = 0. The impulse P on e_beta changes the
    // rates by M^-1 e_beta P: the coordinates the mass matrix couples to beta (the housing, a rigid
    // gear's rotor through its reflected inertia) take their share; a compliant gear's rotor is held
    // only by its spring, which carries no impulse, and the backlash and the currents do not jump.
    const double rebound = stop.restitution * std::fabs(rate) >= stop.rest_rate ? -stop.restitution * rate : 0.0;
    const Vec4 response = solve_mass_matrix(d.reduced_mass, Vec4(Vec4::Unit(kElevation)));
    const double impulse = (rebound - rate) / response[kElevation];
    for (int body = 0; body < 4; ++body)
        if (layout.independent(body) && body != kElevation) state[layout.rate_slot[body]] += impulse * response[body];
    state[layout.rate_slot[kElevation]] = rebound;
}

void ElevationStopElement::decide_rest(const SwitchingContext& context, const Modes& previous, Modes& modes,
                                       double* state) const {
    if (previous.elevation_stop != 0 || modes.elevation_stop != 0) return;  // not just released
    const ElevationStopParameters& stop = context.params.elevation_stop;
    const StateLayout& layout = context.params.layout;
    if (state[layout.rate_slot[kElevation]] != 0.0) return;
    double& beta = state[layout.angle_slot[kElevation]];
    const int on = beta == stop.upper ? 1 : (beta == stop.lower ? -1 : 0);
    if (on == 0) return;
    const double pushed = context.dynamics.acceleration[kElevation];
    if (on * pushed > 0.0) {
        modes.elevation_stop = on;
    } else {
        // Stopped dead on it (a plastic impact) while the torques pull it away: it leaves at once, from
        // one rounding unit inside, as after a release.
        beta = std::nextafter(beta, on > 0 ? -HUGE_VAL : HUGE_VAL);
    }
}

std::string ElevationStopElement::describe(const Modes& before, const Modes& after) const {
    if (!changed(before, after)) return std::string();
    return switching::transition(stop_name(before.elevation_stop), stop_name(after.elevation_stop));
}

}  // namespace gimbal
