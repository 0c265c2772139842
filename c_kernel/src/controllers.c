#include "gimbal_kernel/controllers.h"

#include <math.h>
#include <string.h>

#include "gimbal_kernel/set_points.h"

enum { kNone = 0, kPid = 1, kStateFeedback = 2, kReplay = 3 };

/* Python's max(a, b) and min(a, b), whose bits these controllers keep: the first unless the second
   is strictly beyond it. */
static double py_max(double a, double b) { return b > a ? b : a; }
static double py_min(double a, double b) { return b < a ? b : a; }

int gimbal_controller_kind(const char* name) {
    static const char* const kNames[] = {"none", "pid", "state_feedback", "replay"};
    for (int kind = 0; kind < 4; ++kind)
        if (strcmp(name, kNames[kind]) == 0) return kind;
    return -1;
}

/* The axis' voltage, clamped to +-u_limit; the value before the clamp goes to *asked. */
static double axis_pid(GimbalAxisPid* p, double e, double rate, double h, double ref_rate,
                       const double* ref_acceleration, double* asked) {
    if (p->has_prev) {
        const double raw = (e - p->e_prev) / h;
        p->derivative += (h / (p->d_filter_s + h)) * (raw - p->derivative);
    }
    p->e_prev = e, p->has_prev = 1;
    if (p->ki != 0.0 && !((double)p->saturated * e > 0.0)) {
        p->integral += e * h;
        if (fabs(p->ki * p->integral) > p->i_limit) p->integral = copysign(p->i_limit / fabs(p->ki), p->integral);
    }
    double u = p->kp * e + p->ki * p->integral + p->kd * p->derivative - p->k_gyro * rate + p->k_ff * ref_rate;
    if (ref_acceleration != NULL) u = u + p->k_acc * *ref_acceleration; /* a moving target's set points only */
    p->saturated = u > p->u_limit ? 1 : (u < -p->u_limit ? -1 : 0);
    *asked = u;
    return py_min(py_max(u, -p->u_limit), p->u_limit);
}

static double prepared_set_point(const GimbalSetPoints* points, long k, int axis, double measured) {
    const double principal = points->values[2 * k + axis];
    return points->unwrap[axis] ? gimbal_angle_nearest_turn(principal, measured) : principal;
}

static void state_feedback(GimbalController* c, double h, double alpha, double beta, double w_az, double w_el,
                           const double r[2], double u[2]) {
    if (c->rate_from_encoder) {
        if (c->has_prev_angle) {
            w_az = (alpha - c->prev_angle[0]) / h, w_el = (beta - c->prev_angle[1]) / h;
        } else {
            w_az = 0.0, w_el = 0.0;
        }
        c->prev_angle[0] = alpha, c->prev_angle[1] = beta, c->has_prev_angle = 1;
    }
    const double x[4] = {alpha - r[0], beta - r[1], w_az, w_el};
    for (int i = 0; i < 2; ++i) {
        double sum = 0.0;
        for (int j = 0; j < 4; ++j) sum = sum + c->gain[4 * i + j] * x[j];
        const double v = -sum + c->state_ki[i] * c->state_integral[i];
        const double limited = py_min(py_max(v, -c->u_limit[i]), c->u_limit[i]);
        c->asked[i] = v;
        if (c->state_ki[i] != 0.0 && limited == v) c->state_integral[i] += -x[i] * h; /* only when unsaturated */
        u[i] = limited;
    }
}

/* The PID or state feedback toward the set points r, their rates, and with a moving target their
 * accelerations and the gyro's rates on track (NULL otherwise). */
static void control(GimbalController* c, double h, const double measured[5], const double r[2], const double r_dot[2],
                    const double* r_ddot, const double* on_track, double u[2], double reference[2]) {
    const double alpha = measured[0], beta = measured[1];
    reference[0] = r[0], reference[1] = r[1];
    /* The payload gyro gives the inertial rate about the elevation axis (gyro[0]) and the
       cross-elevation rate (gyro[2]); divided by cos(beta), the azimuth rate that moves the line of
       sight (secant correction, bounded near the zenith). */
    double w_az = measured[4] / py_max(cos(beta), 0.2), w_el = measured[2];
    if (on_track != NULL) { /* tracking: the departure from the line of sight's rate on track */
        w_az = (measured[4] - on_track[1]) / py_max(cos(beta), 0.2), w_el = measured[2] - on_track[0];
    }
    if (c->kind == kPid) {
        u[0] = axis_pid(&c->axis[0], r[0] - alpha, w_az, h, r_dot[0], r_ddot, &c->asked[0]);
        u[1] = axis_pid(&c->axis[1], r[1] - beta, w_el, h, r_dot[1], r_ddot == NULL ? NULL : r_ddot + 1, &c->asked[1]);
        return;
    }
    state_feedback(c, h, alpha, beta, w_az, w_el, r, u);
}

void gimbal_controller_step(GimbalController* c, long k, double h, const double measured[5], const double* set_point,
                            double u[2], double reference[2]) {
    if (c->kind == kNone) {
        u[0] = c->voltage[0], u[1] = c->voltage[1];
        c->asked[0] = u[0], c->asked[1] = u[1];
        return;
    }
    if (c->kind == kReplay) {
        u[0] = c->replayed[2 * k], u[1] = c->replayed[2 * k + 1];
        c->asked[0] = u[0], c->asked[1] = u[1];
        return;
    }
    const double alpha = measured[0];
    double r[2], r_dot[2];
    const double* r_ddot = NULL;     /* the set points' accelerations, with a moving target */
    const double* on_track = NULL;   /* the gyro's rates on track (x2, z2), with a moving target */
    if (set_point != NULL) {
        r[0] = set_point[0], r[1] = set_point[1], r_dot[0] = set_point[2], r_dot[1] = set_point[3];
    } else {
        r[0] = prepared_set_point(&c->set_points, k, 0, alpha), r[1] = prepared_set_point(&c->set_points, k, 1, measured[1]);
        r_dot[0] = c->set_points.rates[2 * k], r_dot[1] = c->set_points.rates[2 * k + 1];
        if (c->set_points.accelerations != NULL) r_ddot = c->set_points.accelerations + 2 * k;
        if (c->set_points.gyro_rates != NULL) on_track = c->set_points.gyro_rates + 2 * k;
    }
    control(c, h, measured, r, r_dot, r_ddot, on_track, u, reference);
}

void gimbal_controller_track(GimbalController* c, double h, const double measured[5], const double set_point[4],
                             const double accelerations[2], const double on_track[2], double u[2], double reference[2]) {
    if (c->kind != kPid && c->kind != kStateFeedback) {
        gimbal_controller_step(c, 0, h, measured, set_point, u, reference);
        return;
    }
    const double r[2] = {set_point[0], set_point[1]}, r_dot[2] = {set_point[2], set_point[3]};
    control(c, h, measured, r, r_dot, accelerations, on_track, u, reference);
}
