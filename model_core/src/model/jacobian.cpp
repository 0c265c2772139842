// d(dx/dt)/dx (gimbal_model.hpp, evaluate_jacobian), from the same passes as the dynamics: the
// drive train's elements (gear_backlash, current_limiter), the disturbance elements (cable, cogging),
// the multibody terms, the dry friction element's hold torques, the axis end stops' reactions while a
// body rests on one, and the state rows of the elements with states of their own.
#include "gimbal/model/gimbal_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gimbal {
namespace {

// The disturbance elements' derivatives (disturbance_torques.hpp): the cable's -k and -c on its joint,
// the cogging's dT/dq_m on its rotor. Full coordinates: a rigid axis's rotor column reaches the load
// through the projection to padded coordinates, as its forces do through the reduction.
void add_disturbance_force_derivatives(const DisturbanceParameters& disturbances, const Vec4& q, Mat4x12& force) {
    for (int axis = 0; axis < 2; ++axis) {
        const int rotor = rotor_index(axis), load = load_index(axis);
        const CableRestraint& cable = disturbances.cable[axis];
        force(load, kAngleColumn + load) -= cable.stiffness;
        force(load, kRateColumn + load) -= cable.damping;
        force(rotor, kAngleColumn + rotor) += cogging_torque_slope(disturbances.cogging[axis], q[rotor]);
    }
}

// Derivatives of the full generalized forces of the drive train: viscous friction, then per axis the
// gear's shaft torque and the motor's torque, then the disturbance elements if any is on (the order of
// the sums is the results' bits).
Mat4x12 drive_train_force_derivatives(const ModelParameters& params, const Modes& modes, const Vec4& q) {
    Mat4x12 force = Mat4x12::Zero();
    for (int body = 0; body < 4; ++body) force(body, kRateColumn + body) -= params.viscous_friction[body];
    for (int axis = 0; axis < 2; ++axis) {
        add_gear_force_derivatives(params, modes, axis, force);
        add_motor_force_derivatives(params, modes, axis, force);
    }
    if (params.disturbances.active) add_disturbance_force_derivatives(params.disturbances, q, force);
    return force;
}

// The rigid-body terms, which vary slowly with the configuration and the rates (gravity, carrier
// motion, gyroscopic and centripetal forces, the mass matrix's dependence on the angles), by forward
// differences of J(q) and f(q, qd), added to `force`; dJ/dq_j (full coordinates) to
// `inertia_derivative`. A Rosenbrock method keeps its order only with the whole Jacobian.
void add_rigid_body_derivatives(const ModelParameters& params, const BaseKinematics& base, const Dynamics& d,
                                Mat4x12& force, Mat4 (&inertia_derivative)[4]) {
    const Vec4& q = d.full.angle;
    const Vec4& qd = d.full.rate;
    Mat4 mass_matrix, perturbed_mass;
    Vec4 bias, perturbed_bias;
    compute_mass_matrix_and_bias(params.multibody, base, q, qd, mass_matrix, bias);
    const double root_epsilon = std::sqrt(std::numeric_limits<double>::epsilon());
    for (int j = 0; j < 4; ++j) {
        Vec4 shifted = q;
        inertia_derivative[j].setZero();
        if (depends_on_angle(params.multibody, j)) {
            const double step = root_epsilon * std::max(1.0, std::fabs(q[j]));
            shifted[j] += step;
            compute_mass_matrix_and_bias(params.multibody, base, shifted, qd, perturbed_mass, perturbed_bias);
            inertia_derivative[j] = (perturbed_mass - mass_matrix) / step;
            force.col(j) += (perturbed_bias - bias) / step;
        }
        shifted = qd;
        const double rate_step = root_epsilon * std::max(1.0, std::fabs(qd[j]));
        shifted[j] += rate_step;
        compute_mass_matrix_and_bias(params.multibody, base, q, shifted, perturbed_mass, perturbed_bias);
        force.col(kRateColumn + j) += (perturbed_bias - bias) / rate_step;
    }
}

// To padded coordinates: q_full = T q_padded, forces projected with T^T; and
// d(T^T J T)/dq_padded,k = sum_j T(j, k) T^T dJ/dq_j T.
Mat4x12 to_padded(const Mat4& T, const Mat4x12& force, const Mat4 (&inertia_derivative)[4],
                  Mat4 (&padded_inertia_derivative)[4]) {
    Mat4x12 applied;
    applied.block<4, 4>(0, 0) = T.transpose() * force.block<4, 4>(0, 0) * T;
    applied.block<4, 4>(0, 4) = T.transpose() * force.block<4, 4>(0, 4) * T;
    applied.block<4, 4>(0, 8) = T.transpose() * force.block<4, 4>(0, 8);
    for (int k = 0; k < 4; ++k) {
        Mat4 full = Mat4::Zero();
        for (int j = 0; j < 4; ++j)
            if (T(j, k) != 0.0) full += T(j, k) * inertia_derivative[j];
        padded_inertia_derivative[k] = T.transpose() * full * T;
    }
    return applied;
}

// The integrated state's rows: the kinematic identities, the accelerations, and the rows of the
// elements with a state of their own (the inductive current, the backlash, the amplifier's integrator), in
// the layout's slots.
void write_state_rows(const ModelParameters& params, const Modes& modes, const Mat4& T, const Mat4x12& acceleration,
                      double* column_major) {
    const StateLayout& layout = params.layout;
    const int n = layout.size;
    // Column of the padded-derivative matrices that a state slot stands for.
    int column_of_slot[kMaxStateSize];
    for (int k = 0; k < n; ++k) column_of_slot[k] = -1;
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        column_of_slot[layout.angle_slot[body]] = kAngleColumn + body;
        column_of_slot[layout.rate_slot[body]] = kRateColumn + body;
    }
    for (int axis = 0; axis < 2; ++axis) {
        if (layout.current_slot[axis] >= 0) column_of_slot[layout.current_slot[axis]] = kCurrentColumn + axis;
        if (layout.backlash_slot[axis] >= 0) column_of_slot[layout.backlash_slot[axis]] = kBacklashColumn + axis;
    }
    Eigen::Map<Eigen::MatrixXd> jac(column_major, n, n);
    jac.setZero();
    auto fill_row = [&](int row, const Row12& derivative) {
        for (int slot = 0; slot < n; ++slot)
            if (column_of_slot[slot] >= 0) jac(row, slot) = derivative(column_of_slot[slot]);
    };
    for (int body = 0; body < 4; ++body) {
        if (!layout.independent(body)) continue;
        jac(layout.angle_slot[body], layout.rate_slot[body]) = 1.0;
        fill_row(layout.rate_slot[body], acceleration.row(body));
    }
    Row12 row;
    for (int axis = 0; axis < 2; ++axis) {
        if (current_state_row(params, modes, axis, T, row)) fill_row(layout.current_slot[axis], row);
        if (backlash_state_row(params, modes, axis, T, row)) fill_row(layout.backlash_slot[axis], row);
        add_amplifier_state_entries(params, modes, axis, jac);
    }
}

}  // namespace

