// Current-commanded drives (docs/physics.md section 4.6) through the core's C interface, in every
// integration method of the Co-Simulation step:
// - the closed current loop of an inductive motor: with back-emf feed-forward the amplifier cancels the
//   back-emf exactly, so the loop is the locked-rotor loop whatever the rotor does. The gains derived
//   from the bandwidth (pole-zero cancellation) give i(t) = i_cmd (1 - exp(-2 pi f_c t)); explicit K_p,
//   K_i give the step response of (K_p s + K_i) / (L s^2 + (R + K_p) s + K_i): every sample, the rise
//   time (10 % - 90 %) and the overshoot at the analytic peak time against the closed form;
// - the bus voltage: |amplifier1.u| <= U_L at every sample through a long saturation, and anti-windup:
//   the pole-zero loop has no overshoot, and after the saturation ends the current still does not pass
//   the command (without the freeze the integrator winds up and the current peaks at 3.144 A for 3 A);
// - the quasi-static reduction: i = i_cmd while free, (U_L - k_emf w) / R while the bus limits it;
// - FMU-state transparency in current drive: save, continue, restore, continue gives the same bits;
// - the refusals of bad values, each naming the variable; the indicators of a voltage-driven FMU.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "check.hpp"
#include "core_settings.hpp"
#include "gimbal/gimbal_c_api.h"
#include "gimbal/model/variables.hpp"
#include "gimbal/switching_elements/switching_element.hpp"

using namespace gimbal;

