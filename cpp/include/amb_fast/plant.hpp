// The continuous plant of MODEL.md sections 1-2: platform, magnet pair, optional first-order lags.
#pragma once

#include <Eigen/Dense>
#include <optional>
#include <string>

#include "amb_fast/inline.hpp"

namespace amb_fast {

enum class ForceLaw { linear, nonlinear };

// SI units; bandwidths in Hz, an empty one is an ideal (pass-through) stage.
struct Rig {
    double mass = 0.92;          // kg
    double kyy = -53.3e3;        // N/m, position stiffness (negative: destabilising)
    double kiy = 47.19;          // N/A, current stiffness
    double bias_current = 0.65;  // A
    ForceLaw force_law = ForceLaw::linear;
    std::optional<double> amp_bandwidth;       // Hz, amplifier current loop
    std::optional<double> eddy_bandwidth;      // Hz, eddy-current force lag
    std::optional<double> sensor_bandwidth;    // Hz, displacement sensor
    int substeps = 2;                          // integrator steps per sample for the non-linear force law
    double sensor_noise = 0.0;                 // m rms, white, added to the sensor output (seen by the controller too)
    double force_noise = 0.0;                  // N rms, white, added to the recorded force (not to the applied one)
    double mass_loading = 0.0;                 // kg moving with the platform beyond `mass` (transducer, stinger)
    std::optional<double> force_coupling_tau;  // s, AC coupling of the piezo force transducer; empty = DC
    std::optional<double> clearance;           // m, mechanical clearance; empty: the air gap (non-linear law) or none
    std::optional<double> current_limit;       // A, amplifier limit on |i|; empty: i0 (non-linear law) or none
    double dead_time = 0.0;                    // s, transport delay from the current command to the amplifier

    // Throws std::invalid_argument naming the parameter and the value.
    void validate() const;
    // What the dynamics move: the known mass plus the mass loading (kg). Eq. 9 uses `mass` alone.
    double moving_mass() const { return mass + mass_loading; }
    // Nominal air gap g = i0 Kiy / (-Kyy) (m) of the force law that linearises to kyy, kiy.
    double gap() const;
    // |y| at which the platform touches down (m); infinite when there is no limit.
    double touchdown_at() const;
    // Largest |current command| the amplifier delivers (A): with the non-linear law the coil currents
    // i0 +/- i cannot go negative, so at most i0; infinite when there is no limit.
    double command_limit() const;
    // Force of the magnet pair on the platform (N) at displacement y (m) and control current i (A).
    double magnet_force(double y, double i) const;

    bool operator==(const Rig& o) const {
        return mass == o.mass && kyy == o.kyy && kiy == o.kiy && bias_current == o.bias_current &&
               force_law == o.force_law && amp_bandwidth == o.amp_bandwidth && eddy_bandwidth == o.eddy_bandwidth &&
               sensor_bandwidth == o.sensor_bandwidth && substeps == o.substeps && sensor_noise == o.sensor_noise &&
               force_noise == o.force_noise && mass_loading == o.mass_loading &&
               force_coupling_tau == o.force_coupling_tau && clearance == o.clearance &&
               current_limit == o.current_limit && dead_time == o.dead_time;
    }
};

// The differential magnet pair of MODEL.md section 4, its constants worked out once:
// F = km [ (i0 - i)^2 / (g - y)^2 - (i0 + i)^2 / (g + y)^2 ], linearising to -kyy y - kiy i.
struct MagnetPair {
    explicit MagnetPair(const Rig& rig)
        : i0(rig.bias_current), g(rig.gap()), km(rig.kiy * g * g / (4.0 * i0)), kyy(rig.kyy), kiy(rig.kiy) {}

    double force(double y, double i) const {
        const double r = 1.0 / ((g - y) * (g + y));  // one division for both coils
        const double lower = (i0 - i) * (g + y) * r, upper = (i0 + i) * (g - y) * r;
        return km * (lower * lower - upper * upper);
    }
    // What the linearised law leaves out: force(y, i) - (-kyy y - kiy i).
    double remainder(double y, double i) const { return force(y, i) + kyy * y + kiy * i; }

