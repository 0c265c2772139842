/* A target's recorded position relative to the gimbal (the ship-motion FMU's target outputs,
 * docs/ship_motion_fmu.md): a table read as the recorded motions are (recorded_motion_csv.h) with
 * the columns time [s] and x, y, z [m], the target's position from the gimbal in G, and optionally
 * their rates x_dot, y_dot, z_dot [m/s] and accelerations x_ddot, y_ddot, z_ddot [m/s2]; each column
 * a not-a-knot cubic spline (cubic_spline.h), a missing rate or acceleration the derivative of the
 * position's spline. `gimbal2axis system` writes such a table of a scene's moving target. */
#ifndef GIMBAL_KERNEL_RECORDED_TARGET_H
#define GIMBAL_KERNEL_RECORDED_TARGET_H

#include <stddef.h>

/* The outputs: position, velocity, acceleration, each x, y, z. */
enum { GIMBAL_RECORDED_TARGET_OUTPUTS = 9 };

/* What gimbal_recorded_target_read says of a file. */
enum {
    GIMBAL_RECORDED_TARGET_OUT_OF_MEMORY = -1,
    GIMBAL_RECORDED_TARGET_READ = 0,
    GIMBAL_RECORDED_TARGET_BAD_TABLE = 1,   /* the text: line and column in the message */
    GIMBAL_RECORDED_TARGET_BAD_COLUMNS = 2  /* the header's names: which and why in the message */
};

typedef struct GimbalRecordedTarget GimbalRecordedTarget;

#ifdef __cplusplus
extern "C" {
#endif

/* The target of a file's bytes into *target (free it with gimbal_recorded_target_free); on a refusal
 * *target is NULL and `message` the reason, one sentence without the file's name. */
int gimbal_recorded_target_read(const char* text, size_t length, GimbalRecordedTarget** target, char* message,
                                size_t size);

void gimbal_recorded_target_free(GimbalRecordedTarget* target);

/* The table's first and last time [s]. */
double gimbal_recorded_target_start(const GimbalRecordedTarget* target);
double gimbal_recorded_target_end(const GimbalRecordedTarget* target);

/* The 9 outputs at time t (outside the table the end intervals' cubics continue). */
void gimbal_recorded_target_row(const GimbalRecordedTarget* target, double t, double outputs[GIMBAL_RECORDED_TARGET_OUTPUTS]);

#ifdef __cplusplus
}
#endif

#endif
