#include "gimbal/simulation/parameter_building.hpp"

#include "gimbal/integrators/integrator.hpp"
#include "gimbal/model/variable_groups.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstring>
#include <sstream>

namespace gimbal {
namespace {

struct Checker {
    const double (&values)[kRealVariableCount];
    std::string& error;

    double get(RealVariable vr) const { return values[vr]; }

    bool fail(const std::string& message) {
        error = message;
        return false;
    }

    bool require(RealVariable vr, bool ok, const char* rule) {
        if (ok) return true;
        std::ostringstream s;
        s << kRealVariables[vr].name << " = " << values[vr] << " is invalid: " << rule;
        return fail(s.str());
    }
    // The variable's own min and max of the .def table (modelDescription.xml's, inclusive). "> 0" is
    // min = kAboveZero, "< 1" max = kBelowOne: subnormal numbers are refused too.
    bool within_declared_bounds(RealVariable vr) {
        const VariableInfo& v = kRealVariables[vr];
        const double x = values[vr];
        if (x >= v.min && x <= v.max) return true;
        std::ostringstream rule;
        if (v.min == kAboveZero && v.max == kBelowOne) {
            rule << "it must lie in (0, 1) (and not be subnormal)";
        } else if (v.min == kAboveZero) {
            rule << "it must be > 0 (and not subnormal)";
        } else if (x < v.min) {
            rule << "it must be >= " << v.min;
        } else {
            rule << "it must be <= " << v.max;
        }
        return require(vr, false, rule.str().c_str());
    }
};

// The same for an Integer parameter (its bounds are whole numbers).
bool integer_within_declared_bounds(IntegerVariable vi, int value, std::string& error) {
    const VariableInfo& v = kIntegerVariables[vi];
    if (value >= v.min && value <= v.max) return true;
    std::ostringstream s;
    s << v.name << " = " << value << " is invalid: it must ";
    if (v.max == kNoMax) s << "be >= " << v.min;
    else if (v.min == kNoMin) s << "be <= " << v.max;
    else s << "lie in [" << v.min << ", " << v.max << "]";
    error = s.str();
    return false;
}

// The Enumeration items of modelDescription.xml (enumeration_types.def) are the core's enum values
// and exactly the values accepted below.
namespace enumeration {
#define TYPE(id, description)
#define ITEM(type, item, value, description) constexpr int type##_##item = value;
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE

struct Item {
    const char* type;
    const char* name;
    int value;
};
constexpr Item kItems[] = {
#define TYPE(id, description)
#define ITEM(type, item, value, description) {#type, #item, value},
#include "gimbal/enumeration_types.def"
#undef ITEM
#undef TYPE
};

// The items of `type` are first, first + 1, ..., last, each once.
constexpr bool items_are(const char* type, int first, int last) {
    int count = 0;
    for (const Item& item : kItems) {
        if (!variable_table::joins(item.type, type, "")) continue;
        ++count;
        if (item.value < first || item.value > last) return false;
        for (const Item& other : kItems)
            if (&other != &item && variable_table::joins(other.type, type, "") && other.value == item.value) return false;
    }
    return count == last - first + 1;
}

static_assert(GearModel_rigid == static_cast<int>(GearModel::rigid) &&
                  GearModel_compliant == static_cast<int>(GearModel::compliant) &&
                  GearModel_backlash == static_cast<int>(GearModel::backlash) && items_are("GearModel", 0, 2),
              "GearModel items: rigid, compliant, backlash, and the validation accepts 0..2");
static_assert(MotorModel_quasi_static == static_cast<int>(MotorModel::quasi_static) &&
                  MotorModel_inductive == static_cast<int>(MotorModel::inductive) && items_are("MotorModel", 0, 1),
              "MotorModel items: quasi_static, inductive, and the validation accepts 0..1");
static_assert(DriveMode_voltage == static_cast<int>(DriveMode::voltage) &&
                  DriveMode_current == static_cast<int>(DriveMode::current) && items_are("DriveMode", 0, 1),
              "DriveMode items: voltage, current, and the validation accepts 0..1");
static_assert(GearStart_in_mesh_unless_given == static_cast<int>(GearStart::in_mesh_unless_given) &&
                  GearStart_in_mesh == static_cast<int>(GearStart::in_mesh) &&
                  GearStart_as_given == static_cast<int>(GearStart::as_given) &&
                  items_are("GearStart", 0, 2),
              "GearStart items: in_mesh_unless_given, in_mesh, as_given (GimbalInstance::load_start_state), and "
              "the validation accepts 0..2");
static_assert(IntegrationMethod_cvode_bdf == static_cast<int>(IntegrationMethod::bdf_analytic_jacobian) &&
                  IntegrationMethod_cvode_bdf_dq == static_cast<int>(IntegrationMethod::bdf_difference_jacobian) &&
                  IntegrationMethod_cvode_adams == static_cast<int>(IntegrationMethod::adams) &&
                  IntegrationMethod_arkode_erk == static_cast<int>(IntegrationMethod::explicit_runge_kutta) &&
                  IntegrationMethod_automatic == static_cast<int>(IntegrationMethod::automatic) &&
                  IntegrationMethod_dormand_prince == static_cast<int>(IntegrationMethod::dormand_prince) &&
                  IntegrationMethod_rodas4 == static_cast<int>(IntegrationMethod::rosenbrock) &&
                  IntegrationMethod_real_time == static_cast<int>(IntegrationMethod::real_time) &&
                  items_are("IntegrationMethod", 0, kIntegrationMethodCount - 1),
              "IntegrationMethod items are the core's methods, and the validation accepts 0..kIntegrationMethodCount-1");
static_assert(variable_table::joins(variable_table::kInteger[vi_gear1_model].declared_type, "GearModel", "") &&
                  variable_table::joins(variable_table::kInteger[vi_gear2_model].declared_type, "GearModel", "") &&
                  variable_table::joins(variable_table::kInteger[vi_motor1_model].declared_type, "MotorModel", "") &&
                  variable_table::joins(variable_table::kInteger[vi_motor2_model].declared_type, "MotorModel", "") &&
                  variable_table::joins(variable_table::kInteger[vi_solver_method].declared_type, "IntegrationMethod", "") &&
                  variable_table::joins(variable_table::kInteger[vi_gear1_start].declared_type, "GearStart", "") &&
                  variable_table::joins(variable_table::kInteger[vi_gear2_start].declared_type, "GearStart", "") &&
                  variable_table::joins(variable_table::kInteger[vi_motor1_drive].declared_type, "DriveMode", "") &&
                  variable_table::joins(variable_table::kInteger[vi_motor2_drive].declared_type, "DriveMode", ""),
              "the structural selectors are declared with the Enumeration types they are validated against");

// An Enumeration-typed parameter takes exactly its type's items; the refusal lists them (the start
// value marked as the default), so a new item needs no new message.
bool is_item(const char* type, int value) {
    for (const Item& item : kItems)
        if (variable_table::joins(item.type, type, "") && item.value == value) return true;
    return false;
}

bool within_items(IntegerVariable vi, int value, std::string& error) {
    const VariableInfo& v = kIntegerVariables[vi];
    if (is_item(v.declared_type, value)) return true;
    std::ostringstream s;
    s << v.name << " = " << value << " is invalid: it must be an item of " << v.declared_type << ":";
    const char* separator = " ";
    for (const Item& item : kItems) {
        if (!variable_table::joins(item.type, v.declared_type, "")) continue;
        s << separator << item.value << " (" << item.name
          << (item.value == static_cast<int>(v.start) ? ", the default)" : ")");
        separator = ", ";
    }
    error = s.str();
    return false;
}
}  // namespace enumeration

bool build_inertia(Checker& check, const BodyParameterVariables& body, Mat3& inertia) {
    const InertiaVariables& i = body.inertia;
    const double xx = check.get(i.xx), yy = check.get(i.yy), zz = check.get(i.zz), xy = check.get(i.xy),
                 xz = check.get(i.xz), yz = check.get(i.yz);
    inertia << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(inertia, Eigen::EigenvaluesOnly);
    const Vec3 principal = solver.eigenvalues();  // ascending
    std::ostringstream s;
    s << body.prefix << ".I_xx .. " << body.prefix << ".I_yz";
    if (principal[0] <= 0.0) {
        s << " is invalid: the inertia tensor must be positive definite (principal moments " << principal.transpose()
          << ")";
        return check.fail(s.str());
    }
    // Triangle inequality of a real mass distribution; a flat body sits exactly on it.
    if (principal[0] + principal[1] < principal[2] * (1.0 - 1e-12)) {
        s << " is invalid: the principal moments " << principal.transpose()
          << " violate the triangle inequality I1 + I2 >= I3";
        return check.fail(s.str());
    }
    return true;
}

// Rules of one variable alone: finite, and within its declared bounds. Only the rules that tie
// variables together are written out below.
bool check_single_variable_rules(Checker& check, const int (&integers)[kIntegerVariableCount]) {
    for (unsigned vr = 0; vr < kRealVariableCount; ++vr) {
        if (kRealVariables[vr].causality != Causality::parameter) continue;
        if (!check.require(static_cast<RealVariable>(vr), std::isfinite(check.values[vr]), "it must be finite") ||
            !check.within_declared_bounds(static_cast<RealVariable>(vr)))
            return false;
    }
    for (unsigned vi = 0; vi < kIntegerVariableCount; ++vi) {
        if (kIntegerVariables[vi].causality != Causality::parameter) continue;
        const IntegerVariable variable = static_cast<IntegerVariable>(vi);
        const bool enumeration_typed = kIntegerVariables[vi].declared_type[0] != '\0';
        if (enumeration_typed ? !enumeration::within_items(variable, integers[vi], check.error)
                              : !integer_within_declared_bounds(variable, integers[vi], check.error))
            return false;
    }
    return true;
}

// The dry friction element's parameters of one body (switching_elements/dry_friction.hpp).
bool read_dry_friction(Checker& check, const DryFrictionVariables& vars, DryFrictionParameters& friction) {
    const double (&values)[kRealVariableCount] = check.values;
    const RealVariable slip = vars.slip_torque, breakaway = vars.breakaway_torque, stick_speed = vars.stick_speed,
                       damping = vars.damping_factor;
    if (!check.require(slip, values[slip] <= values[breakaway], "T_din must not exceed T_max") ||
        (values[breakaway] > 0.0 && !check.require(stick_speed, values[stick_speed] > 0.0,
                                                   "it must be > 0 when the body has dry friction (T_max > 0)")))
        return false;
    friction = DryFrictionParameters{values[slip], values[breakaway], values[stick_speed], values[damping]};
    return true;
}

// The four bodies (multibody/) with their viscous and dry friction, the base point and gravity.
bool read_bodies(Checker& check, ModelParameters& params) {
    const double (&values)[kRealVariableCount] = check.values;
    for (int k = 0; k < 4; ++k) {
        const BodyParameterVariables& vars = kBodyParameters[k];
        RigidBody& body = params.multibody.bodies[k];
        if (!build_inertia(check, vars, body.inertia)) return false;
        body.mass = values[vars.mass];
        body.centre_of_mass = read_vector(values, vars.centre_of_mass);
        params.viscous_friction[k] = values[vars.viscous_friction];
        if (!read_dry_friction(check, vars.dry_friction, params.dry_friction[k])) return false;
    }
    params.multibody.d_ab = read_vector(values, kBasePointB);
    params.multibody.gravity = values[vr_g];
    prepare_multibody(params.multibody);
    return true;
}

// The motors (current_limiter.hpp, voltage_clamp.hpp) and the gears (gear_backlash.hpp).
bool read_drive_train(Checker& check, ModelParameters& params) {
    const double (&values)[kRealVariableCount] = check.values;
    struct MotorVariables { RealVariable R, L, k_torque, k_emf, i_L, U_L; };
    const MotorVariables motors[2] = {
        {vr_motor1_R, vr_motor1_L, vr_motor1_k_torque, vr_motor1_k_emf, vr_motor1_i_L, vr_motor1_U_L},
        {vr_motor2_R, vr_motor2_L, vr_motor2_k_torque, vr_motor2_k_emf, vr_motor2_i_L, vr_motor2_U_L},
    };
    struct GearVariables { RealVariable N, k_s, c_s, eta; };
    const GearVariables gears[2] = {{vr_gear1_N, vr_gear1_k_s, vr_gear1_c_s, vr_gear1_eta},
                                    {vr_gear2_N, vr_gear2_k_s, vr_gear2_c_s, vr_gear2_eta}};
    for (int j = 0; j < 2; ++j) {
        const MotorVariables& m = motors[j];
        params.motor[j] = MotorParameters{values[m.R], values[m.L], values[m.k_torque], values[m.k_emf],
                                          values[m.i_L], values[m.U_L]};
        const GearVariables& g = gears[j];
        if (!check.require(g.N, values[g.N] != 0.0, "a gear ratio must not be 0")) return false;
        // The free play relaxes at k_s / c_s (docs/physics.md 4.2); a damping so small that the rate
        // overflows is no damping: 0 is the pure dead zone.
        if (!check.require(g.c_s, values[g.c_s] == 0.0 || std::isfinite(values[g.k_s] / values[g.c_s]),
                           "k_s / c_s overflows: set c_s = 0 for the pure dead zone, or a c_s that is no "
                           "smaller than k_s * 1e-300"))
            return false;
        params.gear[j] = GearParameters{values[g.N], values[g.k_s], values[g.c_s], values[g.eta]};
    }
    return true;
}

// The servo amplifiers of current drive (switching_elements/amplifier_saturation.hpp). f_c > 0 and
// K_p, K_i >= 0 are the variables' own bounds (checked whatever the drive, so that a bad value is refused
// when it is set); a gain left at 0 is derived from the bandwidth by pole-zero cancellation.
bool read_amplifiers(Checker& check, const bool (&flags)[kBooleanVariableCount], ModelParameters& params) {
    const double (&values)[kRealVariableCount] = check.values;
    struct AmplifierVariables { RealVariable f_c, K_p, K_i; BooleanVariable feedforward; };
    const AmplifierVariables amplifiers[2] = {
        {vr_amplifier1_f_c, vr_amplifier1_K_p, vr_amplifier1_K_i, vb_amplifier1_back_emf_feedforward},
        {vr_amplifier2_f_c, vr_amplifier2_K_p, vr_amplifier2_K_i, vb_amplifier2_back_emf_feedforward},
    };
    for (int j = 0; j < 2; ++j) {
        const AmplifierVariables& a = amplifiers[j];
        AmplifierParameters& amplifier = params.amplifier[j];
        amplifier.bandwidth = values[a.f_c];
        amplifier.proportional_gain = values[a.K_p] > 0.0 ? values[a.K_p]
                                                          : cancelling_proportional_gain(params.motor[j], values[a.f_c]);
        amplifier.integral_gain = values[a.K_i] > 0.0 ? values[a.K_i]
                                                      : cancelling_integral_gain(params.motor[j], values[a.f_c]);
        amplifier.back_emf_feedforward = flags[a.feedforward];
        if (!check.require(a.f_c, std::isfinite(amplifier.proportional_gain) && std::isfinite(amplifier.integral_gain),
                           "the gains derived from it (2*pi*f_c*L, 2*pi*f_c*R) overflow"))
            return false;
    }
    return true;
}

// The cable restraints and the cogging (multibody/disturbance_torques.hpp). Their bounds (k, c,
// T_cogging >= 0, cogging_periods >= 1) were checked with the other single-variable rules.
void read_disturbances(const double (&values)[kRealVariableCount], const int (&integers)[kIntegerVariableCount],
                       DisturbanceParameters& disturbances) {
    struct CableVariables { RealVariable k, c, angle_0; };
    const CableVariables cables[2] = {{vr_cable1_k, vr_cable1_c, vr_cable1_angle_0},
                                      {vr_cable2_k, vr_cable2_c, vr_cable2_angle_0}};
    struct CoggingVariables { RealVariable amplitude; IntegerVariable periods; RealVariable phase; };
    const CoggingVariables coggings[2] = {{vr_motor1_T_cogging, vi_motor1_cogging_periods, vr_motor1_cogging_phase},
                                          {vr_motor2_T_cogging, vi_motor2_cogging_periods, vr_motor2_cogging_phase}};
    for (int j = 0; j < 2; ++j) {
        const CableVariables& c = cables[j];
        disturbances.cable[j] = CableRestraint{values[c.k], values[c.c], values[c.angle_0]};
        const CoggingVariables& g = coggings[j];
        disturbances.cogging[j] = Cogging{values[g.amplitude], integers[g.periods], values[g.phase]};
    }
}

// The axis end stops (switching_elements/axis_stop.hpp), one per AXIS_STOP row of switching_elements.def,
// each switched on by its ELEMENT row's Boolean. e in [0, 1] and w_rest > 0 are the variables' own bounds;
// the order of the stops is checked whether or not the stop is on, so that a value set for it is refused
// when it is set, not when the stop is switched on later.
bool read_axis_stops(Checker& check, const bool (&flags)[kBooleanVariableCount],
                     AxisStopParameters (&stops)[kAxisStopCount]) {
    for (int k = 0; k < kAxisStopCount; ++k) {
        const AxisStopDeclaration& declared = kAxisStops[k];
        const char* element_switch = declaration_of(declared.element).element_switch;
        AxisStopParameters& stop = stops[k];
        stop.present = false;
        for (unsigned vb = 0; vb < kBooleanVariableCount; ++vb)
            if (std::strcmp(kBooleanVariables[vb].name, element_switch) == 0) stop.present = flags[vb];
        stop.lower = check.get(declared.lower);
        stop.upper = check.get(declared.upper);
        stop.restitution = check.get(declared.restitution);
        stop.rest_rate = check.get(declared.rest_rate);
        const std::string rule = std::string("it must be below ") + kRealVariables[declared.upper].name;
        if (!check.require(declared.lower, stop.lower < stop.upper, rule.c_str())) return false;
    }
    return true;
}

// solver.*: the method (its range checked from the table; here: one this binary has), its step limit and
// substeps.
bool read_solver(const int (&integers)[kIntegerVariableCount], ModelParameters& params, std::string& error) {
    params.max_steps = integers[vi_solver_max_steps];
    if (!kSundialsAvailable && is_sundials_method(static_cast<IntegrationMethod>(integers[vi_solver_method]))) {
        error = "solver.method = " + std::to_string(integers[vi_solver_method]) +
                " is not available in this binary: it was built without SUNDIALS (as the FMU's win64 binary and "
                "builds from its sources/ are), and methods 0-3 are SUNDIALS' CVODE and ARKODE; use 4 (automatic: "
                "Dormand-Prince 5(4), RODAS4 while stiff; the default), 5 (Dormand-Prince 5(4) only), 6 (RODAS4 only) "
                "or 7 (real time)";
        return false;
    }
    params.method = integers[vi_solver_method];
    params.substeps = integers[vi_solver_substeps];
    return true;
}

// The structural selectors (docs/physics.md section 6).
// Their values were checked against their Enumeration items with the other single-variable rules.
void read_fidelity(const int (&integers)[kIntegerVariableCount], const bool (&flags)[kBooleanVariableCount],
                   ModelParameters& params) {
    const IntegerVariable gear_models[2] = {vi_gear1_model, vi_gear2_model};
    const IntegerVariable motor_models[2] = {vi_motor1_model, vi_motor2_model};
    const IntegerVariable drives[2] = {vi_motor1_drive, vi_motor2_drive};
    for (int j = 0; j < 2; ++j) {
        const int gear_model = integers[gear_models[j]], motor_model = integers[motor_models[j]];
        params.fidelity.gear[j] = static_cast<GearModel>(gear_model);
        params.fidelity.motor[j] = static_cast<MotorModel>(motor_model);
        params.fidelity.drive[j] = static_cast<DriveMode>(integers[drives[j]]);
    }
    params.fidelity.dry_friction = flags[vb_dry_friction];
    params.fidelity.fixed_base = flags[vb_base_fixed];
}

}  // namespace

bool build_model_parameters(const double (&values)[kRealVariableCount], const int (&integers)[kIntegerVariableCount],
                            const bool (&flags)[kBooleanVariableCount], ModelParameters& params, std::string& error) {
    Checker check{values, error};
    if (!check_single_variable_rules(check, integers) || !read_bodies(check, params)) return false;
    params.energy_accounting = flags[vb_energy_accounting];
    if (!read_drive_train(check, params) || !read_amplifiers(check, flags, params) ||
        !read_solver(integers, params, error))
        return false;
    read_disturbances(values, integers, params.disturbances);
    if (!read_axis_stops(check, flags, params.axis_stop)) return false;
    read_fidelity(integers, flags, params);
    // Checked against its Enumeration items with the other single-variable rules.
    params.gear_start[0] = static_cast<GearStart>(integers[vi_gear1_start]);
    params.gear_start[1] = static_cast<GearStart>(integers[vi_gear2_start]);
    params.finalize();
    params.relative_tolerance = values[vr_solver_rtol];
    params.absolute_tolerance = values[vr_solver_atol];
    return true;
}

bool validate_start_state(const double (&values)[kRealVariableCount], const ModelParameters& params, std::string& error) {
    Checker check{values, error};
    for (RealVariable vr : kStartState)
        if (!check.require(vr, std::isfinite(values[vr]), "a start value must be finite")) return false;
    const RealVariable currents[2] = {vr_i_R1, vr_i_R2}, backlash[2] = {vr_theta_b1, vr_theta_b2};
    for (int j = 0; j < 2; ++j) {
        // States a reduced fidelity removed are derived, and their start values are not used.
        if (params.layout.current_slot[j] >= 0 &&
            !check.require(currents[j], std::fabs(values[currents[j]]) <= params.motor[j].current_limit,
                           "a start current must not exceed the current limit i_L"))
            return false;
        if (params.layout.backlash_slot[j] >= 0 &&
            !check.require(backlash[j], std::fabs(values[backlash[j]]) <= params.gear[j].half_backlash,
                           "a start backlash state must lie within +-eta"))
            return false;
    }
    for (int k = 0; k < kAxisStopCount; ++k) {
        const AxisStopParameters& stop = params.axis_stop[k];
        const AxisStopDeclaration& declared = kAxisStops[k];
        const RealVariable angle = kStartState[kAngles + declared.coordinate];
        const std::string rule = "the start value must lie within the " + axis_stop_name(k) + "s, [" +
                                 kRealVariables[declared.lower].name + ", " + kRealVariables[declared.upper].name + "]";
        if (stop.present &&
            !check.require(angle, values[angle] >= stop.lower && values[angle] <= stop.upper, rule.c_str()))
            return false;
    }
    return true;
}

}  // namespace gimbal