    double i0, g, km, kyy, kiy;
};

// Fixed state positions; a stage that is switched off keeps its state at exactly zero.
namespace state {
constexpr int y = 0, v = 1, i = 2, i_f = 3, ys = 4, size = 5;
}
using StateVector = Eigen::Matrix<double, state::size, 1>;
using StateMatrix = Eigen::Matrix<double, state::size, state::size>;
using InputMatrix = Eigen::Matrix<double, state::size, 2>;  // columns: force f, current command

// The state augmented with the two held inputs: X = [x, f, i_cmd]. Inputs are constant over a sample,
// so X' = [[A, B], [0, 0]] X and its matrix exponential propagates the linear plant exactly.
namespace augmented {
constexpr int f = state::size, i_cmd = state::size + 1, size = state::size + 2;
}
using AugmentedVector = Eigen::Matrix<double, augmented::size, 1>;
using Propagator = Eigen::Matrix<double, augmented::size, augmented::size>;

// The dead time as whole samples and the fraction of a sample left over (s, 0 <= fraction < T).
struct DeadTime {
    int samples;
    double fraction;
};
// The [13/13] Pade approximant's coefficients (Higham 2005, as Eigen's MatrixFunctions and scipy's expm): the
// holds' exponentials (nd_loop's hold, the Campbell diagram's speed_loops).
inline constexpr double pade13[] = {64764752532480000.0,
                                    32382376266240000.0,
                                    7771770303897600.0,
                                    1187353796428800.0,
                                    129060195264000.0,
                                    10559470521600.0,
                                    670442572800.0,
                                    33522128640.0,
                                    1323241920.0,
                                    40840800.0,
                                    960960.0,
                                    16380.0,
                                    182.0,
                                    1.0};

// The most whole samples of dead time a loop models (split_dead_time refuses more).
constexpr double max_dead_samples = 1000.0;
DeadTime split_dead_time(double dead_time, double T);

// The exact one-sample map of the linear plant with the fractional part of the dead time: over
// [kT, kT + fraction) the amplifier still receives the previous command, so
// x[k+1] = Phi x[k] + Gf f[k] + G0 u[k] + G1 u[k-1] (modified z-transform of the zero-order hold),
// G0 = Gamma_u(T - fraction), G1 = Phi(T - fraction) Gamma_u(fraction); without a fraction G1 = 0.
struct SampleMap {
    StateMatrix Phi;
    StateVector Gf, G0, G1;
};
SampleMap sample_map(const Rig& rig, double T);

// The exact one-sample map of the linear plant, written out. The lags form a cascade (amplifier ->
// eddy current -> platform -> sensor), so Phi is block lower-triangular in that order: only 16 of
// its 25 entries can be non-zero, and only those are multiplied. The loops that use it are bound by
// the latency of the sample-to-sample chain, so independent terms are summed pairwise. Every loop
// (single runs and batched sweeps) calls this one function, so all agree bit for bit.
#if defined(__GNUC__) || defined(__clang__)
#define AMB_FAST_PAIRED_MAP 1
#else
#define AMB_FAST_PAIRED_MAP 0
#endif

// The map's coefficients: doubles, or each broadcast to every SIMD lane (C = LaneVector, lanes.hpp) so
// that loops run side by side multiply whole vectors instead of broadcasting a scalar every sample.
template <class C>
struct CascadeCoefficients {
    // The rows one by one, for a double or for loops side by side in SIMD lanes.
    template <class T>
    AMB_FAST_ALWAYS_INLINE void advance_rows(T& xy, T& xv, T& xi, T& xf, T& xs, double f, T u) const {
        const T ny = (yy * xy + yv * xv) + (yi * xi + yf * xf) + (y_f * f + y_u * u);
        const T nv = (vy * xy + vv * xv) + (vi * xi + vf * xf) + (v_f * f + v_u * u);
        xs = advance_lags(xy, xv, xi, xf, xs, f, u);
        xy = ny;
        xv = nv;
    }
    // The rows after y and v: the sensor's new value returned, the eddy and coil currents advanced,
    // all from the old state.
    template <class T>
    AMB_FAST_ALWAYS_INLINE T advance_lags(T xy, T xv, T& xi, T& xf, T xs, double f, T u) const {
        const T ns = ((sy * xy + sv * xv) + (si * xi + sf * xf)) + (ss * xs + (s_f * f + s_u * u));
        xf = (fi * xi + ff * xf) + f_u * u;
        xi = ii * xi + i_u * u;
        return ns;
    }
    // The same with the previous command u_prev felt over the dead time's fraction of the sample.
    template <class T>
    AMB_FAST_ALWAYS_INLINE void advance(T& xy, T& xv, T& xi, T& xf, T& xs, double f, T u, T u_prev) const {
        const T ny = ((yy * xy + yv * xv) + (yi * xi + yf * xf) + (y_f * f + y_u * u)) + y_p * u_prev;
        const T nv = ((vy * xy + vv * xv) + (vi * xi + vf * xf) + (v_f * f + v_u * u)) + v_p * u_prev;
        const T ns = (((sy * xy + sv * xv) + (si * xi + sf * xf)) + (ss * xs + (s_f * f + s_u * u))) + s_p * u_prev;
        xf = ((fi * xi + ff * xf) + f_u * u) + f_p * u_prev;
        xi = (ii * xi + i_u * u) + i_p * u_prev;
        xy = ny;
        xv = nv;
        xs = ns;
    }
    // Every coefficient broadcast to the lanes of D: fill(D& lanes, double value).
    template <class D, class Fill>
    CascadeCoefficients<D> broadcast(Fill fill) const {
        CascadeCoefficients<D> out;
        const double* from[] = {&yy, &yv,  &yi,  &yf,  &vy,  &vv,  &vi,  &vf,  &ii,  &fi,  &ff,  &sy,  &sv,  &si, &sf,
                                &ss, &y_f, &v_f, &s_f, &y_u, &v_u, &i_u, &f_u, &s_u, &y_p, &v_p, &i_p, &f_p, &s_p};
        D* to[] = {&out.yy,  &out.yv,  &out.yi,  &out.yf,  &out.vy,  &out.vv,  &out.vi,  &out.vf,  &out.ii,  &out.fi,
                   &out.ff,  &out.sy,  &out.sv,  &out.si,  &out.sf,  &out.ss,  &out.y_f, &out.v_f, &out.s_f, &out.y_u,
                   &out.v_u, &out.i_u, &out.f_u, &out.s_u, &out.y_p, &out.v_p, &out.i_p, &out.f_p, &out.s_p};
        for (std::size_t k = 0; k < sizeof from / sizeof from[0]; ++k) fill(*to[k], *from[k]);
        return out;
    }

