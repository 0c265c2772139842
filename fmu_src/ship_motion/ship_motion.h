/* The ship's motion as the scenes' sea state makes it (gimbal2axis/scene/base_motion.py, type
 * "sea_state"), from the same C kernel (c_kernel/include/gimbal_kernel/sea_state.h, sum_of_sines.h): per degree of
 * freedom a JONSWAP sum of sinusoids, evaluated on the grid t_k = k h from t = 0, row by row as the
 * scene runner's motion.sample(times) evaluates it, so that row k has the same bits. No FMI here. */
#ifndef SHIP_MOTION_H
#define SHIP_MOTION_H

#include <stddef.h>

#include "gimbal_kernel/sum_of_sines.h"

/* The degrees of freedom in the order whose index seeds each one's generator (default_rng([seed,
 * index])), as base_motion.py numbers them. */
enum { SHIP_PITCH, SHIP_YAW, SHIP_ROLL, SHIP_SURGE, SHIP_SWAY, SHIP_HEAVE, SHIP_MOTION_DOFS };

/* The outputs, in the order of the gimbal's base inputs (base_motion.INPUTS): delta, psi, gamma,
 * their rates and accelerations, v_a[1..3], a_a[1..3]. */
enum { SHIP_MOTION_OUTPUTS = 15 };

/* What the outputs are: the sea state of the parameters, or a recording (recorded_motion.h). */
enum { SHIP_MOTION_SEA_STATE = 0, SHIP_MOTION_RECORDED = 1 };

/* What the target outputs are: none (0), or a table of the target's position (recorded_target.h). */
enum { SHIP_TARGET_NONE = 0, SHIP_TARGET_RECORDED = 1 };

extern const char* const kShipDofNames[SHIP_MOTION_DOFS];

typedef struct {
    double significant_amplitude[SHIP_MOTION_DOFS]; /* rad for pitch, yaw, roll; m for surge, sway, heave; 0: at rest */
    double peak_period[SHIP_MOTION_DOFS];           /* s */
    double gamma[SHIP_MOTION_DOFS];                 /* JONSWAP peak enhancement, >= 1 */
    int components[SHIP_MOTION_DOFS];
    double velocity[3];                             /* constant velocity of point a in G, m/s */
    double band_lower, band_upper;                  /* the frequency band, in multiples of the peak frequency */
    int seed;
    int motion;                                     /* SHIP_MOTION_SEA_STATE or SHIP_MOTION_RECORDED */
    int target;                                     /* SHIP_TARGET_NONE or SHIP_TARGET_RECORDED */
} ShipMotionParameters;

typedef struct {
    long components; /* 0: at rest (significant amplitude 0) */
    double *amplitude, *omega, *phase, *weights, *rotation;
    long cached_block; /* the block of rows in value, rate, acceleration; -1: none */
    double value[GIMBAL_SUM_OF_SINES_BLOCK], rate[GIMBAL_SUM_OF_SINES_BLOCK], acceleration[GIMBAL_SUM_OF_SINES_BLOCK];
} ShipDegreeOfFreedom;

typedef struct {
    ShipMotionParameters parameters;
    ShipDegreeOfFreedom dof[SHIP_MOTION_DOFS];
    double step; /* the grid's step, which the rotation tables are of */
} ShipMotion;

/* Why the parameters are refused, into `message` (a sentence naming the parameter); 0 if they are fine. */
int ship_motion_check(const ShipMotionParameters* parameters, char* message, size_t size);

/* The components of every degree of freedom from checked parameters, and the rotation tables of step
 * `step` (0: only row 0 is right, which does not depend on the step). 0, or -1 when out of memory
 * (`motion` then holds nothing). */
int ship_motion_prepare(ShipMotion* motion, const ShipMotionParameters* parameters, double step);

/* The rotation tables of the grid's step, once it is known. 0, or -1 when out of memory. */
int ship_motion_set_step(ShipMotion* motion, double step);

/* Row `row` of the grid (t = row * step): the 15 outputs. */
void ship_motion_row(ShipMotion* motion, long row, double outputs[SHIP_MOTION_OUTPUTS]);

/* Frees what prepare allocated; `motion` is then empty (release twice is harmless). */
void ship_motion_release(ShipMotion* motion);

#endif
