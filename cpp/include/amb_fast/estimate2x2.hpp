// The two-axis estimate: H = F Y^-1 per line from both experiments' per-period line spectra, with the
// standard errors of its entries (amb_fast.two_axis.Estimate2).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace amb_fast {

// The 2x2 estimate H = F Y^-1 per line from both experiments' per-period line spectra, laid out as
// mimo_line_experiments writes them (2 channels, 2 experiments): F, Y the period means, and the
// variance of H's real and imaginary parts from the linearised dH = (dF - H dY) Y^-1 of every period
// (sum of squares / (P (P - 1))). Matrices per line, row-major 2x2: [line][i][j].
struct Estimate2x2 {
    Eigen::Index lines = 0, periods = 0;
    std::vector<std::complex<double>> H, receptance, force,
        displacement;  // force, displacement: [line][channel][experiment]
    std::vector<double> var_re, var_im;
};
Estimate2x2 estimate_2x2(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines,
                         Eigen::Index periods, Eigen::Index lines);

// The same estimate for N axes (N experiments, N channels): per line F, Y (N x N, [channel][experiment])
// the period means, H = F Y^-1 by LU with partial pivoting, and the variances from the linearised
// dH = (dF - H dY) Y^-1 of every period. Matrices per line, row-major N x N; `lines` of them. With a
// readout (N x N, real, row-major) the displacements are readout times the given ones (the structure's
// reported displacements from its probes' readings).
Estimate2x2 estimate_nxn(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines,
                         Eigen::Index periods, Eigen::Index lines, Eigen::Index n, const double* readout = nullptr);

}  // namespace amb_fast
