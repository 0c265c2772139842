#include "gimbal_kernel/sum_of_sines.h"

#include <math.h>
#include <stdlib.h>

void gimbal_sum_of_sines_weights(long components, const double* amplitude, const double* omega, double* weights) {
    for (long j = 0; j < components; ++j) {
        weights[j] = amplitude[j];
        weights[components + j] = amplitude[j] * omega[j];
        weights[2 * components + j] = -amplitude[j] * (omega[j] * omega[j]);
    }
}

long gimbal_sum_of_sines_rotation_doubles(long components) { return 2 * GIMBAL_SUM_OF_SINES_BLOCK * components; }

void gimbal_sum_of_sines_rotation(double h, long components, const double* omega, double* rotation) {
    const long block = GIMBAL_SUM_OF_SINES_BLOCK;
    double* rotation_cos = rotation;
    double* rotation_sin = rotation + block * components;
    for (long j = 0; j < components; ++j)
        for (long m = 0; m < block; ++m) {
            const double angle = ((double)m * h) * omega[j];
            rotation_cos[j * block + m] = cos(angle);
            rotation_sin[j * block + m] = sin(angle);
        }
}

void gimbal_sum_of_sines_rows(long first, long count, double t0, double h, long components, const double* omega,
                              const double* phase, const double* weights, const double* rotation, double* value,
                              double* rate, double* acceleration) {
    const long block = GIMBAL_SUM_OF_SINES_BLOCK;
    const double* rotation_cos = rotation;
    const double* rotation_sin = rotation + block * components;
    const double* value_weight = weights;
    const double* rate_weight = weights + components;
    const double* acceleration_weight = weights + 2 * components;
    const long end = first + count;
    for (long row = first; row < end;) {
        const long block_start = row - row % block;
        const long stop = block_start + block < end ? block_start + block : end;
        const double start = t0 + (double)block_start * h;
        double* q = value + (row - first);
        double* q_dot = rate + (row - first);
        double* q_ddot = acceleration + (row - first);
        for (long r = 0; r < stop - row; ++r) q[r] = q_dot[r] = q_ddot[r] = 0.0;
        for (long j = 0; j < components; ++j) {
            const double argument = omega[j] * start + phase[j];
            const double start_sin = sin(argument), start_cos = cos(argument);
            const double* c = rotation_cos + j * block + (row - block_start);
            const double* s = rotation_sin + j * block + (row - block_start);
            for (long r = 0; r < stop - row; ++r) {
                const double row_sin = start_sin * c[r] + start_cos * s[r];
                const double row_cos = start_cos * c[r] - start_sin * s[r];
                q[r] += value_weight[j] * row_sin;
                q_dot[r] += rate_weight[j] * row_cos;
                q_ddot[r] += acceleration_weight[j] * row_sin;
            }
        }
        row = stop;
    }
}

int gimbal_sum_of_sines(long rows, double t0, double h, long components, const double* omega, const double* phase,
                        const double* weights, double* value, double* rate, double* acceleration) {
    double* rotation = malloc(sizeof(double) * (size_t)gimbal_sum_of_sines_rotation_doubles(components > 0 ? components : 1));
    if (rotation == NULL) return -1;
    gimbal_sum_of_sines_rotation(h, components, omega, rotation);
    gimbal_sum_of_sines_rows(0, rows, t0, h, components, omega, phase, weights, rotation, value, rate, acceleration);
    free(rotation);
    return 0;
}
