#include "gimbal_kernel/pointing.h"

#include <math.h>

/* The order of every operation is kinematics.py's (numpy evaluates elementwise in the written
 * order; its sums over three components are left to right). */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

void gimbal_inertial_to_base(const double vector[3], const double attitude[3], double out[3]) {
    double x = vector[0], y = vector[1], z = vector[2];
    double c = cos(attitude[0]), s = sin(attitude[0]);
    const double y1 = c * y + s * z, z1 = -s * y + c * z;
    y = y1, z = z1;
    c = cos(attitude[1]), s = sin(attitude[1]);
    const double x2 = c * x + s * y, y2 = -s * x + c * y;
    x = x2, y = y2;
    c = cos(attitude[2]), s = sin(attitude[2]);
    out[0] = c * x - s * z, out[1] = y, out[2] = s * x + c * z;
}

/* The carrier's inertial angular velocity in frame 0 and its derivative from the Euler angles'
 * rates and accelerations (docs/physics.md (2.13); kinematics.carrier_rate_and_acceleration). */
static void carrier_rate(const double attitude[3], const double rates[3], const double accelerations[3], double w[3],
                         double w_dot[3]) {
    const double psi = attitude[1], gamma = attitude[2];
    const double d1 = rates[0], p1 = rates[1], g1 = rates[2];
    const double d2 = accelerations[0], p2 = accelerations[1], g2 = accelerations[2];
    const double cp = cos(psi), sp = sin(psi), cg = cos(gamma), sg = sin(gamma);
    w[0] = d1 * cp * cg - p1 * sg;
    w[1] = -d1 * sp + g1;
    w[2] = d1 * cp * sg + p1 * cg;
    w_dot[0] = d2 * cp * cg - d1 * p1 * sp * cg - d1 * g1 * cp * sg - p2 * sg - p1 * g1 * cg;
    w_dot[1] = -d2 * sp - d1 * p1 * cp + g2;
    w_dot[2] = d2 * cp * sg - d1 * p1 * sp * sg + d1 * g1 * cp * cg + p2 * cg - p1 * g1 * sg;
}

/* u = p / r and its derivatives (kinematics.unit_and_derivatives): p = r u. 0 when p is no direction. */
static int unit_and_derivatives(const double p[3], const double p_dot[3], const double p_ddot[3], double* r,
                                double* r_dot, double u[3], double u_dot[3], double u_ddot[3]) {
    *r = sqrt(dot3(p, p));
    if (!(*r > 0.0) || !isfinite(*r)) return 0;
    for (int i = 0; i < 3; ++i) u[i] = p[i] / *r;
    *r_dot = dot3(u, p_dot);
    for (int i = 0; i < 3; ++i) u_dot[i] = (p_dot[i] - u[i] * *r_dot) / *r;
    const double r_ddot = dot3(u_dot, p_dot) + dot3(u, p_ddot);
    for (int i = 0; i < 3; ++i) u_ddot[i] = (p_ddot[i] - u[i] * r_ddot - 2.0 * u_dot[i] * *r_dot) / *r;
    return 1;
}

/* v = C u in frame 0 and its derivatives, with C = 0TG, C' = -[w x] C. */
static void in_base_frame(const double u[3], const double u_dot[3], const double u_ddot[3], const double attitude[3],
                          const double rates[3], const double accelerations[3], double v[3], double v_dot[3],
                          double v_ddot[3]) {
    double w[3], w_dot[3];
    carrier_rate(attitude, rates, accelerations, w, w_dot);
    double c_u_dot[3], c_u_ddot[3], w_v[3];
    gimbal_inertial_to_base(u, attitude, v);
    gimbal_inertial_to_base(u_dot, attitude, c_u_dot);
    cross3(w, v, w_v);
    for (int i = 0; i < 3; ++i) v_dot[i] = c_u_dot[i] - w_v[i];
    gimbal_inertial_to_base(u_ddot, attitude, c_u_ddot);
    double w_dot_v[3], w_v_dot[3], w_c_u_dot[3];
    cross3(w_dot, v, w_dot_v);
    cross3(w, v_dot, w_v_dot);
    cross3(w, c_u_dot, w_c_u_dot);
    for (int i = 0; i < 3; ++i) v_ddot[i] = c_u_ddot[i] - w_dot_v[i] - w_v_dot[i] - w_c_u_dot[i];
}

/* The angles alpha, beta of direction v and their first two derivatives; 0 when v is on the axis. */
static int angles_of(const double v[3], const double v_dot[3], const double v_ddot[3], GimbalPointing* out) {
    const double x = v[0], y = v[1], z = v[2];
    const double x1 = v_dot[0], y1 = v_dot[1], z1 = v_dot[2];
    const double x2 = v_ddot[0], y2 = v_ddot[1], z2 = v_ddot[2];
    const double rho2 = x * x + y * y;
    if (!(rho2 > 0.0)) return 0;
    const double rho = sqrt(rho2);
    out->alpha = atan2(-x, y);
    out->beta = atan2(z, rho);
    const double n = x * y1 - x1 * y;
    const double rho2_dot = 2.0 * (x * x1 + y * y1);
    out->alpha_dot = n / rho2;
    out->alpha_ddot = (x * y2 - x2 * y) / rho2 - n * rho2_dot / (rho2 * rho2);
    const double rho_dot = (x * x1 + y * y1) / rho;
    const double rho_ddot = (x1 * x1 + y1 * y1 + x * x2 + y * y2 - rho_dot * rho_dot) / rho;
    const double s2 = rho2 + z * z;
    const double s2_dot = rho2_dot + 2.0 * z * z1;
    const double m = rho * z1 - z * rho_dot;
    out->beta_dot = m / s2;
    out->beta_ddot = (rho * z2 - z * rho_ddot) / s2 - m * s2_dot / (s2 * s2);
    return 1;
}

int gimbal_pointing_command(const double p[3], const double p_dot[3], const double p_ddot[3], const double attitude[3],
                            const double rates[3], const double accelerations[3], GimbalPointing* command) {
    double r, r_dot, u[3], u_dot[3], u_ddot[3];
    if (!unit_and_derivatives(p, p_dot, p_ddot, &r, &r_dot, u, u_dot, u_ddot)) return GIMBAL_POINTING_AT_THE_GIMBAL;
    double v[3], v_dot[3], v_ddot[3];
    in_base_frame(u, u_dot, u_ddot, attitude, rates, accelerations, v, v_dot, v_ddot);
    GimbalPointing out;
    if (!angles_of(v, v_dot, v_ddot, &out)) return GIMBAL_POINTING_ON_THE_AXIS;

    /* the line of sight's inertial rate u x u' (in G), in frame 2 = Rx(beta)^T Rz(alpha)^T 0TG */
    double rate_g[3], rate_0[3];
    cross3(u, u_dot, rate_g);
    gimbal_inertial_to_base(rate_g, attitude, rate_0);
    const double ca = cos(out.alpha), sa = sin(out.alpha), cb = cos(out.beta), sb = sin(out.beta);
    const double r1[3] = {ca * rate_0[0] + sa * rate_0[1], -sa * rate_0[0] + ca * rate_0[1], rate_0[2]};
    out.los_rate[0] = r1[0];
    out.los_rate[1] = cb * r1[1] + sb * r1[2];
    out.los_rate[2] = -sb * r1[1] + cb * r1[2];
    out.range = r, out.range_rate = r_dot;
    *command = out;
    return GIMBAL_POINTING_OK;
}
