// Mass matrix J(q) and bias f(q, qd, base motion) of the four gimbal bodies (MODEL.md section 2).
//
// Derived by projecting Newton-Euler equations on the partial velocities (Kane's method), which
// equals Lagrange's equations for the energies of MODEL.md; tests/symbolic checks that claim.
#pragma once

#include <Eigen/Core>

#include "gimbal/base_kinematics.hpp"

namespace gimbal {

using Vec4 = Eigen::Matrix<double, 4, 1>;
using Mat4 = Eigen::Matrix<double, 4, 4>;

struct RigidBody {
    double mass = 0.0;
    Mat3 inertia = Mat3::Zero();      // about the centre of mass, own frame
    Vec3 centre_of_mass = Vec3::Zero();  // from point b, own frame
};

// Bodies are stored in the order of the generalized coordinates q = [alpha, alpha_m, beta, beta_m].
enum BodyIndex { kAzimuthBody = 0, kAzimuthRotor = 1, kElevationBody = 2, kElevationRotor = 3 };

struct MultibodyModel {
    RigidBody bodies[4];
    Vec3 d_ab = Vec3::Zero();  // frame 0
    double gravity = 9.81;
};

struct MultibodyEnergy {
    double kinetic = 0.0;    // inertial kinetic energy
    double potential = 0.0;  // gravity, relative to point a
};

// J qdd = Xi + f, with J symmetric positive definite.
void compute_mass_matrix_and_bias(const MultibodyModel& model, const BaseKinematics& base,
                                  const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias);

// Inertial angular velocity of the elevation payload in its own frame (what a payload gyro reads).
Vec3 payload_angular_velocity(const BaseKinematics& base, const Vec4& q, const Vec4& qd);

// velocity_a_in_G is needed here only: the dynamics do not depend on it (Galilean invariance).
MultibodyEnergy compute_energy(const MultibodyModel& model, const BaseKinematics& base,
                               const Vec3& velocity_a_in_G, const Vec4& q, const Vec4& qd);

}  // namespace gimbal
