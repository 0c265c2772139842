// Every refusal names the variable and the rule; the defaults are valid.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "check.hpp"
#include "gimbal/simulation/parameter_building.hpp"

using namespace gimbal;

namespace {

struct Values {
    double v[kRealVariableCount];
    bool flags[kBooleanVariableCount];
    int integers[kIntegerVariableCount];
    Values() {
        for (unsigned i = 0; i < kIntegerVariableCount; ++i) integers[i] = static_cast<int>(kIntegerVariables[i].start);
        for (unsigned i = 0; i < kRealVariableCount; ++i) v[i] = kRealVariables[i].start;
        for (unsigned i = 0; i < kBooleanVariableCount; ++i) flags[i] = kBooleanVariables[i].start != 0.0;
    }
};

// Sets one value away from the defaults and returns the refusal message ("" if accepted).
std::string refusal(RealVariable vr, double value) {
    Values values;
    values.v[vr] = value;
    ModelParameters params;
    std::string error;
    if (build_model_parameters(values.v, values.integers, values.flags, params, error) && validate_start_state(values.v, params, error)) return "";
    return error;
}

bool names(const std::string& message, const char* name) { return message.find(name) != std::string::npos; }

// The outcome of the defaults with some values changed: "" if accepted, else the refusal.
std::string outcome(const Values& values) {
    ModelParameters params;
    std::string error;
    if (build_model_parameters(values.v, values.integers, values.flags, params, error) &&
        validate_start_state(values.v, params, error))
        return "";
    return error;
}

// The finite min and max columns of real_variables.def.
constexpr int finite_bounds(double min, double max) {
    return (min > -std::numeric_limits<double>::infinity() ? 1 : 0) + (max < std::numeric_limits<double>::infinity() ? 1 : 0);
}
constexpr int kDeclaredRealBounds = 0
#define X(id, name, causality, variability, initial, declared_type, unit, display_unit, start, min, max, description) \
    +finite_bounds(min, max)
#include "gimbal/real_variables.def"
#undef X
    ;

// The min and max columns of the tables (modelDescription.xml's bounds) are what the validation
// enforces: just outside a bound refused (naming the variable), the bound itself accepted. A bound
// alone does not lift the rules that tie variables together: T_max = 0 needs T_din = 0.
void check_declared_bounds() {
    int bounds = 0;
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        const VariableInfo& info = kRealVariables[vr];
        const double limits[2] = {info.min, info.max};
        for (int side = 0; side < 2; ++side) {
            const double bound = limits[side];
            if (!std::isfinite(bound)) continue;
            ++bounds;
            Values at;
            at.v[vr] = bound;
            const std::string name = info.name;
            if (name.size() > 6 && name.compare(name.size() - 6, 6, ".T_max") == 0) {
                const std::string slip = name.substr(0, name.size() - 6) + ".T_din";
                for (unsigned other = 0; other < kRealVariableCount; ++other)
                    if (slip == kRealVariables[other].name) at.v[other] = 0.0;
            }
            const std::string accepted = outcome(at);
            if (!accepted.empty()) std::fprintf(stderr, "%s = %.17g (its bound) refused: %s\n", info.name, bound, accepted.c_str());
            CHECK(accepted.empty());
            Values outside;
            outside.v[vr] = std::nextafter(bound, side == 0 ? -HUGE_VAL : HUGE_VAL);
            const std::string refused = outcome(outside);
            if (!names(refused, info.name)) std::fprintf(stderr, "%s = %.17g (beyond its bound) not refused by name\n", info.name, outside.v[vr]);
            CHECK(names(refused, info.name));
        }
    }
    // Every finite min and max of real_variables.def, counted from the .def itself: none lost on the way
    // into the table the validation reads.
    CHECK(bounds > 0 && bounds == kDeclaredRealBounds);
    for (unsigned vi = 0; vi < kIntegerVariableCount; ++vi) {
        const VariableInfo& info = kIntegerVariables[vi];
        int low = 0, high = 0;
        if (info.declared_type[0] != '\0') {
            low = 1 << 30, high = -(1 << 30);
            for (const EnumerationItem& item : kEnumerationItems) {
                if (std::string(item.type) != info.declared_type) continue;
                Values at;
                at.integers[vi] = item.value;
                CHECK(outcome(at).empty());
                low = std::min(low, item.value), high = std::max(high, item.value);
            }
        } else if (std::isfinite(info.min)) {
            low = static_cast<int>(info.min);
            high = std::isfinite(info.max) ? static_cast<int>(info.max) : std::numeric_limits<int>::max();
            Values at;
            at.integers[vi] = low;
            CHECK(outcome(at).empty());
        } else {
            continue;
        }
        Values below;
        below.integers[vi] = low - 1;
        CHECK(names(outcome(below), info.name));
        if (high < std::numeric_limits<int>::max()) {
            Values above;
            above.integers[vi] = high + 1;
            CHECK(names(outcome(above), info.name));
        }
    }
}

}  // namespace

