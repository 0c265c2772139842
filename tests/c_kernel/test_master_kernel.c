/* The C kernel as the native drivers link it (the static library gimbal_master_kernel, built by
 * CMake): values worked out by hand for the PID, the sensors and the state feedback, and the sums of
 * sinusoids asked for in pieces against the whole grid and the direct formula. tests/c_kernel/test_kernel.py
 * checks the same kernel as the Python extension builds it, against references of every term. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/gyro.h"
#include "gimbal_kernel/sensors.h"
#include "gimbal_kernel/sum_of_sines.h"

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
    GimbalSensors sensors = {0};
    sensors.encoder_resolution = 0.5, sensors.gyro_noise = noise;
    double measured[7] = {0.75, 0.25, 1.0, 2.0, 3.0, 7.0, 7.0};
    gimbal_sensors_measure(&sensors, 1, measured);
    /* 1.5 and 0.5 resolution steps round to the even neighbours 2 and 0 */
    CHECK(measured[0] == 1.0 && measured[1] == 0.0);
    CHECK(measured[2] == 1.125 && measured[3] == 1.5 && measured[4] == 4.0);
    /* an encoder offset is added before the quantization: 0.75 + 0.5 = 1.25 -> 1.0 (even), 0.25 - 0.5 -> -0.0 */
    sensors.encoder_offset[0] = 0.5, sensors.encoder_offset[1] = -0.5, sensors.gyro_noise = NULL;
    double offset[7] = {0.75, 0.25, 1.0, 2.0, 3.0, 0.0, 0.0};
    gimbal_sensors_measure(&sensors, 0, offset);
    CHECK(offset[0] == 1.0 && offset[1] == -0.0 && offset[2] == 1.0 && offset[4] == 3.0);
}

/* Indirect: a carrier turning at 1 rad/s about z0, the azimuth turned by pi/2 and the elevation by
 * pi/2 with joint rates 2 and 3: w1 = Rz(pi/2)^T [0, 0, 1] + [0, 0, 2] = [0, 0, 3];
 * w2 = Rx(pi/2)^T [0, 0, 3] + [3, 0, 0] = [3, 3, 0] (Rx(b)^T maps z1 to +y2 when b = pi/2). */
static void indirect_by_hand(void) {
    const double carrier[6] = {0.0, 0.0, 1.0, 1.0, 0.0, 0.0};
    GimbalSensors sensors = {0};
    sensors.indirect = 1, sensors.carrier_rate = carrier, sensors.h = 0.5;
    const double half_pi = 1.5707963267948966;
    double measured[7] = {half_pi, half_pi, 9.0, 9.0, 9.0, 2.0, 3.0};
    gimbal_sensors_measure(&sensors, 0, measured);
    CHECK(fabs(measured[2] - 3.0) < 1e-15 && fabs(measured[3] - 3.0) < 1e-15 && fabs(measured[4]) < 1e-15);
    /* row 1: the carrier turns about x0 at 1 rad/s; at a = b = 0 and no joint motion w2 = [1, 0, 0] */
    double level[7] = {0.0, 0.0, 9.0, 9.0, 9.0, 0.0, 0.0};
    gimbal_sensors_measure(&sensors, 1, level);
    CHECK(level[2] == 1.0 && level[3] == 0.0 && level[4] == 0.0);
    /* joint rates from the encoders: 0 at the first sample, then backward differences over h */
    sensors.joint_rate_from_encoders = 1;
    double first[7] = {0.0, 0.0, 9.0, 9.0, 9.0, 5.0, 5.0}, second[7] = {0.25, 0.5, 9.0, 9.0, 9.0, 5.0, 5.0};
    gimbal_sensors_measure(&sensors, 0, first);
    CHECK(fabs(first[2]) < 1e-15 && fabs(first[3]) < 1e-15 && fabs(first[4] - 1.0) < 1e-15);
    gimbal_sensors_measure(&sensors, 1, second);
    /* a' = 0.5, b' = 1: w1 = Rz(0.25)^T [1, 0, 0] + [0, 0, 0.5], w2 = Rx(0.5)^T w1 + [1, 0, 0] */
    const double w1x = cos(0.25), w1y = -sin(0.25), w1z = 0.5;
    CHECK(fabs(second[2] - (w1x + 1.0)) < 1e-15);
    CHECK(fabs(second[3] - (cos(0.5) * w1y + sin(0.5) * w1z)) < 1e-15);
    CHECK(fabs(second[4] - (-sin(0.5) * w1y + cos(0.5) * w1z)) < 1e-15);
}

/* The gyro's deterministic terms by hand: axes matrix, error table, quantization, delay line. */
static void gyro_by_hand(void) {
    GimbalGyro gyro = {0};
    gyro.enabled = 1;
    const double axes[9] = {1.5, 0.25, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0};
    for (int i = 0; i < 9; ++i) gyro.axes[i] = axes[i];
    const double error[12] = {0.125, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    gyro.error = error, gyro.quantum = 0.25, gyro.delay = 2;
    const double rates[9] = {1.0, 2.0, 3.0, 2.0, 0.0, 1.0, 0.0, 0.0, 0.0};
    double out[9];
    gimbal_gyro_series(&gyro, 3, rates, out);
    /* sample 0: [1.5 + 0.5 + 0.125, 2, -3] -> quantized [2.0 (2.125 -> 8.5 quanta -> 8), 2, -3]; held
     * through the delay line for samples 1 and 2 (the line starts full of the first sample) */
    for (int k = 0; k < 3; ++k) CHECK(out[3 * k] == 2.0 && out[3 * k + 1] == 2.0 && out[3 * k + 2] == -3.0);
    double more[3], zero[3] = {0.0, 0.0, 0.0};
    gimbal_gyro_measure(&gyro, 3, zero, more);   /* sample 1's value comes out: [3, 0, -1] */
    CHECK(more[0] == 3.0 && more[1] == 0.0 && more[2] == -1.0);
    /* a filter of unit DC gain starts settled: a constant rate comes out unchanged */
    GimbalGyro filtered = {0};
    filtered.enabled = 1, filtered.filtered = 1;
    filtered.axes[0] = filtered.axes[4] = filtered.axes[8] = 1.0;
    const double a[4] = {0.5, 0.25, -0.25, 0.5}, b[2] = {0.25, 0.75}, c[2] = {1.0, 0.0};
    for (int i = 0; i < 4; ++i) filtered.filter_a[i] = a[i];
    filtered.filter_b[0] = b[0], filtered.filter_b[1] = b[1], filtered.filter_c[0] = c[0], filtered.filter_c[1] = c[1];
    /* (I - A)^-1 B for this A, B: [[0.5, -0.25], [0.25, 0.5]]^-1 [0.25, 0.75] = [1, 1] (c x = 1) */
    filtered.filter_settled[0] = 1.0, filtered.filter_settled[1] = 1.0;
    const double steady[6] = {2.0, -4.0, 0.5, 2.0, -4.0, 0.5};
    double steady_out[6];
    gimbal_gyro_series(&filtered, 2, steady, steady_out);
    for (int i = 0; i < 6; ++i) CHECK(steady_out[i] == steady[i]);
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
    indirect_by_hand();
    gyro_by_hand();
    sums_of_sines();
    if (failures == 0) printf("master kernel: all checks passed\n");
    return failures == 0 ? 0 : 1;
}
