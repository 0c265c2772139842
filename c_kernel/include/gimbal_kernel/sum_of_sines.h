/* Sums of sinusoids on a uniform time grid, with their first two derivatives, for the base
 * motions (sinusoids, sea state) of the scene runner and of the benchmark and scene drivers:
 *     q(t_k) = sum_j A_j sin(w_j t_k + phi_j),  q' = sum_j A_j w_j cos(...),  q'' = -sum_j A_j w_j^2 sin(...)
 * for t_k = t0 + k h.
 *
 * Per block of GIMBAL_SUM_OF_SINES_BLOCK rows, sin and cos of each component at the block's start
 * (libm), turned to the rows inside it by the rotation (cos, sin)(w_j m h), m < BLOCK (tabulated once
 * per grid): a few multiply-adds per component and row instead of a sin and a cos. Blocks start at
 * multiples of BLOCK rows from t0, so a row's value depends only on its index: a shortened run, or
 * rows asked for a few at a time, give the same bits as the whole grid. The sums run over j in order
 * (no reassociation: -ffp-contract=off and no -ffast-math), so the bits do not depend on threads. */
#ifndef GIMBAL_KERNEL_SUM_OF_SINES_H
#define GIMBAL_KERNEL_SUM_OF_SINES_H

enum { GIMBAL_SUM_OF_SINES_BLOCK = 128 };

#ifdef __cplusplus
extern "C" {
#endif

/* The weights of value, rate and acceleration per component, 3 x components: A, A w, -A w^2. */
void gimbal_sum_of_sines_weights(long components, const double* amplitude, const double* omega, double* weights);

/* How many doubles the rotation table of `components` sinusoids takes: 2 x BLOCK x components. */
long gimbal_sum_of_sines_rotation_doubles(long components);

/* The rotation table of a grid of step h into `rotation` (gimbal_sum_of_sines_rotation_doubles). */
void gimbal_sum_of_sines_rotation(double h, long components, const double* omega, double* rotation);

/* Rows first .. first + count - 1 of the grid (value[0] is row `first`), with the grid's rotation table. */
void gimbal_sum_of_sines_rows(long first, long count, double t0, double h, long components, const double* omega,
                              const double* phase, const double* weights, const double* rotation, double* value,
                              double* rate, double* acceleration);

/* Rows 0 .. rows - 1 of the grid; 0, or -1 when the rotation table could not be allocated. */
int gimbal_sum_of_sines(long rows, double t0, double h, long components, const double* omega, const double* phase,
                        const double* weights, double* value, double* rate, double* acceleration);

#ifdef __cplusplus
}
#endif
#endif
