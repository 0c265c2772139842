/* The pointing command toward a moving target (docs/physics.md, section 9): the gimbal angles that
 * point the line of sight at the target from the moving carrier, their rates and accelerations (the
 * built-in controllers' set points and feed-forward), and the line of sight's inertial rate on track
 * (what the payload gyro reads when the line of sight follows the target). The controller FMU computes
 * it once per communication point from its target inputs; the scene runner's numpy form
 * (gimbal2axis/target/kinematics.py, vectorised over a run) is the same arithmetic in the same order,
 * and tests/c_kernel/test_pointing_kernel.py holds the two together.
 *
 * Frames: G with z up; the base attitude 0TG = Ry(-gamma) Rz(-psi) Rx(-delta); the line of sight the
 * y axis of body 2, Rz(alpha) Rx(beta) [0, 1, 0] in frame 0. From the target's position relative to
 * the gimbal in G and its first two time derivatives: u = p / |p| and its derivatives, v = 0TG u with
 * v' = 0TG u' - w x v (w the carrier's inertial angular velocity in frame 0), alpha = atan2(-v_x, v_y),
 * beta = atan2(v_z, hypot(v_x, v_y)). Singular on the azimuth axis (v_x = v_y = 0, the keyhole), where
 * alpha' is unbounded. */
#ifndef GIMBAL_KERNEL_POINTING_H
#define GIMBAL_KERNEL_POINTING_H

typedef struct {
    double alpha, beta;            /* principal: alpha in (-pi, pi], |beta| <= pi/2 [rad] */
    double alpha_dot, beta_dot;    /* [rad/s] */
    double alpha_ddot, beta_ddot;  /* [rad/s2] */
    double los_rate[3];            /* [rad/s] in frame 2: about x2 (elevation axis), y2 (the line of sight), z2 */
    double range, range_rate;      /* |p| [m] and its rate [m/s] */
} GimbalPointing;

/* What gimbal_pointing_command says. */
enum {
    GIMBAL_POINTING_OK = 0,
    GIMBAL_POINTING_AT_THE_GIMBAL = 1,  /* |p| = 0 (or not finite): no direction */
    GIMBAL_POINTING_ON_THE_AXIS = 2     /* the target exactly on the azimuth axis: alpha undefined */
};

#ifdef __cplusplus
extern "C" {
#endif

/* 0TG vector = Ry(-gamma) Rz(-psi) Rx(-delta) vector: a vector in G in the carrier's frame 0 for the
 * base attitude (delta, psi, gamma) (kinematics.inertial_to_base; the fixed target's set points too). */
void gimbal_inertial_to_base(const double vector[3], const double attitude[3], double out[3]);

/* The command toward the target at p [m], p' [m/s], p'' [m/s2] (in G, relative to the gimbal) for the
 * base attitude (delta, psi, gamma) [rad], its rates and accelerations; `command` is written only when
 * GIMBAL_POINTING_OK. */
int gimbal_pointing_command(const double p[3], const double p_dot[3], const double p_ddot[3], const double attitude[3],
                            const double rates[3], const double accelerations[3], GimbalPointing* command);

#ifdef __cplusplus
}
#endif
#endif
