#include "amb_fast/experiment.hpp"

#include <algorithm>

#include "amb_fast/errors.hpp"

namespace amb_fast {

LineEstimate run_experiment(const Rig& rig, const Controller& controller, const Eigen::Ref<const Eigen::VectorXd>& period_force,
                            Eigen::Index settle_periods, Eigen::Index periods, LinePlan plan, std::uint64_t seed,
                            int median_window, bool steady_start) {
    const Eigen::Index L = plan.period;
    require(period_force.size() == L, "excitation length", period_force.size(), "one period of plan.period samples");
    require_finite_samples("excitation", period_force.data(), L);
    require(settle_periods >= 0, "settle_periods", settle_periods, ">= 0");
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    plan.periods_per_block = periods_per_block(periods);
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
