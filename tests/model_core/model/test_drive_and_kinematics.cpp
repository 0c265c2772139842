// Component equations against the seed, in isolation: signs and limits that a slip would break.
#include <cmath>

#include "check.hpp"
#include "gimbal/multibody/base_kinematics.hpp"
#include "gimbal/multibody/drive_train.hpp"
#include "gimbal/hybrid_system/gimbal_hybrid_system.hpp"
#include "gimbal/model/gimbal_model.hpp"

#include <Eigen/Dense>

using namespace gimbal;

int main() {
    MotorParameters motor{2.0, 1e-3, 0.05, 0.04, 4.0, 24.0};
    // (2.142 - 2.145)
    CHECK_NEAR(clamp_voltage(motor, 30.0), 24.0, 0.0);
    CHECK_NEAR(clamp_voltage(motor, -1e9), -24.0, 0.0);
    CHECK_NEAR(clamp_voltage(motor, 5.5), 5.5, 0.0);
    // (2.62): positive voltage drives the current up, back-emf of a forward-spinning rotor opposes it.
    CHECK_NEAR(armature_current_rate(motor, 10.0, 1.0, 50.0), (10.0 - 2.0 - 0.04 * 50.0) / 1e-3, 1e-9);
    CHECK(armature_current_rate(motor, 0.0, 0.0, 10.0) < 0.0);
    CHECK_NEAR(electromagnetic_torque(motor, 2.0), 0.1, 1e-15);

    GearParameters gear{50.0, 1000.0, 2.0, 0.0};
    // (2.79): a rotor ahead of N times the load winds the gear positively...
    const double deflection = gear_deflection(gear, 50.0 * 0.1 + 0.5, 0.1);
    CHECK_NEAR(deflection, 0.01, 1e-15);
    // ...and (2.77) gives a positive torque on the load (it is dragged along), -T_E/N on the rotor.
    CHECK_NEAR(gear_shaft_torque(gear, deflection, 0.2, 0.0, 0.0), 1000.0 * 0.01 + 2.0 * 0.2, 1e-12);
    CHECK_NEAR(gear_shaft_torque(gear, 0.01, 0.0, 0.004, 0.0), 1000.0 * 0.006, 1e-12);

    // (2.81): inside the gap theta_b relaxes towards theta_d; at a stop only motion back into the gap is allowed.
    GearParameters backlash_gear{50.0, 1000.0, 2.0, 1e-3};
    const double pulling_out = free_backlash_rate(backlash_gear, 2e-3, 0.0, 1e-3);  // theta_d beyond +eta
    CHECK_NEAR(pulling_out, 1000.0 / 2.0 * 1e-3, 1e-12);
    CHECK_NEAR(backlash_rate(backlash_gear, 2e-3, 0.0, 1e-3, +1), 0.0, 0.0);          // held at +eta
    CHECK_NEAR(backlash_rate(backlash_gear, 2e-3, 0.0, 1e-3, 0), pulling_out, 0.0);   // free in the gap
    CHECK(backlash_rate(backlash_gear, 0.0, -1.0, 1e-3, +1) < 0.0);                   // released back into the gap
    CHECK_NEAR(backlash_rate(backlash_gear, -2e-3, 0.0, -1e-3, -1), 0.0, 0.0);        // held at -eta
    CHECK(backlash_rate(backlash_gear, 0.0, 1.0, -1e-3, -1) > 0.0);
    // At contact the shaft torque is c_s X, so its sign is the side's: (2.77) with dtheta_b = 0.
    CHECK_NEAR(gear_shaft_torque(backlash_gear, 2e-3, 0.0, 1e-3, 0.0), 2.0 * pulling_out, 1e-12);
    // Limiter (2.63): the steady current the free circuit heads for.
    CHECK_NEAR(unlimited_steady_current(motor, 10.0, 50.0), (10.0 - 0.04 * 50.0) / 2.0, 1e-15);

    // T_outros (2.106): with body 0 held and body 2 slipping, the other torque on body 0 is what the
    // free bodies' accelerations leave unbalanced: F_0 - J_0F qdd_F, with J_FF qdd_F = F_F + T_slip_F.
    {
        Eigen::Matrix4d a = Eigen::Matrix4d::Random();
        const Mat4 mass_matrix = a * a.transpose() + 4.0 * Mat4::Identity();
        const Vec4 applied(0.3, -1.2, 0.8, 0.05);
        ModelParameters params;
        params.dry_friction[2] = DryFrictionParameters{0.2, 0.3, 0.01, 0.1};
        Modes modes;
        modes.friction[0] = FrictionMode::hold;
        modes.friction[2] = FrictionMode::slip_positive;
        const Vec4 other = other_torques(mass_matrix, applied, modes, params.dry_friction);
        const int free_bodies[3] = {1, 2, 3};
        Eigen::Matrix3d block;
        Eigen::Vector3d rhs;
        for (int r = 0; r < 3; ++r) {
            rhs[r] = applied[free_bodies[r]] - (free_bodies[r] == 2 ? 0.2 : 0.0);
            for (int c = 0; c < 3; ++c) block(r, c) = mass_matrix(free_bodies[r], free_bodies[c]);
        }
        const Eigen::Vector3d free_acceleration = block.ldlt().solve(rhs);
        double expected = applied[0];
        for (int c = 0; c < 3; ++c) expected -= mass_matrix(0, free_bodies[c]) * free_acceleration[c];
        CHECK_NEAR(other[0], expected, 1e-12);
    }
    CHECK(friction_mode_indicator(FrictionMode::hold, 1e-4) == 0);
    CHECK(friction_mode_indicator(FrictionMode::at_max_negative, 0.0) == 1);  // friction -T_max: driven +
    CHECK(friction_mode_indicator(FrictionMode::slip_negative, -1.0) == -2);
    CHECK(friction_mode_indicator(FrictionMode::none, -3.0) == -2);

    // Base kinematics: the time derivative of w0 matches a central difference of (2.13) along the arc.
    BaseMotion base;
    base.attitude = Vec3(0.3, -0.7, 1.1);
    base.attitude_rate = Vec3(0.4, 0.9, -0.6);
    base.attitude_accel = Vec3(-1.2, 0.5, 2.0);
    const double h = 1e-6;
    const Vec3 numeric = (evaluate_base_kinematics(base.advanced(h), 9.81).angular_velocity -
                          evaluate_base_kinematics(base.advanced(-h), 9.81).angular_velocity) / (2 * h);
    const Vec3 analytic = evaluate_base_kinematics(base, 9.81).angular_accel;
    CHECK((numeric - analytic).norm() < 1e-8);
    // w0 is the angular velocity of G_T_0: skew(w0) = G_T_0^T d(G_T_0)/dt.
    const Mat3 rotation_rate = (evaluate_base_kinematics(base.advanced(h), 9.81).G_T_0 -
                                evaluate_base_kinematics(base.advanced(-h), 9.81).G_T_0) / (2 * h);
    const BaseKinematics k = evaluate_base_kinematics(base, 9.81);
    const Mat3 skew = k.G_T_0.transpose() * rotation_rate;
    CHECK((Vec3(skew(2, 1), skew(0, 2), skew(1, 0)) - k.angular_velocity).norm() < 1e-8);
    // Gravity points down in G whatever the attitude.
    CHECK((k.G_T_0 * k.gravity - Vec3(0, 0, -9.81)).norm() < 1e-12);
    // The carrier's trigonometry at an integrator stage from that of the arc start: the same as the
    // library's to rounding, for offsets on both sides of the 1e-3 rad switch to the library.
    {
        const Vec3 start(0.3, -1.2, 2.9);
        const AttitudeTrig reference = attitude_trig(start);
        for (double offset : {-1e-3, -3e-4, -1e-9, 0.0, 2e-7, 5e-4, 1e-3, 1.5e-3, 0.2}) {
            const Vec3 attitude = start + Vec3(offset, -0.7 * offset, 0.3 * offset);
            const AttitudeTrig near = attitude_trig_near(reference, start, attitude);
            const AttitudeTrig exact = attitude_trig(attitude);
            CHECK_NEAR(near.pitch.sin, exact.pitch.sin, 4e-16);
            CHECK_NEAR(near.pitch.cos, exact.pitch.cos, 4e-16);
            CHECK_NEAR(near.yaw.sin, exact.yaw.sin, 4e-16);
            CHECK_NEAR(near.yaw.cos, exact.yaw.cos, 4e-16);
            CHECK_NEAR(near.roll.sin, exact.roll.sin, 4e-16);
            CHECK_NEAR(near.roll.cos, exact.roll.cos, 4e-16);
        }
    }
    return check_report("drive_and_kinematics");
}
