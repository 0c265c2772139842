// An instance's input handling (simulation/step_inputs.cpp): the inputs a step starts from, read off
// the variable values; whether they continue the running ones (then the integrator keeps its history);
// the inputs a step that ended early carried to where it ended; the base motion as plain numbers.
#pragma once

#include <algorithm>
#include <cmath>

#include "gimbal/multibody/drive_train.hpp"
#include "gimbal/model/gimbal_model.hpp"
#include "gimbal/model/variable_groups.hpp"
#include "gimbal/model/variables.hpp"

namespace gimbal {

// Read at every doStep: defined here, inline.

// The inputs of a step from `step_start` (model time): the voltages as set, clamped, with the
// derivatives given for this step; the base motion.
inline StepInputs read_step_inputs(const ModelParameters& params, const double (&reals)[kRealVariableCount],
                                   const double (&voltage_rate)[2], double step_start) {
    StepInputs inputs;
    inputs.commanded_voltage[0] = reals[vr_u_R1];
    inputs.commanded_voltage[1] = reals[vr_u_R2];
    for (int axis = 0; axis < 2; ++axis) {
        inputs.voltage[axis] = clamp_voltage(params.motor[axis], inputs.commanded_voltage[axis]);
        inputs.voltage_rate[axis] = voltage_rate[axis];
    }
    // Current drive: the current command, clamped to +-i_L like a voltage to +-U_L; the voltage input
    // is not used (nor ramped), so that the voltage clamp never acts.
    const RealVariable commands[2] = {vr_i_R1_cmd, vr_i_R2_cmd};
    for (int axis = 0; axis < 2; ++axis) {
        if (params.fidelity.drive[axis] != DriveMode::current) continue;
        inputs.commanded_voltage[axis] = inputs.voltage[axis] = inputs.voltage_rate[axis] = 0.0;
        const double limit = params.motor[axis].current_limit;
        inputs.commanded_current[axis] = reals[commands[axis]];
        inputs.current_command[axis] = std::clamp(reals[commands[axis]], -limit, limit);
    }
    inputs.base.attitude = read_vector(reals, kBaseMotion.attitude);
    inputs.base.attitude_rate = read_vector(reals, kBaseMotion.attitude_rate);
    inputs.base.attitude_accel = read_vector(reals, kBaseMotion.attitude_accel);
    inputs.base.velocity_a = read_vector(reals, kBaseMotion.velocity_a);
    inputs.base.acceleration_a = read_vector(reals, kBaseMotion.acceleration_a);
    inputs.step_start_time = step_start;
    return inputs;
}

// Whether the voltages at the start of a step continue the running ramps: then nothing jumps. A
// master's own arithmetic may differ from ours in the last bits, hence the tolerance.
inline bool voltages_continue(const StepInputs& running, const StepInputs& next, double time) {
    for (int axis = 0; axis < 2; ++axis) {
        if (running.current_command[axis] != next.current_command[axis]) return false;
        if (running.voltage_rate[axis] == 0.0 && next.voltage_rate[axis] == 0.0) {
            if (running.voltage[axis] != next.voltage[axis]) return false;
            continue;
        }
        const double expected = ramped_voltage(running, axis, time);
        if (std::fabs(next.commanded_voltage[axis] - expected) > 1e-12 * std::max(1.0, std::fabs(expected)))
            return false;
    }
    return true;
}

inline bool same_base_motion(const BaseMotion& a, const BaseMotion& b) {
    return a.attitude == b.attitude && a.attitude_rate == b.attitude_rate && a.attitude_accel == b.attitude_accel &&
           a.velocity_a == b.velocity_a && a.acceleration_a == b.acceleration_a;
}

// Whether `next` continues `running` at `time`: the held voltages are the same (or follow the running
// ramps, within a master's rounding) and the base motion continues the running constant-acceleration
// arc. Then the right-hand side does not jump at the step boundary.
inline bool continues_running_inputs(const StepInputs& running, const StepInputs& next, double time) {
    return voltages_continue(running, next, time) &&
           same_base_motion(next.base, running.base.advanced(time - running.step_start_time));
}

// Whether a step from `running` to `next` changes the voltages the integrator follows (it keeps its
// history but must take the new ramps).
inline bool voltages_changed(const StepInputs& running, const StepInputs& next) {
    return next.voltage_rate[0] != running.voltage_rate[0] || next.voltage_rate[1] != running.voltage_rate[1] ||
           next.commanded_voltage[0] != running.commanded_voltage[0] ||
           next.commanded_voltage[1] != running.commanded_voltage[1] ||
           next.commanded_current[0] != running.commanded_current[0] ||
           next.commanded_current[1] != running.commanded_current[1];
}

// After a step that ended early at `time`: the inputs as the step carried them there (the carrier's
// arc unless the base is fixed, ramped voltages), written to the input variables, so that a master
// that sets nothing new continues the same problem.
void carry_inputs_to(const StepInputs& running, double time, bool fixed_base, double (&reals)[kRealVariableCount]);

// A base motion as 15 numbers (an FMU state's): attitude, rate, acceleration, v_a, a_a.
void write_base_motion(const BaseMotion& base, double* values);
BaseMotion read_base_motion(const double* values);

}  // namespace gimbal
