#include "ship_motion.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "gimbal_kernel/sea_state.h"

const char* const kShipDofNames[SHIP_MOTION_DOFS] = {"pitch", "yaw", "roll", "surge", "sway", "heave"};

/* The output column of each degree of freedom: an angle's value (its rate 3 and its acceleration 6
 * columns further), or a translation's velocity (its acceleration 3 further). The bow points along
 * y: surge is y_G, sway x_G, heave z_G (base_motion.TRANSLATION_AXES). */
static const int kColumn[SHIP_MOTION_DOFS] = {0, 1, 2, 9 + 1, 9 + 0, 9 + 2};
static int is_angle(int dof) { return dof <= SHIP_ROLL; }

int ship_motion_check(const ShipMotionParameters* parameters, char* message, size_t size) {
    for (int dof = 0; dof < SHIP_MOTION_DOFS; ++dof) {
        const char* name = kShipDofNames[dof];
        const double amplitude = parameters->significant_amplitude[dof];
        if (!isfinite(amplitude) || amplitude < 0.0) {
            snprintf(message, size, "%s.significant_amplitude = %g must be finite and >= 0 (0: at rest)", name, amplitude);
            return 1;
        }
        if (!isfinite(parameters->peak_period[dof]) || !(parameters->peak_period[dof] > 0.0)) {
            snprintf(message, size, "%s.peak_period = %g s must be finite and > 0", name, parameters->peak_period[dof]);
            return 1;
        }
        if (!isfinite(parameters->gamma[dof]) || !(parameters->gamma[dof] >= 1.0)) {
            snprintf(message, size, "%s.gamma = %g (JONSWAP peak enhancement) must be finite and >= 1 (1: Pierson-Moskowitz)",
                     name, parameters->gamma[dof]);
            return 1;
        }
        if (parameters->components[dof] < 1) {
            snprintf(message, size, "%s.components = %d must be >= 1", name, parameters->components[dof]);
            return 1;
        }
    }
    for (int axis = 0; axis < 3; ++axis)
        if (!isfinite(parameters->velocity[axis])) {
            snprintf(message, size, "velocity[%d] = %g m/s must be finite", axis + 1, parameters->velocity[axis]);
            return 1;
        }
    if (!isfinite(parameters->band_upper) || !(parameters->band_lower > 0.0) ||
        !(parameters->band_lower < parameters->band_upper)) {
        snprintf(message, size, "band.lower = %g, band.upper = %g: the band must satisfy 0 < band.lower < band.upper, finite",
                 parameters->band_lower, parameters->band_upper);
        return 1;
    }
    if (parameters->seed < 0) {
        snprintf(message, size, "seed = %d must be >= 0 (as numpy's default_rng requires)", parameters->seed);
        return 1;
    }
    return 0;
}

void ship_motion_release(ShipMotion* motion) {
    for (int dof = 0; dof < SHIP_MOTION_DOFS; ++dof) {
        ShipDegreeOfFreedom* d = &motion->dof[dof];
        free(d->amplitude);
        free(d->omega);
        free(d->phase);
        free(d->weights);
        free(d->rotation);
        d->amplitude = d->omega = d->phase = d->weights = d->rotation = NULL;
        d->components = 0;
        d->cached_block = -1;
    }
}

int ship_motion_set_step(ShipMotion* motion, double step) {
    motion->step = step;
    for (int dof = 0; dof < SHIP_MOTION_DOFS; ++dof) {
        ShipDegreeOfFreedom* d = &motion->dof[dof];
        d->cached_block = -1;
        if (d->components == 0) continue;
        if (d->rotation == NULL) {
            d->rotation = malloc(sizeof(double) * (size_t)gimbal_sum_of_sines_rotation_doubles(d->components));
            if (d->rotation == NULL) return -1;
        }
        gimbal_sum_of_sines_rotation(step, d->components, d->omega, d->rotation);
    }
    return 0;
}

int ship_motion_prepare(ShipMotion* motion, const ShipMotionParameters* parameters, double step) {
    ship_motion_release(motion);
    motion->parameters = *parameters;
    for (int dof = 0; dof < SHIP_MOTION_DOFS; ++dof) {
        ShipDegreeOfFreedom* d = &motion->dof[dof];
        if (parameters->significant_amplitude[dof] == 0.0) continue; /* at rest, as a scene without it */
        const long count = parameters->components[dof];
        d->amplitude = malloc(sizeof(double) * (size_t)count);
        d->omega = malloc(sizeof(double) * (size_t)count);
        d->phase = malloc(sizeof(double) * (size_t)count);
        d->weights = malloc(3 * sizeof(double) * (size_t)count);
        if (d->amplitude == NULL || d->omega == NULL || d->phase == NULL || d->weights == NULL) {
            ship_motion_release(motion);
            return -1;
        }
        d->components = count;
        /* default_rng([seed, index]): the seed (>= 0, < 2^31) and the index are one uint32 word each. */
        const uint32_t entropy[2] = {(uint32_t)parameters->seed, (uint32_t)dof};
        gimbal_sea_state_components(entropy, 2, parameters->significant_amplitude[dof], parameters->peak_period[dof],
                                    parameters->gamma[dof], count, parameters->band_lower, parameters->band_upper,
                                    d->amplitude, d->omega, d->phase);
        gimbal_sum_of_sines_weights(count, d->amplitude, d->omega, d->weights);
    }
    if (ship_motion_set_step(motion, step) != 0) {
        ship_motion_release(motion);
        return -1;
    }
    return 0;
}

void ship_motion_row(ShipMotion* motion, long row, double outputs[SHIP_MOTION_OUTPUTS]) {
    const long block = GIMBAL_SUM_OF_SINES_BLOCK;
    /* base_motion._SumOfSines.sample: zeros, the angles' offsets (0 for a sea state) plus their sums,
     * the constant velocity plus the translations' rates. */
    for (int k = 0; k < SHIP_MOTION_OUTPUTS; ++k) outputs[k] = 0.0;
    for (int axis = 0; axis < 3; ++axis) outputs[9 + axis] = motion->parameters.velocity[axis];
    for (int dof = 0; dof < SHIP_MOTION_DOFS; ++dof) {
        ShipDegreeOfFreedom* d = &motion->dof[dof];
        if (d->components == 0) continue;
        /* A whole block of rows at once, as the scene runner's grid has them: the block's sines and
         * cosines once, then the rotation per row. */
        const long block_index = row / block;
        if (d->cached_block != block_index) {
            gimbal_sum_of_sines_rows(block_index * block, block, 0.0, motion->step, d->components, d->omega, d->phase,
                                     d->weights, d->rotation, d->value, d->rate, d->acceleration);
            d->cached_block = block_index;
        }
        const long r = row - block_index * block;
        const int column = kColumn[dof];
        if (is_angle(dof)) {
            outputs[column] += d->value[r];
            outputs[column + 3] = d->rate[r];
            outputs[column + 6] = d->acceleration[r];
        } else {
            outputs[column] += d->rate[r];
            outputs[column + 3] = d->acceleration[r];
        }
    }
}
