#include "amb_fast/batch.hpp"

#include <algorithm>
#include <exception>
#include <limits>
#include <stdexcept>
#include <thread>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/steady.hpp"

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

// Points that can share lock step: the same rig (so the same plant map, transducer and noise levels),
// and controllers of the same capacity, delay and sample rate.
bool same_group(const SweepPoint& a, const SweepPoint& b) {
    return a.rig == b.rig && controller_capacity(a.controller.order()) == controller_capacity(b.controller.order()) &&
           a.controller.delay == b.controller.delay && a.controller.fs == b.controller.fs;
}

// Lane arrays, structure of arrays: entry c of lane g at c * lanes + g.
struct Lanes {
    Lanes(Eigen::Index lanes, int N, int delay)
        : n(static_cast<std::size_t>(lanes)),
          y(n), v(n), i(n), f(n), s(n), e(n), u(n), cs(n), acc(n), saturated(n), peak(n), uprev(n),
          state(n * static_cast<std::size_t>(N)), next(state.size()), A(n * static_cast<std::size_t>(N * N)),
          B(state.size()), C(state.size()), D(n), held(n * static_cast<std::size_t>(std::max(delay, 1))) {}
    std::size_t n;
    std::vector<double> y, v, i, f, s, e, u, cs, acc, saturated, peak, uprev;  // plant state, e, u, scratch
    std::vector<double> state, next, A, B, C, D, held;                // controller state, coefficients, delay line
};

// One sample for every lane: what Loop::run_linear does for one loop (the same ControlLaw operations in
// the same order, the same CascadeMap), as passes over the lanes that vectorise.
template <int N, int sensed, bool delayed, bool checked>
void step_lanes(Lanes& L, std::size_t head, const double* __restrict noise, double* __restrict out_y,
                const CascadeMap& map, double limit, double force) {
    const std::size_t n = L.n;
    double* __restrict e = L.e.data();
    double* __restrict u = L.u.data();
    double* __restrict cs = L.cs.data();
    double* __restrict acc = L.acc.data();
    double* __restrict s = L.state.data();
    double* __restrict next = L.next.data();
    const double* __restrict A = L.A.data();
    const double* __restrict B = L.B.data();
    const double* __restrict C = L.C.data();
    const double* __restrict D = L.D.data();
    const double* __restrict measured = sensed == state::ys ? L.s.data() : L.y.data();
    for (std::size_t g = 0; g < n; ++g) e[g] = measured[g] + noise[g];
    for (std::size_t g = 0; g < n; ++g) cs[g] = C[g] * s[g];
    for (int j = 1; j < N; ++j)
        for (std::size_t g = 0; g < n; ++g) cs[g] += C[j * n + g] * s[j * n + g];
    for (int r = 0; r < N; ++r) {
        for (std::size_t g = 0; g < n; ++g) acc[g] = A[(r * N) * n + g] * s[g];
        for (int j = 1; j < N; ++j)
            for (std::size_t g = 0; g < n; ++g) acc[g] += A[(r * N + j) * n + g] * s[j * n + g];
        for (std::size_t g = 0; g < n; ++g) next[r * n + g] = acc[g] + B[r * n + g] * e[g];
    }
    std::copy(L.next.begin(), L.next.end(), L.state.begin());
    for (std::size_t g = 0; g < n; ++g) u[g] = cs[g] + D[g] * e[g];
    if constexpr (delayed) {  // u[k - d] out, u[k] in
        double* __restrict held = L.held.data() + head * n;
        for (std::size_t g = 0; g < n; ++g) {
            const double older = held[g];
            held[g] = u[g];
            u[g] = older;
        }
    }
    double* __restrict y = L.y.data();
    double* __restrict v = L.v.data();
    double* __restrict i = L.i.data();
    double* __restrict f = L.f.data();
    double* __restrict ys = L.s.data();
    double* __restrict saturated = L.saturated.data();
    double* __restrict peak = L.peak.data();
    double* __restrict uprev = L.uprev.data();
    for (std::size_t g = 0; g < n; ++g) {
        if constexpr (checked) {  // the amplifier's limit, as in Loop::run_linear
            const double wanted = u[g];
            u[g] = std::clamp(wanted, -limit, limit);
            saturated[g] += u[g] != wanted;
        }
        out_y[g] = e[g];
    }
    if (map.fractional) {
        for (std::size_t g = 0; g < n; ++g) {
            map.advance(y[g], v[g], i[g], f[g], ys[g], force, u[g], uprev[g]);
            uprev[g] = u[g];
        }
    } else {
        for (std::size_t g = 0; g < n; ++g) map.advance(y[g], v[g], i[g], f[g], ys[g], force, u[g]);
    }
    if constexpr (checked)
        for (std::size_t g = 0; g < n; ++g) peak[g] = std::max(peak[g], std::abs(y[g]));
}

