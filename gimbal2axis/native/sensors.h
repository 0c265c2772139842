/* What the controller sees of the FMU's outputs: the encoder angles quantized to the encoder's
 * resolution, the payload gyro with white noise drawn before the run (gimbal2axis/scene/sensors.py draws it
 * from the scene's seed). */
#ifndef GIMBAL_KERNEL_SENSORS_H
#define GIMBAL_KERNEL_SENSORS_H

#include "layout.h"

#define GIMBAL_SENSORS_FIELDS(FIELD, ARRAY)                                                      \
    FIELD(double, encoder_resolution, double) /* rad; 0: the exact angle */                      \
    FIELD(const double*, gyro_noise, pointer) /* (n + 1) x 3, added to the gyro; NULL: none */
GIMBAL_STRUCT(GimbalSensors, GIMBAL_SENSORS_FIELDS)

/* The measurement at communication point k, in place: measured = (alpha, beta, gyro[3]), the FMU's
 * values in, what the sensors give out. */
#ifdef __cplusplus
extern "C" {
#endif
void gimbal_sensors_measure(const GimbalSensors* sensors, long k, double measured[5]);
#ifdef __cplusplus
}
#endif
#endif
