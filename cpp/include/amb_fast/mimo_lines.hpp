// The MIMO loop's experiments reduced to line spectra, and the 2x2 estimate from them.
//
// From rest the loop runs sample by sample (mimo.hpp) and every period is transformed. From the
// periodic steady state the line spectra are drawn directly, exactly in distribution: the loop is
// linear, so every period's spectrum at a harmonic line w (z = e^{jw}) is, with V the white probe
// noise's spectrum and z0, zL the state at the period's ends,
//
//     Y = C (zI - M)^-1 (Bf F + Bn V - z (zL - z0)) + Dn V,
//
// where V at distinct lines is independent complex normal (variance L sigma^2 / 2 in each part), and
// zL = M^L z0 + w with w the state's response to the period's noise: normal, correlated with V at the
// lines (its mean given them, plus a residual drawn with the covariance left over). Nothing is
// approximated; the costly part is one Hessenberg solve per line, not four thousand samples.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <cstdint>
#include <vector>

#include "amb_fast/mimo.hpp"

namespace amb_fast {

// Experiments in lock step (as mimo_experiments, K = seeds.size()), reduced to the line spectra of every
// recorded period: lines[((period * bins + j) * channels + channel) * K + experiment] = the unscaled
// DFT of that period of that channel at bins[j] (force: p channels, displacement: q). From rest the loop
// runs sample by sample and settles for settle_periods first; with steady_start the spectra are drawn
// directly (see above), settle_periods is irrelevant, and the bins must lie strictly between 0 and L/2.
// The force transducers' white noise enters nothing else: its per-period line spectra are independent
// complex normals of variance L sigma^2 (from rest it is added sample by sample instead).
void mimo_line_experiments(const MimoModel& model, const double* const* period_force, Eigen::Index L,
                           Eigen::Index settle_periods, Eigen::Index periods, const std::vector<std::uint64_t>& seeds,
                           bool steady_start, const std::vector<Eigen::Index>& bins, std::complex<double>* force_lines,
                           std::complex<double>* displacement_lines);

// LU factors of zI - H for an upper Hessenberg H, pivoting between neighbouring rows: O(n^2) to factor
// and per solve, where a dense LU is O(n^3).
class HessenbergLU {
public:
    HessenbergLU(const Eigen::MatrixXd& H, std::complex<double> z);
    void solve(std::complex<double>* x) const;             // (zI - H) x = b, b in x
    void solve_transposed(std::complex<double>* x) const;  // (zI - H)^T x = b, b in x

private:
    Eigen::Index n_;
    Eigen::MatrixXcd U_;
    std::vector<std::complex<double>> inverse_diagonal_;
    std::vector<std::complex<double>> multiplier_;  // step j: row j + 1 -= multiplier_[j] row j
    std::vector<char> swapped_;                     // step j swapped rows j and j + 1 first
};

// The 2x2 estimate H = F Y^-1 per line from both experiments' per-period line spectra, laid out as
// mimo_line_experiments writes them (2 channels, 2 experiments): F, Y the period means, and the
// variance of H's real and imaginary parts from the linearised dH = (dF - H dY) Y^-1 of every period
// (sum of squares / (P (P - 1))). Matrices per line, row-major 2x2: [line][i][j].
struct Estimate2x2 {
    Eigen::Index lines = 0, periods = 0;
    std::vector<std::complex<double>> H, receptance, force, displacement;  // force, displacement: [line][channel][experiment]
    std::vector<double> var_re, var_im;
};
Estimate2x2 estimate_2x2(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines,
                         Eigen::Index periods, Eigen::Index lines);

}  // namespace amb_fast
