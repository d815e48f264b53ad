// A Campbell diagram's linear algebra: the sampled loop at many values of one parameter (the rotor's
// speed) and each loop's poles with its modes' shapes at a few chosen rows, on the core's threads.
#pragma once

#include <Eigen/Dense>
#include <complex>

namespace amb_fast {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The sampled loops of a plant affine in one parameter p: for each of `count` values p, the plant
// A0 + p A1 (n x n) with inputs B (n x k) held over T, Phi and Gamma from the exact zero-order hold
// (the matrix exponential of [[A T, B T], [0, 0]]), closed as
//     M = [[Phi, 0], [lower]] + [[Gamma], [0]] feedback      (m x m, m = n + lower.rows())
// with feedback (k x m) and lower ((m - n) x m) the controller's rows. out: count row-major m x m matrices.
void sampled_loops(const RowMatrixXd& A0, const RowMatrixXd& A1, const RowMatrixXd& B, double T, const double* values,
                   Eigen::Index count, const RowMatrixXd& feedback, const RowMatrixXd& lower, int workers,
                   double* out);

// For each of `count` real m x m matrices (stack: row-major, one after the other): its eigenvalues
// (values[k * m + i], balanced as `eigenvalues` does) and, for each eigenvalue with a non-zero angle, R v
// for its eigenvector v of unit norm (shapes[(k * r + j) * m + i], R: r x m; zero for an eigenvalue on the
// positive real axis). The vectors by inverse iteration on the Hessenberg form; a repeated eigenvalue's
// copies start from different vectors, so that together they span its eigenvectors' plane.
void loop_modes(const double* stack, Eigen::Index count, Eigen::Index m, const RowMatrixXd& R, int workers,
                std::complex<double>* values, std::complex<double>* shapes);

}  // namespace amb_fast
