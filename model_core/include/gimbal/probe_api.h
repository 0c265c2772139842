/* Test hook into the dynamics core, built as libgimbal_probe.so (never part of the FMU).
 * It lets the Python tests evaluate J(q) and f(q, qd, base motion) of MODEL.md section 2
 * directly, so they can be compared with an independent symbolic derivation. */
#ifndef GIMBAL_PROBE_API_H
#define GIMBAL_PROBE_API_H

#ifdef __cplusplus
extern "C" {
#endif

/* Bodies are ordered as the generalized coordinates q = [alpha, alpha_m, beta, beta_m]:
 * index 0 = body 1 (azimuth housing), 1 = rotor R1, 2 = body 2 (elevation payload), 3 = rotor R2. */
typedef struct GimbalProbeRigidBodyInput {
    double mass[4];            /* kg */
    double inertia[4][6];      /* I_xx, I_yy, I_zz, I_xy, I_xz, I_yz about the centre of mass, own frame, kg.m2 */
    double com[4][3];          /* d_bc (frame 1), d_be (frame R1), d_bd (frame 2), d_bf (frame R2), m */
    double d_ab[3];            /* frame 0, m */
    double g;                  /* m/s2 */
    double q[4];               /* rad */
    double qd[4];              /* rad/s */
    double attitude[3];        /* delta (pitch), psi (yaw), gamma (roll), rad */
    double attitude_rate[3];   /* rad/s */
    double attitude_accel[3];  /* rad/s2 */
    double v_a[3];             /* velocity of point a, G coordinates, m/s */
    double a_a[3];             /* acceleration of point a, G coordinates, m/s2 */
} GimbalProbeRigidBodyInput;

/* Writes J (row-major 4x4) and f (4) such that J qdd = Xi + f. Returns 0 on success. */
int gimbal_probe_mass_matrix_and_bias(const GimbalProbeRigidBodyInput* input, double J_row_major[16], double f[4]);

#ifdef __cplusplus
}
#endif
#endif
