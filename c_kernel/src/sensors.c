#include "gimbal_kernel/sensors.h"

#include <math.h>
#include <stddef.h>

static double encoder(double angle, double offset, double resolution) {
    if (offset != 0.0) angle += offset;   /* skipped at 0: -0.0 + 0.0 would turn the sign bit */
    /* nearbyint rounds half to even, as Python's round() did */
    return resolution > 0.0 ? resolution * nearbyint(angle / resolution) : angle;
}

/* The payload's inertial rate from the carrier gyro's reading through the gimbal's kinematics
 * (docs/physics.md 3.1): w1 = Rz(a)^T w0 + [0, 0, a'], w2 = Rx(b)^T w1 + [b', 0, 0]. */
static void carry_to_payload(const double carrier[3], double alpha, double beta, double alpha_rate,
                             double beta_rate, double payload[3]) {
    const double ca = cos(alpha), sa = sin(alpha), cb = cos(beta), sb = sin(beta);
    const double w1x = ca * carrier[0] + sa * carrier[1];
    const double w1y = -sa * carrier[0] + ca * carrier[1];
    const double w1z = carrier[2] + alpha_rate;
    payload[0] = w1x + beta_rate;
    payload[1] = cb * w1y + sb * w1z;
    payload[2] = -sb * w1y + cb * w1z;
}

static void indirect_rate(GimbalSensors* s, long k, double measured[7]) {
    double alpha_rate = measured[5], beta_rate = measured[6];
    if (s->joint_rate_from_encoders) {
        /* the first sample has no predecessor: its difference is 0 */
        if (k > 0) {
            alpha_rate = (measured[0] - s->previous_encoder[0]) / s->h;
            beta_rate = (measured[1] - s->previous_encoder[1]) / s->h;
        } else {
            alpha_rate = 0.0, beta_rate = 0.0;
        }
        s->previous_encoder[0] = measured[0], s->previous_encoder[1] = measured[1];
    }
    carry_to_payload(s->carrier_rate + 3 * k, measured[0], measured[1], alpha_rate, beta_rate, measured + 2);
}

void gimbal_sensors_measure(GimbalSensors* s, long k, double measured[7]) {
    measured[0] = encoder(measured[0], s->encoder_offset[0], s->encoder_resolution);
    measured[1] = encoder(measured[1], s->encoder_offset[1], s->encoder_resolution);
    if (s->indirect)
        indirect_rate(s, k, measured);
    else
        gimbal_gyro_measure(&s->gyro, k, measured + 2, measured + 2);
    if (s->gyro_noise != NULL)
        for (int j = 0; j < 3; ++j) measured[2 + j] = measured[2 + j] + s->gyro_noise[3 * k + j];
}