namespace {

using namespace core_settings;
std::string& g_last_error = last_error;

// Null when initialization refused it (the message in g_last_error); *unavailable when the method is not
// in this binary.
GimbalCore* make(const std::vector<Setting>& settings, int method, int substeps = 400, bool* unavailable = nullptr) {
    GimbalCore* core = gimbal_core_create(record, always, nullptr);
    gimbal_core_set_integer(core, vi_solver_method, method);
    if (method == 7) gimbal_core_set_integer(core, vi_solver_substeps, substeps);
    for (const Setting& s : settings) {
        if (s.type == GIMBAL_REAL) gimbal_core_set_real(core, s.vr, s.value);
        if (s.type == GIMBAL_INTEGER) gimbal_core_set_integer(core, s.vr, static_cast<int>(s.value));
        if (s.type == GIMBAL_BOOLEAN) gimbal_core_set_boolean(core, s.vr, static_cast<int>(s.value));
    }
    g_last_error.clear();
    if (gimbal_core_initialize(core, 0.0) != GIMBAL_OK) {
        if (unavailable) *unavailable = g_last_error.find("not available in this binary") != std::string::npos;
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

// Motor 1 current-driven and inductive on a rigid gear, no friction, no carrier motion, no gravity: its
// loop alone. Motor 2 stays in voltage drive at 0 V.
std::vector<Setting> loop_settings(double command) {
    return {integer(vi_motor1_drive, 1),     integer(vi_gear1_model, 0),  integer(vi_gear2_model, 0),
            flag(vb_dry_friction, false),    flag(vb_base_fixed, true),   real(vr_g, 0.0),
            real(vr_motor1_U_L, 100.0),      real(vr_motor1_i_L, 10.0),   real(vr_solver_rtol, 1e-10),
            real(vr_solver_atol, 1e-12),     real(vr_i_R1_cmd, command)};
}

constexpr double kPi = 3.14159265358979323846;

// The step response of (K_p s + K_i) / (L s^2 + (R + K_p) s + K_i) to a unit step (underdamped gains).
struct SecondOrder {
    double L, R, K_p, K_i;
    std::complex<double> pole() const {
        const double a = L, b = R + K_p, c = K_i;
        return {-b / (2 * a), std::sqrt(4 * a * c - b * b) / (2 * a)};
    }
    // y(t) = 1 + 2 Re[r e^{p t}], r the residue of Y(s) = N(s) / (s D(s)) at p.
    std::complex<double> residue() const {
        const std::complex<double> p = pole();
        return (K_p * p + K_i) / (p * L * (p - std::conj(p)));
    }
    double step(double t) const { return 1.0 + 2.0 * std::real(residue() * std::exp(pole() * t)); }
    double slope(double t) const { return 2.0 * std::real(residue() * pole() * std::exp(pole() * t)); }
    // The first time y reaches `level` (bisection on the rising edge), and the first peak (y' = 0).
    double reaching(double level) const {
        double lo = 0.0, hi = 1e-6;
        while (step(hi) < level) lo = hi, hi *= 1.5;
        for (int k = 0; k < 200; ++k) {
            const double mid = 0.5 * (lo + hi);
            (step(mid) < level ? lo : hi) = mid;
        }
        return 0.5 * (lo + hi);
    }
    double peak() const {
        const double wd = std::imag(pole());
        double lo = reaching(0.5), hi = lo + kPi / wd;  // y' changes sign once in between
        for (int k = 0; k < 200; ++k) {
            const double mid = 0.5 * (lo + hi);
            (slope(mid) > 0.0 ? lo : hi) = mid;
        }
        return 0.5 * (lo + hi);
    }
};

// Steps the instance through `times` (increasing), calling sample(t) at each.
template <class Sample>
bool run_through(GimbalCore* core, const std::vector<double>& times, Sample sample) {
    double t = 0.0;
    for (double next : times) {
        if (next > t && gimbal_core_do_step(core, t, next - t) != GIMBAL_OK) {
            std::fprintf(stderr, "step at t = %g refused: %s\n", t, g_last_error.c_str());
            ++check::failures;
            return false;
        }
        t = next;
        sample(t);
    }
    return true;
}

void first_order_loop(int method) {
    const double command = 1.5, f_c = 200.0;
    std::vector<Setting> settings = loop_settings(command);
    settings.push_back(real(vr_amplifier1_f_c, f_c));
    bool unavailable = false;
    GimbalCore* core = make(settings, method, 400, &unavailable);
    if (core == nullptr) {
        if (unavailable) return;
        std::fprintf(stderr, "%s: refused: %s\n", kMethodNames[method], g_last_error.c_str());
        ++check::failures;
        return;
    }
    std::vector<double> times;
    for (int k = 1; k <= 50; ++k) times.push_back(1e-4 * k);
    double worst = 0.0;
    run_through(core, times, [&](double t) {
        const double expected = command * (1.0 - std::exp(-2.0 * kPi * f_c * t));
        worst = std::max(worst, std::fabs(get(core, vr_i_R1) - expected));
    });
    std::printf("  %-15s first order (pole-zero gains, f_c = %g Hz): largest error %.3g A of %g A\n",
                kMethodNames[method], f_c, worst, command);
    CHECK(worst <= 1e-6 * command);
    CHECK(get(core, vi_motor1_amplifier_saturated) == 0);
    gimbal_core_destroy(core);
}

void second_order_loop(int method) {
    const double command = 1.5;
    const SecondOrder loop{0.002, 2.0, 5.0, 40000.0};  // motor1.L, motor1.R (start values), explicit gains
    std::vector<Setting> settings = loop_settings(command);
    settings.push_back(real(vr_amplifier1_K_p, loop.K_p));
    settings.push_back(real(vr_amplifier1_K_i, loop.K_i));
    bool unavailable = false;
    GimbalCore* core = make(settings, method, 400, &unavailable);
    if (core == nullptr) {
        if (unavailable) return;
        std::fprintf(stderr, "%s: refused: %s\n", kMethodNames[method], g_last_error.c_str());
        ++check::failures;
        return;
    }
    const double t10 = loop.reaching(0.1), t90 = loop.reaching(0.9), tp = loop.peak();
    std::vector<double> times;
    for (int k = 1; k <= 100; ++k) times.push_back(5e-5 * k);
    times.push_back(t10), times.push_back(t90), times.push_back(tp);
    std::sort(times.begin(), times.end());
    double worst = 0.0, at10 = 0.0, at90 = 0.0, atp = 0.0;
    run_through(core, times, [&](double t) {
        const double i = get(core, vr_i_R1);
        worst = std::max(worst, std::fabs(i - command * loop.step(t)));
        if (t == t10) at10 = i;
        if (t == t90) at90 = i;
        if (t == tp) atp = i;
    });
    // The rise time the samples imply: each crossing moved by its level's error over the slope there.
    const double shift10 = (at10 - 0.1 * command) / (command * loop.slope(t10));
    const double shift90 = (at90 - 0.9 * command) / (command * loop.slope(t90));
    const double rise = t90 - t10, rise_error = std::fabs(shift90 - shift10) / rise;
    const double overshoot = loop.step(tp) - 1.0, overshoot_error = std::fabs((atp / command - 1.0) - overshoot) / overshoot;
    std::printf("  %-15s second order (K_p = %g, K_i = %g): largest error %.3g A; rise time %.6g s (error %.2g "
                "relative), overshoot %.6g %% (error %.2g relative)\n",
                kMethodNames[method], loop.K_p, loop.K_i, worst, rise, rise_error, 100 * overshoot, overshoot_error);
    CHECK(worst <= 1e-6 * command);
    CHECK(rise_error <= 1e-6);
    CHECK(overshoot_error <= 1e-6);
    gimbal_core_destroy(core);
}

// A 3 A step with the pole-zero gains at 2 kHz needs 75 V at once: the amplifier saturates at 24 V for
// about a millisecond. The unsaturated loop would not overshoot; with conditional integration the
// integrator keeps its value while saturated, and the current approaches 3 A from below.
void saturation_and_anti_windup(int method) {
    const double command = 3.0, bus = 24.0;
    const std::vector<Setting> settings = {
        integer(vi_motor1_drive, 1),  flag(vb_base_fixed, true),   real(vr_motor1_U_L, bus),
        real(vr_motor1_i_L, 4.0),     real(vr_solver_rtol, 1e-9),  real(vr_solver_atol, 1e-11),
        real(vr_i_R1_cmd, command)};
    bool unavailable = false;
    GimbalCore* core = make(settings, method, 200, &unavailable);
    if (core == nullptr) {
        if (unavailable) return;
        std::fprintf(stderr, "%s: refused: %s\n", kMethodNames[method], g_last_error.c_str());
        ++check::failures;
        return;
    }
    std::vector<double> times;
    for (int k = 1; k <= 400; ++k) times.push_back(1e-5 * k);
    double largest_voltage = 0.0, largest_current = 0.0, released_at = -1.0;
    bool saturated_seen = false;
    run_through(core, times, [&](double t) {
        largest_voltage = std::max(largest_voltage, std::fabs(get(core, vr_amplifier1_u)));
        largest_current = std::max(largest_current, get(core, vr_i_R1));
        const int saturated = get(core, vi_motor1_amplifier_saturated);
        saturated_seen = saturated_seen || saturated == 1;
        if (saturated_seen && saturated == 0 && released_at < 0.0) released_at = t;
    });
    const double final_current = get(core, vr_i_R1);
    std::printf("  %-15s saturation: |u| <= %.15g V (bus %g V), released at %.3g ms, largest current %.9g A "
                "(command %g A), %.9g A at 4 ms\n",
                kMethodNames[method], largest_voltage, bus, 1e3 * released_at, largest_current, command, final_current);
    CHECK(saturated_seen);
    CHECK(released_at > 0.0);
    CHECK(largest_voltage <= bus * (1.0 + 1e-12));
    CHECK(largest_current <= command * (1.0 + 1e-6));
    // After the release the cancelled pole L/R reappears: x_I - R i, negative from the saturation, decays
    // with L/R = 1 ms and the current creeps up to the command from below (3.7 mA short at 4 ms).
    CHECK(final_current < command && std::fabs(final_current - command) <= 2e-3 * command);
    gimbal_core_destroy(core);
}

// The quasi-static motor in current drive: the ideal current source, limited by the bus voltage against
// the back-emf.
void quasi_static(int method) {
    const double bus = 5.0;
    const std::vector<Setting> settings = {integer(vi_motor1_drive, 1), integer(vi_motor1_model, 0),
                                           flag(vb_base_fixed, true),   real(vr_motor1_U_L, bus),
                                           real(vr_i_R1_cmd, 3.0)};  // R = 2 Ohm: 2.5 A at most at rest
    GimbalCore* core = make(settings, method);
    if (core == nullptr) return;  // unavailable (the loop tests report a refusal)
    double worst_limited = 0.0, worst_free = 0.0;
    bool saturated = true, free = true;
    double t = 0.0;
    for (int k = 0; k < 40; ++k, t += 1e-3) {
        if (k == 20) gimbal_core_set_real(core, vr_i_R1_cmd, -1.0);
        if (gimbal_core_do_step(core, t, 1e-3) != GIMBAL_OK) {
            ++check::failures;
            break;
        }
        const double i = get(core, vr_i_R1), w = get(core, vr_alpha_m_dot);
        if (k < 20) {
            saturated = saturated && get(core, vi_motor1_amplifier_saturated) == 1;
            worst_limited = std::max(worst_limited, std::fabs(i - (bus - 0.06 * w) / 2.0));
            CHECK(std::fabs(get(core, vr_amplifier1_u) - bus) <= 1e-12);
        } else {
            free = free && get(core, vi_motor1_amplifier_saturated) == 0;
            worst_free = std::max(worst_free, std::fabs(i + 1.0));
        }
    }
    std::printf("  %-15s quasi-static: bus-limited current off by %.3g A, commanded current off by %.3g A\n",
                kMethodNames[method], worst_limited, worst_free);
    CHECK(saturated && free);
    CHECK(worst_limited <= 1e-12 && worst_free == 0.0);
    gimbal_core_destroy(core);
}

// Save mid-run, continue, restore, continue: the same bits, with saturations and limiter events in between.
void snapshot_transparency(int method) {
    const std::vector<Setting> settings = {integer(vi_motor1_drive, 1), integer(vi_motor2_drive, 1),
                                           integer(vi_motor2_model, 0), real(vr_g, 9.81)};
    GimbalCore* core = make(settings, method, 20);
    if (core == nullptr) return;
    auto command = [](int k) { return 3.5 * std::sin(0.7 * k) + (k % 7 == 0 ? 2.0 : 0.0); };
    const RealVariable recorded[] = {vr_alpha, vr_beta, vr_alpha_m_dot, vr_i_R1, vr_i_R2, vr_amplifier1_u,
                                     vr_amplifier2_u, vr_amplifier1_x_I, vr_theta_b1, vr_T_E1};
    auto run = [&](int from, int to, std::vector<double>& out) {
        for (int k = from; k < to; ++k) {
            gimbal_core_set_real(core, vr_i_R1_cmd, command(k));
            gimbal_core_set_real(core, vr_i_R2_cmd, -0.5 * command(k + 3));
            if (gimbal_core_do_step(core, 1e-3 * k, 1e-3) != GIMBAL_OK) {
                ++check::failures;
                return;
            }
            for (RealVariable vr : recorded) out.push_back(get(core, vr));
            out.push_back(get(core, vi_motor1_amplifier_saturated));
            out.push_back(get(core, vi_events_total));
        }
    };
    std::vector<double> before, first, second;
    run(0, 10, before);
    std::vector<unsigned char> blob(gimbal_core_snapshot_size());
    CHECK(gimbal_core_save(core, blob.data()) == GIMBAL_OK);
    run(10, 30, first);
    CHECK(gimbal_core_restore(core, blob.data()) == GIMBAL_OK);
    run(10, 30, second);
    const bool same = first.size() == second.size() &&
                      std::memcmp(first.data(), second.data(), first.size() * sizeof(double)) == 0;
    std::printf("  %-15s FMU state: %zu values after the restore %s, %d mode changes\n", kMethodNames[method],
                first.size(), same ? "bit-identical" : "DIFFER", static_cast<int>(first.empty() ? 0 : first.back()));
    CHECK(same);
    CHECK(!first.empty() && first.back() > 0);  // the run did switch modes
    gimbal_core_destroy(core);
}

bool refused_naming(const std::vector<Setting>& settings, const std::string& name) {
    GimbalCore* core = make(settings, 4);
    if (core != nullptr) {
        gimbal_core_destroy(core);
        std::fprintf(stderr, "accepted: %s\n", name.c_str());
        return false;
    }
    const bool named = g_last_error.find(name) != std::string::npos;
    if (!named) std::fprintf(stderr, "refusal without %s: %s\n", name.c_str(), g_last_error.c_str());
    return named;
}

void refusals() {
    CHECK(refused_naming({integer(vi_motor1_drive, 1), real(vr_amplifier1_f_c, 0.0)}, "amplifier1.f_c"));
    CHECK(refused_naming({real(vr_amplifier2_f_c, -5.0)}, "amplifier2.f_c"));  // refused in voltage drive too
    CHECK(refused_naming({integer(vi_motor1_drive, 1), real(vr_amplifier1_K_p, -1.0)}, "amplifier1.K_p"));
    CHECK(refused_naming({integer(vi_motor2_drive, 1), real(vr_amplifier2_K_i, -1e-3)}, "amplifier2.K_i"));
    CHECK(refused_naming({integer(vi_motor1_drive, 1), real(vr_amplifier1_f_c, 1e308), real(vr_motor1_L, 10.0)},
                         "amplifier1.f_c"));
    CHECK(refused_naming({integer(vi_motor2_drive, 2)}, "motor2.drive"));
    // A NaN current command is refused when it is set, by name, before and after initialization.
    GimbalCore* core = gimbal_core_create(record, always, nullptr);
    g_last_error.clear();
    CHECK(gimbal_core_set_real(core, vr_i_R1_cmd, NAN) == GIMBAL_ERROR);
    CHECK(g_last_error.find("i_R1_cmd") != std::string::npos);
    gimbal_core_set_integer(core, vi_motor2_drive, 1);
    CHECK(gimbal_core_initialize(core, 0.0) == GIMBAL_OK);
    g_last_error.clear();
    const unsigned vr = vr_i_R2_cmd;
    const double value = INFINITY;
    CHECK(gimbal_core_set_reals(core, &vr, 1, &value) == GIMBAL_ERROR);
    CHECK(g_last_error.find("i_R2_cmd") != std::string::npos);
    gimbal_core_destroy(core);
}

// Voltage drive: the amplifiers' indicators (their place in switching_elements.def) are constants 1; their
// integrators' states of the continuous-time interface (kAmplifierStates on) are held at 0.
void voltage_drive_indicators() {
    GimbalCore* core = gimbal_core_create(record, always, nullptr);
    gimbal_core_use_continuous_time(core);
    gimbal_core_set_real(core, vr_u_R1, 30.0);
    CHECK(gimbal_core_initialize(core, 0.0) == GIMBAL_OK);
    double indicators[GIMBAL_EVENT_INDICATORS], states[GIMBAL_CONTINUOUS_STATES], derivatives[GIMBAL_CONTINUOUS_STATES];
    CHECK(gimbal_core_get_event_indicators(core, indicators) == GIMBAL_OK);
    CHECK(GIMBAL_EVENT_INDICATORS == kEventIndicatorCount && GIMBAL_CONTINUOUS_STATES == kMaxStateSize);
    constexpr ElementKind kAmplifier = ElementKind::amplifier_saturation;
    const int first = first_indicator_of(kAmplifier);
    CHECK(first > 0);
    for (int k = first; k < first + declaration_of(kAmplifier).instances * declaration_of(kAmplifier).guards; ++k)
        CHECK(indicators[k] == 1.0);
    CHECK(gimbal_core_get_continuous_states(core, states) == GIMBAL_OK);
    CHECK(gimbal_core_get_derivatives(core, derivatives) == GIMBAL_OK);
    for (int axis = 0; axis < kAmplifierIntegratorCount; ++axis)
        CHECK(states[kAmplifierStates + axis] == 0.0 && derivatives[kAmplifierStates + axis] == 0.0);
    CHECK(gimbal_continuous_state_vr(kAmplifierStates) == vr_amplifier1_x_I &&
          gimbal_state_derivative_vr(kAmplifierStates + 1) == vr_der_amplifier2_x_I);
    gimbal_core_destroy(core);
}

}  // namespace

int main() {
    std::printf("current-driven motor 1 (inductive, pole-zero and explicit gains), every method:\n");
    for (int method = 0; method <= 7; ++method) {
        first_order_loop(method);
        second_order_loop(method);
        saturation_and_anti_windup(method);
        quasi_static(method);
        snapshot_transparency(method);
    }
    refusals();
    voltage_drive_indicators();
    return check_report("current drive");
}
