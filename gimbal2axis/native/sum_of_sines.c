/* The base motion's sums of sinusoids on a uniform time grid, with their first two derivatives:
 *     q(t_k) = sum_j A_j sin(w_j t_k + phi_j),  q' = sum_j A_j w_j cos(...),  q'' = -sum_j A_j w_j^2 sin(...)
 * for t_k = t0 + k h. Per block of `block` rows, sin and cos of each component at the block's start
 * (libm), turned to the rows inside it by the rotation (cos, sin)(w_j m h), m < block (tabulated once):
 * a few multiply-adds per component and row instead of a sin and a cos. Blocks start at multiples
 * of `block` rows from t0, so a row's value depends only on its index: a shortened run gives the
 * same bits as the full one. The sums run over j in order (no reassociation: -ffp-contract=off and
 * no -ffast-math), so the bits do not depend on threads or on how many rows are asked for.
 *
 * rotation: 2 * block * components doubles of scratch (the caller's).
 * weights: value, rate and acceleration weights per component (A, A w, -A w^2), 3 * components.
 */
#include <math.h>

void gimbal_sum_of_sines(long rows, double t0, double h, long components, const double* omega, const double* phase,
                         const double* weights, long block, double* rotation, double* value, double* rate,
                         double* acceleration) {
    double* rotation_cos = rotation;
    double* rotation_sin = rotation + block * components;
    for (long j = 0; j < components; ++j)
        for (long m = 0; m < block; ++m) {
            const double angle = ((double)m * h) * omega[j];
            rotation_cos[j * block + m] = cos(angle);
            rotation_sin[j * block + m] = sin(angle);
        }
    const double* value_weight = weights;
    const double* rate_weight = weights + components;
    const double* acceleration_weight = weights + 2 * components;
    for (long first = 0; first < rows; first += block) {
        const double start = t0 + (double)first * h;
        const long count = rows - first < block ? rows - first : block;
        for (long m = 0; m < count; ++m) value[first + m] = rate[first + m] = acceleration[first + m] = 0.0;
        for (long j = 0; j < components; ++j) {
            const double argument = omega[j] * start + phase[j];
            const double start_sin = sin(argument), start_cos = cos(argument);
            for (long m = 0; m < count; ++m) {
                const double c = rotation_cos[j * block + m], s = rotation_sin[j * block + m];
                const double row_sin = start_sin * c + start_cos * s;
                const double row_cos = start_cos * c - start_sin * s;
                value[first + m] += value_weight[j] * row_sin;
                rate[first + m] += rate_weight[j] * row_cos;
                acceleration[first + m] += acceleration_weight[j] * row_sin;
            }
        }
    }
}
