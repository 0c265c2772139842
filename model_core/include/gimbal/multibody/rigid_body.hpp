// Mass matrix J(q) and bias f(q, qd, base motion) of the four gimbal bodies (docs/physics.md section 3).
//
// Derived by projecting Newton-Euler equations on the partial velocities (Kane's method), which
// equals Lagrange's equations for the energies of docs/physics.md section 3.2; tests/support/symbolic checks that claim.
#pragma once

#include <Eigen/Core>

#include "gimbal/multibody/base_kinematics.hpp"

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

// A body's inertia about point b, where every joint axis passes, in its own frame.
struct PivotInertia {
    Mat3 inertia = Mat3::Zero();        // I + m (|d|^2 1 - d d^T)
    Vec3 first_moment = Vec3::Zero();   // m d
};

// What the mass matrix and bias need of the bodies at every evaluation, derived from them once.
struct MultibodyConstants {
    PivotInertia pivot[4];
    bool rotor1_axisymmetric = false;  // about its axis z, centre of mass on it: its angle drops out
    bool rotor2_axisymmetric = false;  // the same about x
};

struct MultibodyModel {
    RigidBody bodies[4];
    Vec3 d_ab = Vec3::Zero();  // frame 0
    double gravity = 9.81;
    // Set by prepare_multibody() once the bodies are final; an unprepared model is still evaluated
    // correctly, deriving the constants at every call.
    bool prepared = false;
    MultibodyConstants constants;
};

// Derives model.constants from model.bodies and marks the model prepared.
void prepare_multibody(MultibodyModel& model);

struct MultibodyEnergy {
    double kinetic = 0.0;    // inertial kinetic energy
    double potential = 0.0;  // gravity, relative to point a
};

// J qdd = Xi + f, with J symmetric positive definite.
//
// J has the arrow pattern below, and the zeros are written: rotor R1 turns on the carrier, so its rate
// couples to nothing; each elevation body couples only to its own rate and the azimuth rate.
//       [ x 0 x x ]
//   J = [ 0 x 0 0 ]
//       [ x 0 x 0 ]
//       [ x 0 0 x ]
void compute_mass_matrix_and_bias(const MultibodyModel& model, const BaseKinematics& base,
                                  const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias);

// Solves J x = rhs for a J with the arrow pattern of compute_mass_matrix_and_bias (symmetric positive
// definite; the entries off the pattern are not read). Eliminating the elevation coordinates first
// creates no fill-in, so it costs four divisions where a dense LLT costs four square roots and a
// triangular solve pair. A J changed so that it loses the pattern (e.g. a rotor slaved to its load
// through a gear ratio, which couples alpha_m to alpha) must be solved some other way.
template <int Columns>
Eigen::Matrix<double, 4, Columns> solve_mass_matrix(const Mat4& mass_matrix,
                                                    const Eigen::Matrix<double, 4, Columns>& rhs) {
    const Mat4& J = mass_matrix;
    const double inv_rotor = 1.0 / J(1, 1);
    const double inv_elevation = 1.0 / J(2, 2);
    const double inv_elevation_rotor = 1.0 / J(3, 3);
    // Row 0 after substituting x2 and x3 from rows 2 and 3: the Schur complement of the azimuth pivot.
    const double coupling2 = J(0, 2) * inv_elevation, coupling3 = J(0, 3) * inv_elevation_rotor;
    const double inv_schur = 1.0 / (J(0, 0) - coupling2 * J(2, 0) - coupling3 * J(3, 0));
    Eigen::Matrix<double, 4, Columns> x;
    x.row(0) = (rhs.row(0) - coupling2 * rhs.row(2) - coupling3 * rhs.row(3)) * inv_schur;
    x.row(1) = rhs.row(1) * inv_rotor;
    x.row(2) = (rhs.row(2) - J(2, 0) * x.row(0)) * inv_elevation;
    x.row(3) = (rhs.row(3) - J(3, 0) * x.row(0)) * inv_elevation_rotor;
    return x;
}

inline Vec4 solve_mass_matrix(const Mat4& mass_matrix, const Vec4& rhs) {
    return solve_mass_matrix<1>(mass_matrix, rhs);
}

// Whether J and f depend on the angle of `body` (q order): a rotor that is axisymmetric about its
// joint axis, with its centre of mass on it, looks the same at every angle.
bool depends_on_angle(const MultibodyModel& model, int body);

// Inertial angular velocity of the elevation payload in its own frame (what a payload gyro reads).
Vec3 payload_angular_velocity(const BaseKinematics& base, const Vec4& q, const Vec4& qd);

// velocity_a_in_G is needed here only: the dynamics do not depend on it (Galilean invariance).
MultibodyEnergy compute_energy(const MultibodyModel& model, const BaseKinematics& base,
                               const Vec3& velocity_a_in_G, const Vec4& q, const Vec4& qd);

}  // namespace gimbal
