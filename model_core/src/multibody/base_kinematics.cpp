#include "gimbal/multibody/base_kinematics.hpp"

#include <cmath>

namespace gimbal {

Mat3 rotation_x(double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Mat3 r;
    r << 1, 0, 0, 0, c, -s, 0, s, c;
    return r;
}

Mat3 rotation_y(double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Mat3 r;
    r << c, 0, s, 0, 1, 0, -s, 0, c;
    return r;
}

Mat3 rotation_z(double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Mat3 r;
    r << c, -s, 0, s, c, 0, 0, 0, 1;
    return r;
}

BaseMotion BaseMotion::advanced(double elapsed) const {
    BaseMotion later = *this;
    later.attitude = attitude + attitude_rate * elapsed + 0.5 * attitude_accel * elapsed * elapsed;
    later.attitude_rate = attitude_rate + attitude_accel * elapsed;
    later.velocity_a = velocity_a + acceleration_a * elapsed;
    return later;
}

SinCos sin_cos(double angle) { return SinCos{std::sin(angle), std::cos(angle)}; }

namespace {

// Small offsets (the carrier's turn within a communication step): the addition theorem with the
// Taylor series of the offset, which at |offset| <= 1e-3 is exact in double precision (the first
// neglected terms are below 1e-22), instead of a library sincos at every integrator stage.
inline SinCos sin_cos_near(const SinCos& reference, double reference_angle, double angle) {
    const double offset = angle - reference_angle;
    if (!(std::fabs(offset) <= 1e-3)) return sin_cos(angle);
    const double square = offset * offset;
    // Reciprocals, not divisions (a division costs a dozen multiplications' time); their rounding
    // enters at square * 1e-16 <= 1e-22.
    constexpr double sixth = 1.0 / 6.0, twentieth = 1.0 / 20.0, twelfth = 1.0 / 12.0, thirtieth = 1.0 / 30.0;
    const double sine = offset * (1.0 - square * sixth * (1.0 - square * twentieth));
    const double cosine = 1.0 - square * 0.5 * (1.0 - square * twelfth * (1.0 - square * thirtieth));
    return SinCos{reference.sin * cosine + reference.cos * sine, reference.cos * cosine - reference.sin * sine};
}

}  // namespace

AttitudeTrig attitude_trig(const Vec3& attitude) {
    return AttitudeTrig{sin_cos(attitude[0]), sin_cos(attitude[1]), sin_cos(attitude[2])};
}

AttitudeTrig attitude_trig_near(const AttitudeTrig& reference, const Vec3& reference_attitude, const Vec3& attitude) {
    return AttitudeTrig{sin_cos_near(reference.pitch, reference_attitude[0], attitude[0]),
                        sin_cos_near(reference.yaw, reference_attitude[1], attitude[1]),
                        sin_cos_near(reference.roll, reference_attitude[2], attitude[2])};
}

BaseKinematics evaluate_base_kinematics(const BaseMotion& base, double gravity) {
    return evaluate_base_kinematics(base, attitude_trig(base.attitude), gravity);
}

BaseKinematics evaluate_base_kinematics(const BaseMotion& base, const AttitudeTrig& trig, double gravity) {
    const double pitch_rate = base.attitude_rate[0], yaw_rate = base.attitude_rate[1],
                 roll_rate = base.attitude_rate[2];
    const double pitch_accel = base.attitude_accel[0], yaw_accel = base.attitude_accel[1],
                 roll_accel = base.attitude_accel[2];
    const double cp = trig.pitch.cos, sp = trig.pitch.sin;
    const double cy = trig.yaw.cos, sy = trig.yaw.sin, cr = trig.roll.cos, sr = trig.roll.sin;

    BaseKinematics out;
    // rotation_x(pitch) * rotation_z(yaw) * rotation_y(roll) multiplied out: Rz Ry has rows
    // (cy cr, -sy, cy sr), (sy cr, cy, sy sr), (-sr, 0, cr); Rx mixes the last two.
    const double sy_cr = sy * cr, sy_sr = sy * sr;
    out.G_T_0 << cy * cr, -sy, cy * sr,
                 cp * sy_cr + sp * sr, cp * cy, cp * sy_sr - sp * cr,
                 sp * sy_cr - cp * sr, sp * cy, sp * sy_sr + cp * cr;
    out.angular_velocity << pitch_rate * cy * cr - yaw_rate * sr,
                            -pitch_rate * sy + roll_rate,
                            pitch_rate * cy * sr + yaw_rate * cr;
    out.angular_accel << pitch_accel * cy * cr - pitch_rate * yaw_rate * sy * cr - pitch_rate * roll_rate * cy * sr
                             - yaw_accel * sr - yaw_rate * roll_rate * cr,
                         -pitch_accel * sy - pitch_rate * yaw_rate * cy + roll_accel,
                         pitch_accel * cy * sr - pitch_rate * yaw_rate * sy * sr + pitch_rate * roll_rate * cy * cr
                             + yaw_accel * cr - yaw_rate * roll_rate * sr;
    // G_T_0^T a, written by component from the scalars: Eigen's product would reload the matrix just
    // stored element by element as SSE packets, and the failed store forwarding costs more than it.
    const Mat3& G = out.G_T_0;
    const Vec3& a = base.acceleration_a;
    out.accel_a = Vec3(G(0, 0) * a.x() + G(1, 0) * a.y() + G(2, 0) * a.z(),
                       G(0, 1) * a.x() + G(1, 1) * a.y() + G(2, 1) * a.z(),
                       G(0, 2) * a.x() + G(1, 2) * a.y() + G(2, 2) * a.z());
    // G_T_0^T (0, 0, -g) is -g times the last row of G_T_0.
    out.gravity = Vec3(-gravity * G(2, 0), -gravity * G(2, 1), -gravity * G(2, 2));
    return out;
}

}  // namespace gimbal
