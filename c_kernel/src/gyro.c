#include "gimbal_kernel/gyro.h"

#include <math.h>
#include <stddef.h>

static void filter_sample(GimbalGyro* g, long k, double sensed[3]) {
    const double* a = g->filter_a;
    for (int axis = 0; axis < 3; ++axis) {
        double* x = g->filter_state + 2 * axis;
        const double u = sensed[axis];
        if (k == 0) x[0] = g->filter_settled[0] * u, x[1] = g->filter_settled[1] * u;
        const double y = g->filter_c[0] * x[0] + g->filter_c[1] * x[1] + g->filter_d * u;
        const double x0 = a[0] * x[0] + a[1] * x[1] + g->filter_b[0] * u;
        const double x1 = a[2] * x[0] + a[3] * x[1] + g->filter_b[1] * u;
        x[0] = x0, x[1] = x1;
        sensed[axis] = y;
    }
}

static void delay_sample(GimbalGyro* g, long k, double value[3]) {
    const long slots = g->delay + 1;
    double* history = g->history;
    if (k == 0)
        for (long slot = 0; slot < slots; ++slot)
            for (int axis = 0; axis < 3; ++axis) history[3 * slot + axis] = value[axis];
    double* newest = history + 3 * (k % slots);
    for (int axis = 0; axis < 3; ++axis) newest[axis] = value[axis];
    /* the slot written `delay` samples ago is the one after the newest: the ring's oldest */
    const double* oldest = history + 3 * ((k + 1) % slots);
    for (int axis = 0; axis < 3; ++axis) value[axis] = oldest[axis];
}

void gimbal_gyro_measure(GimbalGyro* g, long k, const double rate[3], double out[3]) {
    if (!g->enabled) {
        for (int axis = 0; axis < 3; ++axis) out[axis] = rate[axis];
        return;
    }
    const double* m = g->axes;
    double sensed[3] = {m[0] * rate[0] + m[1] * rate[1] + m[2] * rate[2],
                        m[3] * rate[0] + m[4] * rate[1] + m[5] * rate[2],
                        m[6] * rate[0] + m[7] * rate[1] + m[8] * rate[2]};
    if (g->filtered) filter_sample(g, k, sensed);
    if (g->error != NULL)
        for (int axis = 0; axis < 3; ++axis) sensed[axis] += g->error[3 * k + axis];
    if (g->quantum > 0.0)
        for (int axis = 0; axis < 3; ++axis) sensed[axis] = g->quantum * nearbyint(sensed[axis] / g->quantum);
    if (g->delay > 0) delay_sample(g, k, sensed);
    for (int axis = 0; axis < 3; ++axis) out[axis] = sensed[axis];
}

void gimbal_gyro_series(GimbalGyro* g, long count, const double* rates, double* out) {
    for (long k = 0; k < count; ++k) gimbal_gyro_measure(g, k, rates + 3 * k, out + 3 * k);
}
