/* A rate gyro as its datasheet describes it, on three axes, sampled once per communication step:
 *
 *   sensed   = axes * rate                      scale factor error and misalignment (axes = I + E)
 *   filtered = second-order low-pass(sensed)    the bandwidth: natural frequency and damping, one
 *                                               discrete state-space filter per axis
 *   out      = quantize(filtered + error[k])    error: the stochastic terms and the constant bias,
 *                                               drawn before the run (gimbal2axis/scene/sensors.py)
 *   given    = out of `delay` samples before    the sample delay of the gyro's electronics
 *
 * The coefficients (a first-order-hold discretization of the continuous filter, so that a rate
 * that changes linearly between samples is filtered exactly) and the error table are computed in
 * Python; what runs per sample is here, so the compiled and the Python loops give the same bits.
 * The filter starts settled on the first sample and the delay line holds the first sample until
 * it has `delay` of its own: a gyro switched on before the run. */
#ifndef GIMBAL_KERNEL_GYRO_H
#define GIMBAL_KERNEL_GYRO_H

#include "gimbal_kernel/layout.h"

#define GIMBAL_GYRO_MAX_DELAY 16

#define GIMBAL_GYRO_FIELDS(FIELD, ARRAY)                                                                \
    FIELD(int, enabled, int)   /* 0: the exact rate (every other field unused) */                        \
    FIELD(int, filtered, int)  /* 0: no bandwidth limit */                                               \
    ARRAY(double, axes, double, 9)           /* row-major, applied to the true rate */                   \
    ARRAY(double, filter_a, double, 4)       /* x' = A x + B u, y = C x + D u; A row-major */            \
    ARRAY(double, filter_b, double, 2) ARRAY(double, filter_c, double, 2) FIELD(double, filter_d, double) \
    ARRAY(double, filter_settled, double, 2) /* the state a constant unit input settles to */            \
    ARRAY(double, filter_state, double, 6)   /* two per axis */                                          \
    FIELD(const double*, error, pointer)     /* (n + 1) x 3 rad/s, added after the filter; NULL: none */ \
    FIELD(double, quantum, double)           /* rad/s; 0: no quantization */                             \
    FIELD(long, delay, long)                 /* samples, 0 .. GIMBAL_GYRO_MAX_DELAY */                   \
    ARRAY(double, history, double, 3 * (GIMBAL_GYRO_MAX_DELAY + 1))
GIMBAL_STRUCT(GimbalGyro, GIMBAL_GYRO_FIELDS)

#ifdef __cplusplus
extern "C" {
#endif

/* The gyro's output at sample k (k = 0 starts a run: it settles the filter and fills the delay
 * line) for the true rate `rate` [rad/s]; out may be rate. */
void gimbal_gyro_measure(GimbalGyro* gyro, long k, const double rate[3], double out[3]);

/* Samples 0 .. count - 1 of a whole series at once: rates and out are count x 3 (they may be the
 * same array). */
void gimbal_gyro_series(GimbalGyro* gyro, long count, const double* rates, double* out);

#ifdef __cplusplus
}
#endif
#endif
