#include "gimbal/multibody/rigid_body.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace gimbal {
namespace {

// Every joint axis is a coordinate axis of the parent frame (z of frame 0 for the azimuth bodies, x of
// the housing frame 1 for the elevation bodies), so a joint rotation is a 2-D rotation of two vector
// components: kept as the cosine and sine of the angle rather than as a 3x3 matrix.
struct JointRotation {
    double c = 1.0;
    double s = 0.0;
};

JointRotation joint_rotation(double angle) { return {std::cos(angle), std::sin(angle)}; }

// rotation_z(angle)^T v: parent coordinates into the frame turned by angle about z.
Vec3 into_frame_turned_about_z(const JointRotation& r, const Vec3& v) {
    return Vec3(r.c * v.x() + r.s * v.y(), r.c * v.y() - r.s * v.x(), v.z());
}

// rotation_z(angle) v: back to parent coordinates.
Vec3 out_of_frame_turned_about_z(const JointRotation& r, const Vec3& v) {
    return Vec3(r.c * v.x() - r.s * v.y(), r.s * v.x() + r.c * v.y(), v.z());
}

Vec3 into_frame_turned_about_x(const JointRotation& r, const Vec3& v) {
    return Vec3(v.x(), r.c * v.y() + r.s * v.z(), r.c * v.z() - r.s * v.y());
}

Vec3 out_of_frame_turned_about_x(const JointRotation& r, const Vec3& v) {
    return Vec3(v.x(), r.c * v.y() - r.s * v.z(), r.s * v.y() + r.c * v.z());
}

// A rotor whose mass distribution is unchanged by turning it about its joint axis contributes the same
// terms at every angle of its own: it is evaluated at angle 0 and its sin/cos never computed. The
// comparisons are exact on purpose: a nearly symmetric rotor takes the general path.
bool axisymmetric_about_z(const RigidBody& body) {
    const Mat3& I = body.inertia;
    return I(0, 0) == I(1, 1) && I(0, 1) == 0.0 && I(1, 0) == 0.0 && I(0, 2) == 0.0 && I(2, 0) == 0.0 &&
           I(1, 2) == 0.0 && I(2, 1) == 0.0 && body.centre_of_mass.x() == 0.0 && body.centre_of_mass.y() == 0.0;
}

bool axisymmetric_about_x(const RigidBody& body) {
    const Mat3& I = body.inertia;
    return I(1, 1) == I(2, 2) && I(0, 1) == 0.0 && I(1, 0) == 0.0 && I(0, 2) == 0.0 && I(2, 0) == 0.0 &&
           I(1, 2) == 0.0 && I(2, 1) == 0.0 && body.centre_of_mass.y() == 0.0 && body.centre_of_mass.z() == 0.0;
}

JointRotation rotor_rotation_about_z(const RigidBody& rotor, double angle) {
    return axisymmetric_about_z(rotor) ? JointRotation{} : joint_rotation(angle);
}

JointRotation rotor_rotation_about_x(const RigidBody& rotor, double angle) {
    return axisymmetric_about_x(rotor) ? JointRotation{} : joint_rotation(angle);
}

// Motion of one body at the current state with qdd = 0, in the body's own frame.
struct BodyMotion {
    Vec3 angular_velocity;    // inertial
    Vec3 angular_accel_bias;  // inertial angular acceleration when qdd = 0
};

// A body turning at `rate` about z of a parent frame whose inertial rate and acceleration are given in
// parent coordinates. parent_rate x (ez rate) = rate (p_y, -p_x, 0) is written out.
BodyMotion motion_about_z(const JointRotation& r, double rate, const Vec3& parent_rate, const Vec3& parent_accel) {
    const Vec3 p = into_frame_turned_about_z(r, parent_rate);
    BodyMotion m;
    m.angular_velocity = Vec3(p.x(), p.y(), p.z() + rate);
    const Vec3 a = into_frame_turned_about_z(r, parent_accel);
    m.angular_accel_bias = Vec3(a.x() + rate * p.y(), a.y() - rate * p.x(), a.z());
    return m;
}

// The same about x: parent_rate x (ex rate) = rate (0, p_z, -p_y).
BodyMotion motion_about_x(const JointRotation& r, double rate, const Vec3& parent_rate, const Vec3& parent_accel) {
    const Vec3 p = into_frame_turned_about_x(r, parent_rate);
    BodyMotion m;
    m.angular_velocity = Vec3(p.x() + rate, p.y(), p.z());
    const Vec3 a = into_frame_turned_about_x(r, parent_accel);
    m.angular_accel_bias = Vec3(a.x(), a.y() + rate * p.z(), a.z() - rate * p.y());
    return m;
}

// Every joint axis passes through point b, so projecting a body's Newton-Euler equations on its
// partial velocities (axis x d for the centre of mass, axis for the rotation) gives
//   axis . (d x F + T),
// the component along the axis of the moment about b. With the inertia about b, that moment is the
// single rigid-body equation below, and the mass matrix entries are axis_i . I_b axis_j.
// The helpers below build every Vec3 from scalar expressions and never use Eigen's vector operators on
// 3-vectors: those load two components as one SSE packet right after they were stored one by one, and
// the failed store-to-load forwarding cost more than the arithmetic (about half of the call, measured).
inline PivotInertia about_pivot(const RigidBody& body) {
    const Vec3& d = body.centre_of_mass;
    const double m = body.mass;
    const double mx = m * d.x(), my = m * d.y(), mz = m * d.z();
    const double mxx = mx * d.x(), myy = my * d.y(), mzz = mz * d.z();
    const double mxy = mx * d.y(), mxz = mx * d.z(), myz = my * d.z();
    const Mat3& I = body.inertia;
    PivotInertia p;
    p.inertia << I(0, 0) + (myy + mzz), I(0, 1) - mxy, I(0, 2) - mxz,
                 I(1, 0) - mxy, I(1, 1) + (mxx + mzz), I(1, 2) - myz,
                 I(2, 0) - mxz, I(2, 1) - myz, I(2, 2) + (mxx + myy);
    p.first_moment = Vec3(mx, my, mz);
    return p;
}

inline Vec3 times(const Mat3& A, const Vec3& v) {
    return Vec3(A(0, 0) * v.x() + A(0, 1) * v.y() + A(0, 2) * v.z(),
                A(1, 0) * v.x() + A(1, 1) * v.y() + A(1, 2) * v.z(),
                A(2, 0) * v.x() + A(2, 1) * v.y() + A(2, 2) * v.z());
}

inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return Vec3(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
}

void derive_constants(const MultibodyModel& model, MultibodyConstants& constants) {
    for (int k = 0; k < 4; ++k) constants.pivot[k] = about_pivot(model.bodies[k]);
    constants.rotor1_axisymmetric = axisymmetric_about_z(model.bodies[kAzimuthRotor]);
    constants.rotor2_axisymmetric = axisymmetric_about_x(model.bodies[kElevationRotor]);
}

// Moment about b of apparent gravity and the inertial forces with qdd = 0 (the d'Alembert moment).
// m d x (w x (w x d)) = w x (m (|d|^2 1 - d d^T) w) folds the centre-of-mass terms into the gyroscopic one.
inline Vec3 bias_moment(const PivotInertia& p, const BodyMotion& m, const Vec3& apparent_gravity) {
    const Vec3& w = m.angular_velocity;
    const Vec3 gravity_moment = cross(p.first_moment, apparent_gravity);
    const Vec3 inertia_accel = times(p.inertia, m.angular_accel_bias);
    const Vec3 gyroscopic = cross(w, times(p.inertia, w));
    return Vec3(gravity_moment.x() - inertia_accel.x() - gyroscopic.x(),
                gravity_moment.y() - inertia_accel.y() - gyroscopic.y(),
                gravity_moment.z() - inertia_accel.z() - gyroscopic.z());
}

}  // namespace

