#include "gimbal_kernel/cubic_spline.h"

#include <math.h>
#include <stdlib.h>

long gimbal_cubic_spline_coefficient_count(long n) { return n < 2 ? 0 : 4 * (n - 1); }

/* Solves the tridiagonal system (lower[i] = A[i+1][i], diagonal[i] = A[i][i], upper[i] = A[i][i+1])
 * in place into b, with partial pivoting as LAPACK's dgtsv: the not-a-knot rows are not diagonally
 * dominant. `lower` becomes the second superdiagonal of U. 0, or 1 when the matrix is singular. */
static int solve_tridiagonal(long n, double* lower, double* diagonal, double* upper, double* b) {
    for (long i = 0; i < n - 1; ++i) {
        if (fabs(diagonal[i]) >= fabs(lower[i])) {
            if (diagonal[i] == 0.0) return 1;
            const double factor = lower[i] / diagonal[i];
            diagonal[i + 1] -= factor * upper[i];
            b[i + 1] -= factor * b[i];
            lower[i] = 0.0;
        } else { /* rows i and i + 1 interchanged */
            const double factor = diagonal[i] / lower[i];
            diagonal[i] = lower[i];
            const double below = diagonal[i + 1];
            diagonal[i + 1] = upper[i] - factor * below;
            if (i < n - 2) {
                lower[i] = upper[i + 1];
                upper[i + 1] = -factor * lower[i];
            } else {
                lower[i] = 0.0;
            }
            upper[i] = below;
            const double swapped = b[i];
            b[i] = b[i + 1];
            b[i + 1] = swapped - factor * b[i + 1];
        }
    }
    if (diagonal[n - 1] == 0.0) return 1;
    b[n - 1] /= diagonal[n - 1];
    b[n - 2] = (b[n - 2] - upper[n - 2] * b[n - 1]) / diagonal[n - 2];
    for (long i = n - 3; i >= 0; --i) b[i] = (b[i] - upper[i] * b[i + 1] - lower[i] * b[i + 2]) / diagonal[i];
    return 0;
}

int gimbal_cubic_spline_fit(long n, const double* x, const double* y, double* coefficients) {
    if (n < 4) return 1;
    double* work = malloc(sizeof(double) * (size_t)(5 * n));
    if (work == NULL) return -1;
    double *dx = work, *slope = work + n, *lower = work + 2 * n, *diagonal = work + 3 * n, *upper = work + 4 * n;
    double* b = malloc(sizeof(double) * (size_t)n);
    if (b == NULL) {
        free(work);
        return -1;
    }
    for (long i = 0; i < n - 1; ++i) {
        dx[i] = x[i + 1] - x[i];
        slope[i] = (y[i + 1] - y[i]) / dx[i];
    }
    /* Interior rows: dx_i s_{i-1} + 2 (dx_{i-1} + dx_i) s_i + dx_{i-1} s_{i+1} = 3 (dx_i m_{i-1} + dx_{i-1} m_i). */
    for (long i = 1; i < n - 1; ++i) {
        lower[i - 1] = dx[i];
        diagonal[i] = 2.0 * (dx[i - 1] + dx[i]);
        upper[i] = dx[i - 1];
        b[i] = 3.0 * (dx[i] * slope[i - 1] + dx[i - 1] * slope[i]);
    }
    /* Not-a-knot rows, as scipy writes them. */
    const double first_span = x[2] - x[0];
    diagonal[0] = dx[1];
    upper[0] = first_span;
    b[0] = ((dx[0] + 2.0 * first_span) * dx[1] * slope[0] + dx[0] * dx[0] * slope[1]) / first_span;
    const double last_span = x[n - 1] - x[n - 3];
    diagonal[n - 1] = dx[n - 3];
    lower[n - 2] = last_span;
    b[n - 1] = (dx[n - 2] * dx[n - 2] * slope[n - 3] + (2.0 * last_span + dx[n - 2]) * dx[n - 3] * slope[n - 2]) /
               last_span;
    const int singular = solve_tridiagonal(n, lower, diagonal, upper, b);
    if (singular == 0) {
        /* scipy's CubicHermiteSpline from the slopes b. */
        for (long i = 0; i < n - 1; ++i) {
            const double t = (b[i] + b[i + 1] - 2.0 * slope[i]) / dx[i];
            coefficients[4 * i + 0] = t / dx[i];
            coefficients[4 * i + 1] = (slope[i] - b[i]) / dx[i] - t;
            coefficients[4 * i + 2] = b[i];
            coefficients[4 * i + 3] = y[i];
        }
    }
    free(b);
    free(work);
    return singular;
}

long gimbal_cubic_spline_first_overflow(long n, const double* x, const double* coefficients) {
    for (long i = 0; i + 1 < n; ++i) {
        /* With |d| <= reach and reach >= 1, every partial sum of Horner's scheme, and of the
         * derivatives' (factors 3 and 6 at most), is at most 6 sum|c_k| reach^3 in magnitude. */
        const double* c = coefficients + 4 * i;
        const double reach = fmax(1.0, 2.0 * (x[i + 1] - x[i]));
        const double bound = 6.0 * (fabs(c[0]) + fabs(c[1]) + fabs(c[2]) + fabs(c[3])) * reach * reach * reach;
        if (!isfinite(bound)) return i;
    }
    return -1;
}

/* The interval i with x_i <= t < x_{i+1}; the first one before x_0, the last one from x_{n-2} on. */
static long interval_of(long n, const double* x, double t) {
    long low = 0, high = n - 2;
    while (low < high) {
        const long middle = low + (high - low + 1) / 2;
        if (x[middle] <= t)
            low = middle;
        else
            high = middle - 1;
    }
    return low;
}

double gimbal_cubic_spline_evaluate(long n, const double* x, const double* coefficients, double t, int derivative) {
    const long i = interval_of(n, x, t);
    const double* c = coefficients + 4 * i;
    const double d = t - x[i];
    switch (derivative) {
        case 0: return ((c[0] * d + c[1]) * d + c[2]) * d + c[3];
        case 1: return (3.0 * c[0] * d + 2.0 * c[1]) * d + c[2];
        default: return 6.0 * c[0] * d + 2.0 * c[1];
    }
}
