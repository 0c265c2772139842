/* The components of a sea state (scene base_motion type "sea_state", and the ship-motion FMU): per
 * degree of freedom, a sum of sinusoids whose one-sided spectrum has the JONSWAP shape
 *     S(w) ~ w^-5 exp(-1.25 (w_p / w)^4) gamma^exp(-(w - w_p)^2 / (2 sigma^2 w_p^2)),
 * sigma = 0.07 for w <= w_p, else 0.09, w_p = 2 pi / peak period, and whose variance is
 * (significant amplitude / 2)^2. One frequency per equal bin of [band_low, band_high] * w_p, at a
 * uniformly drawn place in its bin; phases uniform in [0, 2 pi); both drawn from numpy's
 * default_rng(entropy) (numpy_random.h): first the frequencies' places, then the phases.
 *
 * The arithmetic follows the numpy code the scenes were made with (the reference kept in
 * tests/c_kernel/test_sea_state_kernel.py) operation by operation: np.linspace's edges (i * step + start, the
 * last edge the stop itself), the shape with libm's exp and pow, numpy's pairwise summation of the
 * bins' variances. One implementation for the scene runner and the FMU: the same parameters give
 * the same bits in both. (numpy's own exp and pow may be SIMD code that rounds the last bit
 * differently from libm; the RNG draws are exact.) */
#ifndef GIMBAL_KERNEL_SEA_STATE_H
#define GIMBAL_KERNEL_SEA_STATE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Why gimbal_sea_state_components refused its arguments. */
typedef enum {
    GIMBAL_SEA_STATE_OK = 0,
    GIMBAL_SEA_STATE_BAD_AMPLITUDE,   /* significant amplitude not finite or < 0 */
    GIMBAL_SEA_STATE_BAD_PERIOD,      /* peak period not finite or <= 0 */
    GIMBAL_SEA_STATE_BAD_GAMMA,       /* gamma (peak enhancement) not finite or < 1 */
    GIMBAL_SEA_STATE_BAD_COMPONENTS,  /* fewer than 1 component */
    GIMBAL_SEA_STATE_BAD_BAND         /* not 0 < band_low < band_high, finite */
} GimbalSeaStateStatus;

/* numpy's pairwise sum of x[0 .. count - 1] (np.add.reduce of a contiguous float64 array). */
double gimbal_pairwise_sum(const double* x, long count);

/* Amplitudes, frequencies [rad/s] and phases [rad] of `components` sinusoids of one degree of
 * freedom (the unit of the amplitudes is the significant amplitude's). `entropy`: numpy's
 * default_rng([seed, index]) as uint32 words (numpy_random.h). */
GimbalSeaStateStatus gimbal_sea_state_components(const uint32_t* entropy, long words, double significant_amplitude,
                                                 double peak_period, double gamma, long components, double band_low,
                                                 double band_high, double* amplitude, double* omega, double* phase);

#ifdef __cplusplus
}
#endif
#endif
