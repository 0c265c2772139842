/* The C kernel as the native drivers link it (the static library gimbal_master_kernel, built by
 * CMake): values worked out by hand for the PID, the sensors and the state feedback, and the sums of
 * sinusoids asked for in pieces against the whole grid and the direct formula. tests/test_kernel.py
 * checks the same kernel as the Python extension builds it, against references of every term. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "controllers.h"
#include "sensors.h"
#include "sum_of_sines.h"

static int failures = 0;
#define CHECK(condition)                                                  \
    do {                                                                  \
        if (!(condition)) {                                               \
            fprintf(stderr, "%s:%d: failed: %s\n", __FILE__, __LINE__, #condition); \
            ++failures;                                                   \
        }                                                                 \
    } while (0)

static void pid_by_hand(void) {
    /* kp = 2, ki = 10, kd = 0.5 (no filter), k_gyro = 0.25, k_ff = 1 on the azimuth, h = 0.5. */
    GimbalController c;
    memset(&c, 0, sizeof c);
    c.kind = gimbal_controller_kind("pid");
    GimbalAxisPid* axis = &c.axis[0];
    axis->kp = 2.0, axis->ki = 10.0, axis->kd = 0.5, axis->k_gyro = 0.25, axis->k_ff = 1.0;
    axis->i_limit = axis->u_limit = c.axis[1].i_limit = c.axis[1].u_limit = 100.0;
    double u[2], reference[2];
    /* step 0: e = 1, integral 0.5, no derivative yet, w_az = 2 / cos(0): 2 + 5 - 0.5 + 0.75 */
    const double measured0[5] = {0.0, 0.0, 0.0, 0.0, 2.0}, set_point0[4] = {1.0, 0.0, 0.75, 0.0};
    gimbal_controller_step(&c, 0, 0.5, measured0, set_point0, u, reference);
    CHECK(u[0] == 7.25 && u[1] == 0.0 && reference[0] == 1.0);
    /* step 1: e = 3, integral 2, derivative (3 - 1) / 0.5 = 4: 6 + 20 + 2 */
    const double measured1[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, set_point1[4] = {3.0, 0.0, 0.0, 0.0};
    gimbal_controller_step(&c, 1, 0.5, measured1, set_point1, u, reference);
    CHECK(u[0] == 28.0);
    /* saturated at +-u_limit, and the integral holds while the output pushes that way */
    axis->u_limit = 10.0;
    gimbal_controller_step(&c, 2, 0.5, measured1, set_point1, u, reference);
    CHECK(u[0] == 10.0 && axis->saturated == 1);
    const double integral = axis->integral;
    gimbal_controller_step(&c, 3, 0.5, measured1, set_point1, u, reference);
    CHECK(axis->integral == integral);
}

static void state_feedback_by_hand(void) {
    /* u = -K x + ki int(r - angle), x = (alpha - r1, beta - r2, w_az, w_el); rates from the encoder. */
    GimbalController c;
    memset(&c, 0, sizeof c);
    c.kind = gimbal_controller_kind("state_feedback");
    const double gain[8] = {10.0, 0.0, 1.0, 0.0, 0.0, 20.0, 0.0, 2.0};
    memcpy(c.gain, gain, sizeof gain);
    c.state_ki[0] = 4.0;
    c.u_limit[0] = c.u_limit[1] = 100.0;
    c.rate_from_encoder = 1;
    double u[2], reference[2];
    const double set_point[4] = {0.5, 0.25, 0.0, 0.0};
    const double at_rest[5] = {0.0, 0.0, 9.0, 9.0, 9.0}; /* the gyro is not read */
    gimbal_controller_step(&c, 0, 0.5, at_rest, set_point, u, reference);
    CHECK(u[0] == 5.0 && u[1] == 5.0 && c.state_integral[0] == 0.25); /* no rate yet; integral of 0.5 */
    const double moved[5] = {0.5, 0.0, 9.0, 9.0, 9.0};
    gimbal_controller_step(&c, 1, 0.5, moved, set_point, u, reference);
    CHECK(u[0] == 0.0 && u[1] == 5.0); /* -(0 + 1 * 1) + 4 * 0.25, w_az = 0.5 / 0.5; -(20 * -0.25) */
}

static void sensors_by_hand(void) {
    const double noise[6] = {0.0, 0.0, 0.0, 0.125, -0.5, 1.0};
    const GimbalSensors sensors = {0.5, noise};
    double measured[5] = {0.75, 0.25, 1.0, 2.0, 3.0};
    gimbal_sensors_measure(&sensors, 1, measured);
    /* 1.5 and 0.5 resolution steps round to the even neighbours 2 and 0 */
    CHECK(measured[0] == 1.0 && measured[1] == 0.0);
    CHECK(measured[2] == 1.125 && measured[3] == 1.5 && measured[4] == 4.0);
}

static void sums_of_sines(void) {
    enum { COMPONENTS = 3, ROWS = 700 };
    const double amplitude[COMPONENTS] = {0.3, 0.05, 1.2}, omega[COMPONENTS] = {0.7, 5.1, 2.2},
                 phase[COMPONENTS] = {0.1, 2.0, 4.0}, t0 = 0.5, h = 1e-3;
    double weights[3 * COMPONENTS], whole[3][ROWS], pieces[3][ROWS];
    static double rotation[2 * GIMBAL_SUM_OF_SINES_BLOCK * COMPONENTS];
    CHECK(gimbal_sum_of_sines_rotation_doubles(COMPONENTS) == 2 * GIMBAL_SUM_OF_SINES_BLOCK * COMPONENTS);
    gimbal_sum_of_sines_weights(COMPONENTS, amplitude, omega, weights);
    CHECK(gimbal_sum_of_sines(ROWS, t0, h, COMPONENTS, omega, phase, weights, whole[0], whole[1], whole[2]) == 0);
    gimbal_sum_of_sines_rotation(h, COMPONENTS, omega, rotation);
    for (long first = 0; first < ROWS; first += 45) {
        const long count = ROWS - first < 45 ? ROWS - first : 45;
        gimbal_sum_of_sines_rows(first, count, t0, h, COMPONENTS, omega, phase, weights, rotation, pieces[0] + first,
                                 pieces[1] + first, pieces[2] + first);
    }
    CHECK(memcmp(whole, pieces, sizeof whole) == 0);
    double worst = 0.0;
    for (long k = 0; k < ROWS; ++k) {
        double q = 0.0, q_dot = 0.0, q_ddot = 0.0;
        for (int j = 0; j < COMPONENTS; ++j) {
            const double argument = omega[j] * (t0 + k * h) + phase[j];
            q += amplitude[j] * sin(argument);
            q_dot += amplitude[j] * omega[j] * cos(argument);
            q_ddot -= amplitude[j] * omega[j] * omega[j] * sin(argument);
        }
        worst = fmax(worst, fmax(fabs(q - whole[0][k]), fmax(fabs(q_dot - whole[1][k]), fabs(q_ddot - whole[2][k]))));
    }
    CHECK(worst < 1e-13);
}

int main(void) {
    pid_by_hand();
    state_feedback_by_hand();
    sensors_by_hand();
    sums_of_sines();
    if (failures == 0) printf("master kernel: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
