/* A recorded base motion (scene type "recorded", docs/scenes.md): the file's table
 * (recorded_motion_csv.h), its columns checked and mapped onto the 15 base inputs (the order of
 * scene/base_motion.INPUTS), each splined (cubic_spline.h, not-a-knot). Column `time` [s] and any of
 * delta, psi, gamma [rad] (or pitch_deg, yaw_deg, roll_deg), their `_dot` and `_ddot` [rad/s,
 * rad/s2], x, y, z [m] of point a in G; a missing rate or acceleration is the derivative of the
 * angle's spline, v_a and a_a those of the position's; absent quantities are 0. The scene runner
 * (through ctypes) and the ship-motion FMU both evaluate it here: the same file gives the same bits. */
#ifndef GIMBAL_KERNEL_RECORDED_MOTION_H
#define GIMBAL_KERNEL_RECORDED_MOTION_H

#include <stddef.h>

enum { GIMBAL_RECORDED_MOTION_OUTPUTS = 15 };

/* What gimbal_recorded_motion_read says of a file. */
enum {
    GIMBAL_RECORDED_MOTION_OUT_OF_MEMORY = -1,
    GIMBAL_RECORDED_MOTION_READ = 0,
    GIMBAL_RECORDED_MOTION_BAD_TABLE = 1,   /* the text: line and column in the message */
    GIMBAL_RECORDED_MOTION_BAD_COLUMNS = 2  /* the header's names: which and why in the message */
};

typedef struct GimbalRecordedMotion GimbalRecordedMotion;

#ifdef __cplusplus
extern "C" {
#endif

/* The motion of a file's bytes into *motion (free it with gimbal_recorded_motion_free); on a refusal
 * *motion is NULL and `message` the reason, one sentence without the file's name. */
int gimbal_recorded_motion_read(const char* text, size_t length, GimbalRecordedMotion** motion, char* message,
                                size_t size);

void gimbal_recorded_motion_free(GimbalRecordedMotion* motion);

/* The recording's first and last time [s]. */
double gimbal_recorded_motion_start(const GimbalRecordedMotion* motion);
double gimbal_recorded_motion_end(const GimbalRecordedMotion* motion);

/* The 15 base inputs at time t (outside the recording the end intervals' cubics continue). */
void gimbal_recorded_motion_row(const GimbalRecordedMotion* motion, double t, double outputs[GIMBAL_RECORDED_MOTION_OUTPUTS]);

/* The rows of `count` times into outputs (count x 15, row by row). */
void gimbal_recorded_motion_sample(const GimbalRecordedMotion* motion, long count, const double* t, double* outputs);

/* The splined position x, y, z of point a at `count` times (count x 3; 0 where the file has none). */
void gimbal_recorded_motion_position(const GimbalRecordedMotion* motion, long count, const double* t, double* positions);

#ifdef __cplusplus
}
#endif

#endif
