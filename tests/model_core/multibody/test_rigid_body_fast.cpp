// The specialised rigid-body dynamics (model_core/src/multibody/rigid_body.cpp, base_kinematics.cpp) against the
// generic implementation they replaced, kept here verbatim as the reference: random full inertia
// tensors, centres of mass anywhere, random base motion and gravity, rotors with and without the
// axial symmetry that lets the fast code skip their trigonometry. Also solve_mass_matrix against LLT.
//
// benchmarks/bench_rigid_body.cpp times the reference against the new code: it includes this file
// with GIMBAL_RIGID_BODY_REFERENCE_ONLY defined, which leaves out the test itself.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <random>
#include <utility>

#include "gimbal/multibody/base_kinematics.hpp"
#include "gimbal/multibody/rigid_body.hpp"

// ---------------------------------------------------------------------------------------------------
// Reference: the generic implementation as it was before the specialisation (rotation matrices built
// for every joint, Newton-Euler force and torque per body projected on the partial velocities).
namespace reference {

using namespace gimbal;

inline BaseKinematics evaluate_base_kinematics(const BaseMotion& base, double gravity) {
    const double pitch = base.attitude[0], yaw = base.attitude[1], roll = base.attitude[2];
    const double pitch_rate = base.attitude_rate[0], yaw_rate = base.attitude_rate[1],
                 roll_rate = base.attitude_rate[2];
    const double pitch_accel = base.attitude_accel[0], yaw_accel = base.attitude_accel[1],
                 roll_accel = base.attitude_accel[2];
    const double cy = std::cos(yaw), sy = std::sin(yaw), cr = std::cos(roll), sr = std::sin(roll);

    BaseKinematics out;
    out.G_T_0 = rotation_x(pitch) * rotation_z(yaw) * rotation_y(roll);
    out.angular_velocity << pitch_rate * cy * cr - yaw_rate * sr,
                            -pitch_rate * sy + roll_rate,
                            pitch_rate * cy * sr + yaw_rate * cr;
    out.angular_accel << pitch_accel * cy * cr - pitch_rate * yaw_rate * sy * cr - pitch_rate * roll_rate * cy * sr
                             - yaw_accel * sr - yaw_rate * roll_rate * cr,
                         -pitch_accel * sy - pitch_rate * yaw_rate * cy + roll_accel,
                         pitch_accel * cy * sr - pitch_rate * yaw_rate * sy * sr + pitch_rate * roll_rate * cy * cr
                             + yaw_accel * cr - yaw_rate * roll_rate * sr;
    const Mat3 zero_T_G = out.G_T_0.transpose();
    out.accel_a = zero_T_G * base.acceleration_a;
    out.gravity = zero_T_G * Vec3(0.0, 0.0, -gravity);
    return out;
}

struct BodyMotion {
    Mat3 frame_T_0;          // maps frame 0 coordinates to the body frame
    Vec3 angular_velocity;   // inertial
    Vec3 angular_accel_bias; // inertial angular acceleration when qdd = 0
    int column_count;
    int column[2];           // which generalized coordinates
    Vec3 axis[2];            // d(angular_velocity)/d(qd_column)
};

struct GimbalMotion {
    BodyMotion body[4];
};

inline void compute_motion(const BaseKinematics& base, const Vec4& q, const Vec4& qd, GimbalMotion& motion) {
    const Vec3 ex = Vec3::UnitX(), ez = Vec3::UnitZ();
    for (int k : {kAzimuthBody, kAzimuthRotor}) {
        BodyMotion& m = motion.body[k];
        m.frame_T_0 = rotation_z(q[k]).transpose();
        const Vec3 base_rate = m.frame_T_0 * base.angular_velocity;
        m.angular_velocity = base_rate + ez * qd[k];
        m.angular_accel_bias = m.frame_T_0 * base.angular_accel + base_rate.cross(ez * qd[k]);
        m.column_count = 1;
        m.column[0] = k;
        m.axis[0] = ez;
    }
    const BodyMotion& housing = motion.body[kAzimuthBody];
    for (int k : {kElevationBody, kElevationRotor}) {
        BodyMotion& m = motion.body[k];
        const Mat3 frame_T_1 = rotation_x(q[k]).transpose();
        m.frame_T_0 = frame_T_1 * housing.frame_T_0;
        const Vec3 housing_rate = frame_T_1 * housing.angular_velocity;
        m.angular_velocity = housing_rate + ex * qd[k];
        m.angular_accel_bias = frame_T_1 * housing.angular_accel_bias + housing_rate.cross(ex * qd[k]);
        m.column_count = 2;
        m.column[0] = kAzimuthBody;
        m.axis[0] = frame_T_1 * ez;
        m.column[1] = k;
        m.axis[1] = ex;
    }
}

inline void compute_mass_matrix_and_bias(const MultibodyModel& model, const BaseKinematics& base,
                                         const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias) {
    GimbalMotion motion;
    compute_motion(base, q, qd, motion);
    const Vec3 accel_b0 = base.accel_a + base.angular_accel.cross(model.d_ab) +
                          base.angular_velocity.cross(base.angular_velocity.cross(model.d_ab));
    const Vec3 apparent_gravity0 = base.gravity - accel_b0;

    mass_matrix.setZero();
    bias.setZero();
    for (int k = 0; k < 4; ++k) {
        const RigidBody& body = model.bodies[k];
        const BodyMotion& m = motion.body[k];
        const Vec3& w = m.angular_velocity;
        const Vec3& d = body.centre_of_mass;
        const Vec3 force = body.mass * (m.frame_T_0 * apparent_gravity0 - m.angular_accel_bias.cross(d) -
                                        w.cross(w.cross(d)));
        const Vec3 torque = -(body.inertia * m.angular_accel_bias + w.cross(body.inertia * w));
        Vec3 partial_velocity[2], inertia_axis[2];
        for (int i = 0; i < m.column_count; ++i) {
            partial_velocity[i] = m.axis[i].cross(d);
            inertia_axis[i] = body.inertia * m.axis[i];
        }
        for (int i = 0; i < m.column_count; ++i) {
            const int row = m.column[i];
            bias[row] += partial_velocity[i].dot(force) + m.axis[i].dot(torque);
            for (int j = 0; j < m.column_count; ++j) {
                mass_matrix(row, m.column[j]) +=
                    body.mass * partial_velocity[i].dot(partial_velocity[j]) + m.axis[i].dot(inertia_axis[j]);
            }
        }
    }
}

inline Vec3 payload_angular_velocity(const BaseKinematics& base, const Vec4& q, const Vec4& qd) {
    const Vec3 housing_rate = rotation_z(q[kAzimuthBody]).transpose() * base.angular_velocity +
                              Vec3::UnitZ() * qd[kAzimuthBody];
    return rotation_x(q[kElevationBody]).transpose() * housing_rate + Vec3::UnitX() * qd[kElevationBody];
}

inline MultibodyEnergy compute_energy(const MultibodyModel& model, const BaseKinematics& base,
                                      const Vec3& velocity_a_in_G, const Vec4& q, const Vec4& qd) {
    GimbalMotion motion;
    compute_motion(base, q, qd, motion);
    const Vec3 velocity_b0 = base.G_T_0.transpose() * velocity_a_in_G + base.angular_velocity.cross(model.d_ab);

    MultibodyEnergy energy;
    for (int k = 0; k < 4; ++k) {
        const RigidBody& body = model.bodies[k];
        const BodyMotion& m = motion.body[k];
        const Vec3& w = m.angular_velocity;
        const Vec3 com_velocity = m.frame_T_0 * velocity_b0 + w.cross(body.centre_of_mass);
        energy.kinetic += 0.5 * body.mass * com_velocity.squaredNorm() + 0.5 * w.dot(body.inertia * w);
        const Vec3 com_position0 = model.d_ab + m.frame_T_0.transpose() * body.centre_of_mass;
        energy.potential -= body.mass * base.gravity.dot(com_position0);
    }
    return energy;
}

}  // namespace reference

