#include "amb_fast/loop.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "amb_fast/errors.hpp"

namespace amb_fast {

Loop::Loop(const Rig& rig, const Pid& pid)
    : rig_(validated(rig)),
      pid_(validated(pid)),
      T_(pid.period()),
      sensed_(rig.sensor_bandwidth ? state::ys : state::y),
      has_amp_(rig.amp_bandwidth.has_value()),
      drive_(force_current_index(rig)) {
    if (rig_.force_law == ForceLaw::linear) {
        P_ = propagator(rig_, T_);
    } else {
        const double h = T_ / rig_.substeps;
        P_ = propagator(rig_, h);
        P_half_ = propagator(rig_, h / 2);
    }
}

void Loop::run(const double* force, Eigen::Index n, double* displacement, double* current) {
    if (rig_.force_law == ForceLaw::linear)
        run_linear(force, n, displacement, current);
    else
        run_nonlinear(force, n, displacement, current);
}

void Loop::run_linear(const double* force, Eigen::Index n, double* displacement, double* current) {
    const StateMatrix Phi = P_.topLeftCorner<state::size, state::size>();
    const StateVector gamma_f = P_.block<state::size, 1>(0, augmented::f);
    const StateVector gamma_i = P_.block<state::size, 1>(0, augmented::i_cmd);
    StateVector x = x_;
    for (Eigen::Index j = 0; j < n; ++j) {
        const double e = x[sensed_];
        const double i_cmd = pid_.step(e);
        displacement[j] = e;
        current[j] = has_amp_ ? x[state::i] : i_cmd;
        // Summed as a tree: the x-to-x dependency chain, not the flop count, bounds this loop.
        const StateVector inputs = gamma_f * force[j] + gamma_i * i_cmd;
        x = ((Phi.col(0) * x[0] + Phi.col(1) * x[1]) + (Phi.col(2) * x[2] + Phi.col(3) * x[3])) +
            (Phi.col(4) * x[4] + inputs);
    }
    x_ = x;
    // Inf and NaN never turn finite again in a linear recursion, so one check per chunk suffices.
    if (!x_.allFinite()) {
        Eigen::Index j = 0;
        while (j < n && std::isfinite(displacement[j])) ++j;
        fail(k_ + j, "the displacement became non-finite: the loop is unstable");
    }
    k_ += n;
}

void Loop::run_nonlinear(const double* force, Eigen::Index n, double* displacement, double* current) {
    const double gap = rig_.gap();
    for (Eigen::Index j = 0; j < n; ++j) {
        const double e = x_[sensed_];
        const double i_cmd = pid_.step(e);
        displacement[j] = e;
        current[j] = has_amp_ ? x_[state::i] : i_cmd;
        AugmentedVector X;
        X << x_, force[j], i_cmd;
        advance_nonlinear(X);
        x_ = X.head<state::size>();
        if (!(std::abs(x_[state::y]) < gap))  // also catches NaN
            fail(k_ + j + 1, "the platform reached the magnet air gap (non-linear force law)");
    }
    k_ += n;
}

// Integrating-factor (Lawson) RK4: the linear plant, lags and held inputs are propagated exactly by
// the matrix exponential; RK4 integrates only the non-linear remainder of the magnet force, which
// acts on v alone. Exact when the remainder vanishes, fourth order otherwise, and free of the
// step-size limit that the fast lags would put on plain RK4.
void Loop::advance_nonlinear(AugmentedVector& X) const {
    using state::v;
    const double h = T_ / rig_.substeps;
    const double kyy = rig_.kyy, kiy = rig_.kiy, inv_m = 1.0 / rig_.mass;
    const auto remainder = [&](double y, double i) {
        return (rig_.magnet_force(y, i) + kyy * y + kiy * i) * inv_m;
    };
    const auto& E = P_;
    const auto& E2 = P_half_;
    const int d = drive_;
    for (int s = 0; s < rig_.substeps; ++s) {
        const AugmentedVector half = E2 * X;
        const AugmentedVector full = E * X;
        const double a = remainder(X[state::y], X[d]);
        const double b = remainder(half[state::y] + 0.5 * h * a * E2(state::y, v), half[d] + 0.5 * h * a * E2(d, v));
        const double c = remainder(half[state::y], half[d]);
        const double dd = remainder(full[state::y] + h * c * E2(state::y, v), full[d] + h * c * E2(d, v));
        X = full + (h / 6.0) * (a * E.col(v) + 2.0 * (b + c) * E2.col(v));
        X[v] += (h / 6.0) * dd;
    }
}

void Loop::fail(Eigen::Index sample, const char* what) const {
    std::ostringstream msg;
    msg << what << " (at sample " << sample << ", t = " << sample * T_ << " s)";
    throw std::overflow_error(msg.str());
}

void simulate(const Rig& rig, const Pid& pid, const double* force, Eigen::Index n, double* displacement,
              double* current) {
    for (Eigen::Index k = 0; k < n; ++k) {
        if (!std::isfinite(force[k])) {
            std::ostringstream msg;
            msg << "force must be finite, got " << force[k] << " at sample " << k;
            throw std::invalid_argument(msg.str());
        }
    }
    Loop loop(rig, pid);
    loop.run(force, n, displacement, current);
}

}  // namespace amb_fast
