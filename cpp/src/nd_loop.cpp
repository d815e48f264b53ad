#include "amb_fast/nd_loop.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>

#include "amb_fast/blocks.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/plant.hpp"

namespace amb_fast {

namespace {
using Eigen::Index;
using Eigen::MatrixXd;
constexpr double two_pi = 6.283185307179586;

std::string shape(const MatrixXd& m) { return std::to_string(m.rows()) + "x" + std::to_string(m.cols()); }

void require_shape(const char* name, const MatrixXd& m, Index rows, Index cols) {
    const std::string expected = std::to_string(rows) + "x" + std::to_string(cols);
    require(m.rows() == rows && m.cols() == cols, name, shape(m), expected.c_str());
    require(m.allFinite(), name, "a non-finite entry", "finite");
}

void validate(const NdStructure& s, const NdChains& c, double fs, const NdController* k) {
    const Index n = s.mass.rows(), N = s.actuators.rows();
    require(n >= 1 && N >= 1 && N <= n, "structure", shape(s.actuators), "N x n actuators with 1 <= N <= n");
    for (auto [name, m] : {std::pair{"mass", &s.mass},
                           {"gyroscopic", &s.gyroscopic},
                           {"stiffness", &s.stiffness},
                           {"damping", &s.damping}})
        require_shape(name, *m, n, n);
    require_shape("actuators", s.actuators, N, n);
    require_shape("probes", s.probes, N, n);
    require(std::isfinite(s.speed), "speed", s.speed, "finite (rad/s)");
    for (auto [name, v] : {std::pair{"kyy", &c.kyy},
                           {"kiy", &c.kiy},
                           {"amp_bandwidth", &c.amp_bandwidth},
                           {"eddy_bandwidth", &c.eddy_bandwidth},
                           {"sensor_bandwidth", &c.sensor_bandwidth},
                           {"mass_loading", &c.mass_loading},
                           {"dead_time", &c.dead_time},
                           {"force_coupling_tau", &c.force_coupling_tau}})
        require(v->size() == N, name, std::to_string(v->size()) + " entries", "one entry per axis");
    for (Index j = 0; j < N; ++j) {
        require(std::isfinite(c.kyy[j]), "kyy", c.kyy[j], "finite (N/m)");
        require(std::isfinite(c.kiy[j]), "kiy", c.kiy[j], "finite (N/A)");
        for (auto [name, v, unit] : {std::tuple{"amp_bandwidth", &c.amp_bandwidth, "Hz; NaN: an ideal stage"},
                                     {"eddy_bandwidth", &c.eddy_bandwidth, "Hz; NaN: an ideal stage"},
                                     {"sensor_bandwidth", &c.sensor_bandwidth, "Hz; NaN: an ideal stage"},
                                     {"force_coupling_tau", &c.force_coupling_tau, "s; NaN: DC coupled"}})
            if (!std::isnan((*v)[j])) require_positive(name, (*v)[j], unit);
        require(std::isfinite(c.mass_loading[j]) && c.mass_loading[j] >= 0, "mass_loading", c.mass_loading[j],
                "finite and >= 0 (kg)");
        require(std::isfinite(c.dead_time[j]) && c.dead_time[j] >= 0, "dead_time", c.dead_time[j],
                "finite and >= 0 (s)");
    }
    if (fs != 0.0 || k) require_positive("fs", fs, "Hz");
    if (!k) return;
    const Index m = k->A.rows();
    require_shape("controller A", k->A, m, m);
    require_shape("controller B", k->B, m, N);
    require_shape("controller C", k->C, N, m);
    require_shape("controller D", k->D, N, N);
}

// Per coordinate its position and velocity, each axis' chain after its coordinate (the first N); returns
// the number of states.
int lay_out(const NdChains& c, Index n, NdLoop& out) {
    const auto N = static_cast<std::size_t>(c.kyy.size());
    out.coil.assign(N, -1), out.eddy.assign(N, -1), out.sensor.assign(N, -1);
    int at = 0;
    for (Index k = 0; k < n; ++k) {
        out.position.push_back(at++);
        out.velocity.push_back(at++);
        if (k >= c.kyy.size()) continue;
        const auto j = static_cast<std::size_t>(k);
        if (!std::isnan(c.amp_bandwidth[k])) out.coil[j] = at++;
        if (!std::isnan(c.eddy_bandwidth[k])) out.eddy[j] = at++;
        if (!std::isnan(c.sensor_bandwidth[k])) out.sensor[j] = at++;
    }
    return at;
}

void continuous(const NdStructure& s, const NdChains& c, NdLoop& out) {
    const Index n = s.mass.rows(), N = s.actuators.rows();
    const int size = lay_out(c, n, out);
    MatrixXd& A = out.A = MatrixXd::Zero(size, size);
    MatrixXd& B = out.B = MatrixXd::Zero(size, 2 * N);
    const MatrixXd& act = s.actuators;
    const MatrixXd mass = s.mass + act.transpose() * c.mass_loading.asDiagonal() * act;
    const Eigen::PartialPivLU<MatrixXd> lu(mass);
    require(lu.rcond() > 1e-14, "mass (with the axes' mass loading)", "a singular matrix", "invertible");
    const MatrixXd stiffness = lu.solve(s.stiffness + act.transpose() * c.kyy.asDiagonal() * act);
    const MatrixXd damping = lu.solve(s.damping + s.speed * s.gyroscopic);
    const MatrixXd forcing = lu.solve(act.transpose());  // n x N: a unit force at each axis' bearing plane
    for (Index r = 0; r < n; ++r) {
        const int vr = out.velocity[static_cast<std::size_t>(r)];
        A(out.position[static_cast<std::size_t>(r)], vr) = 1.0;
        for (Index k = 0; k < n; ++k) {
            A(vr, out.position[static_cast<std::size_t>(k)]) = -stiffness(r, k);
            A(vr, out.velocity[static_cast<std::size_t>(k)]) = -damping(r, k);
        }
        B.block(vr, 0, 1, N) = forcing.row(r);
    }
    out.S = MatrixXd::Zero(N, size);
    for (Index j = 0; j < N; ++j) {
        const auto a = static_cast<std::size_t>(j);
        const int coil = out.coil[a], eddy = out.eddy[a], sensor = out.sensor[a];
        // The magnet's force -kiy i_f, from the eddy stage, the coil or the command itself.
        const int source = eddy >= 0 ? eddy : coil;
        for (Index r = 0; r < n; ++r) {
            const int vr = out.velocity[static_cast<std::size_t>(r)];
            (source >= 0 ? A(vr, source) : B(vr, N + j)) += -c.kiy[j] * forcing(r, j);
        }
        // Each first-order stage relaxes to its input at w = 2 pi * bandwidth.
        if (coil >= 0) {
            A(coil, coil) = -two_pi * c.amp_bandwidth[j];
            B(coil, N + j) = two_pi * c.amp_bandwidth[j];
        }
        if (eddy >= 0) {
            A(eddy, eddy) = -two_pi * c.eddy_bandwidth[j];
            (coil >= 0 ? A(eddy, coil) : B(eddy, N + j)) = two_pi * c.eddy_bandwidth[j];
        }
        // The probe reads the structure through its lag, or directly.
        const double w = sensor >= 0 ? two_pi * c.sensor_bandwidth[j] : 0.0;
        if (sensor >= 0) A(sensor, sensor) = -w, out.S(j, sensor) = 1.0;
        for (Index k = 0; k < n; ++k) {
            const int p = out.position[static_cast<std::size_t>(k)];
            if (sensor >= 0) A(sensor, p) += w * s.probes(j, k);
            else out.S(j, p) = s.probes(j, k);
        }
    }
}

// A polynomial of the augmented matrix [[A, B], [0, 0]] keeps its form [[P, Q], [0, c I]]: a product of
// two costs n^3 + n^2 m instead of (n + m)^3.
struct Augmented {
    MatrixXd P, Q;
    double c;
    Augmented operator*(const Augmented& y) const { return {P * y.P, P * y.Q + y.c * Q, c * y.c}; }
    Augmented operator+(const Augmented& y) const { return {P + y.P, Q + y.Q, c + y.c}; }
};

// sum_k w[k] X^(2k + 2) + w0 I over (X^2, X^4, X^6).
Augmented sum(const Augmented (&X)[3], const double (&w)[3], double w0) {
    Augmented out{w[0] * X[0].P + w[1] * X[1].P + w[2] * X[2].P, w[0] * X[0].Q + w[1] * X[1].Q + w[2] * X[2].Q, w0};
    out.P.diagonal().array() += w0;
    return out;
}

// exp([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]], returned as [Phi, Gamma]: scaling and squaring with the
// [13/13] Pade approximant (Higham 2005, as Eigen's MatrixFunctions and scipy's expm), on the blocks.
MatrixXd hold(const MatrixXd& A, const MatrixXd& B, double h) {
    const Index n = A.rows(), m = B.cols();
    constexpr const auto& b = pade13;
    const double norm =
        std::max(h * A.cwiseAbs().colwise().sum().maxCoeff(), h * B.cwiseAbs().colwise().sum().maxCoeff());
    int squarings = 0;
    std::frexp(norm / 5.371920351148152, &squarings);  // theta_13
    squarings = std::max(squarings, 0);
    const double scale = std::ldexp(h, -squarings);
    const Augmented X{A * scale, B * scale, 0.0};
    const Augmented X2 = X * X, X4 = X2 * X2, X6 = X4 * X2;
    const Augmented powers[3] = {X2, X4, X6};
    const Augmented U = X * (X6 * sum(powers, {b[9], b[11], b[13]}, 0.0) + sum(powers, {b[3], b[5], b[7]}, b[1]));
    const Augmented V = X6 * sum(powers, {b[8], b[10], b[12]}, 0.0) + sum(powers, {b[2], b[4], b[6]}, b[0]);
    // (V - U)^-1 (V + U): both corners are b0 I, so the quotient's is I and its Q block (V - U)^-1 2 U.Q.
    const Eigen::PartialPivLU<MatrixXd> lu(V.P - U.P);
    MatrixXd Phi = lu.solve(V.P + U.P), Gamma = lu.solve(2.0 * U.Q);
    for (int k = 0; k < squarings; ++k) {
        Gamma = Phi * Gamma + Gamma;
        Phi = Phi * Phi;
    }
    MatrixXd out(n, n + m);
    out << Phi, Gamma;
    return out;
}

// An axis with dead time m T + delta gets a command line (dead1 .. dead<m + (delta > 0)>): x[k+1] = Phi x
// + Gf f + G0 u[k-m] + G1 u[k-m-1], G0 = Gamma_u(T - delta), G1 = Phi(T - delta) Gamma_u(delta).
void discrete(const NdChains& c, double fs, NdLoop& out) {
    const Index n = out.A.rows(), N = c.kyy.size();
    const double T = 1.0 / fs;
    std::vector<DeadTime> splits;
    Index size = n;
    for (Index j = 0; j < N; ++j) {
        splits.push_back(split_dead_time(c.dead_time[j], T));
        out.lines.push_back(splits.back().samples + (splits.back().fraction > 0));
        size += out.lines.back();
    }
    double fraction = -1.0;  // axes of one dead time share the fraction's two holds
    MatrixXd late, early, whole;
    const auto holds = [&](double f) {
        fraction = f;
        late = hold(out.A, out.B, T - f), early = hold(out.A, out.B, f);
    };
    const auto first = std::find_if(splits.begin(), splits.end(), [](DeadTime d) { return d.fraction > 0; });
    if (first == splits.end()) {
        whole = hold(out.A, out.B, T);
    } else {  // the sample as its two pieces: one matrix exponential fewer
        holds(first->fraction);
        whole.resize(n, n + 2 * N);
        whole << late.leftCols(n) * early.leftCols(n),
            late.leftCols(n) * early.rightCols(2 * N) + late.rightCols(2 * N);
    }
    out.Phi = MatrixXd::Zero(size, size);
    out.Gamma = MatrixXd::Zero(size, 2 * N);
    out.Phi.topLeftCorner(n, n) = whole.leftCols(n);
    out.Gamma.topLeftCorner(n, N) = whole.middleCols(n, N);
    Index at = n;
    for (Index j = 0; j < N; ++j) {
        const DeadTime split = splits[static_cast<std::size_t>(j)];
        const int line = out.lines[static_cast<std::size_t>(j)];
        Eigen::VectorXd G0 = whole.col(n + N + j);
        if (split.fraction > 0) {
            if (split.fraction != fraction) holds(split.fraction);
            G0 = late.col(n + N + j);
            out.Phi.block(0, at + line - 1, n, 1) = late.leftCols(n) * early.col(n + N + j);
        }
        if (split.samples == 0) out.Gamma.block(0, N + j, n, 1) = G0;
        else out.Phi.block(0, at + split.samples - 1, n, 1) = G0;
        if (line > 0) out.Gamma(at, N + j) = 1.0;                          // dead1' = u
        for (int k = 1; k < line; ++k) out.Phi(at + k, at + k - 1) = 1.0;  // dead(k+1)' = dead(k)
        at += line;
    }
}

// z[k+1] = M z + Bf f + Bn n, o = C z + Dn n: the plant's states, then the controller's.
void closed(const NdChains& c, double fs, const NdController& k, NdLoop& out) {
    const Index n = out.Phi.rows(), m = k.A.rows(), N = c.kyy.size();
    MatrixXd S = MatrixXd::Zero(N, n);
    S.leftCols(out.S.cols()) = out.S;
    const MatrixXd Gu = out.Gamma.rightCols(N), GuD = Gu * k.D;
    out.M.resize(n + m, n + m);
    out.M << out.Phi + GuD * S, Gu * k.C, k.B * S, k.A;
    out.Bf = MatrixXd::Zero(n + m, N);
    out.Bf.topRows(n) = out.Gamma.leftCols(N);
    out.Bn.resize(n + m, N);
    out.Bn << GuD, k.B;
    out.C = MatrixXd::Zero(2 * N, n + m);
    out.Dn = MatrixXd::Zero(2 * N, N);
    out.C.topLeftCorner(N, n) = S;
    out.Dn.topRows(N).setIdentity();
    Index line = out.A.rows();  // the axis' command line starts here
    for (Index j = 0; j < N; ++j) {
        const auto a = static_cast<std::size_t>(j);
        const int whole = split_dead_time(c.dead_time[j], 1.0 / fs).samples;
        if (out.coil[a] >= 0) {
            out.C(N + j, out.coil[a]) = 1.0;
        } else if (whole > 0) {
            out.C(N + j, line + whole - 1) = 1.0;  // the command dead<whole> samples old
        } else {
            out.C.block(N + j, 0, 1, n) = k.D.row(j) * S;
            out.C.block(N + j, n, 1, m) = k.C.row(j);
            out.Dn.row(N + j) = k.D.row(j);
        }
        line += out.lines[a];
    }
    out.poles = c.force_coupling_tau.unaryExpr(
        [fs](double tau) { return std::isnan(tau) ? 0.0 : std::exp(-1.0 / (fs * tau)); });
}
}  // namespace

NdLoop nd_loop(const NdStructure& structure, const NdChains& chains, double fs, const NdController* controller) {
    validate(structure, chains, fs, controller);
    NdLoop out;
    continuous(structure, chains, out);
    if (fs > 0) discrete(chains, fs, out);
    if (controller) closed(chains, fs, *controller, out);
    return out;
}

std::vector<NdLoop> nd_loops(const std::vector<NdPoint>& points, int workers) {
    std::vector<NdLoop> out(points.size());
    in_blocks(static_cast<Index>(points.size()), 1, workers, [&] {
        return [&](Index begin, Index end) {
            for (Index i = begin; i < end; ++i) {
                const NdPoint& p = points[static_cast<std::size_t>(i)];
                out[static_cast<std::size_t>(i)] =
                    nd_loop(p.structure, p.chains, p.fs, p.closed ? &p.controller : nullptr);
            }
        };
    });
    return out;
}

}  // namespace amb_fast
