// Two-axis sweeps: every point's two experiments as line spectra (mimo_lines.hpp) reduced to the 2x2
// estimate (estimate2x2.hpp), the points claimed in turn by the threads (blocks.hpp).
#pragma once

#include <Eigen/Core>
#include <array>
#include <complex>
#include <cstdint>
#include <vector>

#include "amb_fast/mimo.hpp"

namespace amb_fast {

// Where the points' estimates go (what a sweep keeps of Estimate2x2), each (points, lines, 2, 2)
// row-major: point i's 2x2 matrices of line j start at (i * lines + j) * 4.
struct MimoSweepOutput {
    std::complex<double>*H, *receptance;
    double *var_re, *var_im;
};

// For each point, mimo_line_experiments of its model with its two seeds and settle periods, then
// estimate_2x2: the numbers two_axis.run_experiment gets for that point alone, on `workers` threads
// (<= 0: one per core). period_force: the two experiments' forces (L x 2 each), shared by the points.
void mimo_line_sweep(const std::vector<MimoModel>& models, const double* const* period_force, Eigen::Index L,
                     const std::vector<Eigen::Index>& settle_periods, Eigen::Index periods,
                     const std::vector<std::array<std::uint64_t, 2>>& seeds, bool steady_start,
                     const std::vector<Eigen::Index>& bins, int workers, const MimoSweepOutput& out);

}  // namespace amb_fast
