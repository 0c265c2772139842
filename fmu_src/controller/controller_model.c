#include "controller_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gimbal_kernel/pointing.h"
#include "gimbal_kernel/set_points.h"

enum { kKindNone = 0, kKindPid = 1, kKindStateFeedback = 2 };

void controller_model_reset(ControllerModel* model) {
    memset(model, 0, sizeof *model);
    for (int i = 0; i < REAL_COUNT; ++i) model->real[i] = kControllerReals[i].start;
    for (int i = 0; i < INTEGER_COUNT; ++i) model->integer[i] = kControllerIntegers[i].start;
    for (int i = 0; i < BOOLEAN_COUNT; ++i) model->boolean[i] = kControllerBooleans[i].start;
}

int controller_model_check(const ControllerModel* model, char* message, size_t size) {
    for (int i = 0; i < REAL_COUNT; ++i) {
        const ControllerReal* v = &kControllerReals[i];
        const double value = model->real[i];
        if (v->causality != PARAMETER) continue;
        if (!isfinite(value) || value < v->min || value > v->max) {
            snprintf(message, size, "%s = %.17g is outside [%.17g, %.17g] (or not finite)", v->name, value, v->min, v->max);
            return 0;
        }
    }
    for (int i = 0; i < INTEGER_COUNT; ++i) {
        const ControllerInteger* v = &kControllerIntegers[i];
        if (model->integer[i] < v->min || model->integer[i] > v->max) {
            snprintf(message, size, "%s = %d is outside [%d, %d] (%s)", v->name, model->integer[i], v->min, v->max,
                     v->description);
            return 0;
        }
    }
    /* zero would make every command 0 V and the anti-windup meaningless */
    static const int kLimits[] = {P_AZ_U_LIMIT, P_EL_U_LIMIT};
    for (int axis = 0; axis < 2; ++axis)
        if (!(model->real[kLimits[axis]] > 0.0)) {
            snprintf(message, size, "%s = %.17g must be > 0", kControllerReals[kLimits[axis]].name, model->real[kLimits[axis]]);
            return 0;
        }
    return 1;
}

/* Reals id .. id + count - 1 into `out` (the table lists the parameters of an array in order). */
static void copy_reals(const ControllerModel* model, int id, int count, double* out) {
    for (int i = 0; i < count; ++i) out[i] = model->real[id + i];
}

static void start_axis(const ControllerModel* model, int first, GimbalAxisPid* axis) {
    /* the rows of AXIS_REALS, in its order */
    axis->kp = model->real[first], axis->ki = model->real[first + 1], axis->kd = model->real[first + 2];
    axis->k_gyro = model->real[first + 3], axis->k_ff = model->real[first + 4];
    axis->d_filter_s = model->real[first + 5], axis->i_limit = model->real[first + 6];
    axis->u_limit = model->real[first + 7];
}

void controller_model_start(ControllerModel* model) {
    memset(&model->sensors, 0, sizeof model->sensors);
    memset(&model->controller, 0, sizeof model->controller);
    GimbalSensors* s = &model->sensors;
    s->encoder_resolution = model->real[P_ENCODER_RESOLUTION];
    copy_reals(model, P_ENCODER_OFFSET_1, 2, s->encoder_offset);
    s->gyro.enabled = model->boolean[P_GYRO_ENABLED];
    copy_reals(model, P_GYRO_AXES_1_1, 9, s->gyro.axes);
    s->gyro.quantum = model->real[P_GYRO_QUANTUM];
    s->gyro.delay = model->integer[P_GYRO_DELAY];

    GimbalController* c = &model->controller;
    /* controller.kind's codes, by the kernel's names (checked to 0 .. 2) */
    static const char* const kKindNames[] = {[kKindNone] = "none", [kKindPid] = "pid",
                                             [kKindStateFeedback] = "state_feedback"};
    c->kind = gimbal_controller_kind(kKindNames[model->integer[P_KIND]]);
    copy_reals(model, P_CONSTANT_U_R1, 2, c->voltage);
    c->u_limit[0] = model->real[P_AZ_U_LIMIT], c->u_limit[1] = model->real[P_EL_U_LIMIT];
    start_axis(model, P_AZ_KP, &c->axis[0]);
    start_axis(model, P_EL_KP, &c->axis[1]);
    c->axis[0].k_acc = model->real[P_AZ_K_ACC], c->axis[1].k_acc = model->real[P_EL_K_ACC];
    copy_reals(model, P_K_1_1, 8, c->gain);
    copy_reals(model, P_SF_KI_1, 2, c->state_ki);
    c->rate_from_encoder = model->boolean[P_RATE_FROM_ENCODER];
    gimbal_target_direction(model->real[P_TARGET_AZIMUTH], model->real[P_TARGET_ELEVATION], model->target);
    model->step = 0;
    model->started = 1;
}

