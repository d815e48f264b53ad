#include "amb_fast/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "amb_fast/errors.hpp"
#include "amb_fast/mimo_lines.hpp"

namespace amb_fast {

bool draws_spectra(const Rig& rig, bool steady_start) {
    return steady_start && rig.force_law == ForceLaw::linear && std::isinf(rig.touchdown_at()) &&
           std::isinf(rig.command_limit());
}

namespace {
LineEstimate drawn_experiment(const Rig& rig, const Controller& controller, const double* period_force,
                              Eigen::Index settle_periods, Eigen::Index periods, const LinePlan& plan,
                              std::uint64_t seed, int median_window) {
    PeriodEstimator estimator(plan);
    SteadyLines draw(Loop(rig, controller, seed).linear_model(), plan.period, estimator.bins());
    draw.start(period_force, seed, settle_periods + periods);
    std::vector<std::complex<double>> force(estimator.bins().size()), displacement(force.size());
    for (Eigen::Index p = 0; p < settle_periods + periods; ++p) {
        draw.next(force.data(), displacement.data());
        if (p >= settle_periods) estimator.add_period_lines(force.data(), displacement.data());
    }
    return estimator.estimate(rig.mass, controller.fs, median_window);
}
}  // namespace

LineEstimate run_experiment(const Rig& rig, const Controller& controller,
                            const Eigen::Ref<const Eigen::VectorXd>& period_force, Eigen::Index settle_periods,
                            Eigen::Index periods, LinePlan plan, std::uint64_t seed, int median_window,
                            bool steady_start) {
    const Eigen::Index L = plan.period;
    require(period_force.size() == L, "excitation length", period_force.size(), "one period of plan.period samples");
    require_finite_samples("excitation", period_force.data(), L);
    require(settle_periods >= 0, "settle_periods", settle_periods, ">= 0");
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    plan.periods_per_block = periods_per_block(periods);
    if (draws_spectra(rig, steady_start))
        return drawn_experiment(rig, controller, period_force.data(), settle_periods, periods, plan, seed,
                                median_window);
    Loop loop(rig, controller, seed);
    if (steady_start) loop.start_periodic(period_force.data(), L);
    PeriodEstimator estimator(plan);
    Eigen::VectorXd force(L), displacement(L), current(L);
    Eigen::Index saturated_before_recording = 0;
    for (Eigen::Index p = 0; p < settle_periods + periods; ++p) {
        if (p == settle_periods) saturated_before_recording = loop.saturated_samples();
        loop.run(period_force.data(), L, {force.data(), displacement.data(), current.data()});
        if (p >= settle_periods) estimator.add_period(force.data(), displacement.data(), p * L);
    }
    LineEstimate estimate = estimator.estimate(rig.mass, controller.fs, median_window);
    estimate.saturated_samples = loop.saturated_samples() - saturated_before_recording;
    return estimate;
}

LineEstimate identify(const double* force, const double* displacement, Eigen::Index n, Eigen::Index settle_periods,
                      LinePlan plan, double mass, double fs, int median_window) {
    const Eigen::Index L = plan.period;
    require(L > 0 && n % L == 0, "recording length", n, "a whole number of periods");
    require(settle_periods >= 0, "settle_periods", settle_periods, ">= 0");
    const Eigen::Index periods = n / L - settle_periods;
    require(periods >= 2, "periods after settling", periods, ">= 2 (standard errors need at least two)");
    require_positive("mass", mass, "kg");
    require_positive("fs", fs, "Hz");
    plan.periods_per_block = periods_per_block(periods);
    PeriodEstimator estimator(plan);
    try {
        const Eigen::Index start = settle_periods * L;
        estimator.add_periods(force + start, displacement + start, periods, start);
        return estimator.estimate(mass, fs, median_window);
    } catch (const NonFiniteSamples& bad) {  // name the exact sample
        require_finite_samples("force", force + bad.first, bad.count, bad.first);
        require_finite_samples("displacement", displacement + bad.first, bad.count, bad.first);
        throw;
    }
}

}  // namespace amb_fast
