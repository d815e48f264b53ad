#include "amb_fast/mimo.hpp"

#include <algorithm>
#include <utility>
#include <cstdlib>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

namespace {
// Independent stream seeds for source j of a kind (splitmix64 of the run's seed, the kind and j).
std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t kind, Eigen::Index j) {
    std::uint64_t x = seed + 0x9e3779b97f4a7c15ULL * (2 * static_cast<std::uint64_t>(j) + kind + 1);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

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
    // One map from [z; f; n] to [z'; o], stored by columns: the update is a sum of contiguous columns.
    Mt_ = Eigen::MatrixXd::Zero(n + r, n + p + q);
    Mt_.topLeftCorner(n, n) = model_.M;
    Mt_.block(0, n, n, p) = model_.Bf;
    Mt_.block(0, n + p, n, q) = model_.Bn;
    Mt_.bottomLeftCorner(r, n) = model_.C;
    Mt_.block(n, n + p, r, q) = model_.Dn;
    // The non-zero entries only (the lags' cascades and uncoupled blocks leave many zeros), rows in
    // groups of four padded to the longest of them (ELLPACK): four independent sums per group, so the
    // step is not bound by the latency of one long chain of additions. Rows longest first.
    std::vector<Eigen::Index> order(static_cast<std::size_t>(Mt_.rows()));
    for (Eigen::Index i = 0; i < Mt_.rows(); ++i) order[static_cast<std::size_t>(i)] = i;
    const Eigen::MatrixXd pattern = (Mt_.array() != 0.0).cast<double>().matrix();
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return pattern.row(a).sum() > pattern.row(b).sum(); });
    for (std::size_t g = 0; g < order.size(); g += group) {
        std::vector<std::vector<std::pair<int, double>>> rows(group);
        std::size_t longest = 0;
        for (std::size_t r = 0; r < group; ++r) {
            const Eigen::Index i = g + r < order.size() ? order[g + r] : -1;
            group_rows_.push_back(i);
            if (i < 0) continue;
            for (Eigen::Index j = 0; j < Mt_.cols(); ++j)
                if (Mt_(i, j) != 0.0) rows[r].emplace_back(static_cast<int>(j), Mt_(i, j));
            longest = std::max(longest, rows[r].size());
        }
        group_length_.push_back(static_cast<Eigen::Index>(longest));
        for (std::size_t e = 0; e < longest; ++e)
            for (std::size_t r = 0; r < group; ++r) {
                const bool real = e < rows[r].size();
                entry_col_.push_back(real ? rows[r][e].first : 0);
                entry_value_.push_back(real ? rows[r][e].second : 0.0);
            }
    }
    w_.assign(static_cast<std::size_t>((n + p + q) * lanes_), 0.0);
    next_.assign(static_cast<std::size_t>((n + r) * lanes_), 0.0);
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
    for (Eigen::Index i = 0; i < z.size(); ++i) z[i] = w_[static_cast<std::size_t>(i * lanes_ + lane)];
    return z;
}

void MimoLoop::run(const double* const* force, Eigen::Index n, double* const* recorded, double* const* out) {
    const Eigen::Index ns = model_.states(), p = model_.forces(), q = model_.probes();
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
        if (lanes_ == 2)
            run_block<2>(force, start, m, recorded, out);
        else
            run_block<1>(force, start, m, recorded, out);
        // Inf and NaN never turn finite again in a linear recursion: one check per chunk.
        for (Eigen::Index i = 0; i < ns * lanes_; ++i) {
            if (std::isfinite(w_[static_cast<std::size_t>(i)])) continue;
            std::ostringstream msg;
            msg << "the state became non-finite by sample " << k_ + start + m << ": the loop is unstable";
            throw std::overflow_error(msg.str());
        }
    }
    k_ += n;
}

namespace {
// The lanes of one state entry: a pair of doubles in one SIMD register (GCC/Clang vector extension), or one.
typedef double Pair __attribute__((vector_size(16), may_alias));
template <int K>
struct LaneType {
    using type = double;
};
template <>
struct LaneType<2> {
    using type = Pair;
};
}  // namespace

