// The MIMO loop's experiments reduced to line spectra (the 2x2 estimate from them: estimate2x2.hpp).
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
#include <memory>
#include <optional>
#include <vector>

#include "amb_fast/hessenberg.hpp"
#include "amb_fast/mimo.hpp"
#include "amb_fast/random.hpp"
#include "amb_fast/spectrum.hpp"

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

// The per-line solves of one model, period and set of bins (see the constructor in mimo_lines.cpp):
// everything the drawn spectra need that does not depend on the excitation or the seed, read-only once
// made, so any number of experiments (and threads) draw from one.
struct LineSolves {
    // bins strictly between 0 and L/2.
    LineSolves(const MimoModel& model, Eigen::Index L, std::vector<Eigen::Index> bins);
    // The solves of this model, L and bins: a recent call's (any thread's) if its model was bitwise the
    // same, else made and kept. Repeated experiments on one loop, the N experiments of one run and the
    // identical parts of an uncoupled rig are solved once (the same numbers: the solves are deterministic).
    static std::shared_ptr<const LineSolves> shared(const MimoModel& model, Eigen::Index L,
                                                    const std::vector<Eigen::Index>& bins);
    std::size_t bytes() const;

    MimoModel model;
    Eigen::Index L;
    std::vector<Eigen::Index> bins;
    std::vector<std::complex<double>> z;  // e^{jw} per line
    Eigen::MatrixXd T_inverse, ML, WL, residual_root, CRz_re, CRz_im, Xn;
    Eigen::MatrixXcd G;
    Eigen::MatrixXd root;  // of the state's stationary noise covariance
};

// Which of the run's noise sources (stream_seed's j) a drawn model's probes and force channels draw from,
// and which part of a larger model it is (independent_parts): by default probe j and channel c
// themselves, part 0.
struct NoiseSources {
    std::vector<Eigen::Index> probes, forces;
    Eigen::Index part = 0;
};

// Where SteadyLines::next() puts line k's channel c of `channels`: at k * line_stride + channel[c] *
// channel_stride (by default line-major, k * channels + c).
struct LineLayout {
    Eigen::Index line_stride = 0, channel_stride = 1;  // line_stride 0: channels
    const Eigen::Index* channel = nullptr;             // nullptr: c
    Eigen::Index at(Eigen::Index k, Eigen::Index c, Eigen::Index channels) const {
        return k * (line_stride ? line_stride : channels) + (channel ? channel[c] : c) * channel_stride;
    }
};

// The drawn line spectra of one experiment at a time, period by period (memory O(lines), however
// many periods): the per-line solves once per model (LineSolves, shareable), then start() per experiment
// and next() per period. The periods are drawn in blocks of up to `block` (their noise's products as
// matrix products, not one matrix-vector product per period), next() hands them out one by one. The
// numbers depend only on the model, the period force, the seed and the period's index (a block draws
// each stream in the order single periods would).
class SteadyLines {
  public:
    // bins strictly between 0 and L/2.
    SteadyLines(const MimoModel& model, Eigen::Index L, std::vector<Eigen::Index> bins, NoiseSources sources = {});
    SteadyLines(std::shared_ptr<const LineSolves> solves, NoiseSources sources = {});
    // A new experiment of `periods` periods: period_force (L x p, sample-major, finite: the callers check
    // it) repeated, noise from seed; the state starts in its periodic steady state, the noise-driven part
    // drawn from its stationary distribution.
    void start(const double* period_force, std::uint64_t seed, Eigen::Index periods);
    // The next period's line spectra: force_lines[line * p + channel] (the recorded, transduced force with
    // the transducer's noise), displacement_lines[line * q + probe] (or where the layouts say). At most
    // `periods` calls after start. Throws std::overflow_error when they are not finite (an unstable loop).
    void next(std::complex<double>* force_lines, std::complex<double>* displacement_lines,
              const LineLayout& force_layout = {}, const LineLayout& displacement_layout = {});
    static constexpr Eigen::Index block = 16;
    const std::vector<Eigen::Index>& bins() const { return solves_->bins; }

  private:
    void draw_block();

    std::shared_ptr<const LineSolves> solves_;
    NoiseSources sources_;
    std::optional<LineTransform> transform_;  // the excitation's lines (made when first needed)
    Eigen::MatrixXcd clean_force_;
    Eigen::VectorXcd det_;                     // the probes' periodic response to the forces
    std::optional<NormalStream> rest_;         // the state's line-free part
    std::vector<NormalStream> probe_, force_;  // per probe, per force channel
    // The current block, a column per period: the probes' noise spectra V as (Re, Im) pairs per line and
    // probe, the state at the periods' ends (Z: the block's start first), the leak of the state's change
    // into the lines (real, imaginary parts).
    Eigen::MatrixXd V_, Z_, draws_, change_re_, change_im_;
    Eigen::Index left_ = 0, drawn_ = 0, next_ = 0;  // periods not yet drawn; in the block; handed out
};

}  // namespace amb_fast
