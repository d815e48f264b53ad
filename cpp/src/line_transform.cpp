// A period's line spectrum: pocketfft's real FFT, or direct sums where few lines are asked
// (LineTransform); the period averaging and the estimate are in spectrum.cpp.
#include "amb_fast/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include "amb_fast/errors.hpp"

// pocketfft's own thread pool is not used: one transform per call, on the caller's thread.
#define POCKETFFT_NO_MULTITHREADING
#include "pocketfft_hdronly.h"

namespace amb_fast {

namespace {
constexpr double two_pi = 6.283185307179586;
using cd = std::complex<double>;
using RealPlan = pocketfft::detail::pocketfft_r<double>;

// The plans of the last few lengths, shared by every estimator on every thread (exec is const and
// allocates its own scratch): a sweep's points and threads pay for one set of twiddles.
std::shared_ptr<const RealPlan> real_plan(Eigen::Index L) {
    static std::mutex guard;
    static std::vector<std::shared_ptr<const RealPlan>> recent;
    const std::lock_guard<std::mutex> lock(guard);
    for (const auto& plan : recent)
        if (static_cast<Eigen::Index>(plan->length()) == L) return plan;
    if (recent.size() == 4) recent.erase(recent.begin());
    recent.push_back(std::make_shared<const RealPlan>(static_cast<std::size_t>(L)));
    return recent.back();
}

#ifndef POCKETFFT_NO_VECTORS
using RealVector = pocketfft::detail::vtype_t<double>;  // SSE2/NEON: 2 doubles; 4 or 8 under -mavx/-mavx512f
constexpr std::size_t vector_lanes = pocketfft::detail::VLEN<double>::val;
#endif

// X_b in FFTPACK's half-complex order (r0, r1, i1, r2, i2, ..., r_{L/2} if L is even), lane by lane.
template <typename Get>
void pick_bins(const std::vector<Eigen::Index>& bins, std::size_t L, Get value, std::complex<double>* lines) {
    for (std::size_t j = 0; j < bins.size(); ++j) {
        const auto b = static_cast<std::size_t>(bins[j]);
        lines[j] = b == 0 ? cd(value(0), 0.0) : 2 * b == L ? cd(value(L - 1), 0.0) : cd(value(2 * b - 1), value(2 * b));
    }
}

// Cost of a direct sum per sample and bin in units of pocketfft's cost_guess, measured on x86-64
// (bench/bench_experiment.py prints both): 2.7-3.5 for L from 1000 to 40000, prime lengths
// (Bluestein) included. The direct sum wins up to about 4 bins of a 4000-sample period.
constexpr double direct_per_sample_and_bin = 3.0;
}  // namespace

double LineTransform::fft_cost(Eigen::Index period) {
    using util = pocketfft::detail::util;
    const auto L = static_cast<std::size_t>(period);
    // pocketfft's choice between its radix plan and Bluestein (pocketfft_r's constructor), halved
    // for a real transform.
    const std::size_t p = L < 50 ? 0 : util::largest_prime_factor(L);
    const double radix = 0.5 * util::cost_guess(L);
    if (p * p <= L) return radix;
    return std::min(radix, 3.0 * util::cost_guess(util::good_size_cmplx(2 * L - 1)));
}

double LineTransform::direct_cost(Eigen::Index period, Eigen::Index bins) {
    return direct_per_sample_and_bin * static_cast<double>(period) * static_cast<double>(bins);
}

LineTransform::LineTransform(Eigen::Index period, std::vector<Eigen::Index> bins, Method method)
    : L_(period), bins_(std::move(bins)), method_(method) {
    require(L_ >= 1, "period", L_, "at least 1 sample");
    for (Eigen::Index b : bins_) require(b >= 0 && 2 * b <= L_, "bin", b, "between 0 and period/2");
    if (method_ == Method::automatic)
        method_ =
            direct_cost(L_, static_cast<Eigen::Index>(bins_.size())) < fft_cost(L_) ? Method::direct : Method::fft;
    if (method_ == Method::fft) {
        plan_ = real_plan(L_);  // the work buffers come with the first transform (an estimator fed
                                // spectra never transforms)
    } else {
        const pocketfft::detail::sincos_2pibyn<double> roots(static_cast<std::size_t>(L_));  // exp(+2 pi i n / L)
        twiddle_.resize(static_cast<std::size_t>(L_));
        for (std::size_t n = 0; n < twiddle_.size(); ++n) twiddle_[n] = {roots[n].r, -roots[n].i};
    }
}

void LineTransform::operator()(const double* x, std::complex<double>* lines) {
    const auto L = static_cast<std::size_t>(L_);
    if (method_ == Method::fft) {
        // In place, FFTPACK's half-complex order: r0, r1, i1, r2, i2, ..., (r_{L/2} if L is even).
        work_.resize(L);
        std::copy(x, x + L, work_.begin());
        plan_->exec(work_.data(), 1.0, true);
        pick_bins(bins_, L, [this](std::size_t i) { return work_[i]; }, lines);
        return;
    }
    const cd* w = twiddle_.data();
    for (std::size_t j = 0; j < bins_.size(); ++j) {
        const auto b = static_cast<std::size_t>(bins_[j]);
        // Four partial sums: independent chains for the pipeline, and a little less rounding.
        double re[4] = {0, 0, 0, 0}, im[4] = {0, 0, 0, 0};
        std::size_t n = 0, k = 0;  // k = b n mod L
        for (; n + 4 <= L; n += 4)
            for (std::size_t q = 0; q < 4; ++q) {
                re[q] += x[n + q] * w[k].real();
                im[q] += x[n + q] * w[k].imag();
                k += b;
                if (k >= L) k -= L;
            }
        for (; n < L; ++n) {
            re[0] += x[n] * w[k].real();
            im[0] += x[n] * w[k].imag();
            k += b;
            if (k >= L) k -= L;
        }
        lines[j] = {(re[0] + re[1]) + (re[2] + re[3]), (im[0] + im[1]) + (im[2] + im[3])};
    }
}

void LineTransform::operator()(const double* x, const double* y, cd* lines_x, cd* lines_y) {
#ifndef POCKETFFT_NO_VECTORS
    if (method_ == Method::fft) {
        // Lane 0 carries x, lane 1 y (further lanes zeros): each lane sees exactly the operations of
        // the one-channel transform, so the digits are the same; the two run in one instruction stream.
        const auto L = static_cast<std::size_t>(L_);
        pair_work_.resize((L + 1) * vector_lanes);  // room to align L vectors
        void* raw = pair_work_.data();
        std::size_t room = pair_work_.size() * sizeof(double);
        auto* v = static_cast<RealVector*>(std::align(alignof(RealVector), L * sizeof(RealVector), raw, room));
        for (std::size_t n = 0; n < L; ++n) {
            RealVector sample{};
            sample[0] = x[n];
            sample[1] = y[n];
            v[n] = sample;
        }
        plan_->exec(v, 1.0, true);
        pick_bins(bins_, L, [v](std::size_t i) { return v[i][0]; }, lines_x);
        pick_bins(bins_, L, [v](std::size_t i) { return v[i][1]; }, lines_y);
        return;
    }
#endif
    (*this)(x, lines_x);
    (*this)(y, lines_y);
}

}  // namespace amb_fast