void evaluate_jacobian(const ModelParameters& params, const Modes& modes, const BaseKinematics& base,
                       const Dynamics& d, double* column_major) {
    // Full coordinates: the switching elements' force derivatives, then the multibody terms.
    Mat4x12 force = drive_train_force_derivatives(params, modes, d.full.angle);
    Mat4 inertia_derivative[4];  // dJ/dq_j, full coordinates
    add_rigid_body_derivatives(params, base, d, force, inertia_derivative);

    const Mat4 T = coordinate_reduction(params);
    Mat4 padded_inertia_derivative[4];
    const Mat4x12 applied = to_padded(T, force, inertia_derivative, padded_inertia_derivative);

    // The dry friction element's hold torques, then the accelerations in padded coordinates.
    const Mat4x12 friction = hold_friction_derivatives(params, modes, d, applied, padded_inertia_derivative);
    Mat4x12 acceleration_rhs = applied + friction;
    for (int k = 0; k < 4; ++k) acceleration_rhs.col(k) -= padded_inertia_derivative[k] * d.acceleration;
    Mat4x12 acceleration = solve_mass_matrix<12>(d.reduced_mass, acceleration_rhs);
    hold_at_axis_stops_derivatives(modes, d.reduced_mass, acceleration);

    write_state_rows(params, modes, T, acceleration, column_major);
}

}  // namespace gimbal
