// Two-axis sweeps: each point's experiments and 2x2 estimate on the thread that claims it.
#include "amb_fast/mimo_sweep.hpp"

#include <algorithm>

#include "amb_fast/blocks.hpp"
#include "amb_fast/estimate2x2.hpp"
#include "amb_fast/mimo_lines.hpp"

namespace amb_fast {

void mimo_line_sweep(const std::vector<MimoModel>& models, const double* const* period_force, Eigen::Index L,
                     const std::vector<Eigen::Index>& settle_periods, Eigen::Index periods,
                     const std::vector<std::array<std::uint64_t, 2>>& seeds, bool steady_start,
                     const std::vector<Eigen::Index>& bins, int workers, const MimoSweepOutput& out) {
    const auto count = static_cast<Eigen::Index>(models.size());
    const auto B = static_cast<Eigen::Index>(bins.size());
    in_blocks(count, 1, workers, [&] {
        // This worker's per-period line spectra (periods, lines, 2 channels, 2 experiments), reused.
        return [&, force = std::vector<std::complex<double>>(static_cast<std::size_t>(periods * B * 4)),
                displacement = std::vector<std::complex<double>>(static_cast<std::size_t>(periods * B * 4))](
                   Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index i = begin; i < end; ++i) {
                const auto k = static_cast<std::size_t>(i);
                const std::vector<std::uint64_t> pair{seeds[k][0], seeds[k][1]};
                mimo_line_experiments(models[k], period_force, L, settle_periods[k], periods, pair, steady_start, bins,
                                      force.data(), displacement.data());
                const Estimate2x2 e = estimate_2x2(force.data(), displacement.data(), periods, B);
                const Eigen::Index at = i * B * 4;
                std::copy(e.H.begin(), e.H.end(), out.H + at);
                std::copy(e.receptance.begin(), e.receptance.end(), out.receptance + at);
                std::copy(e.var_re.begin(), e.var_re.end(), out.var_re + at);
                std::copy(e.var_im.begin(), e.var_im.end(), out.var_im + at);
            }
        };
    });
}

}  // namespace amb_fast