template <int K>
void MimoLoop::run_block(const double* const* force, Eigen::Index start, Eigen::Index m, double* const* recorded,
                         double* const* out) {
    using V = typename LaneType<K>::type;
    const Eigen::Index ns = model_.states(), p = model_.forces(), q = model_.probes(), r = model_.outputs();
    V* __restrict w = reinterpret_cast<V*>(w_.data());
    V* __restrict next = reinterpret_cast<V*>(next_.data());
    const Eigen::Index groups = static_cast<Eigen::Index>(group_length_.size());
    const Eigen::Index* lengths = group_length_.data();
    const Eigen::Index* targets = group_rows_.data();
    // Everything the step touches besides the map, as local pointers and copies (the outputs may alias
    // any double, so members would be reloaded after every store).
    const double* sensor[K];
    const double* force_noise[K];
    double pole[8], qs[K][8];
    require(p <= 8, "force channels", p, "at most 8");
    for (Eigen::Index j = 0; j < p; ++j) pole[j] = model_.transducer_pole[j];
    for (int l = 0; l < K; ++l) {
        sensor[l] = sensor_draws_[l].data();
        force_noise[l] = force_draws_[l].data();
        for (Eigen::Index j = 0; j < p; ++j) qs[l][j] = q_(j, l);
    }
    for (Eigen::Index k = 0; k < m; ++k) {
        for (int l = 0; l < K; ++l) {
            double* lane = reinterpret_cast<double*>(w) + l;
            const double* f = force[l] + (start + k) * p;
            for (Eigen::Index j = 0; j < p; ++j) lane[(ns + j) * K] = f[j];
            for (Eigen::Index j = 0; j < q; ++j) lane[(ns + p + j) * K] = sensor[l][k + j * chunk];
        }
        const int* cols = entry_col_.data();
        const double* values = entry_value_.data();
        for (Eigen::Index g = 0; g < groups; ++g) {
            V a0 = w[0] * 0.0, a1 = a0, a2 = a0, a3 = a0;
            for (Eigen::Index e = 0; e < lengths[g]; ++e, cols += group, values += group) {
                a0 += values[0] * w[cols[0]];
                a1 += values[1] * w[cols[1]];
                a2 += values[2] * w[cols[2]];
                a3 += values[3] * w[cols[3]];
            }
            const Eigen::Index* t = targets + g * group;
            next[t[0]] = a0;
            if (t[1] >= 0) next[t[1]] = a1;
            if (t[2] >= 0) next[t[2]] = a2;
            if (t[3] >= 0) next[t[3]] = a3;
        }
        for (Eigen::Index i = 0; i < ns; ++i) w[i] = next[i];
        for (int l = 0; l < K; ++l) {
            const double* lane = reinterpret_cast<const double*>(next) + l;
            double* o = out[l] + (start + k) * r;
            for (Eigen::Index i = 0; i < r; ++i) o[i] = lane[(ns + i) * K];
            const double* f = force[l] + (start + k) * p;
            double* rec = recorded[l] + (start + k) * p;
            for (Eigen::Index j = 0; j < p; ++j) {
                const double a = pole[j];
                double value = f[j];
                if (a > 0.0) {
                    value -= qs[l][j];
                    qs[l][j] = a * qs[l][j] + (1.0 - a) * f[j];
                }
                rec[j] = value + force_noise[l][k + j * chunk];
            }
        }
    }
    for (int l = 0; l < K; ++l)
        for (Eigen::Index j = 0; j < p; ++j) q_(j, l) = qs[l][j];
}

void MimoLoop::start_periodic(const double* const* period_force, Eigen::Index L) {
    const Eigen::Index ns = model_.states(), p = model_.forces(), q = model_.probes(), r = model_.outputs();
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
    // M^L once for every lane (periodic_start squares it; the solve is cheap beside it).
    Eigen::MatrixXd power = Eigen::MatrixXd::Identity(ns, ns), square = model_.M;
    for (Eigen::Index k = L; k > 0; k >>= 1) {
        if (k & 1) power = power * square;
        square = square * square;
    }
    const auto lu = (Eigen::MatrixXd::Identity(ns, ns) - power).partialPivLu();
    std::vector<Eigen::MatrixXd> roots;
    for (Eigen::Index j = 0; j < q; ++j)
        if (model_.sensor_noise[j] > 0.0)
            roots.push_back(stationary_noise_root(model_.M, model_.Bn.col(j), model_.sensor_noise[j]));
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        Eigen::VectorXd z = lu.solve(probe.state(l));
        NormalStream draws(start_noise_seed(seeds_[l]));
        Eigen::VectorXd v(ns);
        for (const auto& root : roots) {
            draws.fill(v.data(), ns, 1.0);
            z += root * v;
        }
        for (Eigen::Index i = 0; i < ns; ++i) w_[static_cast<std::size_t>(i * lanes_ + l)] = z[i];
        for (Eigen::Index j = 0; j < p; ++j) {
            const double a = model_.transducer_pole[j];
            q_(j, l) = a > 0.0 ? periodic_transducer_start(a, L, probe.q_(j, l)) : 0.0;
        }
    }
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
