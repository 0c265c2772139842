#include "ship_motion_variables.h"

#include <math.h>
#include <stddef.h>

/* Degrees as the scenes convert them (Python's math.radians: degrees * (pi / 180)). */
#define DEGREES(x) ((x) * (3.141592653589793 / 180.0))

/* Start values: the sea state of scenes/ship_stabilization.toml (surge and sway at rest). */
#define DOF_PARAMETERS(dof, angle, amplitude, period, gamma)                                                         \
    {dof ".significant_amplitude", SHIP_PARAMETER, angle ? "rad" : "m", angle ? "deg" : "", amplitude, 0.0, 0,       \
     "significant amplitude of the " dof " motion (twice its standard deviation; 0: no " dof " motion)"},            \
    {dof ".peak_period", SHIP_PARAMETER, "s", "", period, 0.0, 1,                                                    \
     "peak period of the " dof " response spectrum (2 pi / the frequency of its maximum)"},                         \
    {dof ".gamma", SHIP_PARAMETER, "1", "", gamma, 1.0, 0,                                                           \
     "JONSWAP peak enhancement of the " dof " spectrum (1: Pierson-Moskowitz)"}

/* target = 1: the table's x, y, z and their derivatives (connect to the controller's inputs of the
 * same names); 0 otherwise. */
#define TARGET_OUTPUTS(quantity, unit, what)                                                                         \
    {"target." quantity "[1]", SHIP_OUTPUT, unit, "", 0, -HUGE_VAL, 0, what ", x component in G (target = 1; else 0)"}, \
    {"target." quantity "[2]", SHIP_OUTPUT, unit, "", 0, -HUGE_VAL, 0, what ", y component in G (target = 1; else 0)"}, \
    {"target." quantity "[3]", SHIP_OUTPUT, unit, "", 0, -HUGE_VAL, 0, what ", z component in G (target = 1; else 0)"}

const ShipRealVariable kShipRealVariables[SHIP_REAL_COUNT] = {
    {"base.delta", SHIP_OUTPUT, "rad", "deg", 0, -HUGE_VAL, 0, "carrier pitch angle delta (connect to the gimbal's base.delta)"},
    {"base.psi", SHIP_OUTPUT, "rad", "deg", 0, -HUGE_VAL, 0, "carrier yaw angle psi (connect to the gimbal's base.psi)"},
    {"base.gamma", SHIP_OUTPUT, "rad", "deg", 0, -HUGE_VAL, 0, "carrier roll angle gamma (connect to the gimbal's base.gamma)"},
    {"base.delta_dot", SHIP_OUTPUT, "rad/s", "deg/s", 0, -HUGE_VAL, 0, "rate of the carrier pitch angle, d(delta)/dt, exact"},
    {"base.psi_dot", SHIP_OUTPUT, "rad/s", "deg/s", 0, -HUGE_VAL, 0, "rate of the carrier yaw angle, d(psi)/dt, exact"},
    {"base.gamma_dot", SHIP_OUTPUT, "rad/s", "deg/s", 0, -HUGE_VAL, 0, "rate of the carrier roll angle, d(gamma)/dt, exact"},
    {"base.delta_ddot", SHIP_OUTPUT, "rad/s2", "deg/s2", 0, -HUGE_VAL, 0, "acceleration of the carrier pitch angle, exact"},
    {"base.psi_ddot", SHIP_OUTPUT, "rad/s2", "deg/s2", 0, -HUGE_VAL, 0, "acceleration of the carrier yaw angle, exact"},
    {"base.gamma_ddot", SHIP_OUTPUT, "rad/s2", "deg/s2", 0, -HUGE_VAL, 0, "acceleration of the carrier roll angle, exact"},
    {"base.v_a[1]", SHIP_OUTPUT, "m/s", "", 0, -HUGE_VAL, 0, "velocity of point a, x component in the inertial frame G: velocity[1] + sway rate"},
    {"base.v_a[2]", SHIP_OUTPUT, "m/s", "", 0, -HUGE_VAL, 0, "velocity of point a, y component in the inertial frame G: velocity[2] + surge rate"},
    {"base.v_a[3]", SHIP_OUTPUT, "m/s", "", 0, -HUGE_VAL, 0, "velocity of point a, z component in the inertial frame G: velocity[3] + heave rate"},
    {"base.a_a[1]", SHIP_OUTPUT, "m/s2", "", 0, -HUGE_VAL, 0, "acceleration of point a, x component in G (sway; gravity not in it)"},
    {"base.a_a[2]", SHIP_OUTPUT, "m/s2", "", 0, -HUGE_VAL, 0, "acceleration of point a, y component in G (surge; gravity not in it)"},
    {"base.a_a[3]", SHIP_OUTPUT, "m/s2", "", 0, -HUGE_VAL, 0, "acceleration of point a, z component in G (heave; gravity not in it)"},
    TARGET_OUTPUTS("position", "m", "the target's position relative to the gimbal"),
    TARGET_OUTPUTS("velocity", "m/s", "the rate of the target's position"),
    TARGET_OUTPUTS("acceleration", "m/s2", "the second derivative of the target's position"),
    DOF_PARAMETERS("pitch", 1, DEGREES(2.0), 7.0, 3.3),
    DOF_PARAMETERS("yaw", 1, DEGREES(1.0), 12.0, 1.0),
    DOF_PARAMETERS("roll", 1, DEGREES(5.0), 9.0, 3.3),
    DOF_PARAMETERS("surge", 0, 0.0, 8.0, 3.3),
    DOF_PARAMETERS("sway", 0, 0.0, 8.0, 3.3),
    DOF_PARAMETERS("heave", 0, 1.0, 8.0, 3.3),
    {"velocity[1]", SHIP_PARAMETER, "m/s", "", 0.0, -HUGE_VAL, 0, "constant velocity of point a, x component in G"},
    {"velocity[2]", SHIP_PARAMETER, "m/s", "", 6.0, -HUGE_VAL, 0, "constant velocity of point a, y component in G (the bow's direction)"},
    {"velocity[3]", SHIP_PARAMETER, "m/s", "", 0.0, -HUGE_VAL, 0, "constant velocity of point a, z component in G"},
    {"band.lower", SHIP_PARAMETER, "1", "", 0.5, 0.0, 1, "lower edge of the spectra's frequency band, in multiples of each peak frequency"},
    {"band.upper", SHIP_PARAMETER, "1", "", 3.0, 0.0, 1, "upper edge of the spectra's frequency band, in multiples of each peak frequency (> band.lower)"},
};