// Every lane in the periodic steady state, exactly as Loop::start_periodic puts a single run there: one
// period from rest without noise or limits by the same kernel, then z0 = M^N z0 + zN per lane, the
// stationary noise state drawn from the point's own stream, and the transducer's steady state.
template <int N, int sensed>
void start_lanes_periodic(Lanes& lane, const SweepPoint* points, const Eigen::VectorXd& period_force,
                          const CascadeMap& map, ForceTransducer& transducer) {
    const Rig& rig = points[0].rig;
    const DeadTime dead = split_dead_time(rig.dead_time, points[0].controller.period());
    const int d = points[0].controller.delay + dead.samples;
    const std::size_t n = lane.n;
    const Eigen::Index L = period_force.size();
    Lanes probe(static_cast<Eigen::Index>(n), N, d);
    probe.A = lane.A, probe.B = lane.B, probe.C = lane.C, probe.D = lane.D;
    std::vector<double> quiet(n, 0.0), scratch(n);
    std::size_t head = 0;
    const double none = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < L; ++j) {
        d > 0 ? step_lanes<N, sensed, true, false>(probe, head, quiet.data(), scratch.data(), map, none, period_force[j])
              : step_lanes<N, sensed, false, false>(probe, head, quiet.data(), scratch.data(), map, none, period_force[j]);
        if (d > 0 && ++head == static_cast<std::size_t>(d)) head = 0;
    }
    Rig linear = rig;  // what the single run's probe sees
    linear.force_law = ForceLaw::linear;
    linear.sensor_noise = linear.force_noise = 0.0;
    linear.clearance.reset();
    linear.current_limit.reset();
    const SampleMap plant = sample_map(linear, points[0].controller.period());
    ForceTransducer settled(rig, points[0].controller.period());
    Eigen::VectorXd recorded(L);
    settled.record(period_force.data(), L, recorded.data());
    transducer.set_state(periodic_transducer_start(transducer.pole(), L, settled.state()));
    for (std::size_t g = 0; g < n; ++g) {
        Controller c = points[g].controller;
        c.delay = d;
        const int order = c.order(), prev = int(dead.fraction > 0.0);
        Eigen::VectorXd z(state::size + order + d + prev);
        z.head<state::size>() << probe.y[g], probe.v[g], probe.i[g], probe.f[g], probe.s[g];
        if (prev) z[z.size() - 1] = probe.uprev[g];
        for (int j = 0; j < order; ++j) z[state::size + j] = probe.state[static_cast<std::size_t>(j) * n + g];
        for (int j = 0; j < d; ++j)
            z[state::size + order + j] = probe.held[((head + static_cast<std::size_t>(j)) % static_cast<std::size_t>(d)) * n + g];
        const ClosedLoopMap loop(plant, sensed, c, dead.fraction);
        z = periodic_start(loop.M, L, z);
        if (rig.sensor_noise > 0.0) {
            NormalStream draws(start_noise_seed(points[g].seed));
            Eigen::VectorXd w(z.size());
            draws.fill(w.data(), w.size(), 1.0);
            z += stationary_noise_root(loop.M, loop.noise_in, rig.sensor_noise) * w;
        }
        lane.y[g] = z[0], lane.v[g] = z[1], lane.i[g] = z[2], lane.f[g] = z[3], lane.s[g] = z[4];
        for (int j = 0; j < order; ++j) lane.state[static_cast<std::size_t>(j) * n + g] = z[state::size + j];
        for (int j = 0; j < d; ++j) lane.held[static_cast<std::size_t>(j) * n + g] = z[state::size + order + j];
        if (prev) lane.uprev[g] = z[z.size() - 1];
    }
}

