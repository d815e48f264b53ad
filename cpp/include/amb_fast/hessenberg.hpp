// Solves of zI - H for an upper Hessenberg H at many shifts z: the per-line solves of the drawn spectra
// (mimo_lines.hpp), where a dense LU per line would cost O(n^3).
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace amb_fast {

// LU factors of z_l I - H for an upper Hessenberg H and four shifts z_l at once (lane l), each
// pivoting between neighbouring rows on its own: O(n^2) to factor and per solve, where a dense LU is
// O(n^3). The four lanes' numbers sit side by side (real and imaginary parts apart), so the compiler runs
// the lanes in SIMD registers and the latency-bound chains of one solve overlap; every lane gets the
// operations it would get alone, whichever lanes it shares.
class HessenbergLU {
  public:
    static constexpr int lanes = 4;
    explicit HessenbergLU(const Eigen::MatrixXd& H);  // storage only: factor() before solving
    void factor(const std::complex<double>* z);       // z[0..lanes): the shifts
    // (z_l I - H) x_l = b_l in place; x_l's entry i at re[i * lanes + l], im[i * lanes + l].
    void solve(double* re, double* im) const;
    void solve_transposed(double* re, double* im) const;  // (z_l I - H)^T x_l = b_l
    Eigen::Index size() const { return n_; }

  private:
    Eigen::Index n_;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> H_;
    std::vector<double> ur_, ui_;  // U, row-major, lane-minor: [(i * n + c) * lanes + l]
    std::vector<double> dr_, di_;  // 1 / U(j, j) per lane: [j * lanes + l]
    std::vector<double> mr_, mi_;  // step j: row j + 1 -= m_j row j
    std::vector<double> swapped_;  // step j swapped rows j and j + 1 first (1) or not (0)
};

}  // namespace amb_fast
