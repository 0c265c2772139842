// Micro-benchmark of the rigid-body part of the right-hand side: the generic implementation the
// specialised one replaced (the reference copy in tests/model_core/multibody/test_rigid_body_fast.cpp) against the current
// model_core code, in CPU nanoseconds per call.
//
//   build-rb/benchmarks/bench_rigid_body [calls per measurement, default 2000000]
//
// Inputs cycle through a table of random states so that nothing can be hoisted out of the loop, and
// every output feeds a checksum that is printed, so that nothing can be discarded.
#define GIMBAL_RIGID_BODY_REFERENCE_ONLY
#include "test_rigid_body_fast.cpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <vector>

using namespace gimbal;

namespace {

constexpr int kTableSize = 256;  // a power of two; small enough to stay in L1

struct Case {
    MultibodyModel model;
    BaseMotion base_motion;
    BaseKinematics base;  // of base_motion, for the parts timed without the base kinematics
    random_gimbal::State state;
    Mat4 mass_matrix;     // at that state, for the solves
    Eigen::Matrix<double, 4, 12> many_rhs;
};

double cpu_seconds() {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

// The reference is compiled in this file: keep it out of line like the library code it is compared
// with, so that neither gets inlined into the timing loop.
__attribute__((noinline)) BaseKinematics old_base(const BaseMotion& motion, double gravity) {
    return reference::evaluate_base_kinematics(motion, gravity);
}
__attribute__((noinline)) void old_rigid_body(const MultibodyModel& model, const BaseKinematics& base, const Vec4& q,
                                              const Vec4& qd, Mat4& J, Vec4& f) {
    reference::compute_mass_matrix_and_bias(model, base, q, qd, J, f);
}
__attribute__((noinline)) Vec4 llt_solve(const Mat4& J, const Vec4& rhs) { return J.llt().solve(rhs); }
__attribute__((noinline)) Vec4 arrow_solve(const Mat4& J, const Vec4& rhs) { return solve_mass_matrix(J, rhs); }
__attribute__((noinline)) Eigen::Matrix<double, 4, 12> llt_solve_many(const Mat4& J,
                                                                       const Eigen::Matrix<double, 4, 12>& rhs) {
    return J.llt().solve(rhs);
}
__attribute__((noinline)) Eigen::Matrix<double, 4, 12> arrow_solve_many(const Mat4& J,
                                                                         const Eigen::Matrix<double, 4, 12>& rhs) {
    return solve_mass_matrix(J, rhs);
}
__attribute__((noinline)) double old_output_quantities(const Case& c) {
    const MultibodyEnergy e =
        reference::compute_energy(c.model, c.base, c.base_motion.velocity_a, c.state.q, c.state.qd);
    return e.kinetic + e.potential + reference::payload_angular_velocity(c.base, c.state.q, c.state.qd).sum();
}
__attribute__((noinline)) double new_output_quantities(const Case& c) {
    const MultibodyEnergy e = compute_energy(c.model, c.base, c.base_motion.velocity_a, c.state.q, c.state.qd);
    return e.kinetic + e.potential + payload_angular_velocity(c.base, c.state.q, c.state.qd).sum();
}

// ns per call of `body(case)`, the best of a few repetitions (the least disturbed by the machine).
template <typename Body>
double time_per_call(const std::vector<Case>& cases, long calls, double& checksum, Body body) {
    double best = 1e300;
    for (int repetition = 0; repetition < 5; ++repetition) {
        double sum = 0.0;
        const double start = cpu_seconds();
        for (long i = 0; i < calls; ++i) sum += body(cases[i & (kTableSize - 1)]);
        best = std::min(best, (cpu_seconds() - start) / calls * 1e9);
        checksum += sum;
    }
    return best;
}

void report(const char* what, double old_ns, double new_ns) {
    std::printf("  %-46s %7.1f ns  %7.1f ns  %5.2fx\n", what, old_ns, new_ns, old_ns / new_ns);
}

void run(const char* title, const std::vector<Case>& cases, long calls) {
    double checksum = 0.0;
    auto rigid_old = [](const Case& c) {
        Mat4 J;
        Vec4 f;
        old_rigid_body(c.model, c.base, c.state.q, c.state.qd, J, f);
        return J(0, 0) + f.sum();
    };
    auto rigid_new = [](const Case& c) {
        Mat4 J;
        Vec4 f;
        compute_mass_matrix_and_bias(c.model, c.base, c.state.q, c.state.qd, J, f);
        return J(0, 0) + f.sum();
    };
    auto base_old = [](const Case& c) {
        const BaseKinematics k = old_base(c.base_motion, c.model.gravity);
        return k.G_T_0(1, 2) + k.angular_accel.x() + k.gravity.y();
    };
    auto base_new = [](const Case& c) {
        const BaseKinematics k = evaluate_base_kinematics(c.base_motion, c.model.gravity);
        return k.G_T_0(1, 2) + k.angular_accel.x() + k.gravity.y();
    };
    auto both_old = [](const Case& c) {
        Mat4 J;
        Vec4 f;
        old_rigid_body(c.model, old_base(c.base_motion, c.model.gravity), c.state.q, c.state.qd, J, f);
        return J(0, 0) + f.sum();
    };
    auto both_new = [](const Case& c) {
        Mat4 J;
        Vec4 f;
        compute_mass_matrix_and_bias(c.model, evaluate_base_kinematics(c.base_motion, c.model.gravity), c.state.q,
                                     c.state.qd, J, f);
        return J(0, 0) + f.sum();
    };
    std::printf("%s\n  %-46s %10s  %10s  %6s\n", title, "", "old", "new", "speedup");
    report("evaluate_base_kinematics", time_per_call(cases, calls, checksum, base_old),
           time_per_call(cases, calls, checksum, base_new));
    report("compute_mass_matrix_and_bias", time_per_call(cases, calls, checksum, rigid_old),
           time_per_call(cases, calls, checksum, rigid_new));
    report("both (the rigid-body part of one RHS)", time_per_call(cases, calls, checksum, both_old),
           time_per_call(cases, calls, checksum, both_new));
    report("solve J x = f: LLT / solve_mass_matrix",
           time_per_call(cases, calls, checksum, [](const Case& c) { return llt_solve(c.mass_matrix, c.many_rhs.col(0)).sum(); }),
           time_per_call(cases, calls, checksum, [](const Case& c) { return arrow_solve(c.mass_matrix, c.many_rhs.col(0)).sum(); }));
    report("solve with 12 right-hand sides",
           time_per_call(cases, calls, checksum, [](const Case& c) { return llt_solve_many(c.mass_matrix, c.many_rhs).sum(); }),
           time_per_call(cases, calls, checksum, [](const Case& c) { return arrow_solve_many(c.mass_matrix, c.many_rhs).sum(); }));
    report("compute_energy + payload_angular_velocity",
           time_per_call(cases, calls, checksum, old_output_quantities),
           time_per_call(cases, calls, checksum, new_output_quantities));
    std::printf("  (checksum %.6g)\n", checksum);
}

std::vector<Case> make_cases(random_gimbal::RotorShape rotor_shape) {
    std::mt19937_64 rng(7);
    std::vector<Case> cases(kTableSize);
    for (Case& c : cases) {
        c.model = random_gimbal::model(rng, rotor_shape, rotor_shape);
        c.base_motion = random_gimbal::base_motion(rng);
        c.base = evaluate_base_kinematics(c.base_motion, c.model.gravity);
        c.state = random_gimbal::state(rng);
        Vec4 f;
        compute_mass_matrix_and_bias(c.model, c.base, c.state.q, c.state.qd, c.mass_matrix, f);
        c.many_rhs = Eigen::Matrix<double, 4, 12>::Random();
    }
    return cases;
}

}  // namespace

int main(int argc, char** argv) {
    const long calls = argc > 1 ? std::atol(argv[1]) : 2000000;
    run("Axisymmetric rotors (the usual gimbal):", make_cases(random_gimbal::RotorShape::axisymmetric), calls);
    run("General rotors (products of inertia, centre of mass off the axis):",
        make_cases(random_gimbal::RotorShape::general), calls);
    return 0;
}
