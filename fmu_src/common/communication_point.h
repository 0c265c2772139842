/* The communication-point rule of every FMU of the project (the gimbal's FMI 2.0 and FMI 3.0
 * Co-Simulation, the ship-motion and controller FMUs), in one place.
 *
 * Masters keep time in different ways: t0 + k*h, a running sum t += h, integer nanoseconds
 * (libcosim), a compensated (Kahan) sum. Over a long run these drift apart by many steps' worth of
 * rounding, so an FMU that keeps a clock of its own and compares the master's point with it refuses
 * some master sooner or later (a running sum against t0 + k*h at 1 ms: after 349.36 s). So the FMU
 * keeps no clock of its own: it takes the master's point as its time, and expects the next point
 * where this step ends, point + h. Every clock style above gives that point to within a few units in
 * the last place (ulp) of the time: t0 + k*h rounds k*h and the sum once each, a running sum gives
 * it exactly, a Kahan sum and integer nanoseconds round once or twice. Nothing accumulates, whatever
 * the run's length or start time. A master in integer nanoseconds may pass the step it was asked
 * for (0.1/3) while its clock moves by the rounded step (33333333 ns): a millionth of the step
 * covers that. A repeated or a skipped step is off by a whole step and is refused, as long as the
 * step is larger than this tolerance (at t = 1.7e9 s, steps above about 1e-6 s); a step below that
 * is below what the master's double clock can resolve, and cannot be told from rounding.
 *
 * The model's own time is the FMU's business: the gimbal's core integrates from t = 0 of its own
 * clock with the step sizes the master passes, so the results are the same, bit for bit, for every
 * clock style and start time whose steps are the same doubles. */
#ifndef GIMBAL_COMMUNICATION_POINT_H
#define GIMBAL_COMMUNICATION_POINT_H

#include <math.h>

/* The distance below which two communication points are the same point (see above). */
static inline double communication_point_tolerance(double expected, double point, double step_size) {
    const double magnitude = fmax(fabs(expected), fabs(point));
    const double unit_in_last_place = nextafter(magnitude, INFINITY) - magnitude;
    return 4.0 * unit_in_last_place + 1e-6 * step_size;
}

/* Whether the master's point is the point where the FMU's last step ended (or where it started). */
static inline int communication_point_matches(double expected, double point, double step_size) {
    return fabs(point - expected) <= communication_point_tolerance(expected, point, step_size);
}

/* How many rows of a fixed grid of step h a step moves (an FMU whose outputs are the rows of one
 * grid, start + k h: the ship-motion FMU), k the rows moved so far. One when the step ends where a
 * step of h from the point would (the master's clock and step rounded as above), or on the grid's
 * next point start + (k + 1) h; none when it is below a millionth of h or ends on the grid's current
 * point start + k h (the master's clock rounding: it moves the time, not the grid); -1 otherwise:
 * another step, which the grid cannot give. A master that sums t += h drifts from the grid by a
 * rounding a step, and ends on its stop time with min(t + h, stop): a last step short of h by all
 * the drift (1.5e-12 s at 20 s of 1 ms steps, 2.5e-9 s after 400 s), or, when its sum fell short of
 * the stop time, one of the drift's size; either ends on a grid point to a few ulp. The points match
 * to the tolerance of a communication point, so the rule is the gimbal's, and nothing accumulates. */
static inline int communication_grid_rows(double point, double step_size, double h, double current_grid_point,
                                          double next_grid_point) {
    const double end = point + step_size;
    if (communication_point_matches(point + h, end, h) || communication_point_matches(next_grid_point, end, h))
        return 1;
    if (step_size < 1e-6 * h || communication_point_matches(current_grid_point, end, h)) return 0;
    return -1;
}

/* Whether a step ending at step_end goes past the experiment's stop time by more than rounding. */
static inline int communication_step_passes_stop_time(double step_end, double stop_time, double step_size) {
    return step_end > stop_time + communication_point_tolerance(stop_time, step_end, step_size);
}

#endif
