/* The C2 cubic spline through samples (x_i, y_i) with scipy's default boundary condition,
 * 'not-a-knot' at both ends (the third derivative continuous at x_1 and x_{n-2}): the recorded base
 * motion's interpolant, shared by the scene runner (through ctypes) and the ship-motion FMU, so both
 * give the same bits. The slopes at the knots solve scipy's tridiagonal system (CubicSpline), here by
 * Gaussian elimination with partial pivoting (LAPACK's dgtsv); the coefficients per interval are
 * scipy's (CubicHermiteSpline), so values agree with scipy's to rounding. */
#ifndef GIMBAL_KERNEL_CUBIC_SPLINE_H
#define GIMBAL_KERNEL_CUBIC_SPLINE_H

#ifdef __cplusplus
extern "C" {
#endif

/* Doubles of the coefficients of a spline through n samples: 4 per interval, 4 (n - 1). */
long gimbal_cubic_spline_coefficient_count(long n);

/* The coefficients of the spline through (x[i], y[i]), i < n, x strictly increasing, n >= 4: on
 * [x_i, x_{i+1}] y = ((c0 d + c1) d + c2) d + c3, d = t - x_i, c_k = coefficients[4 i + k].
 * 0; 1 when n < 4 (scipy's smaller cases are other curves); -1 when out of memory. */
int gimbal_cubic_spline_fit(long n, const double* x, const double* y, double* coefficients);

/* The first interval i (from x_i to x_{i+1}) on which the spline's value, first or second derivative
 * could overflow a double, evaluated anywhere in it or up to its length beyond either end (as the
 * end intervals are when extrapolated); -1 when none could: then every evaluation there is finite. */
long gimbal_cubic_spline_first_overflow(long n, const double* x, const double* coefficients);

/* The spline's value (derivative 0), first or second derivative at t. Outside [x_0, x_{n-1}] the end
 * intervals' cubics continue (as scipy extrapolates). */
double gimbal_cubic_spline_evaluate(long n, const double* x, const double* coefficients, double t, int derivative);

#ifdef __cplusplus
}
#endif

#endif