// ---------------------------------------------------------------------------------------------------
// Random gimbals and states, shared with the benchmark.
namespace random_gimbal {

using namespace gimbal;

inline double uniform(std::mt19937_64& rng, double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(rng);
}

inline Vec3 uniform_vec3(std::mt19937_64& rng, double half_width) {
    return Vec3(uniform(rng, -half_width, half_width), uniform(rng, -half_width, half_width),
                uniform(rng, -half_width, half_width));
}

// A physically possible inertia tensor with products of inertia: principal moments obeying the
// triangle inequality, principal axes in a random orientation.
inline Mat3 full_inertia(std::mt19937_64& rng, double scale) {
    const double a = uniform(rng, 0.2, 1.0) * scale, b = uniform(rng, 0.2, 1.0) * scale;
    const double c = uniform(rng, std::fabs(a - b), a + b);
    const Eigen::Quaterniond orientation(Eigen::Vector4d(uniform_vec3(rng, 1.0).x(), uniform(rng, -1, 1),
                                                         uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized());
    const Mat3 axes = orientation.toRotationMatrix();
    return axes * Vec3(a, b, c).asDiagonal() * axes.transpose();
}

enum class RotorShape {
    general,       // full inertia tensor, centre of mass anywhere, like the housing and payload
    axisymmetric,  // about its joint axis (z for R1, x for R2), centre of mass on the axis
    nearly,        // axisymmetric but for one condition: the fast code must not take its shortcut
};

// An axisymmetric rotor about coordinate axis `axis`, with one symmetry condition broken if `nearly`:
// a product of inertia, unequal transverse moments, or the centre of mass off the axis.
inline void make_rotor(std::mt19937_64& rng, RigidBody& rotor, int axis, double scale, bool nearly) {
    const int t1 = (axis + 1) % 3, t2 = (axis + 2) % 3;  // transverse axes
    const double transverse = uniform(rng, 0.5, 1.0) * scale;
    rotor.inertia.setZero();
    rotor.inertia(axis, axis) = uniform(rng, 0.5, 2.0) * transverse;
    rotor.inertia(t1, t1) = rotor.inertia(t2, t2) = transverse;
    rotor.centre_of_mass.setZero();
    rotor.centre_of_mass[axis] = uniform(rng, -0.1, 0.1);
    if (!nearly) return;
    const double product = 0.1 * transverse;
    switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
        case 0: rotor.inertia(t1, t2) = rotor.inertia(t2, t1) = product; break;
        case 1: rotor.inertia(axis, t1) = rotor.inertia(t1, axis) = product; break;
        case 2: rotor.inertia(axis, t2) = rotor.inertia(t2, axis) = product; break;
        case 3: rotor.inertia(t2, t2) = 1.1 * transverse; break;
        case 4: rotor.centre_of_mass[t1] = 0.01; break;
        default: rotor.centre_of_mass[t2] = 0.01; break;
    }
}

inline MultibodyModel model(std::mt19937_64& rng, RotorShape r1_shape, RotorShape r2_shape) {
    MultibodyModel m;
    const double scale[4] = {0.5, 2e-3, 0.3, 1e-3};
    for (int k = 0; k < 4; ++k) {
        RigidBody& body = m.bodies[k];
        body.mass = uniform(rng, 0.1, 5.0) * (k == kAzimuthRotor || k == kElevationRotor ? 0.1 : 1.0);
        body.inertia = full_inertia(rng, scale[k]);
        body.centre_of_mass = uniform_vec3(rng, 0.1);
    }
    if (r1_shape != RotorShape::general)
        make_rotor(rng, m.bodies[kAzimuthRotor], 2, scale[1], r1_shape == RotorShape::nearly);
    if (r2_shape != RotorShape::general)
        make_rotor(rng, m.bodies[kElevationRotor], 0, scale[3], r2_shape == RotorShape::nearly);
    m.d_ab = uniform_vec3(rng, 0.5);
    m.gravity = uniform(rng, 0.0, 20.0);
    return m;
}

inline BaseMotion base_motion(std::mt19937_64& rng) {
    BaseMotion base;
    base.attitude = uniform_vec3(rng, M_PI);
    base.attitude_rate = uniform_vec3(rng, 3.0);
    base.attitude_accel = uniform_vec3(rng, 20.0);
    base.velocity_a = uniform_vec3(rng, 30.0);
    base.acceleration_a = uniform_vec3(rng, 30.0);
    return base;
}

struct State {
    Vec4 q, qd;
};

inline State state(std::mt19937_64& rng) {
    State s;
    // Rotors spin geared up: many turns and fast rates.
    s.q << uniform(rng, -M_PI, M_PI), uniform(rng, -300.0, 300.0), uniform(rng, -M_PI, M_PI),
        uniform(rng, -300.0, 300.0);
    s.qd << uniform(rng, -5.0, 5.0), uniform(rng, -500.0, 500.0), uniform(rng, -5.0, 5.0),
        uniform(rng, -500.0, 500.0);
    return s;
}

}  // namespace random_gimbal