// A group of linear points in lock step (one rig; controllers of one capacity N and one delay).
template <int N, int sensed>
void run_linear_group(const Eigen::VectorXd& period_force, const SweepPoint* points, Eigen::Index lanes,
                      Eigen::Index periods, const LinePlan& plan, int median_window, bool steady_start,
                      SweepEstimates& out, Eigen::Index first_row) {
    const Rig& rig = points[0].rig;
    const Controller& first = points[0].controller;
    const Eigen::Index L = period_force.size();
    const CascadeMap map(sample_map(rig, first.period()));
    const int d = first.delay + split_dead_time(rig.dead_time, first.period()).samples;
    Lanes lane(lanes, N, d);
    const std::size_t n = lane.n;
    std::vector<PeriodEstimator> estimators;
    std::vector<NormalStream> sensor_noise, force_noise;
    std::vector<double> saturated_before(n);
    for (Eigen::Index g = 0; g < lanes; ++g) {
        const ControlLaw<N> law(points[g].controller);
        for (int r = 0; r < N; ++r) {
            lane.B[r * n + g] = law.B[r], lane.C[r * n + g] = law.C[r];
            for (int j = 0; j < N; ++j) lane.A[(r * N + j) * n + g] = law.At[j * N + r];
        }
        lane.D[g] = law.D;
    }
    const double limit = rig.command_limit(), touchdown = rig.touchdown_at();
    const bool checked = std::isfinite(limit) || std::isfinite(touchdown);
    std::vector<double> displacement(static_cast<std::size_t>(L) * n), noise(displacement.size(), 0.0);
    Eigen::VectorXd lane_y(L), lane_f(L), recorded(L);
    ForceTransducer transducer(rig, first.period());  // sees the same force in every lane
    Eigen::Index last = 0;
    estimators.reserve(n);
    for (Eigen::Index g = 0; g < lanes; ++g) {
        estimators.emplace_back(plan);
        sensor_noise.emplace_back(points[g].seed);
        force_noise.emplace_back(points[g].seed ^ 0x9e3779b97f4a7c15ULL);
        last = std::max(last, points[g].settle_periods + periods);
    }
    std::vector<bool> touched(n, false);
    std::size_t head = 0;
    if (steady_start) start_lanes_periodic<N, sensed>(lane, points, period_force, map, transducer);

    for (Eigen::Index p = 0; p < last; ++p) {
        poll_interrupt();
        if (rig.sensor_noise > 0.0)
            for (std::size_t g = 0; g < n; ++g)
                sensor_noise[g].fill(&noise[g], L, rig.sensor_noise, static_cast<Eigen::Index>(n));
        for (Eigen::Index j = 0; j < L; ++j) {
            const double f = period_force[j];
            const double* noise_now = &noise[static_cast<std::size_t>(j) * n];
            double* out_y = &displacement[static_cast<std::size_t>(j) * n];
            // A limit or a clearance to watch is compiled in only when there is one.
            if (checked)
                d > 0 ? step_lanes<N, sensed, true, true>(lane, head, noise_now, out_y, map, limit, f)
                      : step_lanes<N, sensed, false, true>(lane, head, noise_now, out_y, map, limit, f);
            else
                d > 0 ? step_lanes<N, sensed, true, false>(lane, head, noise_now, out_y, map, limit, f)
                      : step_lanes<N, sensed, false, false>(lane, head, noise_now, out_y, map, limit, f);
            if (d > 0 && ++head == static_cast<std::size_t>(d)) head = 0;
        }
        transducer.record(period_force.data(), L, recorded.data());
        for (std::size_t g = 0; g < n; ++g) {
            if (p == points[g].settle_periods) saturated_before[g] = lane.saturated[g];
            // A single run stops at touchdown; the lane runs on, but records no more.
            if (lane.peak[g] >= touchdown) touched[g] = true;
            const bool recording =
                !touched[g] && p >= points[g].settle_periods && p < points[g].settle_periods + periods;
            lane_f = recorded;
            if (rig.force_noise > 0.0)  // drawn whether recorded or not, as a single run draws it
                force_noise[g].add(lane_f.data(), L, rig.force_noise);
            if (!recording) continue;
            for (Eigen::Index j = 0; j < L; ++j) lane_y[j] = displacement[static_cast<std::size_t>(j) * n + g];
            estimators[g].add_period(lane_f.data(), lane_y.data(), p * L);
        }
    }
    for (std::size_t g = 0; g < n; ++g) {
        const auto row = first_row + static_cast<Eigen::Index>(g);
        if (touched[g]) {
            out.status[row] = static_cast<int>(PointStatus::touchdown);
            continue;
        }
        if (!std::isfinite(lane.y[g] + lane.v[g] + lane.i[g] + lane.f[g] + lane.s[g]))
            throw std::overflow_error("a point of the sweep diverged although its linearised loop is stable");
        LineEstimate e = estimators[g].estimate(rig.mass, first.fs, median_window);
        e.saturated_samples = static_cast<Eigen::Index>(lane.saturated[g] - saturated_before[g]);
        store(out, row, e);
    }
}

