#include "amb_fast/loop.hpp"

#include <algorithm>
#include <type_traits>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

namespace {
// The controller as the loop runs it: its own delay plus the rig's dead time in whole samples.
Controller with_dead_samples(const Controller& controller, const Rig& rig) {
    Controller c = validated(controller);
    c.delay += split_dead_time(validated(rig).dead_time, c.period()).samples;
    return c;
}
}  // namespace

Loop::Loop(const Rig& rig, const Controller& controller, std::uint64_t seed)
    : rig_(validated(rig)),
      controller_(with_dead_samples(controller, rig)),
      T_(controller.period()),
      sensed_(rig.sensor_bandwidth ? state::ys : state::y),
      has_amp_(rig.amp_bandwidth.has_value()),
      drive_(force_current_index(rig)),
      magnets_(rig),
      limit_(rig.command_limit()),
      touchdown_(rig.touchdown_at()),
      seed_(seed),
      sensor_rng_(seed),
      force_rng_(seed ^ 0x9e3779b97f4a7c15ULL),
      transducer_(rig, controller.period()) {
    fraction_ = split_dead_time(rig_.dead_time, T_).fraction;
    if (rig_.force_law == ForceLaw::linear) {
        plant_.emplace(sample_map(rig_, T_));
        map_.emplace(*plant_);
    } else {
        auto stretch = [&](double length) {
            const double h = length / rig_.substeps;
            return Stretch{h, propagator(rig_, h), propagator(rig_, h / 2)};
        };
        if (fraction_ > 0.0) early_ = stretch(fraction_);
        late_ = stretch(T_ - fraction_);
    }
}

void Loop::run(const double* force, Eigen::Index n, Channels out) {
    for (Eigen::Index start = 0; start < n; start += chunk) {
        poll_interrupt();
        const Eigen::Index m = std::min(chunk, n - start);
        const Channels part{out.force + start, out.displacement + start, out.current + start};
        if (rig_.sensor_noise > 0.0) sensor_rng_.fill(sensor_noise_.data(), m, rig_.sensor_noise);
        const double* noise = sensor_noise_.data();
        if (rig_.force_law == ForceLaw::nonlinear) {
            run_nonlinear(force + start, m, part, noise);
            transducer_.record(force + start, m, part.force);
            if (rig_.force_noise > 0.0) force_rng_.add(part.force, m, rig_.force_noise);
        } else {  // the force noise drawn inside the loop (InLoopDraws), added once the transducer has run
            double* force_noise = rig_.force_noise > 0.0 ? force_noise_.data() : nullptr;
            run_linear(force + start, m, part, noise, force_noise);
            transducer_.record(force + start, m, part.force);
            if (force_noise)
                for (Eigen::Index j = 0; j < m; ++j) part.force[j] += force_noise[j];
        }
        k_ += m;
    }
}