void prepare_multibody(MultibodyModel& model) {
    derive_constants(model, model.constants);
    model.prepared = true;
}

namespace {

void mass_matrix_and_bias(const MultibodyModel& model, const MultibodyConstants& constants, const BaseKinematics& base,
                          const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias);

}  // namespace

void compute_mass_matrix_and_bias(const MultibodyModel& model, const BaseKinematics& base,
                                  const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias) {
    if (model.prepared) {
        mass_matrix_and_bias(model, model.constants, base, q, qd, mass_matrix, bias);
        return;
    }
    // Constructed only here: a prepared model (every right-hand side of a run) need not zero them.
    MultibodyConstants derived_here;
    derive_constants(model, derived_here);
    mass_matrix_and_bias(model, derived_here, base, q, qd, mass_matrix, bias);
}

namespace {

void mass_matrix_and_bias(const MultibodyModel& model, const MultibodyConstants& constants, const BaseKinematics& base,
                          const Vec4& q, const Vec4& qd, Mat4& mass_matrix, Vec4& bias) {
    const Vec3& base_rate = base.angular_velocity;
    // Point b is fixed on the carrier: rigid-body acceleration transfer from point a.
    const Vec3 transport = cross(base.angular_accel, model.d_ab);
    const Vec3 centripetal = cross(base_rate, cross(base_rate, model.d_ab));
    // Gravity and the carrier's acceleration act alike on every body: combine them once, in frame 0.
    const Vec3 apparent_gravity0(base.gravity.x() - (base.accel_a.x() + transport.x() + centripetal.x()),
                                 base.gravity.y() - (base.accel_a.y() + transport.y() + centripetal.y()),
                                 base.gravity.z() - (base.accel_a.z() + transport.z() + centripetal.z()));

    // Azimuth housing (body 0); its frame 1 is the parent of both elevation bodies.
    const JointRotation azimuth = joint_rotation(q[kAzimuthBody]);
    const BodyMotion housing = motion_about_z(azimuth, qd[kAzimuthBody], base_rate, base.angular_accel);
    const Vec3 apparent_gravity1 = into_frame_turned_about_z(azimuth, apparent_gravity0);
    const PivotInertia& housing_inertia = constants.pivot[kAzimuthBody];
    const Vec3 housing_moment = bias_moment(housing_inertia, housing, apparent_gravity1);

    // Rotor R1 (body 1) turns about z of frame 0 on its own: it couples to no other coordinate.
    const RigidBody& rotor1 = model.bodies[kAzimuthRotor];
    mass_matrix.setZero();
    mass_matrix(kAzimuthBody, kAzimuthBody) = housing_inertia.inertia(2, 2);
    bias[kAzimuthBody] = housing_moment.z();
    if (constants.rotor1_axisymmetric) {
        // The general terms at angle 0 with the centre of mass at (0, 0, d): I_b is diagonal with equal
        // transverse entries and I_b,zz = I_zz, so gravity and the gyroscopic moment have no z
        // component; only the base's angular acceleration about z remains.
        mass_matrix(kAzimuthRotor, kAzimuthRotor) = rotor1.inertia(2, 2);
        bias[kAzimuthRotor] = -rotor1.inertia(2, 2) * base.angular_accel.z();
    } else {
        const JointRotation turn = joint_rotation(q[kAzimuthRotor]);
        const BodyMotion motion = motion_about_z(turn, qd[kAzimuthRotor], base_rate, base.angular_accel);
        const PivotInertia& pivot = constants.pivot[kAzimuthRotor];
        mass_matrix(kAzimuthRotor, kAzimuthRotor) = pivot.inertia(2, 2);
        bias[kAzimuthRotor] = bias_moment(pivot, motion, into_frame_turned_about_z(turn, apparent_gravity0)).z();
    }

    // Elevation payload (body 2) and rotor R2 (body 3) turn about x of frame 1. In the body frame the
    // azimuth axis is rotation_x(angle)^T ez = (0, s, c), the own axis is ex.
    const Vec3& housing_rate = housing.angular_velocity;
    const Vec3& housing_accel = housing.angular_accel_bias;
    const RigidBody& rotor2 = model.bodies[kElevationRotor];
    const bool symmetric_rotor2 = constants.rotor2_axisymmetric;
    for (int k : {kElevationBody, kElevationRotor}) {
        if (k == kElevationRotor && symmetric_rotor2) continue;
        const JointRotation turn = joint_rotation(q[k]);
        const BodyMotion motion = motion_about_x(turn, qd[k], housing_rate, housing_accel);
        const PivotInertia& pivot = constants.pivot[k];
        const Vec3 moment = bias_moment(pivot, motion, into_frame_turned_about_x(turn, apparent_gravity1));
        const Mat3& I = pivot.inertia;
        // (0, s, c) . I_b (0, s, c), (0, s, c) . I_b ex and ex . I_b (0, s, c).
        const double inertia_azimuth_y = turn.s * I(1, 1) + turn.c * I(1, 2);
        const double inertia_azimuth_z = turn.s * I(2, 1) + turn.c * I(2, 2);
        mass_matrix(kAzimuthBody, kAzimuthBody) += turn.s * inertia_azimuth_y + turn.c * inertia_azimuth_z;
        mass_matrix(kAzimuthBody, k) = turn.s * I(1, 0) + turn.c * I(2, 0);
        mass_matrix(k, kAzimuthBody) = turn.s * I(0, 1) + turn.c * I(0, 2);
        mass_matrix(k, k) = I(0, 0);
        bias[kAzimuthBody] += turn.s * moment.y() + turn.c * moment.z();
        bias[k] = moment.x();
    }
    if (symmetric_rotor2) {
        // The general terms at angle 0 (frame 1, azimuth axis ez) with the centre of mass at (d, 0, 0):
        // I_b = diag(A, B, B), B = I_yy + m d^2. The gyroscopic moment w x I_b w is
        // (0, (A - B) w_x w_z, (B - A) w_x w_y), the gravity moment m d ex x g is (0, -m d g_z, m d g_y).
        const double rate = qd[kElevationRotor];
        const double first_moment = rotor2.mass * rotor2.centre_of_mass.x();
        const double axial = rotor2.inertia(0, 0);
        const double transverse = rotor2.inertia(2, 2) + first_moment * rotor2.centre_of_mass.x();
        const double spin = housing_rate.x() + rate;
        const double accel_z = housing_accel.z() - rate * housing_rate.y();
        mass_matrix(kAzimuthBody, kAzimuthBody) += transverse;
        mass_matrix(kElevationRotor, kElevationRotor) = axial;
        bias[kAzimuthBody] += first_moment * apparent_gravity1.y() - transverse * accel_z -
                              (transverse - axial) * spin * housing_rate.y();
        bias[kElevationRotor] = -axial * housing_accel.x();
    }
}

}  // namespace

