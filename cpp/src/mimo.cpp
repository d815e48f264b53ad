#include "amb_fast/mimo.hpp"

#include <algorithm>
#include <cstring>
#include <utility>
#include <cstdlib>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t kind, Eigen::Index j) {
    // 8 j + kind + 1 is one number per (kind, j) for kind < 8 (the 2 j + kind + 1 of earlier releases gave
    // the force lines' channel 0 the stream of probe 1).
    std::uint64_t x = seed + 0x9e3779b97f4a7c15ULL * (8 * static_cast<std::uint64_t>(j) + kind + 1);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

namespace {
void require_shape(const Eigen::MatrixXd& X, Eigen::Index rows, Eigen::Index cols, const char* name) {
    if (X.rows() == rows && X.cols() == cols && X.allFinite()) return;
    std::ostringstream msg;
    msg << name << " must be a finite " << rows << " x " << cols << " matrix, got " << X.rows() << " x " << X.cols()
        << (X.allFinite() ? "" : " with non-finite entries");
    throw std::invalid_argument(msg.str());
}
}  // namespace

void MimoModel::validate() const {
    const Eigen::Index n = M.rows(), p = Bf.cols(), q = Bn.cols(), r = C.rows();
    require(n > 0, "M rows", n, "> 0");
    require_shape(M, n, n, "M");
    require_shape(Bf, n, p, "Bf");
    require_shape(Bn, n, q, "Bn");
    require(r >= q, "C rows", r, "at least the number of probes (the measured displacements come first)");
    require_shape(C, r, n, "C");
    require_shape(Dn, r, q, "Dn");
    require(transducer_pole.size() == p, "transducer_pole length", transducer_pole.size(), "one per force channel");
    require(force_noise.size() == p, "force_noise length", force_noise.size(), "one per force channel");
    require(sensor_noise.size() == q, "sensor_noise length", sensor_noise.size(), "one per probe");
    for (Eigen::Index j = 0; j < p; ++j) {
        require(transducer_pole[j] >= 0.0 && transducer_pole[j] < 1.0, "transducer_pole", transducer_pole[j],
                "in [0, 1) (0: DC coupled)");
        require(force_noise[j] >= 0.0, "force_noise", force_noise[j], ">= 0 (N rms)");
    }
    for (Eigen::Index j = 0; j < q; ++j) require(sensor_noise[j] >= 0.0, "sensor_noise", sensor_noise[j], ">= 0 (m rms)");
}

