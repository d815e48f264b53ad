// Streaming period averaging, spectra at the excited lines, their period-to-period variance, and the
// stiffness/damping estimate of MODEL.md section 3. Memory is O(period + lines), never O(record).
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <memory>
#include <stdexcept>
#include <vector>

namespace pocketfft::detail {
template <typename T0>
class pocketfft_r;
}  // namespace pocketfft::detail

namespace amb_fast {

struct LinePlan {
    Eigen::Index period = 0;              // samples per period L
    std::vector<Eigen::Index> excited;    // harmonic numbers (DFT bins) of the excited lines, 1..L/2-1
    std::vector<Eigen::Index> unexcited;  // harmonic numbers at which to report levels
    Eigen::Index periods_per_block = 1;   // > 1 only for long records: variance from batch means
    void validate() const;
};

struct LineEstimate {
    Eigen::VectorXcd force;              // N, period-averaged complex amplitude at each excited line
    Eigen::VectorXcd displacement;       // m, likewise
    Eigen::VectorXcd H;                  // N/m, dynamic stiffness F/Y
    Eigen::VectorXd k, c;                // N/m, N s/m: actual coefficients (paper eq. 9)
    Eigen::VectorXd k_std, c_std;        // their standard errors, from the period-to-period variance
    Eigen::VectorXd k_smooth, c_smooth;  // median filtered across lines
    Eigen::VectorXd unexcited_force, unexcited_displacement;  // N, m: amplitudes at unexcited lines
    Eigen::Index periods = 0;                                 // periods averaged
    Eigen::Index blocks = 0;             // independent groups behind the variance (dof = blocks - 1)
    Eigen::Index saturated_samples = 0;  // recorded samples at which the amplifier clipped (simulations)
};

// A non-finite sample somewhere in record samples [first, first + count): the estimator checks whole
// blocks (Inf and NaN survive summation), and whoever holds the data can name the exact sample.
struct NonFiniteSamples : std::invalid_argument {
    NonFiniteSamples(Eigen::Index first, Eigen::Index count);
    Eigen::Index first, count;
};

// The unscaled DFT X_b = sum_n x[n] exp(-2 pi i b n / L) of one period of L real samples at the bins
// asked, by whichever exact method costs less: a real FFT of the whole period (pocketfft, the FFT
// behind numpy.fft; cost from pocketfft's own model, about L log L) or a direct sum per bin over a
// table of the L twiddle factors (about `bins x L`; it wins for a handful of bins). Both agree with
// numpy.fft.rfft to about 1e-15 of the spectrum's largest bin. Memory O(L); one object serves one
// thread at a time.
class LineTransform {
  public:
    enum class Method { automatic, fft, direct };
    LineTransform(Eigen::Index period, std::vector<Eigen::Index> bins, Method method = Method::automatic);

    // lines[j] = X_{bins[j]} of the L samples at x.
    void operator()(const double* x, std::complex<double>* lines);
    // Both channels at once: the same numbers as two calls, the two FFTs run side by side in SIMD
    // lanes (pocketfft's vector types) where the compiler has them.
    void operator()(const double* x, const double* y, std::complex<double>* lines_x, std::complex<double>* lines_y);
    Method method() const { return method_; }
    Eigen::Index period() const { return L_; }

    // The cost model (arbitrary units, the same for both): which method `automatic` picks.
    static double fft_cost(Eigen::Index period);
    static double direct_cost(Eigen::Index period, Eigen::Index bins);

  private:
    Eigen::Index L_;
    std::vector<Eigen::Index> bins_;
    Method method_;
    std::shared_ptr<const pocketfft::detail::pocketfft_r<double>> plan_;  // fft: shared by a thread's users
    std::vector<double> work_;                                            // fft: the period, transformed in place
    std::vector<double> pair_work_;              // fft of two channels: L SIMD vectors (lanes x, y), plus room to align
    std::vector<std::complex<double>> twiddle_;  // direct: exp(-2 pi i n / L), n < L
};

class PeriodEstimator {
  public:
    explicit PeriodEstimator(LinePlan plan);
    // Forgets every period added, keeping the memory (an estimator reused for the next experiment).
    void restart();

    // Adds one period of both channels (plan.period samples each); first_sample is the record index
    // of force[0]. Throws NonFiniteSamples when a block with a non-finite sample closes.
    void add_period(const double* force, const double* displacement, Eigen::Index first_sample = 0) {
        add_periods(force, displacement, 1, first_sample);
    }
    // Adds `count` consecutive periods from contiguous arrays (faster than one at a time).
    void add_periods(const double* force, const double* displacement, Eigen::Index count, Eigen::Index first_sample);
    // Adds one period given as its unscaled line spectra at bins() (what add_period transforms the samples
    // to): for spectra drawn directly (SteadyLines). Not to be mixed with add_period in one experiment.
    void add_period_lines(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines);
    Eigen::Index periods() const { return periods_; }
    // The excited harmonics, then the unexcited ones.
    const std::vector<Eigen::Index>& bins() const { return bins_; }

    // mass (kg) enters k = m w^2 + Re H; fs (Hz) sets the line frequencies; window is odd.
    LineEstimate estimate(double mass, double fs, int median_window) const;

  private:
    void close_block();
    // The closed block's spectra (lines_f_, lines_y_, block means) into the sums and co-moments.
    void add_block();
    void require_finite_block() const;
    // Turns a channel's block sum into its mean; false when the mean repeats `previous` bit for bit (a
    // noise-free periodic channel): its line spectrum is then reused, which saves the transform
    // without changing a digit.
    bool new_mean(Eigen::VectorXd& block, const Eigen::VectorXd& previous) const;

    LinePlan plan_;
    std::vector<Eigen::Index> bins_;     // excited, then unexcited harmonics
    Eigen::VectorXd block_f_, block_y_;  // time-domain sums of the open block's periods
    Eigen::VectorXcd sum_F_, sum_Y_;     // spectra at bins_, summed over the closed blocks' periods
    LineTransform transform_;
    Eigen::Index periods_ = 0, in_block_ = 0, blocks_ = 0, block_first_ = 0;
    Eigen::VectorXd previous_f_, previous_y_;  // the last block means (once have_previous_)
    bool have_previous_ = false;
    Eigen::VectorXcd lines_f_, lines_y_;
    Eigen::VectorXcd open_F_, open_Y_;  // add_period_lines: spectra summed over the open block's periods
    bool from_lines_ = false;           // periods came as spectra (add_period_lines)
    // Welford means and co-moments of the block spectra at the excited lines.
    Eigen::VectorXcd mean_F_, mean_Y_, m_FYc_, m_FF_, m_YY_, m_FY_;
    Eigen::VectorXd m_FFc_, m_YYc_;
};

// Odd-window running median across a sequence; the ends repeat the edge value ("nearest").
Eigen::VectorXd median_filter(const Eigen::VectorXd& x, int window);

}  // namespace amb_fast
