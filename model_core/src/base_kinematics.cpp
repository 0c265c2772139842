#include "gimbal/base_kinematics.hpp"

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

BaseKinematics evaluate_base_kinematics(const BaseMotion& base, double gravity) {
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

}  // namespace gimbal
