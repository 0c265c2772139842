// Prescribed motion of the carrier (body 0) and the kinematic quantities the dynamics need from it.
#pragma once

#include <Eigen/Core>

namespace gimbal {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

Mat3 rotation_x(double angle);
Mat3 rotation_y(double angle);
Mat3 rotation_z(double angle);

// Base motion as the master gives it at one instant (the base.* inputs, docs/physics.md section 2).
struct BaseMotion {
    Vec3 attitude = Vec3::Zero();        // delta (pitch), psi (yaw), gamma (roll)
    Vec3 attitude_rate = Vec3::Zero();
    Vec3 attitude_accel = Vec3::Zero();
    Vec3 velocity_a = Vec3::Zero();      // point a, G coordinates
    Vec3 acceleration_a = Vec3::Zero();  // point a, G coordinates

    // The state reached after `elapsed` seconds of constant attitude and point-a acceleration:
    // the within-step semantics of docs/physics.md section 7.2.
    BaseMotion advanced(double elapsed) const;
};

// What the rigid-body dynamics needs from the base, all in frame 0 coordinates.
struct BaseKinematics {
    Mat3 G_T_0;               // maps frame 0 coordinates to G (2.11)
    Vec3 angular_velocity;    // w0 (2.13)
    Vec3 angular_accel;       // time derivative of w0
    Vec3 accel_a;             // acceleration of point a
    Vec3 gravity;             // gravitational acceleration, -g z_G
};

// Derivative of (2.13) is taken analytically so that w0, its derivative and G_T_0 stay consistent.
BaseKinematics evaluate_base_kinematics(const BaseMotion& base, double gravity);

struct SinCos {
    double sin = 0.0, cos = 1.0;
};
// The trigonometry of the attitude angles (delta, psi, gamma), which is all the kinematics need of them.
struct AttitudeTrig {
    SinCos pitch, yaw, roll;
};
AttitudeTrig attitude_trig(const Vec3& attitude);
// The same for an attitude close to one whose trigonometry is known: offsets up to 1e-3 rad by the
// addition theorem (exact to rounding), larger ones by the library.
AttitudeTrig attitude_trig_near(const AttitudeTrig& reference, const Vec3& reference_attitude, const Vec3& attitude);
BaseKinematics evaluate_base_kinematics(const BaseMotion& base, const AttitudeTrig& trig, double gravity);

}  // namespace gimbal