MimoLoop::MimoLoop(const MimoModel& model, const std::vector<std::uint64_t>& seeds)
    : model_(validated(model)), lanes_(static_cast<Eigen::Index>(seeds.size())), seeds_(seeds) {
    require(lanes_ == 1 || lanes_ == 2, "lanes", lanes_, "1 or 2");
    const Eigen::Index n = model_.states(), p = model_.forces(), q = model_.probes(), r = model_.outputs();
    // One map from [z; f; n] to [z'; o].
    Eigen::MatrixXd Mt = Eigen::MatrixXd::Zero(n + r, n + p + q);
    Mt.topLeftCorner(n, n) = model_.M;
    Mt.block(0, n, n, p) = model_.Bf;
    Mt.block(0, n + p, n, q) = model_.Bn;
    Mt.bottomLeftCorner(r, n) = model_.C;
    Mt.block(n, n + p, r, q) = model_.Dn;
    const Eigen::Index rows = Mt.rows(), per_block = slots / lanes_, blocks = (rows + per_block - 1) / per_block;
    pass_ = blocks <= 1 ? 1 : blocks <= 2 ? 2 : 4;
    const Eigen::Index per_pass = pass_ * per_block;
    passes_ = (rows + per_pass - 1) / per_pass;
    rows_ = passes_ * per_pass;
    // Rows into passes, greedily: the row with the most non-zeros first, then the rows that add the
    // fewest new columns to the pass.
    const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> nonzero = Mt.array() != 0.0;
    std::vector<bool> taken(static_cast<std::size_t>(rows), false);
    std::vector<Eigen::Index> order;  // row at each position (-1: padding)
    for (Eigen::Index pass = 0; pass < passes_; ++pass) {
        Eigen::Array<bool, 1, Eigen::Dynamic> used = Eigen::Array<bool, 1, Eigen::Dynamic>::Constant(Mt.cols(), false);
        for (Eigen::Index at = 0; at < per_pass; ++at) {
            Eigen::Index best = -1, best_cost = 0;
            for (Eigen::Index i = 0; i < rows; ++i) {
                if (taken[static_cast<std::size_t>(i)]) continue;
                const Eigen::Index cost = at == 0 ? -nonzero.row(i).count() : (nonzero.row(i) && !used).count();
                if (best < 0 || cost < best_cost) best = i, best_cost = cost;
            }
            order.push_back(best);
            if (best < 0) continue;
            taken[static_cast<std::size_t>(best)] = true;
            used = used || nonzero.row(best);
        }
    }
    position_.assign(static_cast<std::size_t>(rows), 0);
    for (std::size_t at = 0; at < order.size(); ++at)
        if (order[at] >= 0) position_[static_cast<std::size_t>(order[at])] = static_cast<Eigen::Index>(at);
    for (Eigen::Index pass = 0; pass < passes_; ++pass) {
        const Eigen::Index first = pass * per_pass;
        std::vector<Eigen::Index> columns;
        for (Eigen::Index j = 0; j < Mt.cols(); ++j) {
            bool used = false;
            for (Eigen::Index at = first; at < first + per_pass; ++at)
                used = used || (order[static_cast<std::size_t>(at)] >= 0 && nonzero(order[static_cast<std::size_t>(at)], j));
            if (used) columns.push_back(j);
        }
        // inputs first
        std::stable_partition(columns.begin(), columns.end(), [&](Eigen::Index j) { return j >= n; });
        const auto states = std::count_if(columns.begin(), columns.end(), [&](Eigen::Index j) { return j < n; });
        pass_inputs_.push_back(static_cast<int>(static_cast<Eigen::Index>(columns.size()) - states));
        pass_states_.push_back(static_cast<int>(states));
        for (const Eigen::Index j : columns) {
            offsets_.push_back(static_cast<int>((j >= n ? j - n : position_[static_cast<std::size_t>(j)]) * lanes_));
            for (Eigen::Index b = 0; b < pass_; ++b)
                for (Eigen::Index s = 0; s < slots; ++s) {
                    const Eigen::Index row = order[static_cast<std::size_t>(first + b * per_block + s / lanes_)];
                    coefficients_.push_back(row >= 0 ? Mt(row, j) : 0.0);
                }
        }
    }
    w_.assign(static_cast<std::size_t>(rows_ * lanes_), 0.0);
    next_.assign(static_cast<std::size_t>(rows_ * lanes_), 0.0);
    inputs_.assign(static_cast<std::size_t>(chunk * (p + q) * lanes_), 0.0);
    q_ = Eigen::MatrixXd::Zero(p, lanes_);
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        for (Eigen::Index j = 0; j < q; ++j) sensor_rng_.emplace_back(stream_seed(seeds[l], 0, j));
        for (Eigen::Index j = 0; j < p; ++j) force_rng_.emplace_back(stream_seed(seeds[l], 1, j));
        sensor_draws_.push_back(Eigen::MatrixXd::Zero(chunk, q));
        force_draws_.push_back(Eigen::MatrixXd::Zero(chunk, p));
    }
}

Eigen::VectorXd MimoLoop::state(Eigen::Index lane) const {
    Eigen::VectorXd z(model_.states());
    for (Eigen::Index i = 0; i < z.size(); ++i)
        z[i] = w_[static_cast<std::size_t>(position_[static_cast<std::size_t>(i)] * lanes_ + lane)];
    return z;
}

void MimoLoop::set_state(Eigen::Index i, Eigen::Index lane, double value) {
    w_[static_cast<std::size_t>(position_[static_cast<std::size_t>(i)] * lanes_ + lane)] = value;
}

