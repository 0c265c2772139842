#include "sensors.h"

#include <math.h>
#include <stddef.h>

void gimbal_sensors_measure(const GimbalSensors* sensors, long k, double measured[5]) {
    const double resolution = sensors->encoder_resolution;
    if (resolution > 0.0) {
        /* nearbyint rounds half to even, as Python's round() did */
        measured[0] = resolution * nearbyint(measured[0] / resolution);
        measured[1] = resolution * nearbyint(measured[1] / resolution);
    }
    if (sensors->gyro_noise != NULL)
        for (int j = 0; j < 3; ++j) measured[2 + j] = measured[2 + j] + sensors->gyro_noise[3 * k + j];
}