    C yy, yv, yi, yf, vy, vv, vi, vf, ii, fi, ff, sy, sv, si, sf, ss;  // Phi
    C y_f, v_f, s_f, y_u, v_u, i_u, f_u, s_u;                          // Gf, G0: force, command
    C y_p, v_p, i_p, f_p, s_p;                                         // G1: previous command
};

struct CascadeMap : CascadeCoefficients<double> {
    explicit CascadeMap(const SampleMap& map);  // throws std::logic_error if the map lost the structure

    using CascadeCoefficients<double>::advance;
    AMB_FAST_ALWAYS_INLINE void advance(double& xy, double& xv, double& xi, double& xf, double& xs, double f,
                                        double u) const {
#if AMB_FAST_PAIRED_MAP
        // y and v rows side by side: each lane does the scalar rows' operations in their order.
        const Pair n = ((pair_y * xy + pair_v * xv) + (pair_i * xi + pair_f * xf)) + (pair_force * f + pair_u * u);
        const double ny = n[0], nv = n[1];
        xs = advance_lags(xy, xv, xi, xf, xs, f, u);
        xy = ny;
        xv = nv;
#else
        advance_rows(xy, xv, xi, xf, xs, f, u);
#endif
    }

    bool fractional;  // G1 != 0
#if AMB_FAST_PAIRED_MAP
    using Pair = double __attribute__((vector_size(16)));
    Pair pair_y, pair_v, pair_i, pair_f, pair_force, pair_u;  // the y and v rows' coefficients, paired
#endif
};

// Linear(ised) continuous model x' = A x + B [f, i_cmd].
void continuous_model(const Rig& rig, StateMatrix& A, InputMatrix& B);

// exp([[A, B], [0, 0]] h): the exact zero-order-hold map [Phi, Gamma] over h, inputs carried unchanged.
Propagator propagator(const Rig& rig, double h);

// Index into the augmented state of the current that drives the magnet force: the eddy-current
// state, else the amplifier state, else the held command itself.
int force_current_index(const Rig& rig);

// Current that drives the magnet force and the coil current, by which stages are switched on.
inline double coil_current(const Rig& rig, const StateVector& x, double i_cmd) {
    return rig.amp_bandwidth ? x[state::i] : i_cmd;
}
inline double measured_displacement(const Rig& rig, const StateVector& x) {
    return rig.sensor_bandwidth ? x[state::ys] : x[state::y];
}

}  // namespace amb_fast
