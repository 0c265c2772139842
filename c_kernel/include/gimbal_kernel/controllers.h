/* The built-in controllers of the scene runner (scenes' [controller] type none, pid, state_feedback;
 * replay for measuring the FMU alone), one implementation for every loop that runs them: the
 * compiled loop (master_loop.c), the Python loop through ctypes (gimbal2axis/scene/controllers.py), the
 * benchmark driver and the C scene driver.
 *
 * Called once per communication point with the measurements at t_k (after the sensors) and the set
 * points; returns the voltages (u_R1, u_R2), saturated at +-u_limit like a DAC (the values before
 * the saturation in `asked`). Axis 0 is the azimuth
 * (alpha, motor 1), axis 1 the elevation (beta, motor 2). Every operation and its order is fixed
 * (Python's min/max semantics, sums in order; built with -ffp-contract=off): results keep the bits
 * they were recorded with (tests/package/golden), whichever loop runs them. */
#ifndef GIMBAL_KERNEL_CONTROLLERS_H
#define GIMBAL_KERNEL_CONTROLLERS_H

#include "gimbal_kernel/layout.h"

/* One axis of the PID: u = kp e + ki int(e) + kd de/dt - k_gyro w + k_ff r_dot, de/dt a backward
 * difference through a first-order filter (time constant d_filter_s); anti-windup: the integral
 * stops while the output is saturated in the direction of e, and ki int(e) stays within +-i_limit.
 * With set points that carry accelerations (a moving target), + k_acc r_ddot after the other terms. */
#define GIMBAL_AXIS_PID_FIELDS(FIELD, ARRAY)                                                       \
    FIELD(double, kp, double) FIELD(double, ki, double) FIELD(double, kd, double)                  \
    FIELD(double, k_gyro, double) FIELD(double, k_ff, double) FIELD(double, d_filter_s, double)    \
    FIELD(double, i_limit, double) FIELD(double, u_limit, double) FIELD(double, k_acc, double)     \
    FIELD(double, integral, double) FIELD(double, e_prev, double) FIELD(double, derivative, double) \
    FIELD(int, has_prev, int) FIELD(int, saturated, int)
GIMBAL_STRUCT(GimbalAxisPid, GIMBAL_AXIS_PID_FIELDS)

/* The set points of a whole run, computed before it (gimbal2axis/scene/setpoints.py): row k of values and
 * rates, (n + 1) x 2. An axis with unwrap takes the 2 pi branch of its value nearest the measured
 * angle (the azimuth to a target: a gimbal that turned a full circle keeps tracking).
 * A moving target (gimbal2axis/target) adds, (n + 1) x 2 each, NULL otherwise: accelerations, the
 * set points' second derivatives (fed forward by the PID's k_acc), and gyro_rates, the payload's
 * inertial rate on track about the elevation axis x2 and the cross-elevation axis z2 (what
 * los.omega[1] and los.omega[3] read when the line of sight follows the target): the gyro terms
 * then act on the rate's departure from it, not on the rate itself. */
#define GIMBAL_SET_POINTS_FIELDS(FIELD, ARRAY)                                                        \
    FIELD(const double*, values, pointer) FIELD(const double*, rates, pointer) ARRAY(int, unwrap, int, 2) \
    FIELD(const double*, accelerations, pointer) FIELD(const double*, gyro_rates, pointer)
GIMBAL_STRUCT(GimbalSetPoints, GIMBAL_SET_POINTS_FIELDS)

/* kind: gimbal_controller_kind(name). State feedback: u = -K x + ki int(reference - angle),
 * x = (alpha - r1, beta - r2, w_az, w_el), gain row-major 2 x 4; rates from the gyro or, with
 * rate_from_encoder, backward differences of the encoder angles. */
#define GIMBAL_CONTROLLER_FIELDS(FIELD, ARRAY)                                                        \
    FIELD(int, kind, int) ARRAY(double, voltage, double, 2) ARRAY(double, u_limit, double, 2)         \
    ARRAY(GimbalAxisPid, axis, GimbalAxisPid, 2)                                                      \
    ARRAY(double, gain, double, 8) ARRAY(double, state_ki, double, 2)                                 \
    ARRAY(double, state_integral, double, 2) ARRAY(double, prev_angle, double, 2)                     \
    FIELD(int, rate_from_encoder, int) FIELD(int, has_prev_angle, int)                                \
    FIELD(const double*, replayed, pointer) /* replay: (n + 1) x 2 voltages */                        \
    FIELD(GimbalSetPoints, set_points, GimbalSetPoints)                                               \
    /* the last step's voltages before the clamp to +-u_limit (u itself where nothing clamps): */     \
    /* what the controller asked, recorded beside u so that a run can count and report the clamp */  \
    ARRAY(double, asked, double, 2)
GIMBAL_STRUCT(GimbalController, GIMBAL_CONTROLLER_FIELDS)

#ifdef __cplusplus
extern "C" {
#endif

/* The kind's code for its name in a scene ("none", "pid", "state_feedback", "replay"); -1 for others. */
int gimbal_controller_kind(const char* name);

/* The voltages u at communication point k (step h) from measured = (alpha, beta, gyro[3]).
 * set_point = (r1, r2, r1_dot, r2_dot), or NULL: row k of the controller's set_points. The set
 * points used go to reference (untouched for none and replay, which have none). */
void gimbal_controller_step(GimbalController* controller, long k, double h, const double measured[5],
                            const double* set_point, double u[2], double reference[2]);

/* The step of a controller toward a moving target whose set points come one row at a time (the
 * controller FMU's pointing command, gimbal_kernel/pointing.h): set_point (r1, r2, r1_dot, r2_dot)
 * as in gimbal_controller_step, accelerations (r1_ddot, r2_ddot) fed forward by the PID's k_acc, and
 * on_track, the payload's inertial rate on track about x2 and z2, which the gyro terms act on the
 * departure from (GimbalSetPoints says the same of a whole run's rows). Kinds none and replay step
 * as gimbal_controller_step does at communication point 0. */
void gimbal_controller_track(GimbalController* controller, double h, const double measured[5],
                             const double set_point[4], const double accelerations[2], const double on_track[2],
                             double u[2], double reference[2]);

#ifdef __cplusplus
}
#endif
#endif
