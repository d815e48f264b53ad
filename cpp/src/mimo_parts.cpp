#include <numeric>

#include "amb_fast/mimo.hpp"

namespace amb_fast {

namespace {
// Union-find over the model's nodes: states, then force channels, then probes.
struct Links {
    std::vector<Eigen::Index> parent;
    explicit Links(Eigen::Index nodes) : parent(static_cast<std::size_t>(nodes)) {
        std::iota(parent.begin(), parent.end(), Eigen::Index{0});
    }
    Eigen::Index root(Eigen::Index a) {
        while (parent[static_cast<std::size_t>(a)] != a)
            a = parent[static_cast<std::size_t>(a)] =
                parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(a)])];
        return a;
    }
    void link(Eigen::Index a, Eigen::Index b) { parent[static_cast<std::size_t>(root(a))] = root(b); }
};
}  // namespace

std::vector<MimoPart> independent_parts(const MimoModel& model) {
    const Eigen::Index n = model.states(), p = model.forces(), q = model.probes();
    Links links(n + p + q);
    const auto force = [&](Eigen::Index c) { return n + c; };
    const auto probe = [&](Eigen::Index j) { return n + p + j; };
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index k = 0; k < n; ++k)
            if (model.M(i, k) != 0.0) links.link(i, k);
        for (Eigen::Index c = 0; c < p; ++c)
            if (model.Bf(i, c) != 0.0) links.link(i, force(c));
        for (Eigen::Index j = 0; j < q; ++j)
            if (model.Bn(i, j) != 0.0 || model.C(j, i) != 0.0) links.link(i, probe(j));
    }
    for (Eigen::Index j = 0; j < q; ++j)
        for (Eigen::Index k = 0; k < q; ++k)
            if (model.Dn(j, k) != 0.0) links.link(probe(j), probe(k));
    std::vector<MimoPart> parts;
    std::vector<Eigen::Index> roots;  // parts[t] holds the nodes of root roots[t]
    const auto part_of = [&](Eigen::Index node) -> MimoPart& {
        const Eigen::Index r = links.root(node);
        for (std::size_t t = 0; t < roots.size(); ++t)
            if (roots[t] == r) return parts[t];
        roots.push_back(r);
        return parts.emplace_back();
    };
    for (Eigen::Index i = 0; i < n; ++i) part_of(i).states.push_back(i);
    for (Eigen::Index c = 0; c < p; ++c) part_of(force(c)).forces.push_back(c);
    for (Eigen::Index j = 0; j < q; ++j) part_of(probe(j)).probes.push_back(j);
    return parts;
}

MimoModel MimoPart::model(const MimoModel& whole) const {
    const auto pick = [](const Eigen::MatrixXd& X, const std::vector<Eigen::Index>& rows,
                         const std::vector<Eigen::Index>& cols) {
        Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
        for (std::size_t r = 0; r < rows.size(); ++r)
            for (std::size_t c = 0; c < cols.size(); ++c)
                out(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = X(rows[r], cols[c]);
        return out;
    };
    const auto entries = [](const Eigen::VectorXd& x, const std::vector<Eigen::Index>& at) {
        Eigen::VectorXd out(static_cast<Eigen::Index>(at.size()));
        for (std::size_t k = 0; k < at.size(); ++k) out[static_cast<Eigen::Index>(k)] = x[at[k]];
        return out;
    };
    MimoModel part;
    part.M = pick(whole.M, states, states);
    part.Bf = pick(whole.Bf, states, forces);
    part.Bn = pick(whole.Bn, states, probes);
    part.C = pick(whole.C, probes, states);
    part.Dn = pick(whole.Dn, probes, probes);
    part.transducer_pole = entries(whole.transducer_pole, forces);
    part.sensor_noise = entries(whole.sensor_noise, probes);
    part.force_noise = entries(whole.force_noise, forces);
    return part;
}

}  // namespace amb_fast
