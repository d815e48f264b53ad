#include "amb_fast/batch.hpp"

#include <algorithm>
#include <exception>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

#include "amb_fast/errors.hpp"

namespace amb_fast {

namespace {

constexpr Eigen::Index lanes_per_group = 32;  // gain sets advanced together; their state stays in L1

void store(SweepEstimates& out, Eigen::Index row, const LineEstimate& e) {
    if (e.saturated_samples > 0) {  // flagged, and not passed off as a clean estimate
        out.status[row] = static_cast<int>(PointStatus::saturated);
        return;
    }
    out.H.row(row) = e.H.transpose();
    out.force.row(row) = e.force.transpose();
    out.displacement.row(row) = e.displacement.transpose();
    out.k.row(row) = e.k.transpose();
    out.c.row(row) = e.c.transpose();
    out.k_std.row(row) = e.k_std.transpose();
    out.c_std.row(row) = e.c_std.transpose();
    out.k_smooth.row(row) = e.k_smooth.transpose();
    out.c_smooth.row(row) = e.c_smooth.transpose();
    out.unexcited_force.row(row) = e.unexcited_force.transpose();
    out.unexcited_displacement.row(row) = e.unexcited_displacement.transpose();
    out.status[row] = static_cast<int>(PointStatus::ok);
}

Pid with_gains(const Pid& base, const GainPoint& g) {
    Pid pid = base;
    pid.kp = g.kp;
    pid.ki = g.ki;
    pid.kd = g.kd;
    return pid;
}

// Pointers to one sample's slice of the lane arrays.
struct LaneState {
    double* out_y;
    const double* noise;
    double* held;  // this sample's slot of the delay line
    double *y, *v, *i, *f, *s, *integral, *derivative, *e_prev;
    const double *kp, *ki_T, *kd_gain;
    double *saturated, *peak;  // clipped samples; largest |y| so far
};

// One sample for every lane: what Loop::run_linear does for one loop, branch-free so it vectorises.
template <int sensed, bool delayed, bool checked>
void step_lanes(const LaneState& st, Eigen::Index lanes, const CascadeMap& map, double a, double limit, double force) {
    double* __restrict out_y = st.out_y;
    const double* __restrict noise = st.noise;
    double* __restrict held = st.held;
    double* __restrict y = st.y;
    double* __restrict v = st.v;
    double* __restrict i = st.i;
    double* __restrict f = st.f;
    double* __restrict s = st.s;
    double* __restrict I = st.integral;
    double* __restrict D = st.derivative;
    double* __restrict E = st.e_prev;
    double* __restrict saturated = st.saturated;
    double* __restrict peak = st.peak;
    for (Eigen::Index g = 0; g < lanes; ++g) {
        const double e = (sensed == state::ys ? s[g] : y[g]) + noise[g];
        double u = PidLaw::apply(st.kp[g], st.ki_T[g], st.kd_gain[g], a, e, I[g], D[g], E[g]);
        if constexpr (delayed) {  // u[k - d] out, u[k] in
            const double older = held[g];
            held[g] = u;
            u = older;
        }
        if constexpr (checked) {  // the amplifier's limit, as in Loop::run_linear
            const double wanted = u;
            u = std::clamp(wanted, -limit, limit);
            saturated[g] += u != wanted;
        }
        out_y[g] = e;
        map.advance(y[g], v[g], i[g], f[g], s[g], force, u);
        if constexpr (checked) peak[g] = std::max(peak[g], std::abs(y[g]));
    }
}

// A group of linear points in lock step. Per sample, the inner loop over lanes does for each lane
// what Loop::run_linear does for one (same PidLaw, same CascadeMap), so the numbers are identical.
template <int sensed>
void run_linear_group(const Rig& rig, const Pid& base, const Eigen::VectorXd& period_force, const GainPoint* points,
                      Eigen::Index lanes, Eigen::Index periods, const LinePlan& plan, int median_window,
                      SweepEstimates& out, Eigen::Index first_row) {
    const Eigen::Index L = period_force.size();
    const CascadeMap map(propagator(rig, base.period()));
    const Eigen::Index d = base.delay;
    const double a = PidLaw(base).a;
    std::vector<PeriodEstimator> estimators;
    std::vector<std::mt19937_64> sensor_rng, force_rng;
    std::vector<std::normal_distribution<double>> sensor_normal(lanes), force_normal(lanes);
    // Lane state and gains, structure of arrays, so the lane loop vectorises.
    const auto size = static_cast<std::size_t>(lanes);
    std::vector<double> kp(size), ki_T(size), kd_gain(size);
    std::vector<double> xy(size), xv(size), xi(size), xf(size), xs(size), integral(size), derivative(size), e_prev(size);
    std::vector<double> saturated(size), saturated_before(size), peak(size);
    const double limit = rig.command_limit(), touchdown = rig.touchdown_at();
    const bool checked = std::isfinite(limit) || std::isfinite(touchdown);
    std::vector<double> line(static_cast<std::size_t>(std::max<Eigen::Index>(d, 1)) * size);
    std::vector<double> displacement(static_cast<std::size_t>(L) * size), noise(displacement.size(), 0.0);
    Eigen::VectorXd lane_y(L), lane_f(L), recorded(L);
    ForceTransducer transducer(rig, base.period());  // sees the same force in every lane
    Eigen::Index last = 0;
    estimators.reserve(size);
    for (Eigen::Index g = 0; g < lanes; ++g) {
        const PidLaw law(with_gains(base, points[g]));
        kp[g] = law.kp, ki_T[g] = law.ki_T, kd_gain[g] = law.kd_gain;
        estimators.emplace_back(plan);
        sensor_rng.emplace_back(points[g].seed);
        force_rng.emplace_back(points[g].seed ^ 0x9e3779b97f4a7c15ULL);
        last = std::max(last, points[g].settle_periods + periods);
    }
    std::vector<bool> touched(size, false);
    std::size_t head = 0;

    for (Eigen::Index p = 0; p < last; ++p) {
        if (rig.sensor_noise > 0.0)
            for (Eigen::Index g = 0; g < lanes; ++g)
                for (Eigen::Index j = 0; j < L; ++j)
                    noise[static_cast<std::size_t>(j * lanes + g)] = rig.sensor_noise * sensor_normal[g](sensor_rng[g]);
        for (Eigen::Index j = 0; j < L; ++j) {
            const double f = period_force[j];
            LaneState lanes_now{&displacement[static_cast<std::size_t>(j * lanes)], &noise[static_cast<std::size_t>(j * lanes)],
                                &line[head * size], xy.data(), xv.data(), xi.data(), xf.data(), xs.data(),
                                integral.data(), derivative.data(), e_prev.data(), kp.data(), ki_T.data(),
                                kd_gain.data(), saturated.data(), peak.data()};
            // A limit or a clearance to watch is compiled in only when there is one.
            if (checked)
                d > 0 ? step_lanes<sensed, true, true>(lanes_now, lanes, map, a, limit, f)
                      : step_lanes<sensed, false, true>(lanes_now, lanes, map, a, limit, f);
            else
                d > 0 ? step_lanes<sensed, true, false>(lanes_now, lanes, map, a, limit, f)
                      : step_lanes<sensed, false, false>(lanes_now, lanes, map, a, limit, f);
            if (d > 0 && ++head == static_cast<std::size_t>(d)) head = 0;
        }
        transducer.record(period_force.data(), L, recorded.data());
        for (Eigen::Index g = 0; g < lanes; ++g) {
            if (p == points[g].settle_periods) saturated_before[g] = saturated[g];
            // A single run stops at touchdown; the lane runs on, but records no more.
            if (peak[g] >= touchdown) touched[g] = true;
            const bool recording =
                !touched[g] && p >= points[g].settle_periods && p < points[g].settle_periods + periods;
            lane_f = recorded;
            if (rig.force_noise > 0.0)  // drawn whether recorded or not, as a single run draws it
                for (Eigen::Index j = 0; j < L; ++j) lane_f[j] += rig.force_noise * force_normal[g](force_rng[g]);
            if (!recording) continue;
            for (Eigen::Index j = 0; j < L; ++j) lane_y[j] = displacement[static_cast<std::size_t>(j * lanes + g)];
            if (recording) estimators[g].add_period(lane_f.data(), lane_y.data(), p * L);
        }
    }
    for (Eigen::Index g = 0; g < lanes; ++g) {
        if (touched[g]) {
            out.status[first_row + g] = static_cast<int>(PointStatus::touchdown);
            continue;
        }
        if (!std::isfinite(xy[g] + xv[g] + xi[g] + xf[g] + xs[g]))
            throw std::overflow_error("a point of the sweep diverged although its linearised loop is stable");
        LineEstimate e = estimators[g].estimate(rig.mass, base.fs, median_window);
        e.saturated_samples = static_cast<Eigen::Index>(saturated[g] - saturated_before[g]);
        store(out, first_row + g, e);
    }
}

void run_points(const Rig& rig, const Pid& base, const Eigen::VectorXd& period_force, const GainPoint* points,
                Eigen::Index count, Eigen::Index periods, const LinePlan& plan, int median_window, SweepEstimates& out,
                Eigen::Index first_row) {
    if (rig.force_law == ForceLaw::nonlinear) {
        for (Eigen::Index g = 0; g < count; ++g) {
            try {
                store(out, first_row + g,
                      run_experiment(rig, with_gains(base, points[g]), period_force, points[g].settle_periods, periods,
                                     plan, points[g].seed, median_window));
            } catch (const Touchdown&) {
                out.status[first_row + g] = static_cast<int>(PointStatus::touchdown);
            }
        }
        return;
    }
    for (Eigen::Index start = 0; start < count; start += lanes_per_group) {
        const Eigen::Index lanes = std::min(lanes_per_group, count - start);
        if (rig.sensor_bandwidth)
            run_linear_group<state::ys>(rig, base, period_force, points + start, lanes, periods, plan, median_window,
                                        out, first_row + start);
        else
            run_linear_group<state::y>(rig, base, period_force, points + start, lanes, periods, plan, median_window,
                                       out, first_row + start);
    }
}

}  // namespace

SweepEstimates run_sweep(const Rig& rig, const Pid& base, const Eigen::Ref<const Eigen::VectorXd>& period_force,
                         const std::vector<GainPoint>& points, Eigen::Index periods, LinePlan plan, int median_window,
                         int workers) {
    rig.validate();
    base.validate();
    const Eigen::Index L = plan.period;
    require(period_force.size() == L, "excitation length", period_force.size(), "one period of plan.period samples");
    require_finite_samples("excitation", period_force.data(), L);
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    for (const GainPoint& g : points) {
        with_gains(base, g).validate();
        require(g.settle_periods >= 0, "settle_periods", g.settle_periods, ">= 0");
    }
    plan.periods_per_block = periods_per_block(periods);
    plan.validate();

    const auto n = static_cast<Eigen::Index>(points.size());
    const Eigen::Index lines = static_cast<Eigen::Index>(plan.excited.size());
    const Eigen::Index gaps = static_cast<Eigen::Index>(plan.unexcited.size());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    SweepEstimates out;
    for (auto* m : {&out.H, &out.force, &out.displacement}) m->setConstant(n, lines, {nan, nan});
    for (auto* m : {&out.k, &out.c, &out.k_std, &out.c_std, &out.k_smooth, &out.c_smooth}) m->setConstant(n, lines, nan);
    out.unexcited_force.setConstant(n, gaps, nan);
    out.unexcited_displacement.setConstant(n, gaps, nan);
    out.status.setConstant(n, static_cast<int>(PointStatus::ok));
    out.periods = periods;
    out.blocks = periods / plan.periods_per_block;

    const Eigen::VectorXd force = period_force;
    if (workers <= 0) workers = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    workers = static_cast<int>(std::min<Eigen::Index>(workers, std::max<Eigen::Index>(n, 1)));
    // Contiguous shares, so each point's numbers do not depend on how many workers there are.
    std::vector<std::thread> threads;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(workers));
    for (int w = 0; w < workers; ++w) {
        const Eigen::Index begin = n * w / workers, end = n * (w + 1) / workers;
        threads.emplace_back([&, w, begin, end] {
            try {
                run_points(rig, base, force, points.data() + begin, end - begin, periods, plan, median_window, out,
                           begin);
            } catch (...) {
                errors[static_cast<std::size_t>(w)] = std::current_exception();
            }
        });
    }
    for (auto& t : threads) t.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
    return out;
}

}  // namespace amb_fast
