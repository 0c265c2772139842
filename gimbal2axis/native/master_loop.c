/* The scene runner's communication loop for the built-in controllers (none, PID, state feedback),
 * compiled: the same arithmetic as the Python loop (master.py step_loop with controllers.py),
 * operation for operation, so that both give the same bits; the tests check it.
 *
 * Why it exists: the FMU takes about 8-10 us per 1 ms step of the ship scene; the Python loop with
 * a PID added 3-6 us of its own (interpreter, ctypes), this one adds a fraction of a microsecond.
 * User controllers (type "python") keep the Python loop.
 *
 * Called through ctypes with one struct (MasterLoop, mirrored in compiled_loop.py) and a step range,
 * in chunks, so that Python can show progress and take Ctrl-C between them. The set points of the
 * whole run are computed before, vectorised (setpoints.py); the sensor noise is drawn before too.
 * Build with -ffp-contract=off: a fused multiply-add would give other bits than Python.
 */
#include <math.h>
#include <stddef.h>

typedef int (*ArrayCall)(void* component, const unsigned* refs, size_t count, void* values);
typedef int (*DoStepCall)(void* component, double t, double h, int no_set_prior_state);

enum { kNone = 0, kPid = 1, kStateFeedback = 2, kReplay = 3 };
enum { kFailedNothing = 0, kFailedGetReal = 1, kFailedGetInteger = 2, kFailedSetReal = 3, kFailedDoStep = 4 };

typedef struct {
    double kp, ki, kd, k_gyro, k_ff, d_filter_s, i_limit, u_limit;
    double integral, e_prev, derivative;
    int has_prev, saturated;
} AxisPid;

typedef struct {
    /* the FMU */
    void* component;
    ArrayCall get_real, get_integer, set_real;
    DoStepCall do_step;
    const unsigned *real_vrs, *mode_vrs, *input_vrs;
    long real_count, mode_count, input_count;
    /* records: row k of each, row-major */
    double* rec_real;
    int* rec_mode;
    double* inputs;       /* row k: u_R1, u_R2 (written here), then the base inputs (written before) */
    double* u_cmd;        /* (n + 1) x 2: the controller's outputs */
    double* refs;         /* (n + 1) x 2: the set points, for the record (nan without) */
    double h;
    long n, delay;
    long i_alpha, i_beta, i_gyro[3];
    /* sensors */
    double encoder_resolution;   /* rad; 0: exact */
    const double* gyro_noise;    /* (n + 1) x 3 or NULL */
    /* set points: principal values and rates, (n + 1) x 2; an axis with unwrap[axis] takes the 2 pi
       branch nearest the measured angle (the azimuth to a target) */
    const double* setpoint;
    const double* setpoint_rate;
    int unwrap[2];
    /* controller */
    int kind;
    double voltage[2], u_limit[2];
    AxisPid axis[2];
    double gain[2][4], state_ki[2], state_integral[2], prev_angle[2];
    int rate_from_encoder, has_prev_angle;
    const double* replayed;      /* (n + 1) x 2 voltages of kReplay */
    /* progress */
    long failed_step;
    int failed_call;
} MasterLoop;

static const double kTwoPi = 2.0 * 3.14159265358979311599796346854;  /* 2 * math.pi */

/* Python's max(a, b) and min(a, b): the first unless the second is strictly beyond it. */
static double py_max(double a, double b) { return b > a ? b : a; }
static double py_min(double a, double b) { return b < a ? b : a; }

static double axis_pid(AxisPid* p, double e, double rate, double h, double ref_rate) {
    if (p->has_prev) {
        const double raw = (e - p->e_prev) / h;
        p->derivative += (h / (p->d_filter_s + h)) * (raw - p->derivative);
    }
    p->e_prev = e, p->has_prev = 1;
    if (p->ki != 0.0 && !((double)p->saturated * e > 0.0)) {
        p->integral += e * h;
        if (fabs(p->ki * p->integral) > p->i_limit) p->integral = copysign(p->i_limit / fabs(p->ki), p->integral);
    }
    const double u = p->kp * e + p->ki * p->integral + p->kd * p->derivative - p->k_gyro * rate + p->k_ff * ref_rate;
    p->saturated = u > p->u_limit ? 1 : (u < -p->u_limit ? -1 : 0);
    return py_min(py_max(u, -p->u_limit), p->u_limit);
}

