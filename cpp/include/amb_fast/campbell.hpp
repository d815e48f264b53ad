// A Campbell diagram's linear algebra: the sampled loop at many values of one parameter (the rotor's
// speed) and each loop's poles with its modes' shapes at a few chosen rows, on the core's threads.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace amb_fast {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The sampled loop of a plant affine in one parameter p (the rotor's speed), at many values of p.
// The plant A = A0 + p A1 (n x n) with its commands B (n x k) is held over each of `holds` (s; holds[0] the
// sample period T): X = [Phi(T) | Gamma(T) | Gamma(holds[1]) | ...] (n x (n + k H)), Phi and Gamma the top
// rows of the exponential of [[A h, B h], [0, 0]]. The loop (m x m) is L + X P in its top n rows and L
// below (P: (n + k H) x m, the dead-time lines and the controller; L's top n rows are zero).
struct SpeedLoops {
    RowMatrixXd A0, A1, B;
    std::vector<double> holds;
    RowMatrixXd P, L;
    // Optional: a force rotating at p rad/s, Re(p^2 drive e^{j p t}) on the plant's state (n, complex; empty:
    // none), integrated exactly over the sample in the same exponential (the plant's input G_p = the top
    // rows of its oscillator's columns), and the loop's steady state x (m) at z = e^{j p T}:
    // (z I - M) x = [G_p; 0].
    Eigen::VectorXcd drive;
    // Optional: the rows R (r x m) of the poles' shapes (`loop_modes`); empty: eigenvalues only.
    RowMatrixXd R;
};

// Per value p (in blocks of 8 values, on `workers` threads): the loop (loops: (count, m, m), if not null), its
// eigenvalues (values: (count, m), balanced, by Francis QR on the Hessenberg form, its first shifts at each
// bottom row the previous value's eigenvalues in the block: a fine grid's poles barely move), their shapes if
// R is given (shapes: (count, r, m), as `loop_modes`) and the steady state if a drive is given (states:
// (count, m)). The blocks are fixed, so the digits do not depend on the threads; a value's eigenvalues equal
// its own alone to rounding. No allocation per value (the storage is kept per worker), but where the QR steps
// stall (rare: pairs of equal poles) and Eigen's eigenvalue solver takes over.
void speed_loops(const SpeedLoops& in, const double* values_p, Eigen::Index count, int workers, double* loops,
                 std::complex<double>* values, std::complex<double>* shapes, std::complex<double>* states);

// For each of `count` real m x m matrices (stack: row-major, one after the other): its eigenvalues
// (values[k * m + i], balanced as `eigenvalues` does) and, for each eigenvalue off the real axis, R v for
// its eigenvector v of unit norm (shapes[(k * r + j) * m + i], R: r x m; zero for a real eigenvalue, which
// does not whirl: a Campbell diagram needs none). The eigenvalues warm-started as `speed_loops`' (the stack's order,
// blocks of 8). The vectors by one step of inverse iteration on the Hessenberg form; a repeated eigenvalue's copies
// start from different vectors, so that together they span its eigenvectors' plane.
void loop_modes(const double* stack, Eigen::Index count, Eigen::Index m, const RowMatrixXd& R, int workers,
                std::complex<double>* values, std::complex<double>* shapes);

}  // namespace amb_fast