namespace {

// The linear loop over a stretch of samples with its state in registers: T is double for one loop,
// LaneVector for loops side by side (lanes.hpp), each lane doing exactly what a single run does.
// (Lane vectors first in these structs, so that they sit at multiples of their size: lanes.hpp.)
template <class T, int N>
struct LinearState {
    T y, v, i, f, s_ys, u_prev;  // plant (y, v, coil current, eddy current, sensor) and previous command
    std::array<T, N> s;          // controller
    LaneArray<T> line;           // delay line, ring from head
    std::size_t head = 0;
};

// What a stretch of samples reports besides its outputs.
template <class T>
struct Watch {
    T peak{};                       // lanes: max |y| seen (one loop throws Touchdown at the sample instead)
    decltype(T{} < T{}) clipped{};  // lanes: minus the samples clipped, per lane (-1 where a comparison holds)
    Eigen::Index saturated = 0;     // one loop: samples clipped by the amplifier
};

// Deviates of a noise source drawn inside the loop, one per sample (out[j] = sigma z[j]): the loop is
// bound by the latency of its sample-to-sample chain, and the generator's independent work fills the
// idle issue slots, where drawing them in a pass of their own would cost ~2 ns each.
struct InLoopDraws {
    NormalStream::Local* stream = nullptr;  // none: nothing drawn
    double sigma = 0.0;
    double* out = nullptr;
};

template <class T, int N, int sensed, bool has_amp, bool checked, bool fractional, class Map, bool draw = false>
AMB_FAST_ALWAYS_INLINE void run_samples(const Map& map, const ControlLaw<N, T>& law, LinearState<T, N>& x,
                                        const double* force, Eigen::Index n, const T* noise, T* displacement,
                                        T* current, double limit, Watch<T>& watch, const Loop& owner,
                                        Eigen::Index first_sample, InLoopDraws draws = {}) {
    constexpr bool one = std::is_same_v<T, double>;
    T xy = x.y, xv = x.v, xi = x.i, xf = x.f, xs = x.s_ys, u_prev = x.u_prev;
    std::array<T, N> s = x.s;
    const std::size_t d = x.line.size();
    T* const line = x.line.data();
    std::size_t head = x.head;
    for (Eigen::Index j = 0; j < n; ++j) {
        if constexpr (draw) draws.out[j] = draws.sigma * (*draws.stream)();
        const T e = (sensed == state::ys ? xs : xy) + noise[j];
        T wanted = law(e, s.data());
        if (d > 0) wanted = pass_through_delay(line, d, head, wanted);
        // The amplifier's limit (with none, clamping to +-Inf would change nothing, not even a bit).
        T u = wanted;
        if constexpr (checked) {
            if constexpr (one) {
                u = std::clamp(wanted, -limit, limit);
                watch.saturated += u != wanted;
            } else {
#if AMB_FAST_LANES_OK
                u = lane_clamp(wanted, limit);
                watch.clipped += u != wanted;
#endif
            }
        }
        displacement[j] = e;
        current[j] = has_amp ? xi : u;
        if constexpr (fractional) {
            map.advance(xy, xv, xi, xf, xs, force[j], u, u_prev);
            u_prev = u;
        } else if constexpr (one) {
            map.advance(xy, xv, xi, xf, xs, force[j], u);
        } else {
            map.advance_rows(xy, xv, xi, xf, xs, force[j], u);
        }
        if constexpr (checked) {
            if constexpr (one) {
                owner.check_clearance(xy, first_sample + j + 1);
            } else {
#if AMB_FAST_LANES_OK
                watch.peak = lane_max_abs(watch.peak, xy);
#endif
            }
        }
    }
    x.y = xy, x.v = xv, x.i = xi, x.f = xf, x.s_ys = xs, x.u_prev = u_prev;
    x.s = s;
    x.head = head;
}

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

// Lane g of a value, and setting it: for one loop (double) the value itself.
inline double get_lane(double v, std::size_t) { return v; }
inline void set_lane(double& v, std::size_t, double x) { v = x; }
template <class V>
double get_lane(const V& v, std::size_t g) {
    return v[g];
}
template <class V>
void set_lane(V& v, std::size_t g, double x) {
    v[g] = x;
}

}  // namespace

// A loop's state into lane g of the kernel's registers (its delay line already sized), and back.
struct LoopState {
    template <class T, int N>
    static void gather(const Loop& loop, LinearState<T, N>& x, std::size_t g) {
        const auto& z = loop.x_;
        set_lane(x.y, g, z[state::y]), set_lane(x.v, g, z[state::v]), set_lane(x.i, g, z[state::i]);
        set_lane(x.f, g, z[state::i_f]), set_lane(x.s_ys, g, z[state::ys]), set_lane(x.u_prev, g, loop.u_prev_);
        for (int r = 0; r < N; ++r) set_lane(x.s[static_cast<std::size_t>(r)], g, loop.controller_.state()[r]);
        for (std::size_t j = 0; j < x.line.size(); ++j) set_lane(x.line[j], g, loop.controller_.line(static_cast<int>(j)));
        x.head = 0;
    }
    template <class T, int N>
    static void scatter(Loop& loop, const LinearState<T, N>& x, std::size_t g) {
        loop.x_ << get_lane(x.y, g), get_lane(x.v, g), get_lane(x.i, g), get_lane(x.f, g), get_lane(x.s_ys, g);
        loop.u_prev_ = get_lane(x.u_prev, g);
        for (int r = 0; r < N; ++r) loop.controller_.state()[r] = get_lane(x.s[static_cast<std::size_t>(r)], g);
        const std::size_t d = x.line.size();
        for (std::size_t j = 0; j < d; ++j) loop.controller_.set_line(static_cast<int>(j), get_lane(x.line[(x.head + j) % d], g));
    }
};

