// The MIMO model's validation, the noise streams' seeds, and MimoLoop's construction: the map laid out
// in passes of SIMD row blocks, and the state's place in it.
#include "amb_fast/mimo.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "amb_fast/errors.hpp"

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
    for (Eigen::Index j = 0; j < q; ++j)
        require(sensor_noise[j] >= 0.0, "sensor_noise", sensor_noise[j], ">= 0 (m rms)");
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
                used = used ||
                       (order[static_cast<std::size_t>(at)] >= 0 && nonzero(order[static_cast<std::size_t>(at)], j));
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

}  // namespace amb_fast
