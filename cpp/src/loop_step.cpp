// The loop sample by sample: run() chunk by chunk, the linear law through the kernel (loop_kernel.hpp),
// the non-linear law through its integrator.
#include "amb_fast/loop.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "amb_fast/errors.hpp"
#include "amb_fast/interrupt.hpp"
#include "loop_kernel.hpp"

namespace amb_fast {

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
        with_loop_shape(
            sensed_ == state::ys, has_amp_, checked(), map.fractional,
            [&](auto sensed, auto amp, auto check, auto frac) {
                constexpr int sensed_ = decltype(sensed)::value;
                constexpr bool amp_ = decltype(amp)::value, check_ = decltype(check)::value,
                               frac_ = decltype(frac)::value;
                if (local)
                    run_samples<double, n_, sensed_, amp_, check_, frac_, CascadeMap, true>(
                        map, law, x, force, n, noise, out.displacement, out.current, limit_, watch, *this, k_, draws);
                else
                    run_samples<double, n_, sensed_, amp_, check_, frac_>(
                        map, law, x, force, n, noise, out.displacement, out.current, limit_, watch, *this, k_);
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

}  // namespace amb_fast