bool depends_on_angle(const MultibodyModel& model, int body) {
    if (body == kAzimuthRotor) return !axisymmetric_about_z(model.bodies[kAzimuthRotor]);
    if (body == kElevationRotor) return !axisymmetric_about_x(model.bodies[kElevationRotor]);
    return true;
}

Vec3 payload_angular_velocity(const BaseKinematics& base, const Vec4& q, const Vec4& qd) {
    Vec3 housing_rate = into_frame_turned_about_z(joint_rotation(q[kAzimuthBody]), base.angular_velocity);
    housing_rate.z() += qd[kAzimuthBody];
    Vec3 payload_rate = into_frame_turned_about_x(joint_rotation(q[kElevationBody]), housing_rate);
    payload_rate.x() += qd[kElevationBody];
    return payload_rate;
}

MultibodyEnergy compute_energy(const MultibodyModel& model, const BaseKinematics& base,
                               const Vec3& velocity_a_in_G, const Vec4& q, const Vec4& qd) {
    const Vec3& base_rate = base.angular_velocity;
    const Vec3 velocity_b0 = base.G_T_0.transpose() * velocity_a_in_G + base_rate.cross(model.d_ab);

    const JointRotation azimuth = joint_rotation(q[kAzimuthBody]);
    const Vec3 housing_rate = into_frame_turned_about_z(azimuth, base_rate) + Vec3::UnitZ() * qd[kAzimuthBody];
    const Vec3 velocity_b1 = into_frame_turned_about_z(azimuth, velocity_b0);

    JointRotation turn[4];
    turn[kAzimuthBody] = azimuth;
    turn[kAzimuthRotor] = rotor_rotation_about_z(model.bodies[kAzimuthRotor], q[kAzimuthRotor]);
    turn[kElevationBody] = joint_rotation(q[kElevationBody]);
    turn[kElevationRotor] = rotor_rotation_about_x(model.bodies[kElevationRotor], q[kElevationRotor]);

    MultibodyEnergy energy;
    for (int k = 0; k < 4; ++k) {
        const RigidBody& body = model.bodies[k];
        const Vec3& d = body.centre_of_mass;
        Vec3 w, velocity_b, com_position0;
        if (k == kAzimuthBody || k == kAzimuthRotor) {
            w = into_frame_turned_about_z(turn[k], base_rate) + Vec3::UnitZ() * qd[k];
            velocity_b = into_frame_turned_about_z(turn[k], velocity_b0);
            com_position0 = out_of_frame_turned_about_z(turn[k], d);
        } else {
            w = into_frame_turned_about_x(turn[k], housing_rate) + Vec3::UnitX() * qd[k];
            velocity_b = into_frame_turned_about_x(turn[k], velocity_b1);
            com_position0 = out_of_frame_turned_about_z(azimuth, out_of_frame_turned_about_x(turn[k], d));
        }
        const Vec3 com_velocity = velocity_b + w.cross(d);
        energy.kinetic += 0.5 * body.mass * com_velocity.squaredNorm() + 0.5 * w.dot(body.inertia * w);
        // Height of the centre of mass above point a, via the position in frame 0.
        energy.potential -= body.mass * base.gravity.dot(model.d_ab + com_position0);
    }
    return energy;
}

}  // namespace gimbal
