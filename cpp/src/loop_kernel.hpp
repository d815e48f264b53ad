// Internal to the loop's sources: the linear loop's kernel, which the single run (loop_step.cpp) and
// the lanes side by side (loop_lanes.cpp) share, and LoopState, the state's way into and out of it.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <type_traits>

#include "amb_fast/inline.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/loop.hpp"

namespace amb_fast {

// (In namespace amb_fast rather than an anonymous one: LoopState, the friend of Loop, must name the same
// types in every source that includes this header.)

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

// A loop's state into lane g of the kernel's registers (its delay line already sized), and back.
struct LoopState {
    template <class T, int N>
    static void gather(const Loop& loop, LinearState<T, N>& x, std::size_t g) {
        const auto& z = loop.x_;
        set_lane(x.y, g, z[state::y]), set_lane(x.v, g, z[state::v]), set_lane(x.i, g, z[state::i]);
        set_lane(x.f, g, z[state::i_f]), set_lane(x.s_ys, g, z[state::ys]), set_lane(x.u_prev, g, loop.u_prev_);
        for (int r = 0; r < N; ++r) set_lane(x.s[static_cast<std::size_t>(r)], g, loop.controller_.state()[r]);
        for (std::size_t j = 0; j < x.line.size(); ++j)
            set_lane(x.line[j], g, loop.controller_.line(static_cast<int>(j)));
        x.head = 0;
    }
    template <class T, int N>
    static void scatter(Loop& loop, const LinearState<T, N>& x, std::size_t g) {
        loop.x_ << get_lane(x.y, g), get_lane(x.v, g), get_lane(x.i, g), get_lane(x.f, g), get_lane(x.s_ys, g);
        loop.u_prev_ = get_lane(x.u_prev, g);
        for (int r = 0; r < N; ++r) loop.controller_.state()[r] = get_lane(x.s[static_cast<std::size_t>(r)], g);
        const std::size_t d = x.line.size();
        for (std::size_t j = 0; j < d; ++j)
            loop.controller_.set_line(static_cast<int>(j), get_lane(x.line[(x.head + j) % d], g));
    }
};

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

}  // namespace amb_fast