/* At most 10000 components: the rotation table takes 2 x 128 doubles per component. */
const ShipIntegerVariable kShipIntegerVariables[SHIP_INTEGER_COUNT] = {
    {"pitch.components", 120, 1, 10000, "sinusoids of the pitch motion, one per equal bin of the band"},
    {"yaw.components", 120, 1, 10000, "sinusoids of the yaw motion, one per equal bin of the band"},
    {"roll.components", 120, 1, 10000, "sinusoids of the roll motion, one per equal bin of the band"},
    {"surge.components", 120, 1, 10000, "sinusoids of the surge motion, one per equal bin of the band"},
    {"sway.components", 120, 1, 10000, "sinusoids of the sway motion, one per equal bin of the band"},
    {"heave.components", 120, 1, 10000, "sinusoids of the heave motion, one per equal bin of the band"},
    {"seed", 7, 0, 2147483647, "seed of the frequencies' places in their bins and of the phases (numpy's default_rng([seed, index of the degree of freedom]))"},
    {"motion", SHIP_MOTION_SEA_STATE, SHIP_MOTION_SEA_STATE, SHIP_MOTION_RECORDED,
     "what the outputs are: 0 the sea state of the parameters, 1 the recording in recording_file (splined)"},
    {"target", SHIP_TARGET_NONE, SHIP_TARGET_NONE, SHIP_TARGET_RECORDED,
     "the target outputs: 0 none (zeros), 1 the table in target_file (splined), from t = 0 on the grid as the motion"},
};

const ShipStringVariable kShipStringVariables[SHIP_STRING_COUNT] = {
    {"recording_file", SHIP_EXAMPLE_RECORDING,
     "the recorded motion (CSV: time and any of delta, psi, gamma or pitch_deg, yaw_deg, roll_deg, their _dot and "
     "_ddot, x, y, z) when motion = 1: absolute, or relative to the FMU's resources folder"},
    {"target_file", SHIP_TARGET_TABLE,
     "the target's table (CSV: time, x, y, z [m], the target from the gimbal in G, optionally x_dot ... z_dot, x_ddot "
     "... z_ddot) when target = 1: absolute, or relative to the FMU's resources folder"},
};

double* ship_real_parameter(ShipMotionParameters* parameters, unsigned value_reference) {
    if (value_reference < SHIP_REAL_OUTPUTS || value_reference >= SHIP_REAL_COUNT) return NULL;
    if (value_reference >= SHIP_REAL_VELOCITY) {
        if (value_reference == SHIP_REAL_BAND_LOWER) return &parameters->band_lower;
        if (value_reference == SHIP_REAL_BAND_UPPER) return &parameters->band_upper;
        return &parameters->velocity[value_reference - SHIP_REAL_VELOCITY];
    }
    const unsigned offset = value_reference - SHIP_REAL_OUTPUTS;
    const unsigned dof = offset / 3;
    switch (offset % 3) {
        case 0: return &parameters->significant_amplitude[dof];
        case 1: return &parameters->peak_period[dof];
        default: return &parameters->gamma[dof];
    }
}

int* ship_integer_parameter(ShipMotionParameters* parameters, unsigned value_reference) {
    if (value_reference < SHIP_INTEGER_SEED) return &parameters->components[value_reference];
    if (value_reference == SHIP_INTEGER_SEED) return &parameters->seed;
    if (value_reference == SHIP_INTEGER_MOTION) return &parameters->motion;
    if (value_reference == SHIP_INTEGER_TARGET) return &parameters->target;
    return NULL;
}

void ship_motion_start_parameters(ShipMotionParameters* parameters) {
    for (unsigned vr = SHIP_REAL_OUTPUTS; vr < SHIP_REAL_COUNT; ++vr)
        *ship_real_parameter(parameters, vr) = kShipRealVariables[vr].start;
    for (unsigned vr = 0; vr < SHIP_INTEGER_COUNT; ++vr)
        *ship_integer_parameter(parameters, vr) = kShipIntegerVariables[vr].start;
}
