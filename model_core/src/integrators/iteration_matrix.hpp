// The Rosenbrock iteration matrix A = I / (h gamma) - J, factorized for its solves, with the model's
// kinematic rows eliminated first. A coordinate's row of dx/dt = f is d(angle)/dt = rate: its row of J
// is a unit vector at the rate, so its row of A is fixed, and the angles follow from the rates:
// angle = (b_angle + rate) h gamma. What remains is a system in the other unknowns (8 of the full
// model's 12): a third of the factorization's work and under half of each solve's (the LU and its
// solves were a quarter of all work on the stiff scenes, measured with callgrind).
#pragma once

#include "small_lu.hpp"

namespace gimbal {

template <int Capacity>
class IterationMatrix {
public:
    // `position[k]`' derivative is `velocity[k]`, exactly, for k < pairs (from the system).
    void set_structure(int n, const int* position, const int* velocity, int pairs) {
        n_ = n;
        pairs_ = 0;
        bool kinematic[Capacity] = {};
        for (int k = 0; k < pairs; ++k)
            if (position[k] < 0 || position[k] >= n || velocity[k] < 0 || velocity[k] >= n) return;  // full LU
        for (int k = 0; k < pairs; ++k) kinematic[position[k]] = true;
        // A velocity that is itself eliminated leaves nothing to fold its position into: full LU.
        for (int k = 0; k < pairs; ++k)
            if (kinematic[velocity[k]]) return;
        for (int k = 0; k < pairs; ++k) position_[k] = position[k], velocity_[k] = velocity[k];
        pairs_ = pairs;
        rest_count_ = 0;
        for (int i = 0; i < n; ++i) {
            rest_index_[i] = -1;
            if (!kinematic[i]) rest_index_[i] = rest_count_, rest_[rest_count_++] = i;
        }
    }

    // Factorizes diagonal * I - J for the column-major n x n Jacobian J. False if singular.
    bool factorize(const double* jacobian, double diagonal) {
        inverse_diagonal_ = 1.0 / diagonal;
        reduced_ = pairs_ > 0 && kinematic_rows_hold(jacobian);
        if (!reduced_) {
            double full[Capacity * Capacity];
            for (int j = 0; j < n_; ++j)
                for (int i = 0; i < n_; ++i) full[i + j * n_] = (i == j ? diagonal : 0.0) - jacobian[i + j * n_];
            return lu_.factorize(full, n_);
        }
        // S = A_rr + h gamma A_ra E: the angle columns folded into their rates' columns.
        const int m = rest_count_;
        double reduced[Capacity * Capacity];
        for (int j = 0; j < m; ++j)
            for (int i = 0; i < m; ++i)
                reduced[i + j * m] = (i == j ? diagonal : 0.0) - jacobian[rest_[i] + rest_[j] * n_];
        for (int k = 0; k < pairs_; ++k) {
            const int column = rest_index_[velocity_[k]];
            for (int i = 0; i < m; ++i) {
                coupling_[i][k] = jacobian[rest_[i] + position_[k] * n_];  // J(rest i, angle k)
                reduced[i + column * m] -= inverse_diagonal_ * coupling_[i][k];
            }
        }
        return lu_.factorize(reduced, m);
    }

    // Solves A x = b in place (x holds b on entry).
    void solve(double* x) const {
        if (!reduced_) {
            lu_.solve(x);
            return;
        }
        const int m = rest_count_;
        double rest[Capacity];
        for (int i = 0; i < m; ++i) {
            double sum = x[rest_[i]];
            for (int k = 0; k < pairs_; ++k) sum += inverse_diagonal_ * coupling_[i][k] * x[position_[k]];
            rest[i] = sum;
        }
        lu_.solve(rest);
        for (int k = 0; k < pairs_; ++k) x[position_[k]] = inverse_diagonal_ * (x[position_[k]] + rest[rest_index_[velocity_[k]]]);
        for (int i = 0; i < m; ++i) x[rest_[i]] = rest[i];
    }

private:
    // The structure is used only where J shows it exactly (an approximated row keeps the full LU).
    bool kinematic_rows_hold(const double* jacobian) const {
        for (int k = 0; k < pairs_; ++k)
            for (int j = 0; j < n_; ++j)
                if (jacobian[position_[k] + j * n_] != (j == velocity_[k] ? 1.0 : 0.0)) return false;
        return true;
    }

    int n_ = 0, pairs_ = 0, rest_count_ = 0;
    int position_[Capacity] = {}, velocity_[Capacity] = {};
    int rest_[Capacity] = {}, rest_index_[Capacity] = {};
    bool reduced_ = false;
    double inverse_diagonal_ = 1.0;
    double coupling_[Capacity][Capacity] = {};
    SmallLU<Capacity> lu_;
};

}  // namespace gimbal
