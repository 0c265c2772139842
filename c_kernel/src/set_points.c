#include "gimbal_kernel/set_points.h"

#include "gimbal_kernel/pointing.h"

#include <math.h>

static const double kTwoPi = 2.0 * 3.14159265358979311599796346854; /* 2 * math.pi */

void gimbal_target_direction(double azimuth, double elevation, double direction[3]) {
    direction[0] = -sin(azimuth) * cos(elevation);
    direction[1] = cos(azimuth) * cos(elevation);
    direction[2] = sin(elevation);
}

/* The target in frame 0 (0TG t = Ry(-gamma) Rz(-psi) Rx(-delta) t, as geometry.gimbal_angles_for),
 * then the angles: of the two solutions the one with |beta| <= 90 deg. */
void gimbal_target_angles(const double target[3], const double attitude[3], double angles[2]) {
    double v[3];
    gimbal_inertial_to_base(target, attitude, v);
    angles[0] = atan2(-v[0], v[1]);
    angles[1] = atan2(v[2], hypot(v[0], v[1]));
}

void gimbal_target_set_point(const double target[3], const double attitude[3], const double attitude_rate[3],
                             double value[2], double rate[2]) {
    double ahead[3], angles_ahead[2];
    for (int j = 0; j < 3; ++j) ahead[j] = attitude[j] + GIMBAL_SET_POINT_RATE_STEP_S * attitude_rate[j];
    gimbal_target_angles(target, attitude, value);
    gimbal_target_angles(target, ahead, angles_ahead);
    double turn = angles_ahead[0] - value[0];
    turn -= kTwoPi * nearbyint(turn / kTwoPi);
    rate[0] = turn / GIMBAL_SET_POINT_RATE_STEP_S;
    rate[1] = (angles_ahead[1] - value[1]) / GIMBAL_SET_POINT_RATE_STEP_S;
}

void gimbal_target_set_points(long count, const double target[3], const double* attitude, const double* attitude_rate,
                              double* value, double* rate) {
    for (long k = 0; k < count; ++k)
        gimbal_target_set_point(target, attitude + 3 * k, attitude_rate + 3 * k, value + 2 * k, rate + 2 * k);
}

double gimbal_angle_nearest_turn(double principal, double measured) {
    return principal + kTwoPi * nearbyint((measured - principal) / kTwoPi);
}