namespace {

// Calls f(sensed, has_amp, checked, fractional) with each as a compile-time constant, so the state
// stays in registers and the common case pays for no checks.
template <class F>
void with_loop_shape(bool ys, bool has_amp, bool checked, bool fractional, F&& f) {
    using Y = std::integral_constant<int, state::y>;
    using YS = std::integral_constant<int, state::ys>;
    using T = std::true_type;
    using F_ = std::false_type;
    auto last = [&](auto sensed, auto amp, auto check) {
        fractional ? f(sensed, amp, check, T{}) : f(sensed, amp, check, F_{});
    };
    auto checks = [&](auto sensed, auto amp) { checked ? last(sensed, amp, T{}) : last(sensed, amp, F_{}); };
    auto amps = [&](auto sensed) { has_amp ? checks(sensed, T{}) : checks(sensed, F_{}); };
    ys ? amps(YS{}) : amps(Y{});
}

}  // namespace

void Loop::check_clearance(double y, Eigen::Index sample) const {
    if (std::isfinite(touchdown_) && std::abs(y) >= touchdown_)  // else a diverging y (Inf) is no touchdown
        throw Touchdown(sample * T_, y, static_cast<long>(sample));
}

bool Loop::checked() const { return std::isfinite(limit_) || std::isfinite(touchdown_); }

void Loop::run_linear(const double* force, Eigen::Index n, Channels out, const double* noise, double* force_noise) {
    with_capacity(controller_.capacity(), [&](auto N) {
        constexpr int n_ = decltype(N)::value;
        LinearState<double, n_> x;
        x.line.resize(static_cast<std::size_t>(controller_.controller().delay));
        LoopState::gather(*this, x, 0);
        // Local copies: the coefficients stay in registers instead of being reloaded after every store
        // to the output arrays (which the compiler must assume may alias them).
        const CascadeMap map = *map_;
        const ControlLaw<n_> law = controller_.law<n_>();
        Watch<double> watch;
        std::optional<NormalStream::Local> local;
        InLoopDraws draws;
        if (force_noise) {
            local.emplace(force_rng_);
            draws = {&*local, rig_.force_noise, force_noise};
        }
        with_loop_shape(sensed_ == state::ys, has_amp_, checked(), map.fractional, [&](auto sensed, auto amp, auto check, auto frac) {
            constexpr int sensed_ = decltype(sensed)::value;
            constexpr bool amp_ = decltype(amp)::value, check_ = decltype(check)::value, frac_ = decltype(frac)::value;
            if (local)
                run_samples<double, n_, sensed_, amp_, check_, frac_, CascadeMap, true>(
                    map, law, x, force, n, noise, out.displacement, out.current, limit_, watch, *this, k_, draws);
            else
                run_samples<double, n_, sensed_, amp_, check_, frac_>(map, law, x, force, n, noise, out.displacement,
                                                                      out.current, limit_, watch, *this, k_);
        });
        if (local) local->commit();
        LoopState::scatter(*this, x, 0);
        saturated_ += watch.saturated;
    });
    // Inf and NaN never turn finite again in a linear recursion, so one check per chunk suffices.
    if (!x_.allFinite()) {
        Eigen::Index j = 0;
        while (j < n && std::isfinite(out.displacement[j])) ++j;
        fail(k_ + j, "the displacement became non-finite: the loop is unstable");
    }
}

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
    if (lanes == wide_lanes)
        run_lanes<wide_lanes>(loops, count, force, n, out);
    else
        run_lanes<loop_lanes>(loops, count, force, n, out);
