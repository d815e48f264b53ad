// Many gain sets of one experiment at once: the loops advance in lock step, a structure of arrays
// with the gain sets innermost, split across threads. Each gain set gets exactly the numbers that
// run_experiment gives it alone.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "amb_fast/experiment.hpp"

namespace amb_fast {

enum class PointStatus : int { ok = 0, unstable = 1, touchdown = 2, saturated = 3 };

struct GainPoint {
    double kp, ki, kd;             // A/m, A/(m s), A s/m
    Eigen::Index settle_periods;   // periods before recording
    std::uint64_t seed;            // measurement noise of this point
};

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXcd = Eigen::Matrix<std::complex<double>, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One row per point, one column per excited (or unexcited) line; rows of points that are not ok are NaN.
struct SweepEstimates {
    RowMatrixXcd H, force, displacement;
    RowMatrixXd k, c, k_std, c_std, k_smooth, c_smooth, unexcited_force, unexcited_displacement;
    Eigen::VectorXi status;  // PointStatus
    Eigen::Index periods = 0, blocks = 0;
};

// Runs every point (base's fs, cutoff and delay; the point's gains). workers <= 0 means one thread
// per hardware core.
SweepEstimates run_sweep(const Rig& rig, const Pid& base, const Eigen::Ref<const Eigen::VectorXd>& period_force,
                         const std::vector<GainPoint>& points, Eigen::Index periods, LinePlan plan, int median_window,
                         int workers);

}  // namespace amb_fast