#ifndef GIMBAL_RIGID_BODY_REFERENCE_ONLY

#include "check.hpp"

using namespace gimbal;

namespace {

// Largest relative discrepancy seen per quantity, reported at the end.
struct Worst {
    double base = 0.0, mass_matrix = 0.0, bias = 0.0, payload_rate = 0.0, kinetic = 0.0, potential = 0.0,
           solve = 0.0;
};

template <typename A, typename B>
double relative_difference(const A& fast, const B& slow) {
    const double scale = slow.cwiseAbs().maxCoeff();
    const double difference = (fast - slow).cwiseAbs().maxCoeff();
    return scale == 0.0 ? difference : difference / scale;
}

// The old code is the less accurate of the two: projecting the centripetal force of a fast rotor's
// centre of mass on its partial velocity cancels terms ~1e3 times |f|, which costs it up to ~1e-13
// relative in f (checked against a long double evaluation: new code 5e-15, old 9e-14). Hence 1e-12.
constexpr double kTolerance = 1e-12;

void compare_state(const MultibodyModel& model, const BaseMotion& base_motion, const random_gimbal::State& s,
                   Worst& worst) {
    const BaseKinematics slow_base = reference::evaluate_base_kinematics(base_motion, model.gravity);
    const BaseKinematics base = evaluate_base_kinematics(base_motion, model.gravity);
    const double base_error = std::max({relative_difference(base.G_T_0, slow_base.G_T_0),
                                        relative_difference(base.angular_velocity, slow_base.angular_velocity),
                                        relative_difference(base.angular_accel, slow_base.angular_accel),
                                        relative_difference(base.accel_a, slow_base.accel_a),
                                        relative_difference(base.gravity, slow_base.gravity)});
    CHECK(base_error <= kTolerance);
    worst.base = std::max(worst.base, base_error);

    // The rigid-body part on the same base kinematics, so that its own discrepancy is measured.
    Mat4 slow_J, J;
    Vec4 slow_f, f;
    reference::compute_mass_matrix_and_bias(model, slow_base, s.q, s.qd, slow_J, slow_f);
    // Garbage in the outputs must not leak through: the zeros of the arrow pattern are written.
    J.setConstant(1e300);
    f.setConstant(1e300);
    compute_mass_matrix_and_bias(model, slow_base, s.q, s.qd, J, f);
    const double J_error = relative_difference(J, slow_J), f_error = relative_difference(f, slow_f);
    CHECK(J_error <= kTolerance);
    CHECK(f_error <= kTolerance);
    // The constants derived once (prepare_multibody, as the FMU's parameters are) give the same bits as
    // deriving them at every call.
    MultibodyModel prepared = model;
    prepare_multibody(prepared);
    CHECK(prepared.prepared && !model.prepared);
    Mat4 prepared_J;
    Vec4 prepared_f;
    compute_mass_matrix_and_bias(prepared, slow_base, s.q, s.qd, prepared_J, prepared_f);
    CHECK(prepared_J == J);
    CHECK(prepared_f == f);
    if (J_error > kTolerance || f_error > kTolerance) {
        std::fprintf(stderr, "  J error %.3g, f error %.3g; f fast / reference:\n", J_error, f_error);
        for (int i = 0; i < 4; ++i) std::fprintf(stderr, "  f[%d] %.17g %.17g\n", i, f[i], slow_f[i]);
    }
    worst.mass_matrix = std::max(worst.mass_matrix, J_error);
    worst.bias = std::max(worst.bias, f_error);
    for (const auto& [row, column] : {std::pair{0, 1}, {1, 0}, {1, 2}, {2, 1}, {1, 3}, {3, 1}, {2, 3}, {3, 2}})
        CHECK(J(row, column) == 0.0);

    const double rate_error = relative_difference(payload_angular_velocity(slow_base, s.q, s.qd),
                                                  reference::payload_angular_velocity(slow_base, s.q, s.qd));
    CHECK(rate_error <= kTolerance);
    worst.payload_rate = std::max(worst.payload_rate, rate_error);

    const MultibodyEnergy slow_energy =
        reference::compute_energy(model, slow_base, base_motion.velocity_a, s.q, s.qd);
    const MultibodyEnergy energy = compute_energy(model, slow_base, base_motion.velocity_a, s.q, s.qd);
    const double kinetic_difference = std::fabs(energy.kinetic - slow_energy.kinetic);
    const double kinetic_error =
        slow_energy.kinetic == 0.0 ? kinetic_difference : kinetic_difference / slow_energy.kinetic;
    // The potential is a signed sum: measured against the size of its terms, m g |position|.
    double potential_scale = 0.0;
    for (const RigidBody& body : model.bodies)
        potential_scale += body.mass * model.gravity * (model.d_ab.norm() + body.centre_of_mass.norm());
    const double potential_error =
        potential_scale == 0.0 ? std::fabs(energy.potential)
                               : std::fabs(energy.potential - slow_energy.potential) / potential_scale;
    CHECK(kinetic_error <= kTolerance);
    CHECK(potential_error <= kTolerance);
    worst.kinetic = std::max(worst.kinetic, kinetic_error);
    worst.potential = std::max(worst.potential, potential_error);
}

// solve_mass_matrix against Eigen's dense LLT, within what the conditioning of J allows.
void compare_solve(const Mat4& J, std::mt19937_64& rng, Worst& worst) {
    const Eigen::SelfAdjointEigenSolver<Mat4> spectrum(J, Eigen::EigenvaluesOnly);
    CHECK(spectrum.eigenvalues()[0] > 0.0);
    const double condition = spectrum.eigenvalues()[3] / spectrum.eigenvalues()[0];
    const double allowed = 16.0 * condition * std::numeric_limits<double>::epsilon();
    const Eigen::LLT<Mat4> llt(J);

    const Vec4 rhs = Vec4::Random() * random_gimbal::uniform(rng, 0.1, 100.0);
    const Vec4 x = solve_mass_matrix(J, rhs);
    const double error = (x - llt.solve(rhs)).norm() / x.norm();
    CHECK(error <= allowed);
    worst.solve = std::max(worst.solve, error / condition);

    using Mat4x12 = Eigen::Matrix<double, 4, 12>;
    const Mat4x12 many = Mat4x12::Random();
    const Mat4x12 xs = solve_mass_matrix(J, many);
    const Mat4x12 slow_xs = llt.solve(many);
    for (int column = 0; column < 12; ++column) {
        const double column_error = (xs.col(column) - slow_xs.col(column)).norm() / xs.col(column).norm();
        CHECK(column_error <= allowed);
        worst.solve = std::max(worst.solve, column_error / condition);
    }
}

}  // namespace

