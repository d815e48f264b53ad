// Whole MIMO runs: one from rest (mimo_simulate), and experiments in lock step that settle, then record
// periods (mimo_experiments).
#include "amb_fast/mimo.hpp"

#include <vector>

#include "amb_fast/errors.hpp"

namespace amb_fast {

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
                    Eigen::Map<Eigen::RowVectorXd>(recorded[l] + j * (all_forces ? length : L) + first, L) =
                        rec[l].row(j);
            for (Eigen::Index j = 0; j < q; ++j)
                Eigen::Map<Eigen::RowVectorXd>(measured[l] + j * length + first, L) = out[l].row(j);
        }
    }
}

}  // namespace amb_fast
