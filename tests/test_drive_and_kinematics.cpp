// Component equations against the seed, in isolation: signs and limits that a slip would break.
#include <cmath>

#include "check.hpp"
#include "gimbal/base_kinematics.hpp"
#include "gimbal/drive_train.hpp"

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
    return check_report("drive_and_kinematics");
}