int main() {
    std::mt19937_64 rng(20240611);
    Worst worst;
    constexpr int kStates = 1800;
    const random_gimbal::RotorShape shapes[3] = {random_gimbal::RotorShape::general,
                                                 random_gimbal::RotorShape::axisymmetric,
                                                 random_gimbal::RotorShape::nearly};
    for (int trial = 0; trial < kStates; ++trial) {
        // Every combination of general, axisymmetric and nearly axisymmetric rotors.
        const random_gimbal::RotorShape r1_shape = shapes[trial % 3], r2_shape = shapes[(trial / 3) % 3];
        const MultibodyModel model = random_gimbal::model(rng, r1_shape, r2_shape);
        const BaseMotion base_motion = random_gimbal::base_motion(rng);
        const random_gimbal::State s = random_gimbal::state(rng);
        compare_state(model, base_motion, s, worst);

        Mat4 J;
        Vec4 f;
        compute_mass_matrix_and_bias(model, evaluate_base_kinematics(base_motion, model.gravity), s.q, s.qd, J, f);
        compare_solve(J, rng, worst);
    }

    // A carrier at rest (the fixed-base fidelity) and a gimbal at rest: the degenerate inputs.
    for (int trial = 0; trial < 8; ++trial) {
        const MultibodyModel model = random_gimbal::model(rng, shapes[trial & 1], shapes[(trial & 2) / 2]);
        random_gimbal::State s = random_gimbal::state(rng);
        if (trial & 4) s.qd.setZero();
        compare_state(model, BaseMotion{}, s, worst);
    }

    std::printf("worst relative differences over %d states: base %.2g, J %.2g, f %.2g, payload rate %.2g, "
                "kinetic %.2g, potential %.2g; solve error / cond(J) %.2g\n",
                kStates, worst.base, worst.mass_matrix, worst.bias, worst.payload_rate, worst.kinetic,
                worst.potential, worst.solve);
    return check_report("rigid_body_fast");
}

#endif  // GIMBAL_RIGID_BODY_REFERENCE_ONLY