static double set_point(const MasterLoop* m, long k, int axis, double measured) {
    const double principal = m->setpoint[2 * k + axis];
    if (!m->unwrap[axis]) return principal;
    return principal + kTwoPi * nearbyint((measured - principal) / kTwoPi);
}

static void controller(MasterLoop* m, long k, double alpha, double beta, const double gyro[3], double u[2]) {
    double* ref = m->refs + 2 * k;
    if (m->kind == kNone) {
        u[0] = m->voltage[0], u[1] = m->voltage[1];
        return;
    }
    if (m->kind == kReplay) {
        u[0] = m->replayed[2 * k], u[1] = m->replayed[2 * k + 1];
        return;
    }
    const double r1 = set_point(m, k, 0, alpha), r2 = set_point(m, k, 1, beta);
    ref[0] = r1, ref[1] = r2;
    double w_az = gyro[2] / py_max(cos(beta), 0.2), w_el = gyro[0];
    if (m->kind == kPid) {
        u[0] = axis_pid(&m->axis[0], r1 - alpha, w_az, m->h, m->setpoint_rate[2 * k]);
        u[1] = axis_pid(&m->axis[1], r2 - beta, w_el, m->h, m->setpoint_rate[2 * k + 1]);
        return;
    }
    if (m->rate_from_encoder) {
        if (m->has_prev_angle) {
            w_az = (alpha - m->prev_angle[0]) / m->h, w_el = (beta - m->prev_angle[1]) / m->h;
        } else {
            w_az = 0.0, w_el = 0.0;
        }
        m->prev_angle[0] = alpha, m->prev_angle[1] = beta, m->has_prev_angle = 1;
    }
    const double x[4] = {alpha - r1, beta - r2, w_az, w_el};
    for (int i = 0; i < 2; ++i) {
        double sum = 0.0;
        for (int j = 0; j < 4; ++j) sum = sum + m->gain[i][j] * x[j];
        const double v = -sum + m->state_ki[i] * m->state_integral[i];
        const double limited = py_min(py_max(v, -m->u_limit[i]), m->u_limit[i]);
        if (m->state_ki[i] != 0.0 && limited == v) m->state_integral[i] += -x[i] * m->h;
        u[i] = limited;
    }
}

/* Steps k = first .. last (inclusive; last <= n): the outputs at t_k, the sensors, the controller,
   and, before n, the delayed voltage and one doStep. 0 when done, else the failed call (the step in
   failed_step). */
int gimbal_master_loop(MasterLoop* m, long first, long last) {
    for (long k = first; k <= last; ++k) {
        m->failed_step = k;
        double* y = m->rec_real + k * m->real_count;
        if (m->get_real(m->component, m->real_vrs, (size_t)m->real_count, y) > 1) return m->failed_call = kFailedGetReal;
        if (m->mode_count &&
            m->get_integer(m->component, m->mode_vrs, (size_t)m->mode_count, m->rec_mode + k * m->mode_count) > 1)
            return m->failed_call = kFailedGetInteger;
        double alpha = y[m->i_alpha], beta = y[m->i_beta];
        if (m->encoder_resolution > 0.0) {
            alpha = m->encoder_resolution * nearbyint(alpha / m->encoder_resolution);
            beta = m->encoder_resolution * nearbyint(beta / m->encoder_resolution);
        }
        double gyro[3];
        for (int j = 0; j < 3; ++j)
            gyro[j] = m->gyro_noise ? y[m->i_gyro[j]] + m->gyro_noise[3 * k + j] : y[m->i_gyro[j]];
        double* u = m->u_cmd + 2 * k;
        controller(m, k, alpha, beta, gyro, u);
        if (k == m->n) break;
        double* row = m->inputs + k * m->input_count;
        if (m->delay == 0) {
            row[0] = u[0], row[1] = u[1];
        } else if (k >= m->delay) {
            row[0] = m->u_cmd[2 * (k - m->delay)], row[1] = m->u_cmd[2 * (k - m->delay) + 1];
        } else {
            row[0] = 0.0, row[1] = 0.0;
        }
        if (m->set_real(m->component, m->input_vrs, (size_t)m->input_count, row) > 1) return m->failed_call = kFailedSetReal;
        if (m->do_step(m->component, (double)k * m->h, m->h, 1) > 1) return m->failed_call = kFailedDoStep;
    }
    return kFailedNothing;
}

long gimbal_master_loop_struct_size(void) { return (long)sizeof(MasterLoop); }
