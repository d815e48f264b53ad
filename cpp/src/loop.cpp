#include "amb_fast/loop.hpp"

#include <algorithm>
#include <type_traits>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
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
        if (rig_.force_law == ForceLaw::nonlinear)
            run_nonlinear(force + start, m, part, noise);
        else
            run_linear(force + start, m, part, noise);
        transducer_.record(force + start, m, part.force);
        if (rig_.force_noise > 0.0)
            force_rng_.add(part.force, m, rig_.force_noise);
        k_ += m;
    }
}

// Which state the sensor reads, where the coil current comes from, and whether a current limit or a
// clearance is to be watched are compile-time constants in the kernel, so the state stays in
// registers and the common case pays for no checks.
void Loop::run_linear(const double* force, Eigen::Index n, Channels out, const double* noise) {
    with_capacity(controller_.capacity(), [&](auto N) { run_linear<N>(force, n, out, noise); });
}

template <int N>
void Loop::run_linear(const double* force, Eigen::Index n, Channels out, const double* noise) {
    const bool checked = std::isfinite(limit_) || std::isfinite(touchdown_);
    const bool ys = sensed_ == state::ys;
    auto run = [&](auto sensed, auto has_amp, auto check) {
        if (map_->fractional)
            run_linear<N, decltype(sensed)::value, decltype(has_amp)::value, decltype(check)::value, true>(force, n, out, noise);
        else
            run_linear<N, decltype(sensed)::value, decltype(has_amp)::value, decltype(check)::value, false>(force, n, out, noise);
    };
    using Y = std::integral_constant<int, state::y>;
    using YS = std::integral_constant<int, state::ys>;
    using T = std::true_type;
    using F = std::false_type;
    if (checked) {
        if (ys)
            has_amp_ ? run(YS{}, T{}, T{}) : run(YS{}, F{}, T{});
        else
            has_amp_ ? run(Y{}, T{}, T{}) : run(Y{}, F{}, T{});
    } else {
        if (ys)
            has_amp_ ? run(YS{}, T{}, F{}) : run(YS{}, F{}, F{});
        else
            has_amp_ ? run(Y{}, T{}, F{}) : run(Y{}, F{}, F{});
    }
}

template <int N, int sensed, bool has_amp, bool checked, bool fractional>
void Loop::run_linear(const double* force, Eigen::Index n, Channels out, const double* noise) {
    using namespace state;
    // Local copies: the coefficients and the controller state stay in registers instead of being
    // reloaded after every store to the output arrays (which the compiler must assume may alias them).
    const CascadeMap map = *map_;
    const ControlLaw<N> law = controller_.law<N>();
    std::array<double, N> s;
    std::copy_n(controller_.state(), N, s.begin());
    double xy = x_[y], xv = x_[v], xi = x_[i], xf = x_[i_f], xs = x_[ys];
    double u_prev = u_prev_;
    const double limit = limit_, touchdown = touchdown_;
    const bool has_clearance = std::isfinite(touchdown);  // else a diverging y (Inf) is no touchdown
    Eigen::Index saturated = 0;
    for (Eigen::Index j = 0; j < n; ++j) {
        const double e = (sensed == ys ? xs : xy) + noise[j];
        const double wanted = controller_.delayed(law(e, s.data()));
        // The amplifier's limit (with none, clamping to +-Inf would change nothing, not even a bit).
        const double u = checked ? std::clamp(wanted, -limit, limit) : wanted;
        if constexpr (checked) saturated += u != wanted;
        out.displacement[j] = e;
        out.current[j] = has_amp ? xi : u;
        if constexpr (fractional) {
            map.advance(xy, xv, xi, xf, xs, force[j], u, u_prev);
            u_prev = u;
        } else {
            map.advance(xy, xv, xi, xf, xs, force[j], u);
        }
        if constexpr (checked)
            if (has_clearance && std::abs(xy) >= touchdown)
                throw Touchdown((k_ + j + 1) * T_, xy, static_cast<long>(k_ + j + 1));
    }
    std::copy_n(s.begin(), N, controller_.state());
    saturated_ += saturated;
    u_prev_ = u_prev;
    x_ << xy, xv, xi, xf, xs;
    // Inf and NaN never turn finite again in a linear recursion, so one check per chunk suffices.
    if (!x_.allFinite()) {
        Eigen::Index j = 0;
        while (j < n && std::isfinite(out.displacement[j])) ++j;
        fail(k_ + j, "the displacement became non-finite: the loop is unstable");
    }
}

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
    // One period from rest of the noise-free linear loop without limits, by the same kernel.
    Rig quiet = rig_;
    quiet.force_law = ForceLaw::linear;
    quiet.sensor_noise = quiet.force_noise = 0.0;
    quiet.clearance.reset();
    quiet.current_limit.reset();
    Controller own = controller_.controller();  // the dead time's whole samples are in its delay already
    own.delay -= split_dead_time(rig_.dead_time, T_).samples;
    Loop probe(quiet, own);
    Eigen::VectorXd f(L), y(L), i(L);
    probe.run(period_force, L, {f.data(), y.data(), i.data()});
    const ClosedLoopMap map(plant_ ? *plant_ : sample_map(quiet, T_), sensed_, controller_.controller(), fraction_);
    Eigen::VectorXd z = periodic_start(map.M, L, probe.stacked_state());
    if (rig_.sensor_noise > 0.0) {
        NormalStream draws(start_noise_seed(seed_));
        Eigen::VectorXd w(z.size());
        draws.fill(w.data(), w.size(), 1.0);
        z += stationary_noise_root(map.M, map.noise_in, rig_.sensor_noise) * w;
    }
    set_stacked_state(z);
    transducer_.set_state(periodic_transducer_start(transducer_.pole(), L, probe.transducer().state()));
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
