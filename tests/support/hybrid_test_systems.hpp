// Small hybrid systems with known solutions and known event times, independent of the gimbal: what the
// integrator tests drive every method with (model_core/integrators/).
#pragma once

#include <cmath>
#include <vector>

#include "gimbal/hybrid_system/hybrid_system.hpp"

namespace hybrid_test_systems {

using gimbal::HybridSystem;

constexpr double kGravity = 9.81;

// A ball dropped from 1 m onto a floor, restitution e: bounce k at a known time (bounce_time), and
// the bounces accumulate at t1 (1 + e) / (1 - e) (Zeno).
class BouncingBall final : public HybridSystem {
public:
    explicit BouncingBall(double restitution) : restitution_(restitution) {}
    int state_size() const override { return 2; }
    int event_count() const override { return 1; }
    bool derivative(double, const double* x, double* dx) override {
        dx[0] = x[1];
        dx[1] = -kGravity;
        return true;
    }
    bool has_jacobian() const override { return true; }
    bool jacobian(double, const double*, double* column_major) override {
        column_major[0] = 0.0, column_major[1] = 0.0, column_major[2] = 1.0, column_major[3] = 0.0;
        return true;
    }
    bool time_dependent() const override { return false; }
    void event_functions(double, const double* x, double* g) override { g[0] = x[0]; }
    int update_modes(double time, double* x, const int* directions) override {
        if (directions == nullptr || directions[0] >= 0 || x[1] >= 0.0) return 0;
        x[0] = 0.0;
        x[1] = -restitution_ * x[1];
        times.push_back(time);
        ++bounces;
        return 1;
    }
    // Bounce k (1, 2, ...): t1 (1 + 2 e (1 - e^(k-1)) / (1 - e)), with t1 = sqrt(2 / g).
    double bounce_time(int k) const {
        const double first = std::sqrt(2.0 / kGravity);
        return first * (1.0 + 2.0 * restitution_ * (1.0 - std::pow(restitution_, k - 1)) / (1.0 - restitution_));
    }
    int bounces = 0;
    std::vector<double> times;

private:
    double restitution_;
};

// A switch that chatters: its event function oscillates with the given period, whatever the state.
class Chatter final : public HybridSystem {
public:
    explicit Chatter(double period) : period_(period) {}
    int state_size() const override { return 1; }
    int event_count() const override { return 1; }
    bool derivative(double, const double*, double* dx) override {
        dx[0] = 1.0;
        return true;
    }
    void event_functions(double time, const double*, double* g) override {
        g[0] = std::sin(2.0 * M_PI * time / period_);
    }
    int update_modes(double, double*, const int* directions) override {
        if (directions == nullptr) return 0;
        ++switches;
        return 1;
    }
    long switches = 0;

private:
    double period_;
};

// Two independent decays x' = -x from 1 crossing 0.5 at the same instant, ln 2.
class TwinDecay final : public HybridSystem {
public:
    int state_size() const override { return 2; }
    int event_count() const override { return 2; }
    bool derivative(double, const double* x, double* dx) override {
        dx[0] = -x[0];
        dx[1] = -x[1];
        return true;
    }
    void event_functions(double, const double* x, double* g) override {
        g[0] = x[0] - 0.5;
        g[1] = x[1] - 0.5;
    }
    int update_modes(double time, double*, const int* directions) override {
        if (directions == nullptr) return 0;
        int changes = 0;
        for (int k = 0; k < 2; ++k)
            if (directions[k] != 0) ++changes, crossing_time[k] = time;
        return changes;
    }
    double crossing_time[2] = {-1.0, -1.0};
};

// y' = 1 with one threshold: an event exactly where the test puts it.
class Ramp final : public HybridSystem {
public:
    explicit Ramp(double threshold) : threshold_(threshold) {}
    int state_size() const override { return 1; }
    int event_count() const override { return 1; }
    bool derivative(double, const double*, double* dy) override {
        dy[0] = 1.0;
        return true;
    }
    void event_functions(double, const double* y, double* g) override { g[0] = y[0] - threshold_; }
    int update_modes(double, double*, const int* directions) override {
        if (directions == nullptr || directions[0] == 0) return 0;
        ++crossings;
        return 1;
    }
    int crossings = 0;

private:
    double threshold_;
};

// y' = -y, which cannot be evaluated (non-finite) beyond t = 1.
class Cliff final : public HybridSystem {
public:
    int state_size() const override { return 1; }
    int event_count() const override { return 0; }
    bool derivative(double t, const double* y, double* dy) override {
        dy[0] = t > 1.0 ? NAN : -y[0];
        return t <= 1.0;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
};

// x' = -x + sin t, x(0) = 1: x = (sin t - cos t) / 2 + 1.5 e^-t. Time-dependent, no events.
class ForcedDecay final : public HybridSystem {
public:
    int state_size() const override { return 1; }
    int event_count() const override { return 0; }
    bool derivative(double time, const double* x, double* dx) override {
        dx[0] = -x[0] + std::sin(time);
        return true;
    }
    bool has_jacobian() const override { return true; }
    bool jacobian(double, const double*, double* column_major) override {
        column_major[0] = -1.0;
        return true;
    }
    void event_functions(double, const double*, double*) override {}
    int update_modes(double, double*, const int*) override { return 0; }
    static double exact(double t) { return 0.5 * (std::sin(t) - std::cos(t)) + 1.5 * std::exp(-t); }
};

}  // namespace hybrid_test_systems
