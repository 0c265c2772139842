// Orders of the project's own one-step methods on time-dependent problems with known solutions, their
// continuous extensions, L-stability, and the automatic switch between them.
#include <cmath>
#include <cstdio>
#include <string>

#include "check.hpp"
#include "integrators/one_step_integrator.hpp"
#include "integrators/iteration_matrix.hpp"
#include "integrators/small_lu.hpp"

#include <random>
#include <Eigen/Dense>

using namespace gimbal;

namespace {

// y' = -lambda(t) (y - sin t) + cos t, y(0) = 1: y = sin t + exp(-Lambda(t)), Lambda' = lambda. With a
// constant lambda the problem is linear and time-dependent: a Rosenbrock method that mishandles df/dt
// drops to first order on it.
class ForcedRelaxation final : public HybridSystem {
public:
    // lambda(t) = base + bump * exp(-((t - centre) / width)^2)
    ForcedRelaxation(double base, double bump = 0.0, double centre = 1.5, double width = 0.2)
        : base_(base), bump_(bump), centre_(centre), width_(width) {}
    int state_size() const override { return 1; }
    int event_count() const override { return 0; }
    double lambda(double t) const { return base_ + bump_ * std::exp(-std::pow((t - centre_) / width_, 2)); }
    double exact(double t) const {
        const double integral =
            base_ * t + bump_ * width_ * std::sqrt(M_PI) / 2.0 * (std::erf((t - centre_) / width_) + std::erf(centre_ / width_));
        return std::sin(t) + std::exp(-integral);
    }
    bool derivative(double t, const double* y, double* dy) override {
        dy[0] = -lambda(t) * (y[0] - std::sin(t)) + std::cos(t);
        return true;
    }
    bool has_jacobian() const override { return true; }
    bool jacobian(double t, const double*, double* j) override {
        j[0] = -lambda(t);
        return true;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }

private:
    double base_, bump_, centre_, width_;
};

// A two-state oscillator with forcing, non-stiff: x'' = -x + cos(2t), x(0) = 1, x'(0) = 0:
// x = (4/3) cos t - (1/3) cos 2t. Its Jacobian has a complex pair.
class ForcedOscillator final : public HybridSystem {
public:
    int state_size() const override { return 2; }
    int event_count() const override { return 0; }
    static double exact(double t) { return 4.0 / 3.0 * std::cos(t) - std::cos(2.0 * t) / 3.0; }
    bool derivative(double t, const double* y, double* dy) override {
        dy[0] = y[1];
        dy[1] = -y[0] + std::cos(2.0 * t);
        return true;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
};

// The forced oscillator plus a state b that relaxes onto s = x / 2 - v at the rate 1e8 and acts on
// nothing: b' = s' + rate (s - b), b = s - (s - b)(0) exp(-rate t). Offered as a relaxing state, the
// explicit method takes b exactly: its order stays 5 with steps 5e6 times beyond its stability bound
// for b alone.
class OscillatorWithFollower final : public HybridSystem {
public:
    static constexpr double kRate = 1e8;
    int state_size() const override { return 3; }
    int event_count() const override { return 0; }
    static double x(double t) { return ForcedOscillator::exact(t); }
    static double v(double t) { return -4.0 / 3.0 * std::sin(t) + 2.0 / 3.0 * std::sin(2.0 * t); }
    static double source(double t) { return x(t) / 2.0 - v(t); }
    // b(0) = 0.3 with s(0) = 1/2.
    static double follower(double t) { return source(t) - (0.5 - 0.3) * std::exp(-kRate * t); }
    bool derivative(double t, const double* y, double* dy) override {
        dy[0] = y[1];
        dy[1] = -y[0] + std::cos(2.0 * t);
        const double source_rate = dy[0] / 2.0 - dy[1];
        dy[2] = source_rate + kRate * (y[0] / 2.0 - y[1] - y[2]);
        return true;
    }
    int relaxing_states(RelaxingState* out) const override {
        if (!offered) return 0;
        out[0] = RelaxingState{2, kRate, 0, 2.0, 1};
        return 1;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
    bool offered = true;
};

IntegratorSettings fixed_steps(IntegrationMethod method) {
    IntegratorSettings settings;
    settings.method = method;
    settings.relative_tolerance = 1e3;  // every step accepted: the step size is the one imposed
    settings.absolute_tolerance = 1e3;
    return settings;
}

auto quiet = [](const std::string&) {};

// Global error at t = 1 and the worst error of the continuous extension at the step midpoints, with
// `steps` equal steps.
struct Errors {
    double end = 0.0, dense = 0.0;
};

template <class System, class Exact>
Errors run_fixed(System& system, IntegrationMethod method, int steps, double y0[], Exact exact) {
    OneStepIntegrator integrator(system, fixed_steps(method), quiet, quiet);
    const double h = 1.0 / steps;
    IntegratorMemory memory;
    memory.step_size = h;
    double y[2] = {y0[0], y0[1]};
    CHECK(integrator.resume(0.0, y, memory));
    Errors errors;
    for (int k = 1; k <= steps; ++k) {
        const double end = k == steps ? 1.0 : k * h;
        CHECK(integrator.advance(end, y));
        double middle[2];
        const double t_middle = end - 0.5 * h;
        integrator.dense_output(t_middle, middle);
        errors.dense = std::max(errors.dense, std::fabs(middle[0] - exact(t_middle)));
    }
    CHECK(integrator.statistics().steps == steps);
    errors.end = std::fabs(y[0] - exact(1.0));
    return errors;
}

void check_order(const char* name, IntegrationMethod method, double order, double dense_order) {
    ForcedRelaxation relaxation(2.0);
    ForcedOscillator oscillator;
    for (int problem = 0; problem < 2; ++problem) {
        double y0[2] = {1.0, 0.0};
        Errors coarse, fine;
        if (problem == 0) {
            coarse = run_fixed(relaxation, method, 20, y0, [&](double t) { return relaxation.exact(t); });
            fine = run_fixed(relaxation, method, 40, y0, [&](double t) { return relaxation.exact(t); });
        } else {
            coarse = run_fixed(oscillator, method, 20, y0, ForcedOscillator::exact);
            fine = run_fixed(oscillator, method, 40, y0, ForcedOscillator::exact);
        }
        const double observed = std::log2(coarse.end / fine.end);
        const double observed_dense = std::log2(coarse.dense / fine.dense);
        std::printf("%s, problem %d: global error %.3g -> %.3g (order %.2f), dense %.3g -> %.3g (order %.2f)\n", name,
                    problem, coarse.end, fine.end, observed, coarse.dense, fine.dense, observed_dense);
        CHECK(std::fabs(observed - order) < 0.3);
        CHECK(observed_dense > dense_order - 0.3);
    }
}

}  // namespace

// The iteration matrix's LU against Eigen's, on random matrices that need pivoting, at every size the
// model has.
void check_small_lu() {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int n = 1; n <= 17; ++n) {
        Eigen::MatrixXd a(n, n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) a(i, j) = unit(random);
        if (n > 1) a(0, 0) = 0.0;  // the first pivot must come from another row
        Eigen::VectorXd b(n);
        for (int i = 0; i < n; ++i) b[i] = unit(random);
        SmallLU<24> lu;
        CHECK(lu.factorize(a.data(), n));
        Eigen::VectorXd x = b;
        lu.solve(x.data());
        const Eigen::VectorXd expected = a.partialPivLu().solve(b);
        CHECK((x - expected).norm() <= 1e-12 * (1.0 + expected.norm()));
    }
    Eigen::MatrixXd singular = Eigen::MatrixXd::Zero(3, 3);
    SmallLU<24> lu;
    CHECK(!lu.factorize(singular.data(), 3));
}

// The iteration matrix d I - J with the kinematic rows eliminated first, against Eigen's LU of the
// whole matrix: every layout of the model (4, 3 or 2 coordinates with their rates, other states
// after them, the rates not next to their angles), and the full LU kept when a kinematic row is not
// exactly a unit vector.
void check_iteration_matrix() {
    std::mt19937 random(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    struct Layout { int n, pairs; int position[4], velocity[4]; };
    const Layout layouts[] = {{12, 4, {0, 1, 2, 3}, {4, 5, 6, 7}},  // full fidelity
                              {17, 4, {0, 1, 2, 3}, {4, 5, 6, 7}},  // with the energy accumulators
                              {9, 3, {0, 1, 2}, {3, 4, 5}},
                              {4, 2, {0, 1}, {2, 3}},               // reduced
                              {6, 2, {3, 0}, {1, 5}},
                              {6, 2, {0, 1}, {1, 3}}};             // a velocity that is a position: full LU
    for (const Layout& layout : layouts) {
        for (bool exact_rows : {true, false}) {
            const int n = layout.n;
            Eigen::MatrixXd jacobian(n, n);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) jacobian(i, j) = 100.0 * unit(random);
            for (int k = 0; k < layout.pairs; ++k) {
                jacobian.row(layout.position[k]).setZero();
                jacobian(layout.position[k], layout.velocity[k]) = 1.0;
            }
            if (!exact_rows) jacobian(layout.position[0], layout.velocity[0]) = 1.0 + 1e-9;
            const double diagonal = 37.0;
            IterationMatrix<24> matrix;
            matrix.set_structure(n, layout.position, layout.velocity, layout.pairs);
            CHECK(matrix.factorize(jacobian.data(), diagonal));
            Eigen::VectorXd b(n);
            for (int i = 0; i < n; ++i) b[i] = unit(random);
            Eigen::VectorXd x = b;
            matrix.solve(x.data());
            const Eigen::MatrixXd a = diagonal * Eigen::MatrixXd::Identity(n, n) - jacobian;
            const Eigen::VectorXd expected = a.partialPivLu().solve(b);
            CHECK((x - expected).norm() <= 1e-12 * (1.0 + expected.norm()));
        }
    }
}

// Dormand-Prince with the relaxing state taken exactly: order 5 at the end and 4 in the continuous
// extension for every state, the follower included, with h rate = 5e6.
void check_relaxing_state_is_exact() {
    double previous_end = 0.0, previous_dense = 0.0;
    for (int steps : {20, 40}) {
        OscillatorWithFollower system;
        OneStepIntegrator integrator(system, fixed_steps(IntegrationMethod::dormand_prince), quiet, quiet);
        const double h = 1.0 / steps;
        IntegratorMemory memory;
        memory.step_size = h;
        double y[3] = {1.0, 0.0, 0.3};
        CHECK(integrator.resume(0.0, y, memory));
        double dense = 0.0, follower_dense = 0.0;
        for (int k = 1; k <= steps; ++k) {
            const double end = k == steps ? 1.0 : k * h;
            CHECK(integrator.advance(end, y));
            double middle[3];
            const double t_middle = end - 0.5 * h;
            integrator.dense_output(t_middle, middle);
            dense = std::max(dense, std::fabs(middle[0] - OscillatorWithFollower::x(t_middle)));
            follower_dense = std::max(follower_dense, std::fabs(middle[2] - OscillatorWithFollower::follower(t_middle)));
        }
        const double end_error = std::max(std::fabs(y[0] - OscillatorWithFollower::x(1.0)),
                                          std::fabs(y[2] - OscillatorWithFollower::follower(1.0)));
        std::printf("Dormand-Prince, relaxing follower (rate 1e8), %d steps: end error %.3g (follower %.3g), dense %.3g "
                    "(follower %.3g)\n", steps, end_error, std::fabs(y[2] - OscillatorWithFollower::follower(1.0)), dense,
                    follower_dense);
        CHECK(std::isfinite(end_error) && end_error < 1e-6);
        // The follower is exact but for its source's error, which has the method's orders.
        CHECK(follower_dense < 4.0 * dense + 1e-15);
        if (previous_end > 0.0) {
            CHECK(std::fabs(std::log2(previous_end / end_error) - 5.0) < 0.3);
            CHECK(std::log2(previous_dense / std::max(dense, follower_dense)) > 3.7);
        }
        previous_end = end_error, previous_dense = std::max(dense, follower_dense);
    }
    // The automatic method at a tolerance over [0, 1]: whether it ended in RODAS4, its statistics, y(1).
    struct Automatic {
        bool stiff;
        IntegratorStatistics stats;
        double y[3];
    };
    auto run_automatic = [](bool offered) {
        OscillatorWithFollower system;
        system.offered = offered;
        IntegratorSettings settings;
        settings.method = IntegrationMethod::automatic;
        settings.relative_tolerance = 1e-8;
        settings.absolute_tolerance = 1e-10;
        OneStepIntegrator integrator(system, settings, quiet, quiet);
        Automatic run{false, {}, {1.0, 0.0, 0.3}};
        CHECK(integrator.restart(0.0, run.y));
        for (int k = 1; k <= 100; ++k) CHECK(integrator.advance(0.01 * k, run.y));
        run.stiff = integrator.stiff();
        run.stats = integrator.statistics();
        return run;
    };
    // Offered: no switch to RODAS4 (the follower's rate is no stiffness for a method that takes it
    // exactly), steps set by the oscillator alone.
    const Automatic offered = run_automatic(true);
    std::printf("automatic, relaxing follower: %ld steps, %ld method switches, error %.3g\n", offered.stats.steps,
                offered.stats.method_switches, std::fabs(offered.y[2] - OscillatorWithFollower::follower(1.0)));
    CHECK(offered.stats.method_switches == 0);
    CHECK(!offered.stiff);
    CHECK(offered.stats.steps < 200);
    CHECK(std::fabs(offered.y[2] - OscillatorWithFollower::follower(1.0)) < 1e-7);
    CHECK(std::fabs(offered.y[0] - OscillatorWithFollower::x(1.0)) < 1e-7);
    // Not offered, the same problem is stiff: the automatic method must switch to RODAS4.
    const Automatic integrated = run_automatic(false);
    CHECK(integrated.stiff);
    CHECK(std::fabs(integrated.y[2] - OscillatorWithFollower::follower(1.0)) < 1e-6);
}

int main() {
    check_small_lu();
    check_relaxing_state_is_exact();
    check_iteration_matrix();
    check_order("Dormand-Prince 5(4)", IntegrationMethod::dormand_prince, 5.0, 4.0);
    check_order("RODAS4", IntegrationMethod::rosenbrock, 4.0, 3.0);

    {
        // L-stability: lambda = 1e6 with steps of 0.01 (h lambda = 1e4). RODAS4 damps the transient and
        // follows sin t; the explicit method would need 3e5 steps to stay stable.
        ForcedRelaxation stiff(1e6);
        OneStepIntegrator integrator(stiff, fixed_steps(IntegrationMethod::rosenbrock), quiet, quiet);
        IntegratorMemory memory;
        memory.step_size = 0.01;
        double y[1] = {1.0};
        CHECK(integrator.resume(0.0, y, memory));
        for (int k = 1; k <= 100; ++k) CHECK(integrator.advance(0.01 * k, y));
        CHECK_NEAR(y[0], stiff.exact(1.0), 1e-8);
    }
    {
        // Turns stiff and back: lambda rises from 1 to 1e5 around t = 1.5 and falls again. The automatic
        // method switches to RODAS4 and back, within tolerance all along.
        ForcedRelaxation episode(1.0, 1e5, 1.5, 0.2);
        IntegratorSettings settings;
        settings.method = IntegrationMethod::automatic;
        settings.relative_tolerance = 1e-8;
        settings.absolute_tolerance = 1e-10;
        OneStepIntegrator integrator(episode, settings, quiet, quiet);
        double y[1] = {1.0};
        CHECK(integrator.restart(0.0, y));
        double worst = 0.0;
        bool was_stiff = false;
        for (int k = 1; k <= 3000; ++k) {
            const double t = 1e-3 * k;
            CHECK(integrator.advance(t, y));
            worst = std::max(worst, std::fabs(y[0] - episode.exact(t)));
            if (t > 1.4 && t < 1.6) was_stiff = was_stiff || integrator.stiff();
        }
        const IntegratorStatistics stats = integrator.statistics();
        std::printf("stiff episode: %ld steps, %ld rejected, %ld method switches, worst error %.3g, stiff at the end %d\n",
                    stats.steps, stats.rejected_steps, stats.method_switches, worst, integrator.stiff() ? 1 : 0);
        CHECK(was_stiff);
        CHECK(!integrator.stiff());
        CHECK(stats.method_switches >= 2);
        CHECK(stats.method_switches <= 4);  // into RODAS4 and back, not a flip-flop at either edge
        CHECK(worst < 1e-6);
        // The explicit method alone pays for stability over the episode.
        OneStepIntegrator explicit_only(episode, [&] {
            IntegratorSettings s = settings;
            s.method = IntegrationMethod::dormand_prince;
            return s;
        }(), quiet, quiet);
        double z[1] = {1.0};
        CHECK(explicit_only.restart(0.0, z));
        for (int k = 1; k <= 3000; ++k) CHECK(explicit_only.advance(1e-3 * k, z));
        std::printf("explicit only: %ld steps, %ld right-hand sides; automatic: %ld right-hand sides\n",
                    explicit_only.statistics().steps, explicit_only.statistics().rhs_evaluations, stats.rhs_evaluations);
        CHECK(explicit_only.statistics().rhs_evaluations > 2 * stats.rhs_evaluations);
    }
    return check_report("one_step_methods");
}
