// Many points (rig, controller) of one experiment at once: points whose rig is the same and whose
// controllers share a shape run side by side in SIMD lanes (Loop::run_side_by_side), split across
// threads. Each point gets exactly the numbers that run_experiment gives it alone.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "amb_fast/experiment.hpp"

namespace amb_fast {

enum class PointStatus : int { ok = 0, unstable = 1, touchdown = 2, saturated = 3 };

struct SweepPoint {
    Rig rig;
    Controller controller;
    Eigen::Index settle_periods;  // periods before recording
    std::uint64_t seed;           // measurement noise of this point
};

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXcd = Eigen::Matrix<std::complex<double>, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One row per point, one column per excited (or unexcited) line; rows of points that are not ok are NaN.
struct SweepEstimates {
    // What a sweep returns per point; the lines' force and displacement amplitudes are not kept.
    RowMatrixXcd H;
    RowMatrixXd k, c, k_std, c_std, k_smooth, c_smooth, unexcited_displacement;
    Eigen::VectorXi status;  // PointStatus
    Eigen::VectorXd radius;  // the closed loop's spectral radius, where run_sweep was given the loops' matrices
    Eigen::Index periods = 0, blocks = 0;
};

// The closed loops' matrices of a sweep's points, for their stability check: count = the points, m x m
// each, row-major, one after the other.
struct LoopMatrices {
    const double* stack = nullptr;
    Eigen::Index m = 0;
};

// Runs every point, from rest or (steady_start) from the periodic steady state. All points share the sample rate fs
// (Hz) and the known mass of eq. 9 (kg). workers <= 0 means one thread per hardware core. Given the points' loop
// matrices, each worker first checks its points' stability (eigenvalues as `eigenvalues` computes them): a point whose
// spectral radius is 1 or more is flagged unstable and not run; radius holds every point's.
SweepEstimates run_sweep(const Eigen::Ref<const Eigen::VectorXd>& period_force, const std::vector<SweepPoint>& points,
                         Eigen::Index periods, LinePlan plan, int median_window, int workers, bool steady_start = false,
                         LoopMatrices loops = {});

// The eigenvalues of `count` real m x m matrices (stack: row-major, one after the other) into
// values[k * m + i], on `workers` threads (<= 0: one per core): a sweep's stability checks, which a single
// run makes through the same function (the same digits).
void eigenvalues(const double* stack, Eigen::Index count, Eigen::Index m, std::complex<double>* values, int workers);

}  // namespace amb_fast