void MimoLoop::run(const double* const* force, Eigen::Index n, double* const* recorded, double* const* out) {
    const Eigen::Index p = model_.forces(), q = model_.probes();
    for (Eigen::Index start = 0; start < n; start += chunk) {
        poll_interrupt();
        const Eigen::Index m = std::min(chunk, n - start);
        for (Eigen::Index l = 0; l < lanes_; ++l) {
            for (Eigen::Index j = 0; j < q; ++j)
                if (model_.sensor_noise[j] > 0.0)
                    sensor_rng_[l * q + j].fill(sensor_draws_[l].col(j).data(), m, model_.sensor_noise[j]);
            for (Eigen::Index j = 0; j < p; ++j)
                if (model_.force_noise[j] > 0.0)
                    force_rng_[l * p + j].fill(force_draws_[l].col(j).data(), m, model_.force_noise[j]);
        }
        // The chunk's inputs [f; n] x lanes, sample-major.
        for (Eigen::Index l = 0; l < lanes_; ++l)
            for (Eigen::Index k = 0; k < m; ++k) {
                double* in = inputs_.data() + k * (p + q) * lanes_ + l;
                const double* f = force[l] + (start + k) * p;
                for (Eigen::Index j = 0; j < p; ++j) in[j * lanes_] = f[j];
                for (Eigen::Index j = 0; j < q; ++j) in[(p + j) * lanes_] = sensor_draws_[l](k, j);
            }
        if (lanes_ == 2)
            run_block<2>(force, start, m, recorded, out);
        else
            run_block<1>(force, start, m, recorded, out);
        // Inf and NaN never turn finite again in a linear recursion: one check per chunk.
        for (Eigen::Index i = 0; i < rows_ * lanes_; ++i) {
            if (std::isfinite(w_[static_cast<std::size_t>(i)])) continue;
            std::ostringstream msg;
            msg << "the state became non-finite by sample " << k_ + start + m << ": the loop is unstable";
            throw std::overflow_error(msg.str());
        }
    }
    k_ += n;
}

namespace {
// Four slots in one SIMD register (GCC/Clang vector extension): two 16-byte halves in a portable build,
// one 32-byte register in the AVX2 kernel. Loads and stores go through memcpy (no alignment assumed).
typedef double Quad __attribute__((vector_size(32)));
typedef double Pair __attribute__((vector_size(16)));
typedef double PairU __attribute__((vector_size(16), aligned(8), may_alias));
typedef double QuadU __attribute__((vector_size(32), aligned(8), may_alias));  // for unaligned stores

struct Step {
    Eigen::Index states, forces, probes, outputs, passes, m, start;
    const int *pass_inputs, *pass_states, *offsets;
    const Eigen::Index* output_position;  // of each output row
    const double* coefficients;
    const double* in;  // the chunk's inputs, (forces + probes) x lanes per sample
    double *w, *next;  // [z; o; padding] x lanes, swapped every sample
    const double* const* force;
    double* const* recorded;
    double* const* out;
    const double* pole;
    double* transducer;  // [lane][channel], 8 per lane
    const double* const* force_noise;
    Eigen::Index noise_stride;
};

// A column's value in every slot: (v0, v1, v0, v1) for two lanes, (v, v, v, v) for one. (Through a
// pointer: a function returning a 32-byte vector would change the ABI without AVX.)
template <int K>
__attribute__((always_inline)) inline void column(const double* x, Quad* value) {
    if constexpr (K == 2) {
        Pair pair;
        std::memcpy(&pair, x, sizeof pair);
        *value = __builtin_shufflevector(pair, pair, 0, 1, 0, 1);
    } else {
        const double v = *x;
        *value = Quad{v, v, v, v};
    }
}

// Adds `count` columns of x (at x + offsets[j], K values each) times their coefficients (P blocks of four
// each, from c) to the sums: even columns to `even`, odd ones to `odd` (two short chains, not one long one).
template <int K, int P>
__attribute__((always_inline)) inline void accumulate(const double* x, int count, const int*& offsets,
                                                      const double*& c, Quad* even, Quad* odd) {
    const Quad zero = {0.0, 0.0, 0.0, 0.0};
    Quad v = zero, value = zero;
    int j = 0;
    for (; j + 1 < count; j += 2, c += 8 * P, offsets += 2) {
        column<K>(x + offsets[0], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * b, sizeof v);
            even[b] += v * value;
        }
        column<K>(x + offsets[1], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * (P + b), sizeof v);
            odd[b] += v * value;
        }
    }
    if (j < count) {
        column<K>(x + offsets[0], &value);
        for (int b = 0; b < P; ++b) {
            std::memcpy(&v, c + 4 * b, sizeof v);
            even[b] += v * value;
        }
        c += 4 * P;
        ++offsets;
    }
}

