/* numpy's default_rng(entropy).uniform(low, high), bit for bit, in C: SeedSequence (pool of 4 uint32
 * words mixed from the entropy words) seeds PCG64 (XSL-RR 128/64), whose 53-bit doubles make the
 * uniform draws. The sea state's frequencies and phases are drawn with it (sea_state.h), so that the
 * scene runner (through ctypes) and the ship-motion FMU (fmu_src/ship_motion/) draw the same numbers
 * from the same seed, and both the same as numpy did before the sea state moved to C.
 *
 * The 128-bit arithmetic is done in pairs of uint64 words (no unsigned __int128): MSVC, which builds
 * the Python extension on Windows, has no 128-bit integer type. */
#ifndef GIMBAL_KERNEL_NUMPY_RANDOM_H
#define GIMBAL_KERNEL_NUMPY_RANDOM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A 128-bit unsigned integer as two words. */
typedef struct {
    uint64_t high, low;
} GimbalUint128;

/* PCG64's state: the LCG state and its (odd) increment. */
typedef struct {
    GimbalUint128 state, increment;
} GimbalPcg64;

/* numpy.random.SeedSequence(entropy).generate_state(4, uint64) and PCG64's seeding from it, for the
 * entropy as numpy coerces it to uint32 words (an integer n >= 0 is its base-2^32 digits, least
 * significant first, 0 is one word 0; a list of integers is the concatenation of its items' words). */
void gimbal_pcg64_seed(GimbalPcg64* generator, const uint32_t* entropy, long words);

/* The next 64 random bits (numpy's PCG64.random_raw()). */
uint64_t gimbal_pcg64_next(GimbalPcg64* generator);

/* numpy's Generator.uniform(low, high) for one draw: low + (high - low) * (next >> 11) * 2^-53. */
double gimbal_pcg64_uniform(GimbalPcg64* generator, double low, double high);

/* `count` draws of default_rng(entropy).uniform(low, high, count) into `out` (for the tests). */
void gimbal_random_uniform(const uint32_t* entropy, long words, long count, double low, double high, double* out);

#ifdef __cplusplus
}
#endif
#endif
