// Period averaging and the line estimate (PeriodEstimator), and the median filter across lines; a
// period's line spectrum is in line_transform.cpp.
#include "amb_fast/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "amb_fast/errors.hpp"

namespace amb_fast {

namespace {
constexpr double two_pi = 6.283185307179586;
using cd = std::complex<double>;
}  // namespace

void LinePlan::validate() const {
    require(period >= 4, "period", period, "at least 4 samples");
    require(!excited.empty(), "lines", excited.size(), "at least one excited line");
    require(periods_per_block >= 1, "periods_per_block", periods_per_block, ">= 1");
    for (const auto* set : {&excited, &unexcited})
        for (Eigen::Index b : *set)
            require(b >= 1 && 2 * b < period, "line harmonic", b, "between 1 and below period/2 (Nyquist)");
}

namespace {
std::vector<Eigen::Index> excited_then_unexcited(const LinePlan& plan) {
    std::vector<Eigen::Index> bins = plan.excited;
    bins.insert(bins.end(), plan.unexcited.begin(), plan.unexcited.end());
    return bins;
}
}  // namespace

PeriodEstimator::PeriodEstimator(LinePlan plan)
    : plan_(validated(plan)), bins_(excited_then_unexcited(plan_)), transform_(plan_.period, bins_) {
    restart();
}

void PeriodEstimator::restart() {
    const Eigen::Index L = plan_.period, n = static_cast<Eigen::Index>(plan_.excited.size());
    const auto all = static_cast<Eigen::Index>(bins_.size());
    periods_ = in_block_ = blocks_ = block_first_ = 0;
    have_previous_ = from_lines_ = false;
    sum_F_.setZero(all);
    sum_Y_.setZero(all);
    open_F_.setZero(all);
    open_Y_.setZero(all);
    // The time-domain sums come with the first period of samples (add_periods), then stay.
    for (auto* v : {&block_f_, &block_y_, &previous_f_, &previous_y_})
        if (v->size() == L) v->setZero();
    for (auto* v : {&mean_F_, &mean_Y_, &m_FYc_, &m_FF_, &m_YY_, &m_FY_}) v->setZero(n);
    m_FFc_.setZero(n);
    m_YYc_.setZero(n);
}

NonFiniteSamples::NonFiniteSamples(Eigen::Index first_, Eigen::Index count_)
    : std::invalid_argument("recording has a non-finite sample among samples " + std::to_string(first_) + " to " +
                            std::to_string(first_ + count_ - 1)),
      first(first_),
      count(count_) {}

namespace {
// acc += the sum of m consecutive periods of length L at x, eight at a time: a long record is read at
// close to memory bandwidth instead of being bound by the accumulator's traffic.
void accumulate(Eigen::VectorXd& acc, const double* x, Eigen::Index L, Eigen::Index m) {
    const auto period = [&](Eigen::Index p) { return Eigen::Map<const Eigen::VectorXd>(x + p * L, L); };
    Eigen::Index p = 0;
    for (; p + 8 <= m; p += 8)
        acc += ((period(p) + period(p + 1)) + (period(p + 2) + period(p + 3))) +
               ((period(p + 4) + period(p + 5)) + (period(p + 6) + period(p + 7)));
    for (; p < m; ++p) acc += period(p);
}
}  // namespace

void PeriodEstimator::add_periods(const double* force, const double* displacement, Eigen::Index count,
                                  Eigen::Index first_sample) {
    const Eigen::Index L = plan_.period;
    if (block_f_.size() != L)
        for (auto* v : {&block_f_, &block_y_, &previous_f_, &previous_y_}) v->setZero(L);
    if (plan_.periods_per_block == 1) {  // each period is a block: its mean is the period, no sum needed
        for (; count > 0; --count, force += L, displacement += L, first_sample += L) {
            block_first_ = first_sample;
            // 0 + x, as a sum into the zeroed block gives (-0.0 becomes +0.0), so the digits are the same.
            block_f_ = Eigen::Map<const Eigen::VectorXd>(force, L).array() + 0.0;
            block_y_ = Eigen::Map<const Eigen::VectorXd>(displacement, L).array() + 0.0;
            ++periods_;
            in_block_ = 1;
            close_block();
        }
        return;
    }
    while (count > 0) {
        if (in_block_ == 0) block_first_ = first_sample;
        const Eigen::Index m = std::min(count, plan_.periods_per_block - in_block_);
        accumulate(block_f_, force, L, m);
        accumulate(block_y_, displacement, L, m);
        periods_ += m;
        in_block_ += m;
        if (in_block_ == plan_.periods_per_block) close_block();
        force += m * L;
        displacement += m * L;
        first_sample += m * L;
        count -= m;
    }
}

void PeriodEstimator::add_period_lines(const cd* force_lines, const cd* displacement_lines) {
    const auto all = static_cast<Eigen::Index>(bins_.size());
    const Eigen::Map<const Eigen::VectorXcd> F(force_lines, all), Y(displacement_lines, all);
    from_lines_ = true;
    ++periods_;
    ++in_block_;
    if (plan_.periods_per_block == 1) {
        lines_f_ = F;
        lines_y_ = Y;
        add_block();
        return;
    }
    open_F_ += F;
    open_Y_ += Y;
    if (in_block_ < plan_.periods_per_block) return;
    const double mean = 1.0 / static_cast<double>(plan_.periods_per_block);
    lines_f_ = mean * open_F_;
    lines_y_ = mean * open_Y_;
    open_F_.setZero();
    open_Y_.setZero();
    add_block();
}

void PeriodEstimator::require_finite_block() const {
    if (!std::isfinite(block_f_.sum() + block_y_.sum())) throw NonFiniteSamples(block_first_, in_block_ * plan_.period);
}

bool PeriodEstimator::new_mean(Eigen::VectorXd& block, const Eigen::VectorXd& previous) const {
    if (plan_.periods_per_block > 1) block *= 1.0 / static_cast<double>(plan_.periods_per_block);  // the mean
    const Eigen::Index L = block.size();
    return !have_previous_ || !std::equal(block.data(), block.data() + L, previous.data());
}

void PeriodEstimator::close_block() {
    require_finite_block();
    // Each channel's block mean, transformed (both at once when both changed), kept as the channel's
    // previous mean without a copy; the sums are zeroed for the next block.
    const Eigen::Index L = plan_.period, bins = static_cast<Eigen::Index>(bins_.size());
    const bool new_f = new_mean(block_f_, previous_f_), new_y = new_mean(block_y_, previous_y_);
    lines_f_.resize(bins);
    lines_y_.resize(bins);
    if (new_f && new_y) transform_(block_f_.data(), block_y_.data(), lines_f_.data(), lines_y_.data());
    else if (new_f) transform_(block_f_.data(), lines_f_.data());
    else if (new_y) transform_(block_y_.data(), lines_y_.data());
    if (new_f) previous_f_.swap(block_f_);
    if (new_y) previous_y_.swap(block_y_);
    have_previous_ = true;
    if (plan_.periods_per_block > 1) {  // with one period per block, the next period overwrites them
        block_f_.setZero(L);
        block_y_.setZero(L);
    }
    add_block();
}

void PeriodEstimator::add_block() {
    ++blocks_;
    // The averaged spectra are the sum of the blocks' (the transform is linear): no extra FFT.
    const double G = static_cast<double>(plan_.periods_per_block);
    sum_F_ += G * lines_f_;
    sum_Y_ += G * lines_y_;
    in_block_ = 0;

    // Welford update of the mean and co-moments of the block spectra (two channels, complex).
    const auto F = lines_f_.head(mean_F_.size());
    const auto Y = lines_y_.head(mean_Y_.size());
    const double n = static_cast<double>(blocks_);
    const Eigen::VectorXcd dF = F - mean_F_, dY = Y - mean_Y_;
    mean_F_ += dF / n;
    mean_Y_ += dY / n;
    const Eigen::VectorXcd dF2 = F - mean_F_, dY2 = Y - mean_Y_;
    m_FFc_ += (dF.array() * dF2.conjugate().array()).real().matrix();
    m_YYc_ += (dY.array() * dY2.conjugate().array()).real().matrix();
    m_FYc_ += (dF.array() * dY2.conjugate().array()).matrix();
    m_FF_ += (dF.array() * dF2.array()).matrix();
    m_YY_ += (dY.array() * dY2.array()).matrix();
    m_FY_ += (dF.array() * dY2.array()).matrix();
}

LineEstimate PeriodEstimator::estimate(double mass, double fs, int median_window) const {
    require(blocks_ >= 2, "periods", periods_, "enough for at least 2 independent periods (standard errors)");
    require(median_window >= 1 && median_window % 2 == 1, "median_window", median_window, "an odd number >= 1");
    const Eigen::Index L = plan_.period, n = static_cast<Eigen::Index>(plan_.excited.size());
    if (in_block_ > 0 && !from_lines_) require_finite_block();  // the periods that did not fill a last block
    LineEstimate e;
    e.periods = periods_;
    e.blocks = blocks_;

    // Averaged spectra of every period (those short of a last full block too), scaled to complex
    // amplitudes: a sine of amplitude A reads |A|.
    Eigen::VectorXcd F_all = sum_F_ + open_F_, Y_all = sum_Y_ + open_Y_;  // open_: add_period_lines' last block
    if (in_block_ > 0 && !from_lines_) {
        LineTransform transform = transform_;  // estimate() is const; the transform has scratch space
        Eigen::VectorXcd lines(static_cast<Eigen::Index>(bins_.size()));
        for (auto [block, total] : {std::pair{&block_f_, &F_all}, std::pair{&block_y_, &Y_all}}) {
            transform(block->data(), lines.data());
            *total += lines;
        }
    }
    const double scale = 2.0 / (static_cast<double>(L) * static_cast<double>(periods_));
    e.force = scale * F_all.head(n);
    e.displacement = scale * Y_all.head(n);
    e.H = e.force.cwiseQuotient(e.displacement);

    // Covariances of the averaged spectra (FFT units, like the Welford sums): the batch-means
    // variance of one period is G * var(block means); that of the mean of all periods, / periods.
    const double G = static_cast<double>(plan_.periods_per_block);
    const double to_mean = G / ((static_cast<double>(blocks_) - 1.0) * static_cast<double>(periods_));
    e.k.resize(n);
    e.c.resize(n);
    e.k_std.resize(n);
    e.c_std.resize(n);
    for (Eigen::Index j = 0; j < n; ++j) {
        const double w = two_pi * static_cast<double>(plan_.excited[j]) * fs / static_cast<double>(L);
        const cd H = e.H[j], Y = mean_Y_[j];
        // Linearised: dH = (dF - H dY) / Y. E|dH|^2 and E[dH^2] give the variances of Re and Im.
        const double abs2 =
            (m_FFc_[j] + std::norm(H) * m_YYc_[j] - 2.0 * std::real(std::conj(H) * m_FYc_[j])) * to_mean / std::norm(Y);
        const cd sq = (m_FF_[j] + H * H * m_YY_[j] - 2.0 * H * m_FY_[j]) * to_mean / (Y * Y);
        e.k[j] = mass * w * w + H.real();
        e.c[j] = H.imag() / w;
        e.k_std[j] = std::sqrt(std::max(0.0, 0.5 * (abs2 + sq.real())));
        e.c_std[j] = std::sqrt(std::max(0.0, 0.5 * (abs2 - sq.real()))) / w;
    }
    for (Eigen::Index j = 0; j < n; ++j) {  // no silent Inf or NaN: name the line
        if (!std::isfinite(e.k[j] + e.c[j] + e.k_std[j] + e.c_std[j])) {
            std::ostringstream msg;
            msg << "the estimate is not finite at the excited line " << static_cast<double>(plan_.excited[j]) * fs / L
                << " Hz: the displacement has no component there (|Y| = " << std::abs(e.displacement[j]) << " m)";
            throw std::invalid_argument(msg.str());
        }
    }
    e.k_smooth = median_filter(e.k, median_window);
    e.c_smooth = median_filter(e.c, median_window);

    const Eigen::Index u = static_cast<Eigen::Index>(plan_.unexcited.size());
    e.unexcited_force.resize(u);
    e.unexcited_displacement.resize(u);
    for (Eigen::Index j = 0; j < u; ++j) {
        e.unexcited_force[j] = scale * std::abs(F_all[n + j]);
        e.unexcited_displacement[j] = scale * std::abs(Y_all[n + j]);
    }
    return e;
}

namespace {
// The median of five values by N. Devillard's network of seven compare-exchanges ("Fast median search",
// 1998): the default window, without the general selection's overhead.
double median_of_five(double a, double b, double c, double d, double e) {
    auto order = [](double& lo, double& hi) {
        const double l = std::min(lo, hi), h = std::max(lo, hi);
        lo = l, hi = h;
    };
    order(a, b), order(d, e), order(a, d), order(b, e), order(b, c), order(c, d), order(b, c);
    return c;
}
}  // namespace

Eigen::VectorXd median_filter(const Eigen::VectorXd& x, int window) {
    const Eigen::Index n = x.size(), half = window / 2;
    Eigen::VectorXd out(n);
    if (window == 5) {
        const auto at = [&](Eigen::Index i) { return x[std::clamp<Eigen::Index>(i, 0, n - 1)]; };
        for (Eigen::Index i = 0; i < n; ++i) out[i] = median_of_five(at(i - 2), at(i - 1), at(i), at(i + 1), at(i + 2));
        return out;
    }
    std::vector<double> buf(static_cast<std::size_t>(window));
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = -half; j <= half; ++j)
            buf[static_cast<std::size_t>(j + half)] = x[std::clamp<Eigen::Index>(i + j, 0, n - 1)];
        std::nth_element(buf.begin(), buf.begin() + half, buf.end());
        out[i] = buf[static_cast<std::size_t>(half)];
    }
    return out;
}

}  // namespace amb_fast
