/* The scene runner's communication loop for the built-in controllers, compiled: per communication
 * point the FMU's outputs into the records, the sensors, the controller, and, before the last, the
 * delayed voltage and one doStep (the Python loop, gimbal2axis/master/stepper.py, does the same for
 * user controllers).
 *
 * Why it exists: the FMU takes about 8-10 us per 1 ms step of the ship scene; a loop in Python with
 * a PID added 3-6 us of its own (interpreter, ctypes), this one a fraction of a microsecond.
 *
 * Called through ctypes (gimbal2axis/master/compiled_loop.py, which builds its view of the struct from the
 * layout table) in chunks of steps, so that Python can show progress and take Ctrl-C between them.
 * The set points and the sensor noise of the chunk are computed before. */
#ifndef GIMBAL_KERNEL_MASTER_LOOP_H
#define GIMBAL_KERNEL_MASTER_LOOP_H

#include <stddef.h>

#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/layout.h"
#include "gimbal_kernel/sensors.h"

/* fmi2GetReal, fmi2GetInteger, fmi2SetReal and fmi2DoStep, as the FMU exports them. */
typedef int (*GimbalArrayCall)(void* component, const unsigned* refs, size_t count, void* values);
typedef int (*GimbalDoStepCall)(void* component, double t, double h, int no_set_prior_state);

#define GIMBAL_MASTER_LOOP_FIELDS(FIELD, ARRAY)                                                           \
    /* the FMU */                                                                                         \
    FIELD(void*, component, pointer) FIELD(GimbalArrayCall, get_real, pointer)                             \
    FIELD(GimbalArrayCall, get_integer, pointer) FIELD(GimbalArrayCall, set_real, pointer)                 \
    FIELD(GimbalDoStepCall, do_step, pointer) FIELD(const unsigned*, real_vrs, pointer)                    \
    FIELD(const unsigned*, mode_vrs, pointer) FIELD(const unsigned*, input_vrs, pointer)                   \
    FIELD(long, real_count, long) FIELD(long, mode_count, long) FIELD(long, input_count, long)             \
    /* records, row k of each, row-major; inputs: u_R1, u_R2 (written here), then the base inputs */      \
    FIELD(double*, rec_real, pointer) FIELD(int*, rec_mode, pointer) FIELD(double*, inputs, pointer)       \
    FIELD(double*, u_cmd, pointer)  /* (n + 1) x 2: the controller's outputs */                           \
    FIELD(double*, refs, pointer)   /* (n + 1) x 2: the set points, for the record (NaN without) */       \
    FIELD(double*, u_asked, pointer) /* (n + 1) x 2: the controller's outputs before its clamp, or NULL */ \
    FIELD(double, h, double) FIELD(long, n, long) FIELD(long, delay, long)                                 \
    /* columns of rec_real the sensors read */                                                            \
    FIELD(long, i_alpha, long) FIELD(long, i_beta, long) ARRAY(long, i_gyro, long, 3)                      \
    FIELD(long, i_alpha_dot, long) FIELD(long, i_beta_dot, long)                                           \
    FIELD(GimbalSensors, sensors, GimbalSensors) FIELD(GimbalController, controller, GimbalController)     \
    /* where it stopped: the step, and the call that failed (gimbal_master_loop_call_name) */             \
    FIELD(long, failed_step, long) FIELD(int, failed_call, int)
GIMBAL_STRUCT(GimbalMasterLoop, GIMBAL_MASTER_LOOP_FIELDS)

#ifdef __cplusplus
extern "C" {
#endif

/* Steps k = first .. last (inclusive; last <= n). 0 when done, else the code of the failed call
 * (the step in failed_step). */
int gimbal_master_loop(GimbalMasterLoop* loop, long first, long last);

/* The FMI function a failure code of gimbal_master_loop names ("fmi2DoStep", ...), or NULL. */
const char* gimbal_master_loop_call_name(int code);

#ifdef __cplusplus
}
#endif
#endif
