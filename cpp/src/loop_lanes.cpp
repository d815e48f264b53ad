// Loops side by side in SIMD lanes (lanes.hpp): which loops may share them, and the runner with its
// lane kernels and noise draws.
#include "amb_fast/loop.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/lanes.hpp"
#include "loop_kernel.hpp"

namespace amb_fast {

namespace {

#if AMB_FAST_LANES_OK
// The lanes' kernel: two lanes in the portable build's registers, four in AVX2's where the processor
// has it (the same source compiled for AVX2, so the same IEEE operations in the same order).
template <int K, int N, int sensed, bool has_amp, bool checked, bool fractional>
struct LaneKernel {
    using V = Lanes<K>;
    static void run(const CascadeCoefficients<V>& map, const ControlLaw<N, V>& law, LinearState<V, N>& x,
                    const double* force, Eigen::Index n, const V* noise, V* displacement, V* current, double limit,
                    Watch<V>& watch, const Loop& owner) {
        run_samples<V, N, sensed, has_amp, checked, fractional>(map, law, x, force, n, noise, displacement, current,
                                                                limit, watch, owner, 0);
    }
};
// The noise of K points, out[j K + g] = lane g's: stream by stream, or (AVX2) four streams at once in
// NormalLanes (1.7 against 2.2 ns per deviate; two lanes in SSE2 registers would be slower, 3.2 ns).
template <int K>
struct LaneDraws {
    explicit LaneDraws(NormalStream* const* streams, int count) : streams_(streams), count_(count) {}
    void fill(double* out, Eigen::Index n, double sigma) {
        for (int g = 0; g < count_; ++g) streams_[g]->fill(out + g, n, sigma, K);
    }
    void commit() {}
    NormalStream* const* streams_;
    int count_;
};
#if AMB_FAST_WIDE_LANES
template <>
struct LaneDraws<wide_lanes> {
    explicit LaneDraws(NormalStream* const* streams, int count) : lanes_(streams, count) {}
    __attribute__((target("avx2"))) void fill(double* out, Eigen::Index n, double sigma) { lanes_.fill(out, n, sigma); }
    void commit() { lanes_.commit(); }
    NormalLanes<wide_lanes> lanes_;
};
template <int N, int sensed, bool has_amp, bool checked, bool fractional>
struct LaneKernel<wide_lanes, N, sensed, has_amp, checked, fractional> {
    using V = Lanes<wide_lanes>;
    __attribute__((target("avx2"))) static void run(const CascadeCoefficients<V>& map, const ControlLaw<N, V>& law,
                                                    LinearState<V, N>& x, const double* force, Eigen::Index n,
                                                    const V* noise, V* displacement, V* current, double limit,
                                                    Watch<V>& watch, const Loop& owner) {
        run_samples<V, N, sensed, has_amp, checked, fractional>(map, law, x, force, n, noise, displacement, current,
                                                                limit, watch, owner, 0);
    }
};
#endif
#endif

}  // namespace

bool Loop::can_share_lanes(const Rig& a, const Controller& ca, const Rig& b, const Controller& cb) {
    return a.force_law == ForceLaw::linear && a == b && ca.fs == cb.fs && ca.delay == cb.delay &&
           controller_capacity(ca.order()) == controller_capacity(cb.order());
}

bool Loop::can_run_beside(const Loop& other) const {
    return can_share_lanes(rig_, controller_.controller(), other.rig_, other.controller_.controller());
}

void Loop::run_side_by_side(Loop* const* loops, int count, const double* force, Eigen::Index n, const Channels* out) {
    const int lanes = count > loop_lanes ? lanes_available() : loop_lanes;
    bool together = count > 1 && count <= lanes;
    for (int g = 1; g < count; ++g) together = together && loops[0]->can_run_beside(*loops[g]);
    if (!together) {
        for (int g = 0; g < count; ++g) {
            if (loops[g]->touched_down_) continue;  // what it would record is discarded
            try {
                loops[g]->run(force, n, out[g]);
            } catch (const Touchdown&) {
                loops[g]->touched_down_ = true;
            }
        }
        return;
    }
#if AMB_FAST_LANES_OK
    if (lanes == wide_lanes) run_lanes<wide_lanes>(loops, count, force, n, out);
    else run_lanes<loop_lanes>(loops, count, force, n, out);
#endif
}

#if AMB_FAST_LANES_OK
template <int K>
void Loop::run_lanes(Loop* const* loops, int count, const double* force, Eigen::Index n, const Channels* out) {
    using V = Lanes<K>;
    Loop& head = *loops[0];
    const Rig& rig = head.rig_;
    const CascadeMap& scalar_map = *head.map_;
    alignas(sizeof(V)) const auto map =
        scalar_map.broadcast<V>([](V& lanes, double value) { lane_fill(lanes, value); });
    const auto lanes = static_cast<std::size_t>(K);
    LaneArray<V> noise(chunk), displacement(chunk), current(chunk), force_noise(chunk);
    std::array<NormalStream*, K> sensor_streams{}, force_streams{};
    for (int g = 0; g < count; ++g) {
        sensor_streams[static_cast<std::size_t>(g)] = &loops[g]->sensor_rng_;
        force_streams[static_cast<std::size_t>(g)] = &loops[g]->force_rng_;
    }
    LaneDraws<K> sensor_draws(sensor_streams.data(), count), force_draws(force_streams.data(), count);
    with_capacity(head.controller_.capacity(), [&](auto N) {
        constexpr int n_ = decltype(N)::value;
        // Gather: lane g holds loop g (spare lanes repeat loop 0 and are never written back).
        alignas(sizeof(V)) LinearState<V, n_> x;
        alignas(sizeof(V)) ControlLaw<n_, V> law;
        x.line.resize(static_cast<std::size_t>(head.controller_.controller().delay));
        for (std::size_t g = 0; g < lanes; ++g) {
            const Loop& lp = *loops[g < static_cast<std::size_t>(count) ? g : 0];
            LoopState::gather(lp, x, g);
            const ControlLaw<n_>& own = lp.controller_.law<n_>();
            for (int r = 0; r < n_; ++r) law.B[r][g] = own.B[r], law.C[r][g] = own.C[r];
            for (int r = 0; r < n_ * n_; ++r) law.At[r][g] = own.At[r];
            law.D[g] = own.D;
        }
        for (Eigen::Index start = 0; start < n; start += chunk) {
            poll_interrupt();
            const Eigen::Index m = std::min(chunk, n - start);
            if (rig.sensor_noise > 0.0)  // else the noise stays zero
                sensor_draws.fill(reinterpret_cast<double*>(noise.data()), m, rig.sensor_noise);
            if (rig.force_noise > 0.0)
                force_draws.fill(reinterpret_cast<double*>(force_noise.data()), m, rig.force_noise);
            alignas(sizeof(V)) Watch<V> watch;
            with_loop_shape(head.sensed_ == state::ys, head.has_amp_, head.checked(), scalar_map.fractional,
                            [&](auto sensed, auto amp, auto check, auto frac) {
                                LaneKernel<K, n_, decltype(sensed)::value, decltype(amp)::value, decltype(check)::value,
                                           decltype(frac)::value>::run(map, law, x, force + start, m, noise.data(),
                                                                       displacement.data(), current.data(), head.limit_,
                                                                       watch, head);
                            });
            for (int g = 0; g < count; ++g) {
                Loop& lp = *loops[g];
                const Channels part{out[g].force + start, out[g].displacement + start, out[g].current + start};
                for (Eigen::Index j = 0; j < m; ++j) {
                    part.displacement[j] = displacement[static_cast<std::size_t>(j)][g];
                    part.current[j] = current[static_cast<std::size_t>(j)][g];
                }
                lp.saturated_ -= watch.clipped[g];
                if (std::isfinite(lp.touchdown_) && watch.peak[g] >= lp.touchdown_) lp.touched_down_ = true;
                lp.transducer_.record(force + start, m, part.force);
                if (rig.force_noise > 0.0)
                    for (Eigen::Index j = 0; j < m; ++j) part.force[j] += force_noise[static_cast<std::size_t>(j)][g];
                lp.k_ += m;
            }
        }
        sensor_draws.commit();
        force_draws.commit();
        // Scatter: each loop gets its lane back.
        for (int g = 0; g < count; ++g) {
            Loop& lp = *loops[g];
            LoopState::scatter(lp, x, static_cast<std::size_t>(g));
            if (!lp.touched_down_ && !lp.x_.allFinite())
                lp.fail(lp.k_, "the displacement became non-finite: the loop is unstable");
        }
    });
}
#endif

}  // namespace amb_fast