/* The set points toward the target of the inputs: the pointing command (gimbal_kernel/pointing.h),
 * the azimuth in the turn nearest the encoder's, as the scene runner's loop takes a moving target's. */
static int track(ControllerModel* model, double h, const double measured[7], double u[2], double reference[2],
                 char* message, size_t size) {
    const double* in = model->real;
    const double position[3] = {in[IN_TARGET_POSITION_1], in[IN_TARGET_POSITION_2], in[IN_TARGET_POSITION_3]};
    const double velocity[3] = {in[IN_TARGET_VELOCITY_1], in[IN_TARGET_VELOCITY_2], in[IN_TARGET_VELOCITY_3]};
    const double acceleration[3] = {in[IN_TARGET_ACCELERATION_1], in[IN_TARGET_ACCELERATION_2],
                                    in[IN_TARGET_ACCELERATION_3]};
    const double attitude[3] = {in[IN_BASE_DELTA], in[IN_BASE_PSI], in[IN_BASE_GAMMA]};
    const double attitude_rate[3] = {in[IN_BASE_DELTA_DOT], in[IN_BASE_PSI_DOT], in[IN_BASE_GAMMA_DOT]};
    const double attitude_acceleration[3] = {in[IN_BASE_DELTA_DDOT], in[IN_BASE_PSI_DDOT], in[IN_BASE_GAMMA_DDOT]};
    GimbalPointing command;
    const int status = gimbal_pointing_command(position, velocity, acceleration, attitude, attitude_rate,
                                               attitude_acceleration, &command);
    if (status != GIMBAL_POINTING_OK) {
        /* No direction (a source not yet connected: a master that starts its connections at 0, as
           FMPy's SSP runner does, gives zeros at the first step), or none the azimuth can take: this
           step holds the measured angles, and the host hears why. */
        if (status == GIMBAL_POINTING_AT_THE_GIMBAL)
            snprintf(message, size, "target.position = (%g, %g, %g) m is the gimbal's own place (or not finite): no "
                     "direction to point at (is the target's source connected?); this step holds the measured angles",
                     position[0], position[1], position[2]);
        else
            snprintf(message, size, "target.position = (%g, %g, %g) m lies exactly on the azimuth axis (the keyhole), "
                     "where the azimuth set point is undefined; this step holds the measured angles",
                     position[0], position[1], position[2]);
        const double hold[4] = {measured[0], measured[1], 0.0, 0.0}, none[2] = {0.0, 0.0};
        gimbal_controller_track(&model->controller, h, measured, hold, none, none, u, reference);
        return 0;
    }
    const double set_point[4] = {gimbal_angle_nearest_turn(command.alpha, measured[0]), command.beta,
                                 command.alpha_dot, command.beta_dot};
    const double accelerations[2] = {command.alpha_ddot, command.beta_ddot};
    const double on_track[2] = {command.los_rate[0], command.los_rate[2]};
    gimbal_controller_track(&model->controller, h, measured, set_point, accelerations, on_track, u, reference);
    return 1;
}

int controller_model_step(ControllerModel* model, double h, char* message, size_t size) {
    const double* in = model->real;
    double measured[7] = {in[IN_ALPHA],          in[IN_BETA],     in[IN_LOS_OMEGA_1], in[IN_LOS_OMEGA_2],
                          in[IN_LOS_OMEGA_3],    in[IN_ALPHA_DOT], in[IN_BETA_DOT]};
    model->sensors.h = h;
    gimbal_sensors_measure(&model->sensors, model->step, measured);
    double u[2], reference[2] = {0.0, 0.0};
    int held = 0;
    if (model->integer[P_KIND] == kKindNone) {
        gimbal_controller_step(&model->controller, model->step, h, measured, NULL, u, reference);
    } else if (model->boolean[P_TARGET_MOVING]) {
        held = !track(model, h, measured, u, reference, message, size);
    } else {
        /* The set points as the scene runner prepares them (gimbal2axis/scene/setpoints.py) and its
           loop takes them (controllers.c): the azimuth in the turn nearest the encoder's. */
        const double attitude[3] = {in[IN_BASE_DELTA], in[IN_BASE_PSI], in[IN_BASE_GAMMA]};
        const double attitude_rate[3] = {in[IN_BASE_DELTA_DOT], in[IN_BASE_PSI_DOT], in[IN_BASE_GAMMA_DOT]};
        double value[2], rate[2];
        gimbal_target_set_point(model->target, attitude, attitude_rate, value, rate);
        const double set_point[4] = {gimbal_angle_nearest_turn(value[0], measured[0]), value[1], rate[0], rate[1]};
        gimbal_controller_step(&model->controller, model->step, h, measured, set_point, u, reference);
    }
    model->real[OUT_U_R1] = u[0], model->real[OUT_U_R2] = u[1];
    model->real[OUT_ALPHA_REF] = reference[0], model->real[OUT_BETA_REF] = reference[1];
    model->step += 1;
    return held ? 2 : 1;
}
