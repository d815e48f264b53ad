#include "amb_fast/plant.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include "amb_fast/errors.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace amb_fast {

namespace {
constexpr double two_pi = 6.283185307179586;
}

void Rig::validate() const {
    require_positive("mass", mass, "kg");
    require(std::isfinite(kyy) && kyy != 0.0, "kyy", kyy, "finite and non-zero (N/m)");
    require_positive("kiy", kiy, "N/A");
    require_positive("bias_current", bias_current, "A");
    if (amp_bandwidth) require_positive("amp_bandwidth", *amp_bandwidth, "Hz");
    if (eddy_bandwidth) require_positive("eddy_bandwidth", *eddy_bandwidth, "Hz");
    if (sensor_bandwidth) require_positive("sensor_bandwidth", *sensor_bandwidth, "Hz");
    require(substeps >= 1, "substeps", substeps, "an integer >= 1");
    require(std::isfinite(sensor_noise) && sensor_noise >= 0.0, "sensor_noise", sensor_noise,
            "finite and >= 0 (m rms)");
    require(std::isfinite(force_noise) && force_noise >= 0.0, "force_noise", force_noise, "finite and >= 0 (N rms)");
    require(std::isfinite(mass_loading) && mass_loading >= 0.0, "mass_loading", mass_loading, "finite and >= 0 (kg)");
    if (force_coupling_tau) require_positive("force_coupling_tau", *force_coupling_tau, "s");
    if (current_limit) require_positive("current_limit", *current_limit, "A");
    if (clearance) {
        require_positive("clearance", *clearance, "m");
        if (force_law == ForceLaw::nonlinear)
            require(*clearance < gap(), "clearance", *clearance, "below the air gap i0 Kiy / (-Kyy) (m)");
    }
    require(std::isfinite(dead_time) && dead_time >= 0.0, "dead_time", dead_time, "finite and >= 0 (s)");
    if (force_law == ForceLaw::nonlinear)
        require(kyy < 0.0, "kyy", kyy, "< 0 for the non-linear force law of a biased magnet pair (N/m)");
}

double Rig::gap() const { return bias_current * kiy / (-kyy); }

double Rig::touchdown_at() const {
    if (clearance) return *clearance;
    return force_law == ForceLaw::nonlinear ? gap() : std::numeric_limits<double>::infinity();
}

double Rig::command_limit() const {
    const double coils = force_law == ForceLaw::nonlinear ? bias_current : std::numeric_limits<double>::infinity();
    return current_limit ? std::min(*current_limit, coils) : coils;
}

double Rig::magnet_force(double y, double i) const { return MagnetPair(*this).force(y, i); }

void continuous_model(const Rig& rig, StateMatrix& A, InputMatrix& B) {
    using namespace state;
    A.setZero();
    B.setZero();
    // Where the current driving each stage comes from: a state, or the command itself.
    auto feed = [&](int row, int source_state, double gain) {
        if (source_state >= 0) A(row, source_state) += gain;
        else B(row, 1) += gain;
    };
    const int amp = rig.amp_bandwidth ? i : -1;
    const int eddy = rig.eddy_bandwidth ? i_f : amp;

    A(y, v) = 1.0;
    const double m = rig.moving_mass();
    A(v, y) = -rig.kyy / m;
    B(v, 0) = 1.0 / m;
    feed(v, eddy, -rig.kiy / m);
    if (rig.amp_bandwidth) {
        const double wa = two_pi * *rig.amp_bandwidth;
        A(i, i) = -wa;
        B(i, 1) = wa;
    }
    if (rig.eddy_bandwidth) {
        const double we = two_pi * *rig.eddy_bandwidth;
        A(i_f, i_f) = -we;
        feed(i_f, amp, we);
    }
    if (rig.sensor_bandwidth) {
        const double ws = two_pi * *rig.sensor_bandwidth;
        A(ys, ys) = -ws;
        A(ys, y) = ws;
    }
}

Propagator propagator(const Rig& rig, double h) {
    StateMatrix A;
    InputMatrix B;
    continuous_model(rig, A, B);
    Propagator M = Propagator::Zero();
    M.topLeftCorner<state::size, state::size>() = A * h;
    M.topRightCorner<state::size, 2>() = B * h;
    return M.exp();
}

DeadTime split_dead_time(double dead_time, double T) {
    // Each whole sample of dead time is a state of the loop (its poles, steady start and solves grow as the
    // cube): a bound keeps a mistyped dead time (1 s for 1 ms) from a run of hours, and the int exact.
    const double late = std::floor(dead_time / T);
    require(late <= max_dead_samples, "dead_time", dead_time,
            "at most 1000 samples of the controller (1000 / fs s): each sample of dead time is a state of the loop");
    const int samples = static_cast<int>(late);
    return {samples, std::max(0.0, dead_time - samples * T)};
}

SampleMap sample_map(const Rig& rig, double T) {
    const double fraction = split_dead_time(rig.dead_time, T).fraction;
    const Propagator whole = propagator(rig, T);
    SampleMap map;
    map.Phi = whole.topLeftCorner<state::size, state::size>();
    map.Gf = whole.block<state::size, 1>(0, augmented::f);
    if (fraction == 0.0) {
        map.G0 = whole.block<state::size, 1>(0, augmented::i_cmd);
        map.G1.setZero();
        return map;
    }
    const Propagator late = propagator(rig, T - fraction), early = propagator(rig, fraction);
    map.G0 = late.block<state::size, 1>(0, augmented::i_cmd);
    map.G1 = late.topLeftCorner<state::size, state::size>() * early.block<state::size, 1>(0, augmented::i_cmd);
    return map;
}

CascadeMap::CascadeMap(const SampleMap& map) {
    using namespace state;
    const StateMatrix& P = map.Phi;
    const double skipped = std::abs(P(i, y)) + std::abs(P(i, v)) + std::abs(P(i, i_f)) + std::abs(P(i_f, y)) +
                           std::abs(P(i_f, v)) + P.block<4, 1>(0, ys).cwiseAbs().sum();
    if (skipped > 1e-14 * P.cwiseAbs().maxCoeff())
        throw std::logic_error("amb_fast: the one-sample map lost its cascade structure; please report this rig");
    yy = P(y, y), yv = P(y, v), yi = P(y, i), yf = P(y, i_f);
    vy = P(v, y), vv = P(v, v), vi = P(v, i), vf = P(v, i_f);
    ii = P(i, i), fi = P(i_f, i), ff = P(i_f, i_f);
    sy = P(ys, y), sv = P(ys, v), si = P(ys, i), sf = P(ys, i_f), ss = P(ys, ys);
    y_f = map.Gf[y], v_f = map.Gf[v], s_f = map.Gf[ys];
    y_u = map.G0[y], v_u = map.G0[v], i_u = map.G0[i], f_u = map.G0[i_f], s_u = map.G0[ys];
    y_p = map.G1[y], v_p = map.G1[v], i_p = map.G1[i], f_p = map.G1[i_f], s_p = map.G1[ys];
    fractional = !map.G1.isZero(0.0);
#if AMB_FAST_PAIRED_MAP
    pair_y = Pair{yy, vy}, pair_v = Pair{yv, vv}, pair_i = Pair{yi, vi}, pair_f = Pair{yf, vf};
    pair_force = Pair{y_f, v_f}, pair_u = Pair{y_u, v_u};
#endif
}

int force_current_index(const Rig& rig) {
    if (rig.eddy_bandwidth) return state::i_f;
    if (rig.amp_bandwidth) return state::i;
    return augmented::i_cmd;
}

}  // namespace amb_fast
