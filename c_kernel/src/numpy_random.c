#include "gimbal_kernel/numpy_random.h"

/* SeedSequence's hash and mix constants (numpy/random/bit_generator.pyx). */
enum { kPoolSize = 4, kXShift = 16 };
static const uint32_t kInitA = 0x43b0d7e5u, kMultA = 0x931e8875u, kInitB = 0x8b51f9ddu, kMultB = 0x58f38dedu;
static const uint32_t kMixMultL = 0xca01f9ddu, kMixMultR = 0x4973f715u;

/* PCG64's LCG multiplier, 0x2360ED051FC65DA44385DF649FCCF645. */
static const GimbalUint128 kMultiplier = {0x2360ED051FC65DA4ull, 0x4385DF649FCCF645ull};

static uint32_t hashmix(uint32_t value, uint32_t* hash_constant) {
    value ^= *hash_constant;
    *hash_constant *= kMultA;
    value *= *hash_constant;
    value ^= value >> kXShift;
    return value;
}

static uint32_t mix(uint32_t x, uint32_t y) {
    uint32_t result = kMixMultL * x - kMixMultR * y;
    result ^= result >> kXShift;
    return result;
}

/* SeedSequence.mix_entropy: the pool of 4 words. */
static void mix_entropy(const uint32_t* entropy, long words, uint32_t pool[kPoolSize]) {
    uint32_t hash_constant = kInitA;
    for (long i = 0; i < kPoolSize; ++i) pool[i] = hashmix(i < words ? entropy[i] : 0u, &hash_constant);
    for (long source = 0; source < kPoolSize; ++source)
        for (long target = 0; target < kPoolSize; ++target)
            if (source != target) pool[target] = mix(pool[target], hashmix(pool[source], &hash_constant));
    for (long source = kPoolSize; source < words; ++source)
        for (long target = 0; target < kPoolSize; ++target)
            pool[target] = mix(pool[target], hashmix(entropy[source], &hash_constant));
}

/* SeedSequence.generate_state(4, uint64): 8 uint32 words cycled from the pool, paired little-endian. */
static void generate_state(const uint32_t pool[kPoolSize], uint64_t state[4]) {
    uint32_t hash_constant = kInitB;
    uint32_t words[8];
    for (long i = 0; i < 8; ++i) {
        uint32_t value = pool[i % kPoolSize];
        value ^= hash_constant;
        hash_constant *= kMultB;
        value *= hash_constant;
        value ^= value >> kXShift;
        words[i] = value;
    }
    for (long i = 0; i < 4; ++i) state[i] = (uint64_t)words[2 * i] | ((uint64_t)words[2 * i + 1] << 32);
}

static GimbalUint128 add128(GimbalUint128 a, GimbalUint128 b) {
    GimbalUint128 sum = {a.high + b.high, a.low + b.low};
    if (sum.low < a.low) ++sum.high;
    return sum;
}

/* The full 128-bit product of two 64-bit words, from 32-bit halves. */
static GimbalUint128 multiply64(uint64_t a, uint64_t b) {
    const uint64_t a_low = a & 0xFFFFFFFFull, a_high = a >> 32, b_low = b & 0xFFFFFFFFull, b_high = b >> 32;
    const uint64_t low_low = a_low * b_low, high_low = a_high * b_low, low_high = a_low * b_high,
                   high_high = a_high * b_high;
    const uint64_t middle = (low_low >> 32) + (high_low & 0xFFFFFFFFull) + low_high;
    GimbalUint128 product = {high_high + (high_low >> 32) + (middle >> 32), (middle << 32) | (low_low & 0xFFFFFFFFull)};
    return product;
}

/* a * b modulo 2^128. */
static GimbalUint128 multiply128(GimbalUint128 a, GimbalUint128 b) {
    GimbalUint128 product = multiply64(a.low, b.low);
    product.high += a.high * b.low + a.low * b.high;
    return product;
}

static void step(GimbalPcg64* generator) {
    generator->state = add128(multiply128(generator->state, kMultiplier), generator->increment);
}

void gimbal_pcg64_seed(GimbalPcg64* generator, const uint32_t* entropy, long words) {
    uint32_t pool[kPoolSize];
    uint64_t state[4];
    mix_entropy(entropy, words, pool);
    generate_state(pool, state);
    /* pcg64_set_seed: initial state (state[0] << 64) | state[1], sequence (state[2] << 64) | state[3];
     * pcg_setseq_128_srandom_r: increment = sequence << 1 | 1, state = 0, step, += initial state, step. */
    const GimbalUint128 initial = {state[0], state[1]};
    generator->increment.high = (state[2] << 1) | (state[3] >> 63);
    generator->increment.low = (state[3] << 1) | 1u;
    generator->state.high = generator->state.low = 0;
    step(generator);
    generator->state = add128(generator->state, initial);
    step(generator);
}

uint64_t gimbal_pcg64_next(GimbalPcg64* generator) {
    step(generator);
    /* XSL-RR: the two halves xor-ed, rotated right by the state's top 6 bits. */
    const uint64_t folded = generator->state.high ^ generator->state.low;
    const unsigned rotation = (unsigned)(generator->state.high >> 58);
    return (folded >> rotation) | (folded << ((64u - rotation) & 63u));
}

double gimbal_pcg64_uniform(GimbalPcg64* generator, double low, double high) {
    const double unit = (double)(gimbal_pcg64_next(generator) >> 11) * (1.0 / 9007199254740992.0);
    return low + (high - low) * unit;
}

void gimbal_random_uniform(const uint32_t* entropy, long words, long count, double low, double high, double* out) {
    GimbalPcg64 generator;
    gimbal_pcg64_seed(&generator, entropy, words);
    for (long i = 0; i < count; ++i) out[i] = gimbal_pcg64_uniform(&generator, low, high);
}
