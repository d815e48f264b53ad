#include "amb_fast/batch.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>

#include "amb_fast/blocks.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/loop.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

namespace {

void store(SweepEstimates& out, Eigen::Index row, const LineEstimate& e) {
    if (e.saturated_samples > 0) {  // flagged, and not passed off as a clean estimate
        out.status[row] = static_cast<int>(PointStatus::saturated);
        return;
    }
    out.H.row(row) = e.H.transpose();
    out.k.row(row) = e.k.transpose();
    out.c.row(row) = e.c.transpose();
    out.k_std.row(row) = e.k_std.transpose();
    out.c_std.row(row) = e.c_std.transpose();
    out.k_smooth.row(row) = e.k_smooth.transpose();
    out.c_smooth.row(row) = e.c_smooth.transpose();
    out.unexcited_displacement.row(row) = e.unexcited_displacement.transpose();
    out.status[row] = static_cast<int>(PointStatus::ok);
}

// What a worker reuses from one group of points to the next, instead of allocating and freeing it per
// group (which can return the pages to the system and fault them in again).
struct Workspace {
    Workspace(const LinePlan& plan, Eigen::Index lanes)
        : estimators(static_cast<std::size_t>(lanes), PeriodEstimator(plan)),
          force(static_cast<std::size_t>(lanes), Eigen::VectorXd(plan.period)),
          displacement(force),
          current(force) {}
    std::vector<PeriodEstimator> estimators;
    std::vector<Eigen::VectorXd> force, displacement, current;  // one period of each lane's channels
};

// Up to lanes_available() points of one group, each a Loop of its own as run_experiment makes it, advanced
// side by side in SIMD lanes (Loop::run_side_by_side), so each gets run_experiment's numbers.
void run_linear_group(const Eigen::VectorXd& period_force, const SweepPoint* points, Eigen::Index count,
                      Eigen::Index periods, int median_window, bool steady_start, SweepEstimates& out,
                      Eigen::Index first_row, Workspace& work) {
    const Eigen::Index L = period_force.size();
    const auto n = static_cast<std::size_t>(count);
    std::vector<Loop> loops;
    std::vector<Loop*> running;
    std::vector<PeriodEstimator>& estimators = work.estimators;
    std::vector<Eigen::VectorXd>&force = work.force, &displacement = work.displacement;
    std::vector<Channels> channels;
    std::vector<Eigen::Index> saturated_before(n, 0);
    loops.reserve(n);
    Eigen::Index last = 0;
    for (std::size_t g = 0; g < n; ++g) {
        loops.emplace_back(points[g].rig, points[g].controller, points[g].seed);
        estimators[g].restart();
        channels.push_back({force[g].data(), displacement[g].data(), work.current[g].data()});
        last = std::max(last, points[g].settle_periods + periods);
    }
    if (steady_start) {  // the probes side by side too (Loop::start_periodic in two steps)
        std::vector<Loop> probes;
        std::vector<Loop*> probing;
        probes.reserve(n);
        for (auto& loop : loops) probes.push_back(loop.periodic_probe());
        for (auto& probe : probes) probing.push_back(&probe);
        Loop::run_side_by_side(probing.data(), static_cast<int>(n), period_force.data(), L, channels.data());
        for (std::size_t g = 0; g < n; ++g) loops[g].start_periodic_from(probes[g], L);
    }
    for (auto& loop : loops) running.push_back(&loop);
    for (Eigen::Index p = 0; p < last; ++p) {
        Loop::run_side_by_side(running.data(), static_cast<int>(n), period_force.data(), L, channels.data());
        for (std::size_t g = 0; g < n; ++g) {
            if (p == points[g].settle_periods) saturated_before[g] = loops[g].saturated_samples();
            // A single run stops at touchdown; the lane runs on, but records no more.
            const bool recording =
                !loops[g].touched_down() && p >= points[g].settle_periods && p < points[g].settle_periods + periods;
            if (recording) estimators[g].add_period(force[g].data(), displacement[g].data(), p * L);
        }
    }
    for (std::size_t g = 0; g < n; ++g) {
        const auto row = first_row + static_cast<Eigen::Index>(g);
        if (loops[g].touched_down()) {
            out.status[row] = static_cast<int>(PointStatus::touchdown);
            continue;
        }
        LineEstimate e = estimators[g].estimate(points[g].rig.mass, points[g].controller.fs, median_window);
        e.saturated_samples = loops[g].saturated_samples() - saturated_before[g];
        store(out, row, e);
    }
}

void run_points(const Eigen::VectorXd& period_force, const SweepPoint* points, Eigen::Index count, Eigen::Index periods,
                const LinePlan& plan, int median_window, bool steady_start, SweepEstimates& out, Eigen::Index first_row,
                std::optional<Workspace>& work) {  // work: made when the first group comes
    Eigen::Index start = 0;
    while (start < count) {
        const SweepPoint& head = points[start];
        // One at a time: the non-linear law, and the spectra drawn without a loop (run_experiment's path).
        if (head.rig.force_law == ForceLaw::nonlinear || draws_spectra(head.rig, steady_start)) {
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
        const Eigen::Index most = lanes_available();
        // Points that can share lanes: the same rig (plant map, transducer, noise levels), controllers of
        // one capacity, delay and sample rate.
        const auto fits = [&](const SweepPoint& p) {
            return Loop::can_share_lanes(head.rig, head.controller, p.rig, p.controller);
        };
        while (lanes < most && start + lanes < count && fits(points[start + lanes])) ++lanes;
        if (!work) work.emplace(plan, lanes_available());
        run_linear_group(period_force, points + start, lanes, periods, median_window, steady_start, out,
                         first_row + start, *work);
        start += lanes;
    }
}

}  // namespace

namespace {
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The eigenvalues of one m x m matrix (row-major) into values[0..m), balanced as LAPACK's geev does (the
// small poles keep their digits): the one routine of `eigenvalues` and of run_sweep's stability check.
void eigenvalues_of(const double* matrix, Eigen::Index m, Eigen::EigenSolver<Eigen::MatrixXd>& solver,
                    std::complex<double>* values) {
    const Eigen::MatrixXd A = Eigen::Map<const RowMatrix>(matrix, m, m);
    const Eigen::VectorXd d = balancing(A);
    solver.compute(d.cwiseInverse().asDiagonal() * A * d.asDiagonal(), false);
    if (solver.info() != Eigen::Success) throw std::runtime_error("eigenvalues did not converge");
    for (Eigen::Index i = 0; i < m; ++i) values[i] = solver.eigenvalues()[i];
}
}  // namespace

SweepEstimates run_sweep(const Eigen::Ref<const Eigen::VectorXd>& period_force, const std::vector<SweepPoint>& points,
                         Eigen::Index periods, LinePlan plan, int median_window, int workers, bool steady_start,
                         LoopMatrices loops) {
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
    out.H.setConstant(n, lines, {nan, nan});
    for (auto* m : {&out.k, &out.c, &out.k_std, &out.c_std, &out.k_smooth, &out.c_smooth})
        m->setConstant(n, lines, nan);
    out.unexcited_displacement.setConstant(n, gaps, nan);
    out.status.setConstant(n, static_cast<int>(PointStatus::ok));
    out.periods = periods;
    out.blocks = periods / plan.periods_per_block;

    const Eigen::VectorXd force = period_force;
    out.radius.setConstant(n, nan);
    // Blocks of one point where the points are drawn one at a time, of a lane group where the loops run
    // side by side (a point's numbers are the same in any group: run_experiment's).
    const bool in_lanes = std::any_of(points.begin(), points.end(), [&](const SweepPoint& p) {
        return p.rig.force_law == ForceLaw::linear && !draws_spectra(p.rig, steady_start);
    });
    in_blocks(n, in_lanes ? lanes_available() : 1, workers, [&] {
        return [&, work = std::optional<Workspace>(), solver = Eigen::EigenSolver<Eigen::MatrixXd>(loops.m),
                values = std::vector<std::complex<double>>(static_cast<std::size_t>(loops.m))](
                   Eigen::Index begin, Eigen::Index end) mutable {
            if (!loops.stack) {
                run_points(force, points.data() + begin, end - begin, periods, plan, median_window, steady_start, out,
                           begin, work);
                return;
            }
            // Stability first, then each run of consecutive stable points.
            for (Eigen::Index k = begin; k < end; ++k) {
                eigenvalues_of(loops.stack + k * loops.m * loops.m, loops.m, solver, values.data());
                double radius = 0.0;
                for (const auto& v : values) radius = std::max(radius, std::abs(v));
                out.radius[k] = radius;
                if (!(radius < 1.0)) out.status[k] = static_cast<int>(PointStatus::unstable);
            }
            for (Eigen::Index k = begin; k < end;) {
                if (out.status[k] == static_cast<int>(PointStatus::unstable)) {
                    ++k;
                    continue;
                }
                Eigen::Index stop = k;
                while (stop < end && out.status[stop] != static_cast<int>(PointStatus::unstable)) ++stop;
                run_points(force, points.data() + k, stop - k, periods, plan, median_window, steady_start, out, k,
                           work);
                k = stop;
            }
        };
    });
    return out;
}

void eigenvalues(const double* stack, Eigen::Index count, Eigen::Index m, std::complex<double>* values, int workers) {
    in_blocks(count, 64, workers, [&] {
        return [&, solver = Eigen::EigenSolver<Eigen::MatrixXd>(m)](Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index k = begin; k < end; ++k) eigenvalues_of(stack + k * m * m, m, solver, values + k * m);
        };
    });
}

}  // namespace amb_fast
