// LU factorization with partial pivoting of the Rosenbrock iteration matrix (4-17 unknowns), in place,
// unblocked. Eigen's PartialPivLU on a dynamic-size matrix (sizes vary with the fidelity) costs ~8,000
// instructions for 12 unknowns (its blocked path and dynamic bookkeeping, measured with callgrind on the
// stiff ship scene, 12 % of all work there); these loops cost a quarter of that.
#pragma once

#include <cmath>
#include <utility>

namespace gimbal {

template <int Capacity>
class SmallLU {
public:
    // Factorizes the n x n column-major matrix `a` (leading dimension n). False if singular.
    bool factorize(const double* a, int n) {
        n_ = n;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) lu_[i][j] = a[i + j * n];
        for (int k = 0; k < n; ++k) {
            int pivot = k;
            double largest = std::fabs(lu_[k][k]);
            for (int i = k + 1; i < n; ++i) {
                if (std::fabs(lu_[i][k]) > largest) largest = std::fabs(lu_[i][k]), pivot = i;
            }
            if (!(largest > 0.0) || !std::isfinite(largest)) return false;
            row_[k] = pivot;
            if (pivot != k)
                for (int j = 0; j < n; ++j) std::swap(lu_[k][j], lu_[pivot][j]);
            const double inverse = 1.0 / lu_[k][k];
            for (int i = k + 1; i < n; ++i) {
                const double factor = lu_[i][k] * inverse;
                lu_[i][k] = factor;
                for (int j = k + 1; j < n; ++j) lu_[i][j] -= factor * lu_[k][j];
            }
        }
        return true;
    }

    // Solves in place: x holds the right-hand side on entry.
    void solve(double* x) const {
        for (int k = 0; k < n_; ++k) {
            if (row_[k] != k) std::swap(x[k], x[row_[k]]);
        }
        for (int i = 1; i < n_; ++i) {
            double sum = x[i];
            for (int j = 0; j < i; ++j) sum -= lu_[i][j] * x[j];
            x[i] = sum;
        }
        for (int i = n_ - 1; i >= 0; --i) {
            double sum = x[i];
            for (int j = i + 1; j < n_; ++j) sum -= lu_[i][j] * x[j];
            x[i] = sum / lu_[i][i];
        }
    }

private:
    int n_ = 0;
    double lu_[Capacity][Capacity];  // row-major: the inner loops run along rows
    int row_[Capacity];
};

}  // namespace gimbal
