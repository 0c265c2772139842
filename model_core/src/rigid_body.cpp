#include "gimbal/rigid_body.hpp"

#include <Eigen/Geometry>

namespace gimbal {
namespace {

// Motion of one body at the current state with qdd = 0, in the body's own frame. Its angular velocity
// depends on at most two joint rates (its own, and the azimuth rate for the elevation bodies): the
// partial angular velocities are kept as those columns only.
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

void compute_motion(const BaseKinematics& base, const Vec4& q, const Vec4& qd, GimbalMotion& motion) {
    const Vec3 ex = Vec3::UnitX(), ez = Vec3::UnitZ();
    // Carrier-fixed bodies (azimuth housing and its rotor) turn about z of frame 0.
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
    // Elevation bodies turn about x of the azimuth housing (frame 1).
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

}  // namespace

void compute_mass_matrix_and_bias(const MultibodyModel& model, const BaseKinematics& base,
                                  const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias) {
    GimbalMotion motion;
    compute_motion(base, q, qd, motion);
    // Point b is fixed on the carrier: rigid-body acceleration transfer from point a.
    const Vec3 accel_b0 = base.accel_a + base.angular_accel.cross(model.d_ab) +
                          base.angular_velocity.cross(base.angular_velocity.cross(model.d_ab));
    // Gravity and the carrier's acceleration act alike on every body: combine them once, in frame 0.
    const Vec3 apparent_gravity0 = base.gravity - accel_b0;

    mass_matrix.setZero();
    bias.setZero();
    for (int k = 0; k < 4; ++k) {
        const RigidBody& body = model.bodies[k];
        const BodyMotion& m = motion.body[k];
        const Vec3& w = m.angular_velocity;
        const Vec3& d = body.centre_of_mass;
        // Newton-Euler residual of the body with qdd = 0, projected below on its partial velocities.
        const Vec3 force = body.mass * (m.frame_T_0 * apparent_gravity0 - m.angular_accel_bias.cross(d) -
                                        w.cross(w.cross(d)));
        const Vec3 torque = -(body.inertia * m.angular_accel_bias + w.cross(body.inertia * w));
        Vec3 partial_velocity[2], inertia_axis[2];
        for (int i = 0; i < m.column_count; ++i) {
            partial_velocity[i] = m.axis[i].cross(d);  // of the centre of mass
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

Vec3 payload_angular_velocity(const BaseKinematics& base, const Vec4& q, const Vec4& qd) {
    const Vec3 housing_rate = rotation_z(q[kAzimuthBody]).transpose() * base.angular_velocity +
                              Vec3::UnitZ() * qd[kAzimuthBody];
    return rotation_x(q[kElevationBody]).transpose() * housing_rate + Vec3::UnitX() * qd[kElevationBody];
}

MultibodyEnergy compute_energy(const MultibodyModel& model, const BaseKinematics& base,
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
        // Height of the centre of mass above point a, via the position in frame 0.
        const Vec3 com_position0 = model.d_ab + m.frame_T_0.transpose() * body.centre_of_mass;
        energy.potential -= body.mass * base.gravity.dot(com_position0);
    }
    return energy;
}

}  // namespace gimbal