#endif
}

#if AMB_FAST_LANES_OK
template <int K>
void Loop::run_lanes(Loop* const* loops, int count, const double* force, Eigen::Index n, const Channels* out) {
    using V = Lanes<K>;
    Loop& head = *loops[0];
    const Rig& rig = head.rig_;
    const CascadeMap& scalar_map = *head.map_;
    alignas(sizeof(V)) const auto map = scalar_map.broadcast<V>([](V& lanes, double value) { lane_fill(lanes, value); });
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
                                LaneKernel<K, n_, decltype(sensed)::value, decltype(amp)::value,
                                           decltype(check)::value, decltype(frac)::value>::run(
                                    map, law, x, force + start, m, noise.data(), displacement.data(), current.data(),
                                    head.limit_, watch, head);
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

void Loop::run_nonlinear(const double* force, Eigen::Index n, Channels out, const double* noise) {
    for (Eigen::Index j = 0; j < n; ++j) {
        const double e = x_[sensed_] + noise[j];
        const double wanted = controller_.step(e);
        const double i_cmd = std::clamp(wanted, -limit_, limit_);  // the amplifier's limit
        saturated_ += i_cmd != wanted;
        out.displacement[j] = e;
        out.current[j] = has_amp_ ? x_[state::i] : i_cmd;
        AugmentedVector X;
        if (fraction_ > 0.0) {  // the dead time's fraction with the previous command, then this one
            X << x_, force[j], u_prev_;
            advance_nonlinear(X, early_);
            X[augmented::i_cmd] = i_cmd;
        } else {
            X << x_, force[j], i_cmd;
        }
        advance_nonlinear(X, late_);
        u_prev_ = i_cmd;
        x_ = X.head<state::size>();
        if (std::abs(x_[state::y]) >= touchdown_)
            throw Touchdown((k_ + j + 1) * T_, x_[state::y], static_cast<long>(k_ + j + 1));
        if (!std::isfinite(x_[state::y])) fail(k_ + j + 1, "the displacement became non-finite");
    }
}

// Integrating-factor (Lawson) RK4: the linear plant, lags and held inputs are propagated exactly by
// the matrix exponential; RK4 integrates only the non-linear remainder of the magnet force, which
// acts on v alone. Exact when the remainder vanishes, fourth order otherwise, and free of the
// step-size limit that the fast lags would put on plain RK4. Stages need only y and the driving
// current, so they take two rows of the half-step map, not all of it.
void Loop::advance_nonlinear(AugmentedVector& X, const Stretch& stretch) const {
    using state::v;
    using state::y;
    const double h = stretch.h;
    const double inv_m = 1.0 / rig_.moving_mass();
    const int d = drive_;
    const auto& E = stretch.full;
    const auto& E2 = stretch.half;
    for (int s = 0; s < rig_.substeps; ++s) {
        const double half_y = E2.row(y).dot(X), half_d = E2.row(d).dot(X);
        const AugmentedVector full = E * X;
        const double a = magnets_.remainder(X[y], X[d]) * inv_m;
        const double b = magnets_.remainder(half_y + 0.5 * h * a * E2(y, v), half_d + 0.5 * h * a * E2(d, v)) * inv_m;
        const double c = magnets_.remainder(half_y, half_d) * inv_m;
        const double dd = magnets_.remainder(full[y] + h * c * E2(y, v), full[d] + h * c * E2(d, v)) * inv_m;
        X = full + (h / 6.0) * (a * E.col(v) + 2.0 * (b + c) * E2.col(v));
        X[v] += (h / 6.0) * dd;
    }
}

Eigen::VectorXd Loop::stacked_state() const {
    const Controller& c = controller_.controller();
    const int n = c.order(), d = c.delay;
    const bool fractional = fraction_ > 0.0;
    Eigen::VectorXd z(state::size + n + d + int(fractional));
    z.head<state::size>() = x_;
    if (fractional) z[z.size() - 1] = u_prev_;
    for (int j = 0; j < n; ++j) z[state::size + j] = controller_.state()[j];
    for (int j = 0; j < d; ++j) z[state::size + n + j] = controller_.line(j);
    return z;
}

void Loop::set_stacked_state(const Eigen::VectorXd& z) {
    const Controller& c = controller_.controller();
    const int n = c.order(), d = c.delay;
    x_ = z.head<state::size>();
    if (fraction_ > 0.0) u_prev_ = z[z.size() - 1];
    for (int j = 0; j < n; ++j) controller_.state()[j] = z[state::size + j];
    for (int j = 0; j < d; ++j) controller_.set_line(j, z[state::size + n + j]);
}

void Loop::start_periodic(const double* period_force, Eigen::Index L) {
    Loop probe = periodic_probe();
    Eigen::VectorXd f(L), y(L), i(L);
    probe.run(period_force, L, {f.data(), y.data(), i.data()});
    start_periodic_from(probe, L);
}

Loop Loop::periodic_probe() const {
    // The noise-free linear loop without limits, run by the same kernel.
    Rig quiet = rig_;
    quiet.force_law = ForceLaw::linear;
    quiet.sensor_noise = quiet.force_noise = 0.0;
    quiet.clearance.reset();
    quiet.current_limit.reset();
    Controller own = controller_.controller();  // the dead time's whole samples are in its delay already
    own.delay -= split_dead_time(rig_.dead_time, T_).samples;
    return Loop(quiet, own);
}

void Loop::start_periodic_from(const Loop& probe, Eigen::Index L) {
    const ClosedLoopMap map(plant_ ? *plant_ : sample_map(probe.rig_, T_), sensed_, controller_.controller(), fraction_);
    Eigen::VectorXd z = periodic_start(map.M, L, probe.stacked_state());
    if (rig_.sensor_noise > 0.0) {
        NormalStream draws(start_noise_seed(seed_));
        Eigen::VectorXd w(z.size());
        draws.fill(w.data(), w.size(), 1.0);
        z += covariance_root(stationary_covariance(map.M, map.noise_in, Eigen::VectorXd::Constant(1, rig_.sensor_noise))) * w;
    }
    set_stacked_state(z);
    transducer_.set_state(periodic_transducer_start(transducer_.pole(), L, probe.transducer_.state()));
}

MimoModel Loop::linear_model() const {
    Rig linear = rig_;
    linear.force_law = ForceLaw::linear;
    const SampleMap plant = plant_ ? *plant_ : sample_map(linear, T_);
    const ClosedLoopMap map(plant, sensed_, controller_.controller(), fraction_);
    const Eigen::Index n = map.M.rows();
    MimoModel model;
    model.M = map.M;
    model.Bf = Eigen::MatrixXd::Zero(n, 1);
    model.Bf.topRows(state::size) = plant.Gf;
    model.Bn = map.noise_in;
    model.C = Eigen::MatrixXd::Zero(1, n);
    model.C(0, sensed_) = 1.0;
    model.Dn = Eigen::MatrixXd::Ones(1, 1);
    model.transducer_pole = Eigen::VectorXd::Constant(1, transducer_.pole());
    model.sensor_noise = Eigen::VectorXd::Constant(1, rig_.sensor_noise);
    model.force_noise = Eigen::VectorXd::Constant(1, rig_.force_noise);
    return model;
}

void Loop::fail(Eigen::Index sample, const char* what) const {
    std::ostringstream msg;
    msg << what << " (at sample " << sample << ", t = " << sample * T_ << " s)";
    throw std::overflow_error(msg.str());
}

void simulate(const Rig& rig, const Controller& controller, const double* force, Eigen::Index n, Channels out,
              std::uint64_t seed) {
    require_finite_samples("force", force, n);
    Loop loop(rig, controller, seed);
    loop.run(force, n, out);
}

}  // namespace amb_fast