int main() {
    {
        Values values;
        ModelParameters params;
        std::string error;
        CHECK(build_model_parameters(values.v, values.integers, values.flags, params, error));
        CHECK(error.empty());
        CHECK_NEAR(params.multibody.bodies[kElevationBody].inertia(0, 1), kRealVariables[vr_body2_I_xy].start, 0.0);
        CHECK_NEAR(params.gear[1].ratio, kRealVariables[vr_gear2_N].start, 0.0);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();

    std::string m = refusal(vr_body1_m, -1.0);
    CHECK(names(m, "body1.m") && names(m, ">= 0"));
    m = refusal(vr_gear2_N, 0.0);
    CHECK(names(m, "gear2.N") && names(m, "must not be 0"));
    m = refusal(vr_gear1_k_s, -5.0);
    CHECK(names(m, "gear1.k_s"));
    m = refusal(vr_motor2_L, 0.0);
    CHECK(names(m, "motor2.L") && names(m, "> 0"));
    m = refusal(vr_motor1_R, nan);
    CHECK(names(m, "motor1.R") && names(m, "finite"));
    m = refusal(vr_solver_rtol, 2.0);
    CHECK(names(m, "solver.rtol"));
    m = refusal(vr_alpha_dot, std::numeric_limits<double>::infinity());
    CHECK(names(m, "alpha_dot"));
    // Not positive definite: a negative principal moment.
    m = refusal(vr_rotor1_I_zz, -1e-5);
    CHECK(names(m, "rotor1.I_xx") && names(m, "positive definite"));
    // Positive definite but no real body: I_zz > I_xx + I_yy.
    m = refusal(vr_body2_I_zz, 0.2);
    CHECK(names(m, "body2.I_xx") && names(m, "triangle inequality"));
    // A product of inertia large enough to break definiteness.
    m = refusal(vr_body1_I_xy, 0.2);
    CHECK(names(m, "body1.I_xx") && names(m, "positive definite"));
    m = refusal(vr_rotor1_T_din, 0.01);  // above T_max
    CHECK(names(m, "rotor1.T_din") && names(m, "T_max"));
    m = refusal(vr_rotor2_w_min, 0.0);
    CHECK(names(m, "rotor2.w_min") && names(m, "dry friction"));
    m = refusal(vr_motor1_i_L, 0.0);
    CHECK(names(m, "motor1.i_L"));
    m = refusal(vr_gear2_eta, -1e-4);
    CHECK(names(m, "gear2.eta"));
    // A damping whose relaxation rate k_s / c_s overflows (a subnormal c_s) is refused; 0, the dead zone,
    // and 1e-300 (rate 3e304) are not.
    m = refusal(vr_gear1_c_s, 1e-320);
    CHECK(names(m, "gear1.c_s") && names(m, "k_s / c_s overflows") && names(m, "dead zone"));
    CHECK(refusal(vr_gear1_c_s, 0.0).empty() && refusal(vr_gear1_c_s, 1e-300).empty());
    m = refusal(vr_i_R2, 3.5);  // default i_L of motor 2 is 3 A
    CHECK(names(m, "i_R2") && names(m, "current limit"));
    m = refusal(vr_theta_b1, 3e-4);  // default eta of gear 1 is 2e-4 rad
    CHECK(names(m, "theta_b1") && names(m, "eta"));
    CHECK(refusal(vr_theta_b1, -2e-4).empty());  // exactly at a stop is valid
    // Inputs are not parameters: any finite value is accepted here.
    CHECK(refusal(vr_u_R1, 1e9).empty());
    // "> 0" refuses 0 and the subnormal numbers below its declared min, the least normal double.
    CHECK(names(refusal(vr_motor1_R, 5e-324), "> 0") && refusal(vr_motor1_R, kAboveZero).empty());
    CHECK(names(refusal(vr_solver_rtol, 1.0), "(0, 1)") && refusal(vr_solver_rtol, kBelowOne).empty());
    check_declared_bounds();
    return check_report("parameter_validation");
}