// The whole chunk: every sample, the map by passes of P blocks kept in registers (inputs first, then
// states, each column's coefficients times its value added to every block), the outputs, and the
// transducers. The same source is compiled twice (portable, AVX2), so both kernels do the same IEEE
// operations in the same order.
template <int K, int P>
__attribute__((always_inline)) inline void advance(Step& st) {
    const Eigen::Index p = st.forces, r = st.outputs, ni = st.forces + st.probes;
    double* w = st.w;
    double* next = st.next;
    const Quad zero = {0.0, 0.0, 0.0, 0.0};
    for (Eigen::Index k = 0; k < st.m; ++k) {
        const double* in = st.in + k * ni * K;
        const double* c = st.coefficients;
        const int* offsets = st.offsets;
        for (Eigen::Index pass = 0; pass < st.passes; ++pass) {
            Quad even[P], odd[P];
            for (int b = 0; b < P; ++b) even[b] = odd[b] = zero;
            accumulate<K, P>(in, st.pass_inputs[pass], offsets, c, even, odd);
            accumulate<K, P>(w, st.pass_states[pass], offsets, c, even, odd);
            // Stored in 16-byte halves, as the next sample loads them (a load from part of a wider
            // store is not forwarded from it on every processor).
            for (int b = 0; b < P; ++b) {
                const Quad sum = even[b] + odd[b];
                double* to = next + (pass * P + b) * 4;
                *reinterpret_cast<PairU*>(to) = __builtin_shufflevector(sum, sum, 0, 1);
                *reinterpret_cast<PairU*>(to + 2) = __builtin_shufflevector(sum, sum, 2, 3);
            }
        }
        std::swap(w, next);
        const Eigen::Index sample = st.start + k;
        for (int l = 0; l < K; ++l) {
            double* o = st.out[l] + sample * r;
            for (Eigen::Index i = 0; i < r; ++i) o[i] = w[st.output_position[i] * K + l];
            const double* f = st.force[l] + sample * p;
            double* rec = st.recorded[l] + sample * p;
            double* qs = st.transducer + 8 * l;
            for (Eigen::Index j = 0; j < p; ++j) {
                const double a = st.pole[j];
                double value = f[j];
                if (a > 0.0) {
                    value -= qs[j];
                    qs[j] = a * qs[j] + (1.0 - a) * f[j];
                }
                rec[j] = value + st.force_noise[l][k + j * st.noise_stride];
            }
        }
    }
    st.w = w;
    st.next = next;
}

template <int K, int P>
void advance_portable(Step& st) {
    advance<K, P>(st);
}

#if AMB_FAST_WIDE_LANES
template <int K, int P>
__attribute__((target("avx2"))) void advance_avx2(Step& st) {
    advance<K, P>(st);
}
#endif

template <int K, int P>
void advance_any(Step& st) {
#if AMB_FAST_WIDE_LANES
    if (simd_avx2()) return advance_avx2<K, P>(st);
#endif
    advance_portable<K, P>(st);
}

template <int K>
void advance_lanes(Step& st, int pass) {
    switch (pass) {
        case 1: return advance_any<K, 1>(st);
        case 2: return advance_any<K, 2>(st);
        default: return advance_any<K, 4>(st);
    }
}
}  // namespace

template <int K>
void MimoLoop::run_block(const double* const* force, Eigen::Index start, Eigen::Index m, double* const* recorded,
                         double* const* out) {
    const Eigen::Index p = model_.forces();
    require(p <= 8, "force channels", p, "at most 8");
    double transducer[2 * 8] = {};
    const double* noise[2];
    for (int l = 0; l < K; ++l) {
        noise[l] = force_draws_[l].data();
        for (Eigen::Index j = 0; j < p; ++j) transducer[8 * l + j] = q_(j, l);
    }
    Step st{model_.states(), p, model_.probes(), model_.outputs(), passes_, m, start, pass_inputs_.data(),
            pass_states_.data(), offsets_.data(), position_.data() + model_.states(), coefficients_.data(),
            inputs_.data(), w_.data(), next_.data(), force, recorded, out, model_.transducer_pole.data(), transducer,
            noise, chunk};
    advance_lanes<K>(st, pass_);
    if (st.w != w_.data()) w_.swap(next_);  // an odd number of samples: the state is in the other buffer
    for (int l = 0; l < K; ++l)
        for (Eigen::Index j = 0; j < p; ++j) q_(j, l) = transducer[8 * l + j];
}