template <int N>
void run_linear_group(const Eigen::VectorXd& period_force, const SweepPoint* points, Eigen::Index lanes,
                      Eigen::Index periods, const LinePlan& plan, int median_window, bool steady_start,
                      SweepEstimates& out, Eigen::Index first_row) {
    if (points[0].rig.sensor_bandwidth)
        run_linear_group<N, state::ys>(period_force, points, lanes, periods, plan, median_window, steady_start, out,
                                       first_row);
    else
        run_linear_group<N, state::y>(period_force, points, lanes, periods, plan, median_window, steady_start, out,
                                      first_row);
}

void run_points(const Eigen::VectorXd& period_force, const SweepPoint* points, Eigen::Index count, Eigen::Index periods,
                const LinePlan& plan, int median_window, bool steady_start, SweepEstimates& out,
                Eigen::Index first_row) {
    Eigen::Index start = 0;
    while (start < count) {
        const SweepPoint& head = points[start];
        if (head.rig.force_law == ForceLaw::nonlinear) {
            try {
                store(out, first_row + start,
                      run_experiment(head.rig, head.controller, period_force, head.settle_periods, periods, plan,
                                     head.seed, median_window, steady_start));
            } catch (const Touchdown&) {
                out.status[first_row + start] = static_cast<int>(PointStatus::touchdown);
            }
            ++start;
            continue;
        }
        Eigen::Index lanes = 1;
        while (lanes < lanes_per_group && start + lanes < count && same_group(head, points[start + lanes])) ++lanes;
        const SweepPoint* group = points + start;
        const Eigen::Index row = first_row + start;
        with_capacity(controller_capacity(head.controller.order()), [&](auto N) {
            run_linear_group<N>(period_force, group, lanes, periods, plan, median_window, steady_start, out, row);
        });
        start += lanes;
    }
}

}  // namespace

SweepEstimates run_sweep(const Eigen::Ref<const Eigen::VectorXd>& period_force, const std::vector<SweepPoint>& points,
                         Eigen::Index periods, LinePlan plan, int median_window, int workers, bool steady_start) {
    const Eigen::Index L = plan.period;
    require(period_force.size() == L, "excitation length", period_force.size(), "one period of plan.period samples");
    require_finite_samples("excitation", period_force.data(), L);
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    for (const SweepPoint& g : points) {
        g.rig.validate();
        g.controller.validate();
        require(g.controller.fs == points.front().controller.fs, "fs", g.controller.fs, "the same at every point (Hz)");
        require(g.rig.mass == points.front().rig.mass, "mass", g.rig.mass, "the same at every point (kg)");
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
    // Contiguous shares, so each point's numbers do not depend on how many workers there are. The
    // calling thread computes the first share itself (it is the one that can see Ctrl-C).
    const InterruptCheck* check = interrupt_check();
    std::vector<std::thread> threads;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(workers));
    auto share = [&](int w) {
        const Eigen::Index begin = n * w / workers, end = n * (w + 1) / workers;
        const ScopedInterruptCheck installed(check);
        try {
            run_points(force, points.data() + begin, end - begin, periods, plan, median_window, steady_start, out, begin);
        } catch (...) {
            errors[static_cast<std::size_t>(w)] = std::current_exception();
        }
    };
    for (int w = 1; w < workers; ++w) threads.emplace_back(share, w);
    share(0);
    for (auto& t : threads) t.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
    return out;
}

}  // namespace amb_fast
