#include "gimbal/simulation/step_inputs.hpp"

namespace gimbal {

void carry_inputs_to(const StepInputs& running, double time, bool fixed_base, double (&reals)[kRealVariableCount]) {
    const BaseMotion base = running.base.advanced(time - running.step_start_time);
    const Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                            &base.acceleration_a};
    const RealVector* vectors[5] = {&kBaseMotion.attitude, &kBaseMotion.attitude_rate, &kBaseMotion.attitude_accel,
                                    &kBaseMotion.velocity_a, &kBaseMotion.acceleration_a};
    if (!fixed_base)
        for (int p = 0; p < 5; ++p)
            for (int k = 0; k < 3; ++k) reals[(*vectors[p])[k]] = (*parts[p])[k];
    const RealVariable voltages[2] = {vr_u_R1, vr_u_R2};
    for (int axis = 0; axis < 2; ++axis)
        if (running.voltage_rate[axis] != 0.0) reals[voltages[axis]] = ramped_voltage(running, axis, time);
}

void write_base_motion(const BaseMotion& base, double* values) {
    const Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                            &base.acceleration_a};
    for (int p = 0; p < 5; ++p)
        for (int k = 0; k < 3; ++k) values[3 * p + k] = (*parts[p])[k];
}

BaseMotion read_base_motion(const double* values) {
    BaseMotion base;
    Vec3* parts[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                      &base.acceleration_a};
    for (int p = 0; p < 5; ++p)
        for (int k = 0; k < 3; ++k) (*parts[p])[k] = values[3 * p + k];
    return base;
}

}  // namespace gimbal
