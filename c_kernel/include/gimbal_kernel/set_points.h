/* The built-in controllers' set points toward a line-of-sight target, by inverse kinematics of the
 * target for the measured base attitude: one implementation for the scene runner (computed for a
 * whole run before it, gimbal2axis/scene/setpoints.py) and the controller FMU (one row per
 * communication point, fmu_src/controller/), so both give the same bits.
 *
 * Per row: the principal gimbal angles (alpha, beta) that point the line of sight along the target,
 * and their rates: the difference of the inverse kinematics over GIMBAL_SET_POINT_RATE_STEP_S of
 * attitude moved along the measured base rates, the azimuth's turn wrapped into [-pi, pi] (the
 * target crossing the azimuth's branch cut is no jump of the gimbal). The controllers take the
 * azimuth in the 2 pi branch nearest the measured one (gimbal_angle_nearest_turn). Every operation
 * and its order is fixed (built with -ffp-contract=off; libm's sin, cos, atan2, hypot). */
#ifndef GIMBAL_KERNEL_SET_POINTS_H
#define GIMBAL_KERNEL_SET_POINTS_H

#define GIMBAL_SET_POINT_RATE_STEP_S 1e-6

#ifdef __cplusplus
extern "C" {
#endif

/* The unit vector in G of a target at azimuth and elevation [rad]:
 * (-sin(az) cos(el), cos(az) cos(el), sin(el)). */
void gimbal_target_direction(double azimuth, double elevation, double direction[3]);

/* The principal (alpha, beta) pointing the line of sight along `target` (unit vector in G) for the
 * base attitude (delta, psi, gamma). */
void gimbal_target_angles(const double target[3], const double attitude[3], double angles[2]);

/* One row: the set points `value` (alpha, beta) and their rates `rate` for the base attitude and its
 * rates (delta_dot, psi_dot, gamma_dot). */
void gimbal_target_set_point(const double target[3], const double attitude[3], const double attitude_rate[3],
                             double value[2], double rate[2]);

/* `count` rows at once: attitude and attitude_rate count x 3, value and rate count x 2, row-major. */
void gimbal_target_set_points(long count, const double target[3], const double* attitude, const double* attitude_rate,
                              double* value, double* rate);

/* The angle principal + 2 pi m nearest `measured` (m an integer; halves round to even). */
double gimbal_angle_nearest_turn(double principal, double measured);

#ifdef __cplusplus
}
#endif
#endif
