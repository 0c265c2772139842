// The Jacobian the implicit methods use against central differences of the right-hand side, for every
// fidelity and every mode, at random states with a moving carrier, gravity and products of inertia;
// each case once without and once with the disturbance elements (cable restraints, cogging) on, and
// once in voltage drive and once in current drive (the amplifiers' integrators, free or saturated).
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "check.hpp"
#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/simulation/parameter_building.hpp"

#include <Eigen/Dense>

using namespace gimbal;

namespace {

// The elevation stop's slot among the axis stops (switching_elements.def).
constexpr int kElevationStop = axis_stop_of(ElementKind::elevation_stop);

struct Values {
    double reals[kRealVariableCount];
    int integers[kIntegerVariableCount];
    bool flags[kBooleanVariableCount];
    Values() {
        for (unsigned vr = 0; vr < kRealVariableCount; ++vr) reals[vr] = kRealVariables[vr].start;
        for (unsigned vr = 0; vr < kIntegerVariableCount; ++vr) integers[vr] = static_cast<int>(kIntegerVariables[vr].start);
        for (unsigned vr = 0; vr < kBooleanVariableCount; ++vr) flags[vr] = kBooleanVariables[vr].start != 0.0;
    }
};

constexpr FrictionMode kFrictionModes[5] = {FrictionMode::slip_positive, FrictionMode::slip_negative, FrictionMode::hold,
                                            FrictionMode::at_max_positive, FrictionMode::at_max_negative};

int checked_cases = 0;

void check_case(const ModelParameters& params, const Modes& modes, std::mt19937& random, const std::string& label) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    StepInputs inputs;
    for (int axis = 0; axis < 2; ++axis) {
        inputs.commanded_voltage[axis] = 10.0 * unit(random);
        inputs.voltage[axis] = clamp_voltage(params.motor[axis], inputs.commanded_voltage[axis]);
        if (params.fidelity.drive[axis] == DriveMode::current) {
            inputs.commanded_voltage[axis] = inputs.voltage[axis] = 0.0;
            inputs.commanded_current[axis] = inputs.current_command[axis] = 2.0 * unit(random);
        }
    }
    if (!params.fidelity.fixed_base) {
        inputs.base.attitude = Vec3(0.2 * unit(random), 0.3 * unit(random), 0.2 * unit(random));
        inputs.base.attitude_rate = Vec3(unit(random), unit(random), unit(random));
        inputs.base.attitude_accel = Vec3(3 * unit(random), 3 * unit(random), 3 * unit(random));
        inputs.base.acceleration_a = Vec3(2 * unit(random), 2 * unit(random), 2 * unit(random));
    }
    const double time = 0.0;
    const BaseKinematics base = base_kinematics_at(params, inputs, time);
    const StateLayout& layout = params.layout;
    const int n = layout.size;
    double state[kMaxStateSize];
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        state[layout.angle_slot[body]] = unit(random);
        state[layout.rate_slot[body]] = 2.0 * unit(random);
    }
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) state[layout.current_slot[axis]] = 2.0 * unit(random);
        if (layout.amplifier_slot[axis] >= 0) state[layout.amplifier_slot[axis]] = 10.0 * unit(random);
        if (layout.backlash_slot[axis] >= 0)
            state[layout.backlash_slot[axis]] = modes.gear_contact[axis] != 0
                                                    ? modes.gear_contact[axis] * params.gear[axis].half_backlash
                                                    : 0.5 * params.gear[axis].half_backlash * unit(random);
    }
    Dynamics dynamics;
    evaluate_dynamics(params, inputs, base, time, state, modes, dynamics);
    Eigen::MatrixXd analytic(n, n);
    evaluate_jacobian(params, modes, base, dynamics, analytic.data());

    Eigen::MatrixXd differences(n, n), rounding(n, n);
    Eigen::VectorXd plus(n), minus(n);
    for (int j = 0; j < n; ++j) {
        const double scale = j == layout.backlash_slot[0] || j == layout.backlash_slot[1] ? 1e-4 : 1.0;
        const double step = 1e-6 * std::max(scale, std::fabs(state[j]));
        double shifted[kMaxStateSize];
        std::copy(state, state + n, shifted);
        shifted[j] = state[j] + step;
        evaluate_state_derivative(params, inputs, modes, base, time, shifted, plus.data());
        shifted[j] = state[j] - step;
        evaluate_state_derivative(params, inputs, modes, base, time, shifted, minus.data());
        differences.col(j) = (plus - minus) / (2.0 * step);
        // What rounding of f alone contributes to a central difference.
        rounding.col(j) = 50.0 * std::numeric_limits<double>::epsilon() * plus.cwiseAbs().cwiseMax(minus.cwiseAbs()) / step;
    }
    ++checked_cases;
    for (int i = 0; i < n; ++i) {
        const double row_scale = differences.row(i).cwiseAbs().maxCoeff();
        for (int j = 0; j < n; ++j) {
            const double error = std::fabs(analytic(i, j) - differences(i, j));
            if (error > 1e-5 * row_scale + rounding(i, j) + 1e-12) {
                std::fprintf(stderr, "%s: d(dx/dt)[%d]/dx[%d] analytic %.10g, central differences %.10g\n", label.c_str(),
                             i, j, analytic(i, j), differences(i, j));
                ++check::failures;
            }
        }
    }
}

}  // namespace