void MimoLoop::start_periodic(const double* const* period_force, Eigen::Index L) {
    const Eigen::Index ns = model_.states(), p = model_.forces(), r = model_.outputs();
    MimoModel quiet = model_;
    quiet.sensor_noise.setZero();
    quiet.force_noise.setZero();
    MimoLoop probe(quiet, std::vector<std::uint64_t>(static_cast<std::size_t>(lanes_), 0));
    std::vector<Eigen::MatrixXd> recorded(static_cast<std::size_t>(lanes_), Eigen::MatrixXd(p, L)),
        out(static_cast<std::size_t>(lanes_), Eigen::MatrixXd(r, L));  // column k = sample k: sample-major
    std::vector<double*> rec_ptr, out_ptr;
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        rec_ptr.push_back(recorded[l].data());
        out_ptr.push_back(out[l].data());
    }
    probe.run(period_force, L, rec_ptr.data(), out_ptr.data());
    // M^L once for every lane (the solve is cheap beside it).
    const auto lu = (Eigen::MatrixXd::Identity(ns, ns) - matrix_power(model_.M, L)).partialPivLu();
    const Eigen::MatrixXd root = covariance_root(stationary_noise_covariance(model_));
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        Eigen::VectorXd z = lu.solve(probe.state(l));
        add_stationary_noise(root, seeds_[l], z);
        for (Eigen::Index i = 0; i < ns; ++i) set_state(i, l, z[i]);
        for (Eigen::Index j = 0; j < p; ++j) {
            const double a = model_.transducer_pole[j];
            q_(j, l) = a > 0.0 ? periodic_transducer_start(a, L, probe.q_(j, l)) : 0.0;
        }
    }
}

Eigen::MatrixXd stationary_noise_covariance(const MimoModel& model) {
    return stationary_covariance(model.M, model.Bn, model.sensor_noise);
}

void add_stationary_noise(const Eigen::MatrixXd& root, std::uint64_t seed, Eigen::VectorXd& z) {
    NormalStream draws(start_noise_seed(seed));
    Eigen::VectorXd v(z.size());
    draws.fill(v.data(), z.size(), 1.0);
    z += root * v;
}

void mimo_simulate(const MimoModel& model, const double* force, Eigen::Index n, std::uint64_t seed, double* recorded,
                   double* out) {
    require_finite_samples("force", force, n * model.forces());
    MimoLoop loop(model, {seed});
    loop.run(&force, n, &recorded, &out);
}

void mimo_experiments(const MimoModel& model, const double* const* period_force, Eigen::Index L,
                      Eigen::Index settle_periods, Eigen::Index periods, const std::vector<std::uint64_t>& seeds,
                      bool steady_start, double* const* recorded, double* const* measured, bool all_forces) {
    require(L > 0, "period", L, "> 0 samples");
    require(settle_periods >= 0, "settle_periods", settle_periods, ">= 0");
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    const auto K = static_cast<Eigen::Index>(seeds.size());
    for (Eigen::Index l = 0; l < K; ++l) require_finite_samples("excitation", period_force[l], L * model.forces());
    MimoLoop loop(model, seeds);
    if (steady_start) loop.start_periodic(period_force, L);
    const Eigen::Index p = model.forces(), q = model.probes(), r = model.outputs();
    std::vector<Eigen::MatrixXd> rec(static_cast<std::size_t>(K), Eigen::MatrixXd(p, L)),
        out(static_cast<std::size_t>(K), Eigen::MatrixXd(r, L));
    std::vector<double*> rec_ptr, out_ptr;
    for (Eigen::Index l = 0; l < K; ++l) {
        rec_ptr.push_back(rec[l].data());
        out_ptr.push_back(out[l].data());
    }
    for (Eigen::Index k = 0; k < settle_periods + periods; ++k) {
        loop.run(period_force, L, rec_ptr.data(), out_ptr.data());
        if (k < settle_periods) continue;
        const Eigen::Index first = (k - settle_periods) * L;
        const Eigen::Index length = periods * L;
        for (Eigen::Index l = 0; l < K; ++l) {
            if (all_forces || first == 0)
                for (Eigen::Index j = 0; j < p; ++j)
                    Eigen::Map<Eigen::RowVectorXd>(recorded[l] + j * (all_forces ? length : L) + first, L) = rec[l].row(j);
            for (Eigen::Index j = 0; j < q; ++j)
                Eigen::Map<Eigen::RowVectorXd>(measured[l] + j * length + first, L) = out[l].row(j);
        }
    }
}

}  // namespace amb_fast
