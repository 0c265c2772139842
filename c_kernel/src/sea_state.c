#include "gimbal_kernel/sea_state.h"

#include <math.h>

#include "gimbal_kernel/numpy_random.h"

static const double kPi = 3.141592653589793;

/* numpy's pairwise summation (DOUBLE_pairwise_sum): below 8 terms in order; up to 128 in eight
 * interleaved partial sums combined as a tree, then the rest in order; above, halves at a multiple of 8. */
double gimbal_pairwise_sum(const double* x, long count) {
    if (count < 8) {
        double sum = 0.0;
        for (long i = 0; i < count; ++i) sum += x[i];
        return sum;
    }
    if (count <= 128) {
        double partial[8];
        for (long k = 0; k < 8; ++k) partial[k] = x[k];
        long i = 8;
        for (; i < count - count % 8; i += 8)
            for (long k = 0; k < 8; ++k) partial[k] += x[i + k];
        double sum = ((partial[0] + partial[1]) + (partial[2] + partial[3])) +
                     ((partial[4] + partial[5]) + (partial[6] + partial[7]));
        for (; i < count; ++i) sum += x[i];
        return sum;
    }
    long half = count / 2;
    half -= half % 8;
    return gimbal_pairwise_sum(x, half) + gimbal_pairwise_sum(x + half, count - half);
}

/* The unnormalized JONSWAP shape at omega (base_motion.spectrum_shape, term by term). */
static double jonswap_shape(double omega, double peak_omega, double gamma) {
    const double sigma = omega <= peak_omega ? 0.07 : 0.09;
    const double shape = pow(omega, -5.0) * exp(-1.25 * pow(peak_omega / omega, 4.0));
    const double distance = omega - peak_omega;
    const double exponent = -(distance * distance) / (2.0 * (sigma * sigma) * pow(peak_omega, 2.0));
    return shape * pow(gamma, exp(exponent));
}

/* The first argument of gimbal_sea_state_components it refuses, in the order of its checks, or OK. */
static GimbalSeaStateStatus spectrum_refusal(double significant_amplitude, double peak_period, double gamma,
                                             long components, double band_low, double band_high) {
    if (!isfinite(significant_amplitude) || significant_amplitude < 0.0) return GIMBAL_SEA_STATE_BAD_AMPLITUDE;
    if (!isfinite(peak_period) || !(peak_period > 0.0)) return GIMBAL_SEA_STATE_BAD_PERIOD;
    if (!isfinite(gamma) || !(gamma >= 1.0)) return GIMBAL_SEA_STATE_BAD_GAMMA;
    if (components < 1) return GIMBAL_SEA_STATE_BAD_COMPONENTS;
    if (!isfinite(band_high) || !(band_low > 0.0) || !(band_low < band_high)) return GIMBAL_SEA_STATE_BAD_BAND;
    return GIMBAL_SEA_STATE_OK;
}

GimbalSeaStateStatus gimbal_sea_state_components(const uint32_t* entropy, long words, double significant_amplitude,
                                                 double peak_period, double gamma, long components, double band_low,
                                                 double band_high, double* amplitude, double* omega, double* phase) {
    const GimbalSeaStateStatus refusal =
        spectrum_refusal(significant_amplitude, peak_period, gamma, components, band_low, band_high);
    if (refusal != GIMBAL_SEA_STATE_OK) return refusal;

    const double peak_omega = 2.0 * kPi / peak_period;
    /* np.linspace(start, stop, components + 1): edge i = i * step + start, the last edge stop itself. */
    const double start = band_low * peak_omega, stop = band_high * peak_omega;
    const double edge_step = (stop - start) / (double)components;
    GimbalPcg64 generator;
    gimbal_pcg64_seed(&generator, entropy, words);
    double* bin_variance = amplitude; /* the bins' S(w) dw, until the amplitudes replace them */
    for (long i = 0; i < components; ++i) {
        const double edge = (double)i * edge_step + start;
        const double next_edge = i + 1 == components ? stop : (double)(i + 1) * edge_step + start;
        const double width = next_edge - edge;
        omega[i] = edge + gimbal_pcg64_uniform(&generator, 0.0, 1.0) * width;
        bin_variance[i] = width; /* kept until the shape is known: all places are drawn before the phases */
    }
    for (long i = 0; i < components; ++i) phase[i] = gimbal_pcg64_uniform(&generator, 0.0, 2.0 * kPi);
    for (long i = 0; i < components; ++i) bin_variance[i] = jonswap_shape(omega[i], peak_omega, gamma) * bin_variance[i];
    const double total = gimbal_pairwise_sum(bin_variance, components);
    const double standard_deviation = significant_amplitude / 2.0;
    /* sum(A^2 / 2) = standard_deviation^2 */
    for (long i = 0; i < components; ++i) amplitude[i] = sqrt(2.0 * bin_variance[i] / total) * standard_deviation;
    return GIMBAL_SEA_STATE_OK;
}
