/* What the controller sees of the FMU's outputs.
 *
 * Encoders: the gimbal angles plus an offset, quantized to the resolution.
 * The rate the controller feeds back, about the payload's axes (frame 2), in one of two schemes:
 *   direct:   a gyro on the payload reads los.omega (gyro.h);
 *   indirect: a gyro on the carrier reads the carrier's rate (frame 0; its readings of the whole
 *             run are computed before it, `carrier_rate`, since the carrier's motion is prescribed)
 *             and the gimbal's kinematics carry it to the payload with the encoder angles and the
 *             joint rates (a tachometer's exact alpha_dot, beta_dot, or the encoders' backward
 *             differences):  w2 = Rx(b)^T (Rz(a)^T w0 + [0, 0, a']) + [b', 0, 0].
 * Then, in either scheme, the white noise of the older `gyro_noise_deg_s` setting (drawn before the
 * run; gimbal2axis/scene/sensors.py draws every random number from the scene's seed). */
#ifndef GIMBAL_KERNEL_SENSORS_H
#define GIMBAL_KERNEL_SENSORS_H

#include "gimbal_kernel/gyro.h"
#include "gimbal_kernel/layout.h"

#define GIMBAL_SENSORS_FIELDS(FIELD, ARRAY)                                                          \
    FIELD(double, encoder_resolution, double) /* rad; 0: the exact angle */                          \
    FIELD(const double*, gyro_noise, pointer) /* (n + 1) x 3, added to the rate; NULL: none */       \
    ARRAY(double, encoder_offset, double, 2)  /* rad, added to alpha, beta before quantization */     \
    FIELD(int, indirect, int)                 /* 0: direct (payload gyro), 1: indirect */             \
    FIELD(int, joint_rate_from_encoders, int) /* indirect: 1 backward differences, 0 tachometer */   \
    FIELD(double, h, double)                  /* the sample time of those differences, s */          \
    FIELD(GimbalGyro, gyro, GimbalGyro)       /* direct: the payload gyro */                         \
    FIELD(const double*, carrier_rate, pointer) /* indirect: (n + 1) x 3, the carrier gyro's output */ \
    ARRAY(double, previous_encoder, double, 2)
GIMBAL_STRUCT(GimbalSensors, GIMBAL_SENSORS_FIELDS)

/* measured: (alpha, beta, los.omega[1..3], alpha_dot, beta_dot) of the FMU at communication point k
 * in; (encoder alpha, encoder beta, the rate fed back [3]) out, in place (the last two are left). */
#ifdef __cplusplus
extern "C" {
#endif
void gimbal_sensors_measure(GimbalSensors* sensors, long k, double measured[7]);
#ifdef __cplusplus
}
#endif
#endif
