/* The ship-motion FMU's variables: one table, which the FMI wrapper (ship_motion_fmu_model.c) checks and
 * serves values by and the generator (model_description_generator.c) writes modelDescription.xml from.
 * A variable's value reference is its index in its table. */
#ifndef SHIP_MOTION_VARIABLES_H
#define SHIP_MOTION_VARIABLES_H

#include "gimbal_kernel/recorded_target.h"
#include "ship_motion.h"

typedef enum { SHIP_OUTPUT, SHIP_PARAMETER } ShipCausality;

typedef struct {
    const char* name;
    ShipCausality causality;
    const char* unit;         /* "" for none */
    const char* display_unit; /* "" for none */
    double start;             /* parameters only */
    double min;               /* -HUGE_VAL for none */
    int min_exclusive;        /* the value must be > min (the XML can only say >= min) */
    const char* description;
} ShipRealVariable;

typedef struct {
    const char* name;
    int start, min, max;
    const char* description;
} ShipIntegerVariable;

/* Real value references: the outputs in the order of the gimbal's base inputs, the target's outputs
 * (recorded_target.h's order: position, velocity, acceleration), then the parameters. */
enum {
    SHIP_REAL_TARGET = SHIP_MOTION_OUTPUTS,
    SHIP_REAL_OUTPUTS = SHIP_MOTION_OUTPUTS + GIMBAL_RECORDED_TARGET_OUTPUTS,
    SHIP_REAL_SIGNIFICANT_AMPLITUDE = SHIP_REAL_OUTPUTS, /* + 3 * degree of freedom */
    SHIP_REAL_PEAK_PERIOD,                               /* + 3 * degree of freedom */
    SHIP_REAL_GAMMA,                                     /* + 3 * degree of freedom */
    SHIP_REAL_VELOCITY = SHIP_REAL_OUTPUTS + 3 * SHIP_MOTION_DOFS, /* + 0, 1, 2 */
    SHIP_REAL_BAND_LOWER = SHIP_REAL_VELOCITY + 3,
    SHIP_REAL_BAND_UPPER,
    SHIP_REAL_COUNT
};

typedef struct {
    const char* name;
    const char* start;
    const char* description;
} ShipStringVariable;

/* Integer value references: the components per degree of freedom, the seed, the kind of motion, the
 * kind of target. */
enum {
    SHIP_INTEGER_COMPONENTS = 0,
    SHIP_INTEGER_SEED = SHIP_MOTION_DOFS,
    SHIP_INTEGER_MOTION,
    SHIP_INTEGER_TARGET,
    SHIP_INTEGER_COUNT
};

/* String value references: the recording's file, the target's table (the FMU instance keeps its own
 * copy of each value). */
enum { SHIP_STRING_RECORDING_FILE = 0, SHIP_STRING_TARGET_FILE, SHIP_STRING_COUNT };

/* The target table's file name that `gimbal2axis system` puts in the FMU's resources folder. */
#define SHIP_TARGET_TABLE "target_track.csv"

/* The example recording in the FMU's resources folder (fmu_src/ship_motion/resources/). */
#define SHIP_EXAMPLE_RECORDING "ship_recording.csv"

extern const ShipRealVariable kShipRealVariables[SHIP_REAL_COUNT];
extern const ShipIntegerVariable kShipIntegerVariables[SHIP_INTEGER_COUNT];
extern const ShipStringVariable kShipStringVariables[SHIP_STRING_COUNT];

/* The parameters at their start values. */
void ship_motion_start_parameters(ShipMotionParameters* parameters);

/* The parameter behind a value reference (NULL for an output). */
double* ship_real_parameter(ShipMotionParameters* parameters, unsigned value_reference);
int* ship_integer_parameter(ShipMotionParameters* parameters, unsigned value_reference);

#endif
