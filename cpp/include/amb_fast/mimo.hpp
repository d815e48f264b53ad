// A generic dense multi-input multi-output sampled-data loop, closed and discretised already:
//
//     z[k+1] = M z[k] + Bf f[k] + Bn n[k]        f: held forces (p), n: white probe noise (q)
//     o[k]   = C z[k] + Dn n[k]                  o: the q measured displacements first, then any others
//
// It knows nothing about magnetic bearings beyond these shapes (the Python layer builds the matrices,
// exactly discretised); it adds what the measurement chain does outside the loop: per force channel an
// AC-coupled transducer (q[k+1] = a q[k] + (1 - a) f[k], recorded f - q; a = 0 is DC coupled) and
// white transducer noise, one noise stream per source.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "amb_fast/random.hpp"

namespace amb_fast {

struct MimoModel {
    Eigen::MatrixXd M, Bf, Bn, C, Dn;
    Eigen::VectorXd transducer_pole;  // per force channel, 0 = DC coupled
    Eigen::VectorXd sensor_noise;     // m rms per probe (q)
    Eigen::VectorXd force_noise;      // N rms per force channel (p)

    Eigen::Index states() const { return M.rows(); }
    Eigen::Index forces() const { return Bf.cols(); }
    Eigen::Index probes() const { return Bn.cols(); }
    Eigen::Index outputs() const { return C.rows(); }
    // Throws std::invalid_argument naming the matrix whose shape or values are wrong.
    void validate() const;
};

// The loop keeps its state between calls to run(), so long runs can be streamed. It advances `lanes`
// independent runs of the same model in lock step (each with its own forces, noise and state): they
// share every load of the matrix, and their sample-to-sample chains overlap.
class MimoLoop {
  public:
    MimoLoop(const MimoModel& model, const std::vector<std::uint64_t>& seeds);  // one seed per lane

    Eigen::Index lanes() const { return lanes_; }
    // Advances n samples of every lane. force[l]: n x p, sample-major (row k holds f[k]); recorded[l]:
    // n x p; out[l]: n x r. Throws std::overflow_error if a state stops being finite.
    void run(const double* const* force, Eigen::Index n, double* const* recorded, double* const* out);

    // Starts every lane in the periodic steady state of its L-sample period (L x p, sample-major)
    // repeated forever: z0 = M^L z0 + z_L, the transducers likewise; with probe noise, the
    // noise-driven part of the state is drawn from its stationary distribution.
    void start_periodic(const double* const* period_force, Eigen::Index L);

    // Lane l's state z.
    Eigen::VectorXd state(Eigen::Index lane) const;

  private:
    static constexpr Eigen::Index chunk = 1024;
    template <int K>
    void run_block(const double* const* force, Eigen::Index start, Eigen::Index m, double* const* recorded,
                   double* const* out);
    void set_state(Eigen::Index i, Eigen::Index lane, double value);

    MimoModel model_;
    Eigen::Index lanes_;
    // The map from [z; f; n] to [z'; o], by columns, in row blocks of one SIMD register of four slots:
    // four rows of one lane, or two rows of both (slot s: row s / lanes of the block, lane s % lanes).
    // A pass keeps `pass_` blocks of sums in registers and adds each of its columns' coefficients
    // times the column's value (every lane's) to all of them; the rows are grouped into passes that
    // share few columns (an axis' rows), and a pass visits only the columns its rows use: the input
    // columns (f, n: not waiting for the previous sample) first, then the state columns. Rows padded
    // with zeros to whole passes.
    static constexpr int slots = 4;
    int pass_ = 1;                                // blocks per pass: 1, 2 or 4
    Eigen::Index passes_ = 0, rows_ = 0;          // passes, padded rows
    std::vector<Eigen::Index> position_;          // row i of [z'; o] at position_[i] of the state buffers
    std::vector<int> pass_inputs_, pass_states_;  // columns per pass
    std::vector<int> offsets_;                    // per pass and column: where its value is (in doubles)
    std::vector<double, Eigen::aligned_allocator<double>> coefficients_;  // [pass][column][block][slot]
    std::vector<double, Eigen::aligned_allocator<double>> w_, next_;      // rows by position x lanes
    std::vector<double, Eigen::aligned_allocator<double>> inputs_;        // a chunk's [f; n] x lanes, sample-major
    Eigen::MatrixXd q_;                                                   // transducer states, p x lanes
    std::vector<std::uint64_t> seeds_;
    std::vector<NormalStream> sensor_rng_, force_rng_;         // lane-major: source j of lane l at l*count + j
    std::vector<Eigen::MatrixXd> sensor_draws_, force_draws_;  // per lane: chunk x q, chunk x p
    Eigen::Index k_ = 0;
};

// A part of a model that no other part reaches: its states, and the force channels and probes that touch
// them (indices into the whole model's). Its model keeps only the probes' rows of C (the lines' outputs).
struct MimoPart {
    std::vector<Eigen::Index> states, forces, probes;
    MimoModel model(const MimoModel& whole) const;
};
// The model's independent parts: states linked through M, force channels and probes through the states
// they touch (Bf, Bn, the probes' rows of C), probes through Dn; in order of their first node. One part
// when everything is linked. An uncoupled two-axis rig has two, one per axis.
std::vector<MimoPart> independent_parts(const MimoModel& model);

// Seed of noise source j of a kind (0: probe, 1: force transducer, 2: transducer lines, 3: the state's
// line-free part; kind < 8): splitmix64 of the run's seed, the kind and j, so every source has its own
// stream.
std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t kind, Eigen::Index j);

// The state's stationary distribution under the probes' noise: its covariance (steady.hpp), and
// z += root N(0, I) for a square root of it (covariance_root), from the stream of start_noise_seed(seed).
Eigen::MatrixXd stationary_noise_covariance(const MimoModel& model);
void add_stationary_noise(const Eigen::MatrixXd& root, std::uint64_t seed, Eigen::VectorXd& z);

// Runs the loop from rest: recorded forces (n x p) and outputs (n x r), sample-major.
void mimo_simulate(const MimoModel& model, const double* force, Eigen::Index n, std::uint64_t seed, double* recorded,
                   double* out);

// Experiments in lock step, one per seed: period_force[l] (L x p) repeated for settle + periods, from
// rest or the periodic steady state; the recorded periods' forces recorded[l] (p x periods*L) and
// measured displacements measured[l] (q x periods*L), channel-major (one contiguous record per channel).
// With all_forces false, recorded[l] (p x L) holds the first recorded period only.
void mimo_experiments(const MimoModel& model, const double* const* period_force, Eigen::Index L,
                      Eigen::Index settle_periods, Eigen::Index periods, const std::vector<std::uint64_t>& seeds,
                      bool steady_start, double* const* recorded, double* const* measured, bool all_forces = true);

}  // namespace amb_fast
