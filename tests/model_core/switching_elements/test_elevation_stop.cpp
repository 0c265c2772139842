// The elevation end stop (docs/physics.md section 5.5) through the core's C interface, in every
// integration method of the Co-Simulation step and in a Model Exchange host written here (RK4 with its
// own event location by bisection):
// - event location: a payload with no torque on it moves at constant rate between the stops, so every
//   impact time, and beta after it, is known exactly; beta's error over the rate is the time error of
//   the located impacts;
// - energy with e = 1: the payload swings under gravity with its products of inertia coupling it to
//   the azimuth housing, its rigid gear's rotor reflected onto it; kinetic + potential + magnetic energy
//   + what the resistors took - what the motors took in stays constant across the impacts (a reversal
//   of beta_dot alone, without the mass matrix's impulse, changes it);
// - rest with e = 0 and with e = 0.5 (the Zeno limit of the bounces): the payload ends on the stop,
//   exactly at it with no rate, in the resting mode; a motor voltage that pulls it away releases it;
// - the refusals of bad values, each naming the parameter.
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "check.hpp"
#include "core_settings.hpp"
#include "gimbal/gimbal_c_api.h"
#include "gimbal/model/variables.hpp"

using namespace gimbal;

namespace {

using namespace core_settings;
std::string& g_last_error = last_error;

// An instance with these values; method -1: Model Exchange. Null when initialization refused (the
// message in g_last_error).
GimbalCore* make(const std::vector<Setting>& settings, int method) {
    GimbalCore* core = gimbal_core_create(record, always, nullptr);
    if (method < 0) gimbal_core_use_continuous_time(core);
    else gimbal_core_set_integer(core, vi_solver_method, method);
    if (method == 7) gimbal_core_set_integer(core, vi_solver_substeps, 20);
    for (const Setting& s : settings) {
        if (s.type == GIMBAL_REAL) gimbal_core_set_real(core, s.vr, s.value);
        if (s.type == GIMBAL_INTEGER) gimbal_core_set_integer(core, s.vr, static_cast<int>(s.value));
        if (s.type == GIMBAL_BOOLEAN) gimbal_core_set_boolean(core, s.vr, static_cast<int>(s.value));
    }
    g_last_error.clear();
    if (gimbal_core_initialize(core, 0.0) != GIMBAL_OK) {
        gimbal_core_destroy(core);
        return nullptr;
    }
    return core;
}

double get(GimbalCore* core, RealVariable vr) {
    double value = NAN;
    gimbal_core_get_real(core, vr, &value);
    return value;
}
int get(GimbalCore* core, IntegerVariable vi) {
    int value = -99;
    gimbal_core_get_integer(core, vi, &value);
    return value;
}

// A Model Exchange host: classical RK4 at a fixed step, each step checked for a crossing of the event
// indicators, a crossing located by bisection of the step length to 1e-14 s, the modes decided there.
class ModelExchangeHost {
public:
    explicit ModelExchangeHost(GimbalCore* core) : core_(core) {
        GimbalDiscreteUpdate update{};
        gimbal_core_update_discrete_states(core_, &update);
        gimbal_core_get_continuous_states(core_, x_);
    }
    bool advance_to(double end, double step) {
        while (time_ < end - 1e-15) {
            const double h = std::fmin(step, end - time_);
            double z0[GIMBAL_EVENT_INDICATORS], z1[GIMBAL_EVENT_INDICATORS], x1[n];
            if (!indicators_at(time_, x_, z0) || !rk4(x_, h, x1) || !indicators_at(time_ + h, x1, z1)) return false;
            if (!crossed(z0, z1)) {
                std::copy(x1, x1 + n, x_);
                time_ += h;
                continue;
            }
            double low = 0.0, high = h;
            while (high - low > 1e-14) {
                const double middle = 0.5 * (low + high);
                double xm[n], zm[GIMBAL_EVENT_INDICATORS];
                if (!rk4(x_, middle, xm) || !indicators_at(time_ + middle, xm, zm)) return false;
                (crossed(z0, zm) ? high : low) = middle;
            }
            if (!rk4(x_, high, x1)) return false;
            time_ += high;
            gimbal_core_set_time(core_, time_);
            gimbal_core_set_continuous_states(core_, x1);
            GimbalDiscreteUpdate update{};
            if (gimbal_core_update_discrete_states(core_, &update) != GIMBAL_OK) return false;
            gimbal_core_get_continuous_states(core_, x_);
        }
        gimbal_core_set_time(core_, time_);
        return gimbal_core_set_continuous_states(core_, x_) == GIMBAL_OK;
    }

private:
    static constexpr int n = GIMBAL_CONTINUOUS_STATES;
    static bool crossed(const double* before, const double* after) {
        for (int k = 0; k < GIMBAL_EVENT_INDICATORS; ++k)
            if ((before[k] > 0.0) != (after[k] > 0.0)) return true;
        return false;
    }
    bool derivatives(double t, const double* x, double* dx) {
        gimbal_core_set_time(core_, t);
        return gimbal_core_set_continuous_states(core_, x) == GIMBAL_OK &&
               gimbal_core_get_derivatives(core_, dx) == GIMBAL_OK;
    }
    bool indicators_at(double t, const double* x, double* z) {
        gimbal_core_set_time(core_, t);
        return gimbal_core_set_continuous_states(core_, x) == GIMBAL_OK &&
               gimbal_core_get_event_indicators(core_, z) == GIMBAL_OK;
    }
    bool rk4(const double* x, double h, double* out) {
        double k1[n], k2[n], k3[n], k4[n], stage[n];
        if (!derivatives(time_, x, k1)) return false;
        for (int i = 0; i < n; ++i) stage[i] = x[i] + 0.5 * h * k1[i];
        if (!derivatives(time_ + 0.5 * h, stage, k2)) return false;
        for (int i = 0; i < n; ++i) stage[i] = x[i] + 0.5 * h * k2[i];
        if (!derivatives(time_ + 0.5 * h, stage, k3)) return false;
        for (int i = 0; i < n; ++i) stage[i] = x[i] + h * k3[i];
        if (!derivatives(time_ + h, stage, k4)) return false;
        for (int i = 0; i < n; ++i) out[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        return true;
    }
    GimbalCore* core_;
    double time_ = 0.0;
    double x_[n];
};

// Runs an instance to `end` in communication steps of `step` (Co-Simulation) or host steps of
// `me_step` (Model Exchange), calling `each` at every step's end.
bool run(GimbalCore* core, ModelExchangeHost* host, double start, double end, double step, double me_step,
         const std::function<void()>& each = [] {}) {
    if (host != nullptr) {
        for (double t = start; t < end - 1e-12;) {
            const double next = std::fmin(t + step, end);
            if (!host->advance_to(next, me_step)) return false;
            t = next;
            each();
        }
        return true;
    }
    const int steps = static_cast<int>(std::lround((end - start) / step));
    for (int k = 0; k < steps; ++k) {
        if (gimbal_core_do_step(core, start + k * step, step) != GIMBAL_OK) return false;
        each();
    }
    return true;
}

std::string label(int method) { return method < 0 ? "Model Exchange" : kMethodNames[method]; }

// ---- event location -------------------------------------------------------------------------------

// No torque on the payload: diagonal inertia about its centre of mass on the elevation axis, no
// friction, no gear spring, a fixed carrier at rest.
std::vector<Setting> free_payload(double restitution) {
    return {flag(vb_base_fixed, true), flag(vb_dry_friction, false), flag(vb_elevation_stop, true),
            real(vr_body2_I_xy, 0.0), real(vr_body2_I_xz, 0.0), real(vr_body2_I_yz, 0.0),
            real(vr_body2_d_bd_1, 0.0), real(vr_body2_d_bd_2, 0.0), real(vr_body2_d_bd_3, 0.0),
            real(vr_body2_c_visc, 0.0), integer(vi_gear2_model, 1), real(vr_gear2_k_s, 0.0), real(vr_gear2_c_s, 0.0),
            real(vr_elevation_stop_beta_min, -0.3), real(vr_elevation_stop_beta_max, 0.5),
            real(vr_elevation_stop_e, restitution), real(vr_beta, 0.0), real(vr_beta_dot, 1.0),
            real(vr_solver_rtol, 1e-10), real(vr_solver_atol, 1e-12)};
}

void check_event_location(int method) {
    // beta = t until 0.5 (t = 0.5), back at -e to -0.3, then at e^2 towards 0.5: at t = 2.5
    //   e = 1:   impacts at 0.5, 1.3, 2.1, then beta = 0.5 - 0.4 = 0.1, beta_dot = -1;
    //   e = 0.5: impacts at 0.5, 2.1, then beta = -0.3 + 0.25 * 0.4 = -0.2, beta_dot = 0.25.
    const struct { double e, beta, rate; } cases[] = {{1.0, 0.1, -1.0}, {0.5, -0.2, 0.25}};
    for (const auto& c : cases) {
        GimbalCore* core = make(free_payload(c.e), method);
        CHECK(core != nullptr);
        if (core == nullptr) {
            std::fprintf(stderr, "%s: %s\n", label(method).c_str(), g_last_error.c_str());
            continue;
        }
        const std::unique_ptr<ModelExchangeHost> host(method < 0 ? new ModelExchangeHost(core) : nullptr);
        CHECK(run(core, host.get(), 0.0, 2.5, 0.01, 1e-3));
        const double beta = get(core, vr_beta), rate = get(core, vr_beta_dot);
        // Every impact located dt late moves beta by the rate after it times dt.
        const double time_error = std::fabs(beta - c.beta) / std::fabs(c.rate);
        std::printf("  event location, %-15s e = %.1f: beta error %.2e rad, impact time error %.2e s\n",
                    label(method).c_str(), c.e, beta - c.beta, time_error);
        // The real-time method locates each event in at most 10 iterations, by design (docs/real_time.md).
        CHECK(time_error <= (method == 7 ? 1e-6 : 1e-11));
        CHECK_NEAR(rate, c.rate, 1e-12);
        CHECK(get(core, vi_elevation_stop_contact) == 0);
        gimbal_core_destroy(core);
    }
}

// A plastic impact (e = 0) while a cable pulls the payload back: it stops dead on the stop and leaves it
// at once, never resting there (and no root finder sees a guard stuck on zero at its restart).
void check_plastic_pull_away(int method) {
    std::vector<Setting> settings = free_payload(0.0);
    // k / I_xx = 1 rad^2/s^2: beta = sin(t) reaches the stop at 0.5 at t = asin(0.5), then, stopped
    // dead, swings back as 0.5 cos(t - asin(0.5)).
    settings.push_back(real(vr_cable2_k, 0.05));
    GimbalCore* core = make(settings, method);
    CHECK(core != nullptr);
    if (core == nullptr) return;
    const std::unique_ptr<ModelExchangeHost> host(method < 0 ? new ModelExchangeHost(core) : nullptr);
    double highest = 0.0;
    int contact = 0;
    const bool ran = run(core, host.get(), 0.0, 1.0, 0.01, 1e-3, [&] {
        highest = std::fmax(highest, get(core, vr_beta));
        contact = std::max(contact, get(core, vi_elevation_stop_contact));
    });
    if (!ran) std::fprintf(stderr, "%s: %s\n", label(method).c_str(), g_last_error.c_str());
    CHECK(ran);
    const double beta = get(core, vr_beta), rate = get(core, vr_beta_dot);
    std::printf("  plastic impact, pulled away, %-15s: highest beta %.17g, at 1 s beta %.4f, rate %.4f\n",
                label(method).c_str(), highest, beta, rate);
    CHECK(highest <= 0.5);  // (sampled at the communication points; the analytic check below times the impact)
    CHECK(contact == 0);
    const double since = 1.0 - std::asin(0.5);
    CHECK_NEAR(beta, 0.5 * std::cos(since), method == 7 ? 1e-5 : 1e-8);
    CHECK_NEAR(rate, -0.5 * std::sin(since), method == 7 ? 1e-5 : 1e-8);
    gimbal_core_destroy(core);
}

// ---- energy with e = 1 ------------------------------------------------------------------------------

double energy_balance(GimbalCore* core) {
    return get(core, vr_energy_kinetic) + get(core, vr_energy_potential) + get(core, vr_energy_spring) +
           get(core, vr_energy_magnetic) - get(core, vr_energy_electrical_in) + get(core, vr_energy_resistive) +
           get(core, vr_energy_viscous) + get(core, vr_energy_shaft_damping) + get(core, vr_energy_dry_friction);
}

// The payload off its axis with products of inertia (the defaults), swinging under gravity between
// stops at +-0.12 rad, the housing free to turn; its gear rigid (the rotor's reflected inertia takes
// the impulse with it), the azimuth rotor decoupled (a gear without spring). No friction; with
// `braking` false, no motor braking either (quasi-static motors of 1 MOhm: their back-EMF current
// vanishes), so that the payload swings between its start and the stop for ever.
std::vector<Setting> swinging_payload(double restitution, bool braking) {
    std::vector<Setting> settings = {
            flag(vb_base_fixed, true), flag(vb_dry_friction, false), flag(vb_energy_accounting, true),
            flag(vb_elevation_stop, true), integer(vi_gear2_model, 0), integer(vi_gear1_model, 1),
            real(vr_gear1_k_s, 0.0), real(vr_gear1_c_s, 0.0), real(vr_body1_c_visc, 0.0), real(vr_body2_c_visc, 0.0),
            real(vr_rotor1_c_visc, 0.0), real(vr_rotor2_c_visc, 0.0),
            real(vr_elevation_stop_beta_min, -0.12), real(vr_elevation_stop_beta_max, 0.12),
            real(vr_elevation_stop_e, restitution), real(vr_beta, 0.0), real(vr_solver_rtol, 1e-10),
            real(vr_solver_atol, 1e-12)};
    if (!braking)
        for (int j = 0; j < 2; ++j) {
            settings.push_back(integer(j == 0 ? vi_motor1_model : vi_motor2_model, 0));
            settings.push_back(real(j == 0 ? vr_motor1_R : vr_motor2_R, 1e6));
        }
    return settings;
}

void check_energy(int method) {
    GimbalCore* core = make(swinging_payload(1.0, false), method);
    CHECK(core != nullptr);
    if (core == nullptr) {
        std::fprintf(stderr, "%s: %s\n", label(method).c_str(), g_last_error.c_str());
        return;
    }
    const std::unique_ptr<ModelExchangeHost> host(method < 0 ? new ModelExchangeHost(core) : nullptr);
    const double start = energy_balance(core);
    double worst = 0.0, scale = 0.0, lowest = 0.0, highest = 0.0;
    int impacts = 0;
    double previous_rate = get(core, vr_beta_dot);
    CHECK(run(core, host.get(), 0.0, 1.5, 0.001, 2e-5, [&] {
        worst = std::fmax(worst, std::fabs(energy_balance(core) - start));
        scale = std::fmax(scale, get(core, vr_energy_kinetic));
        const double beta = get(core, vr_beta), rate = get(core, vr_beta_dot);
        lowest = std::fmin(lowest, beta), highest = std::fmax(highest, beta);
        if (rate * previous_rate < 0.0 && std::fabs(std::fabs(beta) - 0.12) < 0.01) ++impacts;
        previous_rate = rate;
    }));
    std::printf("  energy, e = 1,  %-15s: %d impacts, beta in [%.6f, %.6f], balance error %.2e J of %.2e J kinetic "
                "(%.1e)\n", label(method).c_str(), impacts, lowest, highest, worst, scale, worst / scale);
    CHECK(impacts >= 3);
    CHECK(lowest >= -0.12 - 1e-9 && highest <= 0.12 + 1e-9);
    CHECK(worst <= (method == 7 ? 1e-4 : 1e-7) * scale);
    gimbal_core_destroy(core);
}

// ---- rest on the stop, and release ------------------------------------------------------------------

// e = 0: it rests at the first impact; then a motor voltage releases it. e = 0.5, without the motors'
// braking: it bounces (Zeno) until a rebound is slower than w_rest, then rests.
void check_rest(int method, double restitution) {
    const bool bounces = restitution > 0.0;
    std::vector<Setting> settings = swinging_payload(restitution, !bounces);
    settings.push_back(real(vr_elevation_stop_w_rest, 0.01));
    // The default tolerances: at rtol 1e-10, RODAS4 crawls once the motor's current is held at its limit
    // on a rigid gear, with the stop or without it (solver.max_steps exceeded; left alone here).
    settings.push_back(real(vr_solver_rtol, 1e-6));
    settings.push_back(real(vr_solver_atol, 1e-8));
    GimbalCore* core = make(settings, method);
    CHECK(core != nullptr);
    if (core == nullptr) {
        std::fprintf(stderr, "%s: %s\n", label(method).c_str(), g_last_error.c_str());
        return;
    }
    const std::unique_ptr<ModelExchangeHost> host(method < 0 ? new ModelExchangeHost(core) : nullptr);
    int rebounds = 0;  // samples leaving a stop, just after an impact
    CHECK(run(core, host.get(), 0.0, 1.5, 0.001, 2e-5, [&] {
        const double beta = get(core, vr_beta), rate = get(core, vr_beta_dot);
        if (std::fabs(beta) > 0.119 && std::fabs(rate) > 1e-9 && beta * rate < 0.0) ++rebounds;
    }));
    const int side = get(core, vi_elevation_stop_contact);
    const double beta = get(core, vr_beta), rate = get(core, vr_beta_dot);
    const int events = get(core, vi_events_total);
    std::printf("  rest, e = %.1f,  %-15s: contact %+d, beta %.17g, beta_dot %g, %d mode changes, %d samples "
                "rebounding\n", restitution, label(method).c_str(), side, beta, rate, events, rebounds);
    CHECK(bounces ? rebounds >= 3 : rebounds == 0);
    CHECK(side == 1 || side == -1);
    // Held there: exactly on it, and no rate but the rounding of the implicit methods' linear algebra.
    CHECK(beta == side * 0.12);
    CHECK(std::fabs(rate) <= 1e-20);
    if (bounces) {  // no motor torque to release it with (the motors are off the circuit)
        gimbal_core_destroy(core);
        return;
    }
    // The motor pulls it off: the stop lets go, the payload leaves. Its gear is rigid: the rotor turns
    // N times the payload, 24 V drives the motor's current to its limit.
    gimbal_core_set_real(core, vr_u_R2, -side * 12.0);
    const bool ran = run(core, host.get(), 1.5, 1.52, 0.001, 2e-5);
    if (!ran) std::fprintf(stderr, "%s: %s\n", label(method).c_str(), g_last_error.c_str());
    CHECK(ran);
    const double away = side * (side * 0.12 - get(core, vr_beta));
    std::printf("  release,         %-15s: contact %+d, %.3g rad off the stop after 20 ms\n", label(method).c_str(),
                get(core, vi_elevation_stop_contact), away);
    CHECK(get(core, vi_elevation_stop_contact) == 0);
    CHECK(away > 1e-4);
    gimbal_core_destroy(core);
}

// ---- refusals ---------------------------------------------------------------------------------------

void check_refusals() {
    const struct {
        std::vector<Setting> settings;
        const char* names;
    } cases[] = {
        {{real(vr_elevation_stop_beta_min, 0.5), real(vr_elevation_stop_beta_max, 0.5)}, "elevation_stop.beta_min"},
        {{real(vr_elevation_stop_e, 1.5)}, "elevation_stop.e"},
        {{real(vr_elevation_stop_e, -0.1)}, "elevation_stop.e"},
        {{real(vr_elevation_stop_w_rest, 0.0)}, "elevation_stop.w_rest"},
        {{flag(vb_elevation_stop, true), real(vr_beta, 1.6)}, "beta"},
    };
    for (const auto& c : cases) {
        GimbalCore* core = make(c.settings, 4);
        CHECK(core == nullptr);
        if (core != nullptr) gimbal_core_destroy(core);
        const bool named = g_last_error.find(c.names) != std::string::npos;
        if (!named) std::fprintf(stderr, "refusal without '%s': %s\n", c.names, g_last_error.c_str());
        CHECK(named);
    }
    // Off, the start may lie anywhere; on, at the stop itself it is accepted.
    GimbalCore* off = make({real(vr_beta, 1.6)}, 4);
    CHECK(off != nullptr);
    if (off != nullptr) gimbal_core_destroy(off);
    GimbalCore* on_stop = make({flag(vb_elevation_stop, true), real(vr_beta, 1.5707963267948966)}, 4);
    CHECK(on_stop != nullptr);
    if (on_stop != nullptr) gimbal_core_destroy(on_stop);
}

}  // namespace

int main() {
    check_refusals();
    std::vector<int> methods = {-1, 4, 5, 6, 7};
    if (GimbalCore* probe = make({integer(vi_solver_method, 0)}, 0)) {  // SUNDIALS in this build
        gimbal_core_destroy(probe);
        for (int method : {0, 1, 2, 3}) methods.push_back(method);
    }
    for (int method : methods) {
        check_event_location(method);
        check_plastic_pull_away(method);
        check_energy(method);
        check_rest(method, 0.0);
        check_rest(method, 0.5);
    }
    return check_report("elevation_stop");
}