int main() {
    std::mt19937 voltage_random(20261122);
    // Current drive draws from its own generator: the voltage-drive cases are the ones checked before it existed.
    std::mt19937 current_random(20261128);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int gear_model = 0; gear_model <= 2; ++gear_model) {
        for (int motor_model = 0; motor_model <= 1; ++motor_model) {
            for (int friction = 0; friction <= 1; ++friction) {
                for (int fixed_base = 0; fixed_base <= 1; ++fixed_base) {
                  for (int disturbed = 0; disturbed <= 1; ++disturbed) {
                   for (int drive = 0; drive <= 1; ++drive) {
                    Values values;
                    // Current drive: both motors, motor 2 without back-emf feed-forward in the cases with friction.
                    values.integers[vi_motor1_drive] = values.integers[vi_motor2_drive] = drive;
                    values.flags[vb_amplifier2_back_emf_feedforward] = friction == 0;
                    values.integers[vi_gear1_model] = gear_model;
                    values.integers[vi_gear2_model] = gear_model == 0 ? 2 : gear_model;  // mixed fidelities too
                    values.integers[vi_motor1_model] = motor_model;
                    values.integers[vi_motor2_model] = 1 - motor_model;
                    values.flags[vb_dry_friction] = friction != 0;
                    values.flags[vb_base_fixed] = fixed_base != 0;
                    // The elevation end stop: present in every case, the payload resting on it in one
                    // repeat of three (on the stop of the contact's side), free in the others.
                    values.flags[vb_elevation_stop] = true;
                    // Products of inertia and centres of mass off the axes: every rigid-body term present.
                    values.reals[vr_body2_I_xy] = 0.002, values.reals[vr_body2_I_xz] = -0.003, values.reals[vr_body2_I_yz] = 0.001;
                    values.reals[vr_body2_d_bd_1] = 0.01, values.reals[vr_body2_d_bd_2] = 0.02, values.reals[vr_body2_d_bd_3] = -0.03;
                    // Rotors off their axis of symmetry on a moving base; axisymmetric ones (whose angle
                    // the Jacobian then skips) on the fixed base.
                    if (fixed_base == 0) values.reals[vr_rotor1_I_xy] = 1e-6, values.reals[vr_rotor2_d_bf_2] = 0.001;
                    if (disturbed != 0) {
                        // Both cables and both cogging torques, in every fidelity: a rigid axis's
                        // cogging acts through q_m = N q_l, its slope reflected with N^2.
                        values.reals[vr_cable1_k] = 3.0, values.reals[vr_cable1_c] = 0.02, values.reals[vr_cable1_angle_0] = 0.1;
                        values.reals[vr_cable2_k] = 1.5, values.reals[vr_cable2_c] = 0.01, values.reals[vr_cable2_angle_0] = -0.2;
                        values.reals[vr_motor1_T_cogging] = 0.004, values.reals[vr_motor1_cogging_phase] = 0.3;
                        values.reals[vr_motor2_T_cogging] = 0.003, values.reals[vr_motor2_cogging_phase] = -1.1;
                        values.integers[vi_motor1_cogging_periods] = 24, values.integers[vi_motor2_cogging_periods] = 18;
                    }
                    ModelParameters params;
                    std::string error;
                    if (!build_model_parameters(values.reals, values.integers, values.flags, params, error)) {
                        std::fprintf(stderr, "parameters refused: %s\n", error.c_str());
                        ++check::failures;
                        continue;
                    }
                    if ((disturbed != 0) != params.disturbances.active) {
                        std::fprintf(stderr, "the disturbance elements are %s\n", disturbed ? "off" : "on");
                        ++check::failures;
                    }
                    for (int contact = -1; contact <= 1; ++contact) {
                        for (int limited = -1; limited <= 1; ++limited) {
                            for (int repeat = 0; repeat < 3; ++repeat) {
                                Modes modes;
                                for (int axis = 0; axis < 2; ++axis) {
                                    if (params.layout.backlash_slot[axis] >= 0 && params.gear[axis].half_backlash > 0.0)
                                        modes.gear_contact[axis] = axis == 0 ? contact : -contact;
                                    modes.motor_limited[axis] = axis == 0 ? limited : 0;
                                }
                                for (int body = 0; body < 4; ++body)
                                    if (params.coordinate_friction[body].present())
                                        modes.friction[body] = kFrictionModes[(repeat + body + contact + 1) % 5];
                                modes.axis_stop[kElevationStop] = repeat == 1 ? contact : 0;
                                if (drive != 0)
                                    for (int axis = 0; axis < 2; ++axis)
                                        modes.amplifier_saturated[axis] = axis == 0 ? repeat - 1 : (repeat + contact + 3) % 3 - 1;
                                const std::string label = "gear model " + std::to_string(gear_model) + ", motor model " +
                                                          std::to_string(motor_model) + ", friction " +
                                                          std::to_string(friction) + ", fixed base " +
                                                          std::to_string(fixed_base) + ", disturbances " +
                                                          std::to_string(disturbed) + ", contact " + std::to_string(contact) +
                                                          ", limited " + std::to_string(limited) + ", elevation stop " +
                                                          std::to_string(modes.axis_stop[kElevationStop]) + ", drive " +
                                                          std::to_string(drive) + ", amplifiers " +
                                                          std::to_string(modes.amplifier_saturated[0]) + " " +
                                                          std::to_string(modes.amplifier_saturated[1]);
                                check_case(params, modes, drive != 0 ? current_random : voltage_random, label);
                            }
                        }
                    }
                   }
                  }
                }
            }
        }
    }
    std::printf("%d cases\n", checked_cases);
    return check_report("jacobian");
}
