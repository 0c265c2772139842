#include "gimbal/probe_api.h"

#include "gimbal/rigid_body.hpp"

namespace {

gimbal::Vec3 vec3(const double* v) { return gimbal::Vec3(v[0], v[1], v[2]); }

}  // namespace

extern "C" int gimbal_probe_mass_matrix_and_bias(const GimbalProbeRigidBodyInput* input, double J_row_major[16],
                                                 double f[4]) {
    if (input == nullptr || J_row_major == nullptr || f == nullptr) return 1;
    gimbal::MultibodyModel model;
    for (int k = 0; k < 4; ++k) {
        const double* i = input->inertia[k];
        gimbal::RigidBody& body = model.bodies[k];
        body.mass = input->mass[k];
        body.inertia << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
        body.centre_of_mass = vec3(input->com[k]);
    }
    model.d_ab = vec3(input->d_ab);
    model.gravity = input->g;

    gimbal::BaseMotion base;
    base.attitude = vec3(input->attitude);
    base.attitude_rate = vec3(input->attitude_rate);
    base.attitude_accel = vec3(input->attitude_accel);
    base.velocity_a = vec3(input->v_a);
    base.acceleration_a = vec3(input->a_a);
    const gimbal::BaseKinematics kinematics = gimbal::evaluate_base_kinematics(base, model.gravity);

    const gimbal::Vec4 q(input->q[0], input->q[1], input->q[2], input->q[3]);
    const gimbal::Vec4 qd(input->qd[0], input->qd[1], input->qd[2], input->qd[3]);
    gimbal::Mat4 mass_matrix;
    gimbal::Vec4 bias;
    gimbal::compute_mass_matrix_and_bias(model, kinematics, q, qd, mass_matrix, bias);
    for (int r = 0; r < 4; ++r) {
        f[r] = bias[r];
        for (int c = 0; c < 4; ++c) J_row_major[4 * r + c] = mass_matrix(r, c);
    }
    return 0;
}
