#include "gimbal/simulation/linearization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gimbal {
namespace {

static_assert(vr_base_a_a_3 - vr_u_R1 == 16 && vr_u_R2 == vr_u_R1 + 1 && vr_base_delta == vr_u_R1 + 2,
              "the linear model's inputs are the 17 Real inputs in value-reference order");
static_assert(vr_los_omega_3 - vr_alpha == 16 && vr_theta_b2 == vr_alpha + 11 && vr_T_E1 == vr_alpha + 12,
              "the linear model's outputs are alpha .. los.omega[3] in value-reference order");

// The input of index k (0 .. 16) within the step inputs. A voltage is the one applied (after the
// clamp), so that perturbing it bypasses the clamp; the clamp's own derivative is applied apart.
double& input_slot(const ModelParameters& params, StepInputs& inputs, int k) {
    if (k < 2) return params.fidelity.drive[k] == DriveMode::current ? inputs.current_command[k] : inputs.voltage[k];
    const int group = (k - 2) / 3, component = (k - 2) % 3;
    BaseMotion& base = inputs.base;
    Vec3* vectors[5] = {&base.attitude, &base.attitude_rate, &base.attitude_accel, &base.velocity_a,
                        &base.acceleration_a};
    return (*vectors[group])[component];
}

void output_values(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                   const double* state, double* y) {
    const ModelOutputs out = evaluate_outputs(params, inputs, modes, time, state);
    for (int k = 0; k < 4; ++k) {
        y[k] = out.full.angle[k];
        y[4 + k] = out.full.rate[k];
    }
    y[8] = out.full.current[0], y[9] = out.full.current[1];
    y[10] = out.full.backlash[0], y[11] = out.full.backlash[1];
    y[12] = out.shaft_torque[0], y[13] = out.shaft_torque[1];
    for (int k = 0; k < 3; ++k) y[14 + k] = out.payload_angular_velocity[k];
}

void state_rates(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                 const double* state, double* rates) {
    evaluate_state_derivative(params, inputs, modes, base_kinematics_at(params, inputs, time), time, state, rates);
}

// Central differences balance truncation (h^2) against rounding (eps / h) at h ~ eps^(1/3).
double difference_step(double value) {
    return std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::fabs(value));
}

// The output each state slot carries (the state's name in the linear model).
void name_states(const StateLayout& layout, LinearModel& out) {
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        out.state_variable[layout.angle_slot[body]] = static_cast<RealVariable>(kLinearFirstOutput + body);
        out.state_variable[layout.rate_slot[body]] = static_cast<RealVariable>(kLinearFirstOutput + 4 + body);
    }
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) out.state_variable[layout.current_slot[axis]] = axis == 0 ? vr_i_R1 : vr_i_R2;
        if (layout.backlash_slot[axis] >= 0)
            out.state_variable[layout.backlash_slot[axis]] = axis == 0 ? vr_theta_b1 : vr_theta_b2;
        if (layout.amplifier_slot[axis] >= 0)
            out.state_variable[layout.amplifier_slot[axis]] = axis == 0 ? vr_amplifier1_x_I : vr_amplifier2_x_I;
    }
}

// B and D by central differences of the rates and the outputs in each input; a voltage held at its
// clamp passes nothing (voltage_passes[axis] = 0).
void input_columns(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                   const double* state, const double (&voltage_passes)[2], LinearModel& out) {
    const int n = out.state_count;
    double plus[kMaxStateSize], minus[kMaxStateSize];
    double y_plus[kLinearOutputCount], y_minus[kLinearOutputCount];
    for (int k = 0; k < kLinearInputCount; ++k) {
        StepInputs shifted = inputs;
        double& value = input_slot(params, shifted, k);
        const double centre = value, step = difference_step(centre);
        value = centre + step;
        state_rates(params, shifted, modes, time, state, plus);
        output_values(params, shifted, modes, time, state, y_plus);
        value = centre - step;
        state_rates(params, shifted, modes, time, state, minus);
        output_values(params, shifted, modes, time, state, y_minus);
        const double scale = (k < 2 ? voltage_passes[k] : 1.0) / (2.0 * step);
        for (int row = 0; row < n; ++row) out.B[row][k] = (plus[row] - minus[row]) * scale;
        for (int row = 0; row < kLinearOutputCount; ++row) out.D[row][k] = (y_plus[row] - y_minus[row]) * scale;
    }
}

// C by central differences of the outputs in each state.
void state_output_columns(const ModelParameters& params, const StepInputs& inputs, const Modes& modes, double time,
                          const double* state, LinearModel& out) {
    double y_plus[kLinearOutputCount], y_minus[kLinearOutputCount];
    double shifted[kMaxStateSize];
    std::copy(state, state + params.layout.size, shifted);
    for (int col = 0; col < out.state_count; ++col) {
        const double step = difference_step(state[col]);
        shifted[col] = state[col] + step;
        output_values(params, inputs, modes, time, shifted, y_plus);
        shifted[col] = state[col] - step;
        output_values(params, inputs, modes, time, shifted, y_minus);
        shifted[col] = state[col];
        for (int row = 0; row < kLinearOutputCount; ++row) out.C[row][col] = (y_plus[row] - y_minus[row]) / (2.0 * step);
    }
}

}  // namespace

void linearize(const ModelParameters& params, const StepInputs& given_inputs, const Modes& modes, double time,
               const double* state, LinearModel& out) {
    const StateLayout& layout = params.layout;
    const int n = layout.energy_slot >= 0 ? layout.energy_slot : layout.size;
    out = LinearModel();
    out.state_count = n;
    out.modes = modes;
    name_states(layout, out);

    StepInputs inputs = given_inputs;
    inputs.step_start_time = time;
    inputs.voltage_rate[0] = inputs.voltage_rate[1] = 0.0;
    // A held voltage at or beyond its clamp does not respond to a small change (voltage_clamp.hpp,
    // held_clamp_side): its column is 0 and the mode says clamped, on the side of the limit.
    double voltage_passes[2];
    for (int k = 0; k < kLinearInputCount; ++k) out.input_variable[k] = static_cast<RealVariable>(kLinearFirstInput + k);
    for (int axis = 0; axis < 2; ++axis) {
        if (params.fidelity.drive[axis] == DriveMode::current) {
            // Current drive: the column is the current command's; one at or beyond +-i_L passes nothing.
            out.input_variable[axis] = axis == 0 ? vr_i_R1_cmd : vr_i_R2_cmd;
            const double limit = params.motor[axis].current_limit;
            inputs.current_command[axis] = std::clamp(inputs.commanded_current[axis], -limit, limit);
            voltage_passes[axis] = std::fabs(inputs.commanded_current[axis]) >= limit ? 0.0 : 1.0;
            continue;
        }
        const double commanded = inputs.commanded_voltage[axis];
        inputs.voltage[axis] = clamp_voltage(params.motor[axis], commanded);
        const int side = held_clamp_side(params.motor[axis], commanded);
        voltage_passes[axis] = side != 0 ? 0.0 : 1.0;
        if (side != 0) out.modes.voltage_clamped[axis] = side;
    }

    const BaseKinematics base = base_kinematics_at(params, inputs, time);
    Dynamics dynamics;
    evaluate_dynamics(params, inputs, base, time, state, modes, dynamics);
    double jacobian[kMaxStateSize * kMaxStateSize];
    evaluate_jacobian(params, modes, base, dynamics, jacobian);
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col) out.A[row][col] = jacobian[col * layout.size + row];

    input_columns(params, inputs, modes, time, state, voltage_passes, out);
    state_output_columns(params, inputs, modes, time, state, out);
}

}  // namespace gimbal
