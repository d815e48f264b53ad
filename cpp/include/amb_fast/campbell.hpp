// A Campbell diagram's linear algebra: the sampled loop at many values of one parameter (the rotor's
// speed) and each loop's poles with its modes' shapes at a few chosen rows, on the core's threads.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace amb_fast {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The exact zero-order holds of a plant affine in one parameter p: for each of `count` values p and each of
// the hold lengths h (s), [Phi | Gamma] = the top n rows of the matrix exponential of [[A h, B h], [0, 0]]
// for A = A0 + p A1 (n x n), B (n x k). out: (count, holds, n, n + k), row-major.
void hold_stacks(const RowMatrixXd& A0, const RowMatrixXd& A1, const RowMatrixXd& B, const std::vector<double>& holds,
                 const double* values, Eigen::Index count, int workers, double* out);

// For each of `count` real m x m matrices (stack: row-major, one after the other): its eigenvalues
// (values[k * m + i], balanced as `eigenvalues` does) and, for each eigenvalue with a non-zero angle, R v
// for its eigenvector v of unit norm (shapes[(k * r + j) * m + i], R: r x m; zero for an eigenvalue on the
// positive real axis). The vectors by inverse iteration on the Hessenberg form; a repeated eigenvalue's
// copies start from different vectors, so that together they span its eigenvectors' plane.
void loop_modes(const double* stack, Eigen::Index count, Eigen::Index m, const RowMatrixXd& R, int workers,
                std::complex<double>* values, std::complex<double>* shapes);

}  // namespace amb_fast
