// The identification experiment of MODEL.md section 3: simulated (the loop streams its periods into
// the estimator, no time series kept) or recorded (the same estimator over arrays).
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cstdint>

#include "amb_fast/loop.hpp"
#include "amb_fast/spectrum.hpp"

namespace amb_fast {

// Up to 2 * 32 - 1 periods the variance comes from every period; beyond, from batch means of
// floor(periods / 32) consecutive periods (32 to 63 of them): a long record costs few FFTs.
constexpr Eigen::Index max_variance_blocks = 32;
inline Eigen::Index periods_per_block(Eigen::Index periods) {
    return std::max<Eigen::Index>(1, periods / max_variance_blocks);
}

// Whether run_experiment draws the recorded periods' line spectra (SteadyLines, mimo_lines.hpp) instead
// of running the loop sample by sample: from the periodic steady state of a linear rig with nothing to
// watch (no current limit, no clearance). The loop is linear there, so the draw is exact in
// distribution, and the samples would show nothing more.
bool draws_spectra(const Rig& rig, bool steady_start);

// Repeats one period of excitation force (N, plan.period samples) for settle_periods, then records
// `periods` more into the estimator. From rest, or with steady_start from the periodic steady state
// (Loop::start_periodic); where draws_spectra, the periods' spectra are drawn instead (settle periods
// drawn and dropped), with the noise streams of stream_seed(seed, ...) (mimo.hpp).
LineEstimate run_experiment(const Rig& rig, const Controller& controller,
                            const Eigen::Ref<const Eigen::VectorXd>& period_force, Eigen::Index settle_periods,
                            Eigen::Index periods, LinePlan plan, std::uint64_t seed, int median_window,
                            bool steady_start = false);

// The estimator over a recording of n samples per channel (a whole number of periods after settling).
LineEstimate identify(const double* force, const double* displacement, Eigen::Index n, Eigen::Index settle_periods,
                      LinePlan plan, double mass, double fs, int median_window);

}  // namespace amb_fast
