// The C++ core on its own, for the sanitizer build (AMB_FAST_SANITIZE): every path once, with checks
// against independent answers. The Python test suite is the full one; this driver exists so that
// AddressSanitizer and UndefinedBehaviorSanitizer see the core without an interpreter around it.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Eigenvalues>

#include "amb_fast/batch.hpp"
#include "amb_fast/campbell.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/estimate2x2.hpp"
#include "amb_fast/experiment.hpp"
#include "amb_fast/hessenberg.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/loop.hpp"
#include "amb_fast/mimo_lines.hpp"
#include "amb_fast/mimo_sweep.hpp"
#include "amb_fast/random.hpp"
#include "amb_fast/spectrum.hpp"
#include "amb_fast/steady.hpp"

using namespace amb_fast;
using cd = std::complex<double>;

namespace {
int passed = 0, failed = 0;

void check(bool ok, const std::string& what) {
    if (ok) {
        ++passed;
    } else {
        ++failed;
        std::printf("FAILED: %s\n", what.c_str());
    }
}

template <class Error>
void check_throws(const std::function<void()>& run, const std::string& what) {
    try {
        run();
    } catch (const Error&) {
        ++passed;
        return;
    } catch (const std::exception& other) {
        std::printf("FAILED: %s threw something else: %s\n", what.c_str(), other.what());
        ++failed;
        return;
    }
    std::printf("FAILED: %s did not throw\n", what.c_str());
    ++failed;
}

Rig lagged() {
    Rig rig;
    rig.amp_bandwidth = 1500.0;
    rig.eddy_bandwidth = 800.0;
    rig.sensor_bandwidth = 5000.0;
    return rig;
}

struct Gains {
    double kp = 2000.0, ki = 20000.0, kd = 5.0;
    std::optional<double> derivative_cutoff = 1000.0;
    double fs = 4000.0;
    int delay = 1;
    double period() const { return 1.0 / fs; }
    double filter_pole() const { return derivative_cutoff ? std::exp(-2.0 * M_PI * *derivative_cutoff / fs) : 0.0; }
    Controller controller() const { return pid_controller(kp, ki, kd, derivative_cutoff, fs, delay); }
};
Gains baseline() { return {}; }

// Y/F at harmonic b of an L-sample period by composing transfer functions: ys/f = Pf / (1 - Pi G z^-d).
cd receptance(const Rig& rig, const Gains& pid, double b, double L) {
    const Propagator P = propagator(rig, pid.period());
    const cd z = std::polar(1.0, 2.0 * M_PI * b / L);
    Eigen::Matrix<cd, state::size, state::size> M = z * Eigen::Matrix<cd, state::size, state::size>::Identity();
    M -= P.topLeftCorner<state::size, state::size>().cast<cd>();
    const Eigen::Matrix<cd, state::size, 2> X = M.partialPivLu().solve(P.topRightCorner<state::size, 2>().cast<cd>());
    const int sensed = rig.sensor_bandwidth ? state::ys : state::y;
    const double T = pid.period(), a = pid.filter_pole();
    const cd zi = 1.0 / z;
    const cd G = pid.kp + pid.ki * T / (1.0 - zi) + pid.kd * (1.0 - a) * (1.0 - zi) / (T * (1.0 - a * zi));
    return X(sensed, 0) / (1.0 - X(sensed, 1) * G * std::pow(zi, pid.delay));
}

std::vector<double> multisine(Eigen::Index L, int lines) {
    std::vector<double> f(static_cast<std::size_t>(L), 0.0);
    for (int n = 1; n <= lines; ++n)
        for (Eigen::Index k = 0; k < L; ++k)
            f[static_cast<std::size_t>(k)] +=
                0.1 *
                std::cos(2.0 * M_PI * n * static_cast<double>(k) / static_cast<double>(L) - M_PI * n * (n - 1) / lines);
    return f;
}
}  // namespace

int main() {
    const Rig rig = lagged();
    const Gains pid = baseline();
    const Controller ctrl = pid.controller();

    {  // A constant force: the integral brings the platform back, the current balances the force.
        std::vector<double> force(8000, 2.0), recorded(8000), y(8000), i(8000);
        simulate(rig, ctrl, force.data(), 8000, {recorded.data(), y.data(), i.data()});
        check(std::abs(y.back()) < 1e-12, "static displacement returns to zero");
        check(std::abs(i.back() - 2.0 / rig.kiy) < 1e-9 * 2.0 / rig.kiy, "static current = f / Kiy");
    }

    const Eigen::Index L = 400;  // 10 Hz fundamental at 4 kHz
    const int lines = 20;
    const std::vector<double> period = multisine(L, lines);
    const Eigen::Map<const Eigen::VectorXd> period_force(period.data(), L);
    LinePlan plan;
    plan.period = L;
    for (int n = 1; n <= lines; ++n) plan.excited.push_back(n);

    {  // A settled, noise-free experiment equals the exact sampled-data response.
        const LineEstimate e = run_experiment(rig, ctrl, period_force, 40, 4, plan, 0, 5);
        double worst = 0.0;
        for (int n = 1; n <= lines; ++n) {
            const cd exact = receptance(rig, pid, n, static_cast<double>(L));
            worst = std::max(worst, std::abs(1.0 / e.H[n - 1] - exact) / std::abs(exact));
        }
        check(worst < 1e-9, "experiment matches composed transfer functions (" + std::to_string(worst) + ")");
    }

    {  // Sweeps equal single runs bit for bit, with noise, mass loading, AC coupling and a current limit.
        Rig noisy = rig;
        noisy.sensor_noise = 1e-8;
        noisy.force_noise = 1e-3;
        noisy.mass_loading = 0.05;
        noisy.force_coupling_tau = 0.2;
        noisy.current_limit = 5.0;
        std::vector<SweepPoint> points;
        for (int g = 0; g < 37; ++g) {
            Gains p = pid;
            p.kp = 1800.0 + 20.0 * g, p.ki = 1e4, p.kd = 4.0;
            points.push_back({noisy, p.controller(), 3 + g % 2, 100u + g});
        }
        const SweepEstimates s = run_sweep(period_force, points, 3, plan, 5, 2);
        bool same = true;
        for (int g : {0, 17, 36}) {
            const LineEstimate e = run_experiment(noisy, points[g].controller, period_force, points[g].settle_periods,
                                                  3, plan, points[g].seed, 5);
            same = same && (s.H.row(g).transpose() - e.H).cwiseAbs().maxCoeff() == 0.0 && s.status[g] == 0;
        }
        check(same, "sweep rows equal single runs bit for bit");
        const SweepEstimates steady = run_sweep(period_force, points, 3, plan, 5, 2, true);
        bool steady_same = true;
        for (int g : {0, 17, 36}) {
            const LineEstimate e = run_experiment(noisy, points[g].controller, period_force, points[g].settle_periods,
                                                  3, plan, points[g].seed, 5, true);
            steady_same = steady_same && (steady.H.row(g).transpose() - e.H).cwiseAbs().maxCoeff() == 0.0;
        }
        check(steady_same, "steady-start sweep rows equal single steady-start runs bit for bit");
    }

    {  // From the periodic steady state, no settling: the first periods already equal the exact response.
        const LineEstimate e = run_experiment(rig, ctrl, period_force, 0, 2, plan, 0, 5, true);
        double worst = 0.0;
        for (int n = 1; n <= lines; ++n) {
            const cd exact = receptance(rig, pid, n, static_cast<double>(L));
            worst = std::max(worst, std::abs(1.0 / e.H[n - 1] - exact) / std::abs(exact));
        }
        check(worst < 1e-11, "steady start matches composed transfer functions (" + std::to_string(worst) + ")");
    }

    {  // The estimator on known sines: H = F/Y exactly.
        std::vector<double> f(L * 3), y(L * 3);
        for (Eigen::Index k = 0; k < L * 3; ++k) {
            const double t = 2.0 * M_PI * 3.0 * static_cast<double>(k) / static_cast<double>(L);
            f[static_cast<std::size_t>(k)] = std::cos(t);
            y[static_cast<std::size_t>(k)] = 0.5 * std::cos(t - 0.3) + 1e-3 * std::cos(2.0 * t);
        }
        LinePlan three;
        three.period = L;
        three.excited = {3};
        three.unexcited = {6};
        const LineEstimate e = identify(f.data(), y.data(), L * 3, 0, three, 1.0, 4000.0, 1);
        check(std::abs(e.H[0] - std::polar(2.0, 0.3)) < 1e-12, "estimator H of a known sine");
        check(std::abs(e.unexcited_displacement[0] - 1e-3) < 1e-12, "unexcited level of a known harmonic");
        f[L + 7] = NAN;
        check_throws<std::invalid_argument>([&] { identify(f.data(), y.data(), L * 3, 0, three, 1.0, 4000.0, 1); },
                                            "non-finite recording sample");
    }

    {  // Median filter: odd window, edges repeat.
        Eigen::VectorXd x(6);
        x << 5, 1, 9, 2, 8, 3;
        Eigen::VectorXd expected(6);
        expected << 5, 5, 2, 8, 3, 3;
        check((median_filter(x, 3) - expected).cwiseAbs().maxCoeff() == 0.0, "median filter");
        // Window 5 (a sorting network) against sorting each window, ties and edges included.
        Eigen::VectorXd y = Eigen::VectorXd::Random(301).array().round();
        const Eigen::VectorXd fast = median_filter(y, 5);
        bool same = true;
        for (Eigen::Index i = 0; i < y.size(); ++i) {
            std::vector<double> w;
            for (Eigen::Index j = i - 2; j <= i + 2; ++j) w.push_back(y[std::clamp<Eigen::Index>(j, 0, y.size() - 1)]);
            std::sort(w.begin(), w.end());
            same = same && fast[i] == w[2];
        }
        check(same, "median filter, window 5, equals sorting each window");
    }

    {  // Non-linear law: touchdown is an event; small amplitudes agree with the linear law.
        Rig pair = rig;
        pair.force_law = ForceLaw::nonlinear;
        std::vector<double> push(400, 200.0), r(400), y(400), i(400);
        check_throws<Touchdown>([&] { simulate(pair, ctrl, push.data(), 400, {r.data(), y.data(), i.data()}); },
                                "touchdown at the air gap");
        std::vector<double> small(2000), yl(2000), yn(2000), c(2000), r1(2000);
        for (std::size_t k = 0; k < small.size(); ++k) small[k] = 1e-3 * std::sin(0.05 * static_cast<double>(k));
        simulate(rig, ctrl, small.data(), 2000, {r1.data(), yl.data(), c.data()});
        std::vector<double> r2(2000);
        simulate(pair, ctrl, small.data(), 2000, {r2.data(), yn.data(), c.data()});
        double diff = 0.0, peak = 0.0;
        for (std::size_t k = 0; k < yl.size(); ++k)
            diff = std::max(diff, std::abs(yl[k] - yn[k])), peak = std::max(peak, std::abs(yl[k]));
        check(diff < 1e-6 * peak, "non-linear law is linear at small amplitude");
    }

    {  // Noise: the same numbers however a run is cut into calls, and N(0, 1) in its first moments.
        Rig noisy = rig;
        noisy.sensor_noise = 2e-8;
        noisy.force_noise = 1e-3;
        const Eigen::Index n = 5000;
        std::vector<double> f(static_cast<std::size_t>(n)), r1(f.size()), y1(f.size()), i1(f.size());
        for (std::size_t k = 0; k < f.size(); ++k) f[k] = std::sin(0.01 * static_cast<double>(k));
        std::vector<double> r2 = r1, y2 = y1, i2 = i1;
        Loop whole(noisy, ctrl, 42), pieces(noisy, ctrl, 42);
        whole.run(f.data(), n, {r1.data(), y1.data(), i1.data()});
        Eigen::Index at = 0;
        for (Eigen::Index m : {1, 999, 1024, 1, 2000, 975}) {
            pieces.run(f.data() + at, m, {r2.data() + at, y2.data() + at, i2.data() + at});
            at += m;
        }
        check(at == n && r1 == r2 && y1 == y2 && i1 == i2, "noisy loop in pieces equals one call bit for bit");
        NormalStream a(7), b(7);
        std::vector<double> one(100000), cut(100000);
        a.fill(one.data(), 100000, 1.0);
        b.fill(cut.data(), 33333, 1.0);
        b.fill(cut.data() + 33333, 66667, 1.0);
        check(one == cut, "noise stream in pieces equals one call");
#if AMB_FAST_LANES_OK
        {  // streams side by side in SIMD lanes: each lane exactly its own stream, rare paths included
            std::vector<NormalStream> streams, alone;
            for (std::uint64_t seed : {3u, 4u, 5u}) streams.emplace_back(seed), alone.emplace_back(seed);
            std::vector<NormalStream*> ptr;
            for (auto& st : streams) ptr.push_back(&st);
            NormalLanes<2> two(ptr.data(), 2);
            std::vector<double> lanes(2 * 30000), own(30000);
            two.fill(lanes.data(), 10000, 2.0);
            two.fill(lanes.data() + 20000, 20000, 2.0);  // in pieces, as a run's chunks
            two.commit();
            bool same = true;
            for (std::size_t g = 0; g < 2; ++g) {
                alone[g].fill(own.data(), 30000, 2.0);
                for (std::size_t j = 0; j < 30000; ++j) same = same && lanes[2 * j + g] == own[j];
            }
            alone[0].fill(own.data(), 10, 1.0);  // and the streams continue where their lanes stopped
            streams[0].fill(lanes.data(), 10, 1.0);
            for (std::size_t j = 0; j < 10; ++j) same = same && lanes[j] == own[j];
            NormalLanes<4> four(ptr.data(), 3);  // a spare lane, discarded
            std::vector<double> wide(4 * 5000);
            four.fill(wide.data(), 5000, 1.0);
            four.commit();
            for (std::size_t g = 0; g < 3; ++g) {
                alone[g].fill(own.data(), 5000, 1.0);
                for (std::size_t j = 0; j < 5000; ++j) same = same && wide[4 * j + g] == own[j];
            }
            check(same, "noise streams side by side in lanes equal each stream alone bit for bit");
        }
#endif
        double mean = 0.0, var = 0.0;
        for (double z : one) mean += z / 1e5, var += z * z / 1e5;
        check(std::abs(mean) < 5 / std::sqrt(1e5) && std::abs(var - 1) < 5 * std::sqrt(2 / 1e5), "noise moments");
    }

    {  // The estimator's transform: FFT and direct sum agree with a plain DFT of a known signal.
        const Eigen::Index L = 4001;  // prime: pocketfft's Bluestein path
        std::vector<double> x(static_cast<std::size_t>(L));
        for (std::size_t k = 0; k < x.size(); ++k)
            x[k] = std::cos(0.3 * static_cast<double>(k)) + 1e-3 * static_cast<double>(k % 7);
        const std::vector<Eigen::Index> bins{0, 1, 17, 2000};
        std::vector<cd> by_fft(bins.size()), by_sum(bins.size());
        LineTransform fft(L, bins, LineTransform::Method::fft), sum(L, bins, LineTransform::Method::direct);
        fft(x.data(), by_fft.data());
        sum(x.data(), by_sum.data());
        double worst = 0.0, scale = 0.0;
        for (std::size_t j = 0; j < bins.size(); ++j) {
            long double re = 0, im = 0;  // plain DFT in extended precision
            for (Eigen::Index k = 0; k < L; ++k) {
                const long double angle = -2.0L * 3.141592653589793238462643383279502884L *
                                          static_cast<long double>((bins[j] * k) % L) / static_cast<long double>(L);
                re += x[static_cast<std::size_t>(k)] * std::cos(angle);
                im += x[static_cast<std::size_t>(k)] * std::sin(angle);
            }
            const cd exact(static_cast<double>(re), static_cast<double>(im));
            scale = std::max(scale, std::abs(exact));
            worst = std::max({worst, std::abs(by_fft[j] - exact), std::abs(by_sum[j] - exact)});
        }
        check(worst < 1e-12 * scale, "line transform (FFT and direct sum) matches a plain DFT");
    }

    {  // Two channels at once (SIMD lanes where available) give the digits of two separate transforms.
        for (const Eigen::Index L : {Eigen::Index{4000}, Eigen::Index{4001}, Eigen::Index{1000}}) {
            std::vector<double> x(static_cast<std::size_t>(L)), y(x.size());
            for (std::size_t k = 0; k < x.size(); ++k) {
                x[k] = std::sin(0.01 * static_cast<double>(k * k % 997)) + 1e-9 * static_cast<double>(k % 13);
                y[k] = 1e-6 * std::cos(0.7 * static_cast<double>(k)) - 3e-8 * static_cast<double>(k % 5);
            }
            std::vector<Eigen::Index> bins;
            for (Eigen::Index b = 0; 2 * b <= L; b += 7) bins.push_back(b);
            if (L % 2 == 0) bins.push_back(L / 2);
            LineTransform t(L, bins, LineTransform::Method::fft);
            std::vector<cd> x1(bins.size()), y1(bins.size()), x2(bins.size()), y2(bins.size());
            t(x.data(), x1.data());
            t(y.data(), y1.data());
            t(x.data(), y.data(), x2.data(), y2.data());
            check(x1 == x2 && y1 == y2, "paired line transform equals two single ones bit for bit");
        }
    }

    {  // Bad input.
        Rig bad = rig;
        bad.mass = -1.0;
        check_throws<std::invalid_argument>([&] { bad.validate(); }, "negative mass");
        Controller late = ctrl;
        late.delay = -1;
        check_throws<std::invalid_argument>([&] { late.validate(); }, "negative delay");
        Controller big = ctrl;
        big.A = Eigen::MatrixXd::Zero(25, 25);
        check_throws<std::invalid_argument>([&] { big.validate(); }, "controller order past the limit");
        Gains soft = pid;
        soft.kp = 500.0;
        soft.ki = 0.0;
        std::vector<double> ones(40000, 1.0), r(40000), y(40000), i(40000);
        check_throws<std::overflow_error>(
            [&] { simulate(rig, soft.controller(), ones.data(), 40000, {r.data(), y.data(), i.data()}); },
            "unstable loop stops at a non-finite state");
    }

    {  // The dense MIMO loop: two uncoupled first-order lags z' = a z + (1 - a) f, one with a 0.5 coupling
        // into the other, against the recursion written out; the steady start against a long settle;
        // the ziggurat's first two moments.
        MimoModel model;
        model.M = (Eigen::MatrixXd(2, 2) << 0.9, 0.0, 0.5, 0.7).finished();
        model.Bf = (Eigen::MatrixXd(2, 2) << 0.1, 0.0, 0.0, 0.3).finished();
        model.Bn = Eigen::MatrixXd::Zero(2, 2);
        model.C = Eigen::MatrixXd::Identity(2, 2);
        model.Dn = Eigen::MatrixXd::Zero(2, 2);
        model.transducer_pole = Eigen::Vector2d(0.0, 0.5);
        model.sensor_noise = model.force_noise = Eigen::Vector2d::Zero();
        const Eigen::Index n = 300;
        std::vector<double> f(2 * n), rec(2 * n), out(2 * n);
        for (Eigen::Index k = 0; k < 2 * n; ++k) f[k] = std::sin(0.3 * static_cast<double>(k));
        mimo_simulate(model, f.data(), n, 1, rec.data(), out.data());
        double z0 = 0.0, z1 = 0.0, q = 0.0, worst = 0.0;
        for (Eigen::Index k = 0; k < n; ++k) {
            worst = std::max({worst, std::abs(out[2 * k] - z0), std::abs(out[2 * k + 1] - z1),
                              std::abs(rec[2 * k] - f[2 * k]), std::abs(rec[2 * k + 1] - (f[2 * k + 1] - q))});
            q = 0.5 * q + 0.5 * f[2 * k + 1];
            const double next0 = 0.9 * z0 + 0.1 * f[2 * k], next1 = 0.5 * z0 + 0.7 * z1 + 0.3 * f[2 * k + 1];
            z0 = next0;
            z1 = next1;
        }
        check(worst < 1e-14, "MIMO loop equals its recursion written out");
        const Eigen::Index L = 50;
        // Each of the two experiments records 2 channels x 2 periods of L samples.
        std::vector<double> period(f.begin(), f.begin() + 2 * L), steady_rec(8 * L), steady_y(8 * L),
            settled_rec(8 * L), settled_y(8 * L);
        const double* forces[2] = {period.data(), period.data()};
        double* recs[2] = {steady_rec.data(), steady_rec.data() + 4 * L};
        double* ys[2] = {steady_y.data(), steady_y.data() + 4 * L};
        mimo_experiments(model, forces, L, 0, 2, {1, 2}, true, recs, ys);
        double* recs2[2] = {settled_rec.data(), settled_rec.data() + 4 * L};
        double* ys2[2] = {settled_y.data(), settled_y.data() + 4 * L};
        mimo_experiments(model, forces, L, 40, 2, {1, 2}, false, recs2, ys2);
        double gap = 0.0;
        for (std::size_t k = 0; k < steady_y.size(); ++k)
            gap = std::max({gap, std::abs(steady_y[k] - settled_y[k]), std::abs(steady_rec[k] - settled_rec[k])});
        check(gap < 1e-12, "MIMO steady start equals a long settle (" + std::to_string(gap) + ")");
        NormalStream normal(7);
        std::vector<double> draws(200000);
        normal.fill(draws.data(), static_cast<Eigen::Index>(draws.size()), 2.0);
        double mean = 0.0, square = 0.0;
        for (double d : draws) mean += d, square += d * d;
        mean /= static_cast<double>(draws.size());
        square /= static_cast<double>(draws.size());
        check(std::abs(mean) < 0.02 && std::abs(square / 4.0 - 1.0) < 0.02,
              "ziggurat normal draws: mean 0, variance 4");
    }

    {  // The MIMO kernels on a larger sparse loop (rows in several passes, both lane counts): the portable
        // and the AVX2 kernel bit for bit, and both against the recursion written out with Eigen.
        const Eigen::Index n = 23, p = 3, q = 2, r = 4, L = 37;
        std::uint64_t bits = 12345;
        auto uniform = [&] {
            bits = bits * 6364136223846793005ULL + 1442695040888963407ULL;
            return static_cast<double>(bits >> 11) * 0x1.0p-53 - 0.5;
        };
        auto sparse = [&](Eigen::Index rows, Eigen::Index cols, double scale) {
            Eigen::MatrixXd X(rows, cols);
            for (Eigen::Index i = 0; i < rows; ++i)
                for (Eigen::Index j = 0; j < cols; ++j) X(i, j) = uniform() < 0.1 ? scale * uniform() : 0.0;
            return X;
        };
        MimoModel model;
        model.M = sparse(n, n, 0.4);
        model.Bf = sparse(n, p, 1.0);
        model.Bn = sparse(n, q, 1.0);
        model.C = sparse(r, n, 1.0);
        model.Dn = sparse(r, q, 1.0);
        model.transducer_pole = Eigen::Vector3d(0.0, 0.3, 0.9);
        model.sensor_noise = Eigen::Vector2d(0.5, 0.0);
        model.force_noise = Eigen::Vector3d(0.0, 0.1, 0.0);
        std::vector<double> f(static_cast<std::size_t>(L * p));
        for (auto& x : f) x = uniform();
        for (const std::size_t lanes : {std::size_t{1}, std::size_t{2}}) {
            std::vector<std::vector<double>> results;
            for (const SimdKernel kernel : {SimdKernel::portable, SimdKernel::avx2}) {
                set_simd_kernel(kernel);
                std::vector<double> rec(static_cast<std::size_t>(L * p * 2)), out(static_cast<std::size_t>(L * r * 2));
                const double* forces[2] = {f.data(), f.data()};
                double* recs[2] = {rec.data(), rec.data() + L * p};
                double* outs[2] = {out.data(), out.data() + L * r};
                MimoLoop loop(model, std::vector<std::uint64_t>(lanes, 9));
                loop.run(forces, 20, recs, outs);  // in two calls: the state carries over
                const double* forces2[2] = {f.data() + 20 * p, f.data() + 20 * p};
                double* recs2[2] = {recs[0] + 20 * p, recs[1] + 20 * p};
                double* outs2[2] = {outs[0] + 20 * r, outs[1] + 20 * r};
                loop.run(forces2, L - 20, recs2, outs2);
                out.resize(static_cast<std::size_t>(L * r * static_cast<Eigen::Index>(lanes)));
                results.push_back(out);
            }
            set_simd_kernel(SimdKernel::automatic);
            check(results[0] == results[1], std::string("MIMO kernels bit-identical (") + simd_kernel_name() + ", " +
                                                std::to_string(lanes) + " lane(s))");
            // Reference: the same noise draws (the loop's streams), the recursion with Eigen.
            MimoModel quiet = model;
            quiet.sensor_noise.setZero();
            quiet.force_noise.setZero();
            std::vector<double> rec(static_cast<std::size_t>(L * p)), out(static_cast<std::size_t>(L * r));
            mimo_simulate(quiet, f.data(), L, 9, rec.data(), out.data());
            Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
            double worst = 0.0;
            for (Eigen::Index k = 0; k < L; ++k) {
                const Eigen::Map<const Eigen::VectorXd> fk(f.data() + k * p, p);
                const Eigen::VectorXd o = model.C * z;
                for (Eigen::Index i = 0; i < r; ++i) worst = std::max(worst, std::abs(out[k * r + i] - o[i]));
                z = model.M * z + model.Bf * fk;
            }
            check(worst < 1e-12,
                  "MIMO kernel (noise-free) equals the recursion with Eigen (" + std::to_string(worst) + ")");
        }
    }

    {  // A model of two independent parts, their states interleaved: found, and each part's model picked.
        MimoModel model;
        const Eigen::Index n = 5;
        model.M = Eigen::MatrixXd::Zero(n, n);
        for (const auto& [i, j] : {std::pair{0, 2}, std::pair{2, 4}, std::pair{4, 0}, std::pair{1, 3}, std::pair{3, 3}})
            model.M(i, j) = 0.1 * (i + 1) + 0.01 * j;
        model.Bf = Eigen::MatrixXd::Zero(n, 2);
        model.Bf(3, 0) = 1.0, model.Bf(2, 1) = 2.0;  // channel 0 drives part {1, 3}, channel 1 part {0, 2, 4}
        model.Bn = Eigen::MatrixXd::Zero(n, 2);
        model.Bn(0, 0) = 3.0, model.Bn(1, 1) = 4.0;
        model.C = Eigen::MatrixXd::Zero(3, n);  // a third row (not a probe) touching both parts is not a link
        model.C(0, 4) = 5.0, model.C(1, 3) = 6.0, model.C.row(2).setOnes();
        model.Dn = Eigen::MatrixXd::Identity(3, 2);
        model.transducer_pole = Eigen::Vector2d(0.1, 0.2);
        model.sensor_noise = Eigen::Vector2d(1e-6, 2e-6);
        model.force_noise = Eigen::Vector2d(0.3, 0.4);
        const std::vector<MimoPart> parts = independent_parts(model);
        using V = std::vector<Eigen::Index>;
        check(parts.size() == 2 && parts[0].states == V{0, 2, 4} && parts[0].forces == V{1} &&
                  parts[0].probes == V{0} && parts[1].states == V{1, 3} && parts[1].forces == V{0} &&
                  parts[1].probes == V{1},
              "independent_parts: two parts, their states, forces and probes");
        const MimoModel second = parts.size() == 2 ? parts[1].model(model) : model;
        check(second.M.rows() == 2 && second.M(0, 1) == model.M(1, 3) && second.M(1, 1) == model.M(3, 3) &&
                  second.M(1, 0) == 0.0 && second.Bf(1, 0) == 1.0 && second.Bn(0, 0) == 4.0 && second.C.rows() == 1 &&
                  second.C(0, 1) == 6.0 && second.Dn(0, 0) == 1.0 && second.transducer_pole[0] == 0.1 &&
                  second.sensor_noise[0] == 2e-6 && second.force_noise[0] == 0.3,
              "MimoPart::model picks the part's entries");
        model.M(0, 1) = 1e-9;  // any coupling joins them
        check(independent_parts(model).size() == 1, "independent_parts: a coupled model is one part");
    }

    {  // Every noise source of a run has its own stream: no two (kind, j) give one seed.
        std::vector<std::uint64_t> seen;
        for (std::uint64_t kind = 0; kind < 8; ++kind)
            for (Eigen::Index j = 0; j < 64; ++j) seen.push_back(stream_seed(12345, kind, j));
        std::sort(seen.begin(), seen.end());
        check(std::adjacent_find(seen.begin(), seen.end()) == seen.end(), "stream_seed: one stream per (kind, source)");
    }

    {  // Hessenberg LU of zI - H, both solves, against Eigen's dense LU (pivoting exercised: z near H's values).
        const Eigen::Index n = 9;
        Eigen::MatrixXd M(n, n);
        for (Eigen::Index i = 0; i < n; ++i)
            for (Eigen::Index j = 0; j < n; ++j) M(i, j) = std::sin(1.7 * static_cast<double>(i * n + j) + 0.3);
        const Eigen::HessenbergDecomposition<Eigen::MatrixXd> hd(M);
        const Eigen::MatrixXd H = hd.matrixH();
        double worst = 0.0;
        // Four shifts at once, and each again in another lane beside other shifts: the same digits.
        const std::complex<double> shifts[4] = {{0.3, 0.9}, {-1.0, 0.0}, {0.01, -0.02}, {0.7, -0.4}};
        const std::complex<double> rotated[4] = {shifts[3], shifts[0], shifts[1], shifts[2]};
        HessenbergLU lu(H), other(H);
        lu.factor(shifts);
        other.factor(rotated);
        Eigen::VectorXcd b(n);
        for (Eigen::Index i = 0; i < n; ++i)
            b[i] = std::complex<double>(std::cos(static_cast<double>(i)), 0.5 * static_cast<double>(i));
        std::vector<double> xr(n * 4), xi(n * 4), yr(n * 4), yi(n * 4), xr2(n * 4), xi2(n * 4);
        for (Eigen::Index i = 0; i < n; ++i)
            for (int l = 0; l < 4; ++l)
                xr[i * 4 + l] = yr[i * 4 + l] = b[i].real(), xi[i * 4 + l] = yi[i * 4 + l] = b[i].imag();
        xr2 = xr, xi2 = xi;
        lu.solve(xr.data(), xi.data());
        lu.solve_transposed(yr.data(), yi.data());
        other.solve(xr2.data(), xi2.data());
        bool same_in_any_lane = true;
        for (int l = 0; l < 4; ++l) {
            const std::complex<double> z = shifts[l];
            const Eigen::MatrixXcd A = z * Eigen::MatrixXcd::Identity(n, n) - H.cast<std::complex<double>>();
            const Eigen::VectorXcd want_x = A.partialPivLu().solve(b), want_y = A.transpose().partialPivLu().solve(b);
            Eigen::VectorXcd x(n), y(n);
            for (Eigen::Index i = 0; i < n; ++i) {
                x[i] = {xr[i * 4 + l], xi[i * 4 + l]};
                y[i] = {yr[i * 4 + l], yi[i * 4 + l]};
                const int moved = (l + 1) % 4;  // shift l sits in lane l + 1 of `other`
                same_in_any_lane =
                    same_in_any_lane && xr2[i * 4 + moved] == xr[i * 4 + l] && xi2[i * 4 + moved] == xi[i * 4 + l];
            }
            worst = std::max({worst, (x - want_x).norm() / want_x.norm(), (y - want_y).norm() / want_y.norm()});
        }
        check(same_in_any_lane, "Hessenberg LU: a shift's solution does not depend on its lane");
        // The portable and the AVX2 builds of the kernels: the same bits.
        std::vector<std::vector<double>> built;
        for (const SimdKernel kernel : {SimdKernel::portable, SimdKernel::avx2}) {
            set_simd_kernel(kernel);
            HessenbergLU again(H);
            again.factor(rotated);
            std::vector<double> ar(n * 4), ai(n * 4), br(n * 4), bi(n * 4);
            for (Eigen::Index i = 0; i < n * 4; ++i)
                ar[i] = br[i] = std::cos(0.3 * i), ai[i] = bi[i] = std::sin(0.7 * i);
            again.solve(ar.data(), ai.data());
            again.solve_transposed(br.data(), bi.data());
            for (auto* v : {&ai, &br, &bi}) ar.insert(ar.end(), v->begin(), v->end());
            built.push_back(ar);
        }
        set_simd_kernel(SimdKernel::automatic);
        check(built[0] == built[1], std::string("Hessenberg LU kernels bit-identical (") + simd_kernel_name() + ")");
        check(worst < 1e-12, "Hessenberg LU solves equal dense LU (" + std::to_string(worst) + ")");
    }

    {  // The stationary covariance solves P = M P M^T + G S G^T; its root R R^T = P, also for a singular P
        // with entries of very different sizes (a state without noise, states scaled by 1e-6 and 1e3).
        const Eigen::Index n = 6;
        Eigen::MatrixXd M(n, n), G(n, 2);
        for (Eigen::Index i = 0; i < n; ++i)
            for (Eigen::Index j = 0; j < n; ++j) M(i, j) = 0.25 * std::sin(2.3 * static_cast<double>(i * n + j) + 0.1);
        M(0, 0) = 0.999;  // a slow pole
        for (Eigen::Index i = 0; i < n; ++i)
            G(i, 0) = std::cos(static_cast<double>(i)), G(i, 1) = 0.3 * static_cast<double>(i);
        M.row(n - 1).setZero();  // the last state is not driven: P singular
        M.col(n - 1).setZero();
        G.row(n - 1).setZero();
        Eigen::VectorXd units(n);
        units << 1e-6, 1e-6, 1.0, 1e3, 1e3, 1.0;
        M = units.asDiagonal() * M * units.cwiseInverse().asDiagonal();
        G = units.asDiagonal() * G;
        const Eigen::Vector2d sigma(2e-3, 5e-4);
        const Eigen::MatrixXd P = stationary_covariance(M, G, sigma);
        const Eigen::MatrixXd Q = G * sigma.cwiseAbs2().asDiagonal() * G.transpose();
        const Eigen::MatrixXd R = covariance_root(P);
        const Eigen::VectorXd scale = P.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
        const auto relative = [&](const Eigen::MatrixXd& E) {  // entry by entry, against sqrt(P_ii P_jj)
            return (scale.asDiagonal() * E * scale.asDiagonal()).cwiseAbs().maxCoeff();
        };
        const double lyapunov = relative(P - M * P * M.transpose() - Q), root = relative(R * R.transpose() - P);
        check(lyapunov < 1e-12 && root < 1e-12, "stationary covariance solves Lyapunov (" + std::to_string(lyapunov) +
                                                    "), its root squares to it (" + std::to_string(root) + ")");
    }

    {  // A two-axis sweep on two threads: every point's estimate equals its experiments and estimate alone.
        const Eigen::Index L = 64, periods = 3;
        const std::vector<Eigen::Index> bins{1, 2, 5};
        const auto B = static_cast<Eigen::Index>(bins.size());
        std::vector<MimoModel> models;
        for (int g = 0; g < 3; ++g) {
            MimoModel model;
            model.M = (Eigen::MatrixXd(2, 2) << 0.9, 0.02 * g, 0.5, 0.7).finished();  // stable: |z| < 0.98
            model.Bf = (Eigen::MatrixXd(2, 2) << 0.1, 0.02, 0.0, 0.3 + 0.1 * g).finished();
            model.Bn = (Eigen::MatrixXd(2, 2) << 0.2, 0.0, 0.0, 0.1).finished();
            model.C = Eigen::MatrixXd::Identity(2, 2);
            model.Dn = Eigen::MatrixXd::Identity(2, 2);
            model.transducer_pole = Eigen::Vector2d(0.0, 0.5);
            model.sensor_noise = Eigen::Vector2d(1e-3, 2e-3);
            model.force_noise = Eigen::Vector2d(1e-2, 0.0);
            models.push_back(model);
        }
        std::vector<double> x(2 * L), y(2 * L);
        for (Eigen::Index k = 0; k < L; ++k) {
            const double s = std::sin(2 * 3.141592653589793 * static_cast<double>(k) / L) + std::cos(0.7 * k);
            x[2 * k] = x[2 * k + 1] = y[2 * k] = s;
            y[2 * k + 1] = -s;
        }
        const double* forces[2] = {x.data(), y.data()};
        const std::vector<std::array<std::uint64_t, 2>> seeds{{{3, 4}}, {{5, 6}}, {{7, 8}}};
        const std::vector<Eigen::Index> settle{0, 0, 0};
        const std::size_t size = models.size() * static_cast<std::size_t>(B) * 4;
        std::vector<std::complex<double>> H(size), R(size);
        std::vector<double> var_re(size), var_im(size);
        mimo_line_sweep(models, forces, L, settle, periods, seeds, true, bins, 2,
                        {H.data(), R.data(), var_re.data(), var_im.data()});
        bool same = true;
        std::vector<std::complex<double>> fl(static_cast<std::size_t>(periods * B * 4)), dl(fl.size());
        for (std::size_t g = 0; g < models.size(); ++g) {
            mimo_line_experiments(models[g], forces, L, 0, periods, {seeds[g][0], seeds[g][1]}, true, bins, fl.data(),
                                  dl.data());
            const Estimate2x2 e = estimate_2x2(fl.data(), dl.data(), periods, B);
            const std::size_t at = g * static_cast<std::size_t>(B) * 4;
            same = same && std::equal(e.H.begin(), e.H.end(), H.begin() + at) &&
                   std::equal(e.receptance.begin(), e.receptance.end(), R.begin() + at) &&
                   std::equal(e.var_re.begin(), e.var_re.end(), var_re.begin() + at) &&
                   std::equal(e.var_im.begin(), e.var_im.end(), var_im.begin() + at) && std::isfinite(e.var_re[0]);
        }
        check(same, "two-axis sweep on two threads equals each point alone bit for bit");
    }

    {  // speed_loops: a damped oscillator whose damping grows with p, under state feedback, against the
       // hold, force integral and steady state written with A's eigenvectors (no matrix exponential).
        const double T = 2.5e-4, w0 = 2.0 * M_PI * 60.0, k1 = 3e4, k2 = 20.0;
        SpeedLoops in;
        in.A0.resize(2, 2), in.A1.resize(2, 2), in.B.resize(2, 1), in.P.resize(3, 2);
        in.A0 << 0.0, 1.0, -w0 * w0, -5.0;
        in.A1 << 0.0, 0.0, 0.0, -0.01;
        in.B << 0.0, 1.0;
        in.holds = {T};
        in.P << 1.0, 0.0, 0.0, 1.0, -k1, -k2;  // M = Phi - Gamma [k1 k2]
        in.L = RowMatrixXd::Zero(2, 2);
        in.drive = Eigen::VectorXcd::Zero(2);
        in.drive[1] = cd(0.3, -0.2);
        in.R = RowMatrixXd::Identity(2, 2);
        const std::vector<double> speeds = {0.0, 150.0, 900.0, 2000.0, 3000.0, 4100.0, 5000.0, 7000.0, 8000.0};
        const auto count = static_cast<Eigen::Index>(speeds.size());
        std::vector<double> loops(static_cast<std::size_t>(count * 4));
        std::vector<cd> values(static_cast<std::size_t>(count * 2)), shapes(values.size() * 2), states(values.size());
        speed_loops(in, speeds.data(), count, 2, loops.data(), values.data(), shapes.data(), states.data());
        double worst_loop = 0.0, worst_value = 0.0, worst_state = 0.0, worst_shape = 0.0;
        for (Eigen::Index s = 0; s < count; ++s) {
            const double p = speeds[static_cast<std::size_t>(s)];
            const Eigen::Matrix2d A = in.A0 + p * in.A1;
            Eigen::ComplexEigenSolver<Eigen::Matrix2cd> eig(A.cast<cd>());
            const Eigen::Matrix2cd V = eig.eigenvectors(), Vi = V.inverse();
            const Eigen::Vector2cd lambda = eig.eigenvalues(), e = (lambda * T).array().exp();
            const Eigen::Matrix2d Phi = (V * e.asDiagonal() * Vi).real();
            const Eigen::Vector2cd c = Vi * in.B.cast<cd>().col(0);
            const Eigen::Vector2d Gamma =
                (V * ((e.array() - 1.0) / lambda.array() * c.array()).matrix()).real();  // int_0^T e^{As} B ds
            Eigen::Matrix2d M = Phi - Gamma * Eigen::RowVector2d(k1, k2);
            const cd jp(0.0, p), z = std::exp(jp * T);
            const Eigen::Vector2cd f = Vi * (p * p * in.drive);  // int_0^T e^{A(T-s)} f e^{jps} ds
            const Eigen::Vector2cd G = V * ((z - e.array()) / (jp - lambda.array()) * f.array()).matrix();
            const Eigen::Map<const RowMatrixXd> got(loops.data() + s * 4, 2, 2);
            worst_loop = std::max(worst_loop, (got - M).cwiseAbs().maxCoeff() / M.cwiseAbs().maxCoeff());
            const Eigen::Vector2cd expected = Eigen::EigenSolver<Eigen::Matrix2d>(M).eigenvalues();
            const cd* v = values.data() + s * 2;
            worst_value = std::max(worst_value, std::min(std::abs(v[0] - expected[0]) + std::abs(v[1] - expected[1]),
                                                         std::abs(v[0] - expected[1]) + std::abs(v[1] - expected[0])));
            const Eigen::Map<const Eigen::Vector2cd> x(states.data() + s * 2);
            worst_state = std::max(worst_state, ((z * x - M.cast<cd>() * x) - G).norm() / G.norm());
            for (int i = 0; i < 2; ++i) {  // R = I: each shape is the unit eigenvector
                const Eigen::Vector2cd u(shapes[static_cast<std::size_t>(s * 4 + i)],
                                         shapes[static_cast<std::size_t>(s * 4 + 2 + i)]);
                worst_shape = std::max(worst_shape, (M.cast<cd>() * u - v[i] * u).norm() + std::abs(u.norm() - 1.0));
            }
        }
        check(worst_loop < 1e-12, "speed_loops' loops are the exact holds (" + std::to_string(worst_loop) + ")");
        check(worst_value < 1e-12, "speed_loops' poles are the loops' eigenvalues");
        check(worst_state < 1e-10,
              "speed_loops' steady states solve (zI - M) x = [G; 0] (" + std::to_string(worst_state) + ")");
        check(worst_shape < 1e-10, "speed_loops' shapes are unit eigenvectors");
        check_throws<std::invalid_argument>(
            [&] {
                SpeedLoops bad = in;
                bad.P.resize(2, 2);
                speed_loops(bad, speeds.data(), 1, 1, nullptr, values.data(), nullptr, states.data());
            },
            "speed_loops refuses a P of the wrong size");
    }

    {  // speed_loops on the portable and the AVX2 kernels (exponential, QR, inverse iteration): the same digits
        std::srand(11);
        const Eigen::Index n = 9, k = 2, m = 13;
        SpeedLoops in;
        in.A0 = RowMatrixXd::Random(n, n) * 3000.0, in.A1 = RowMatrixXd::Random(n, n), in.B = RowMatrixXd::Random(n, k);
        in.holds = {2.5e-4, 1.5e-4};
        in.P = RowMatrixXd::Random(n + 2 * k, m) * 0.3, in.L = RowMatrixXd::Random(m, m) * 0.3;
        in.L.topRows(n).setZero();
        in.drive = Eigen::VectorXcd::Random(n);
        in.R = RowMatrixXd::Random(3, m);
        const std::vector<double> speeds = {0.0, 300.0, 600.0, 2000.0, 2100.0, 5000.0, 9000.0, 9100.0, 9200.0};
        const auto count = static_cast<Eigen::Index>(speeds.size());
        const auto run = [&](SimdKernel kernel) {
            std::vector<double> loops(static_cast<std::size_t>(count * m * m));
            std::vector<cd> values(static_cast<std::size_t>(count * m)), shapes(values.size() * 3),
                states(values.size());
            set_simd_kernel(kernel);
            speed_loops(in, speeds.data(), count, 2, loops.data(), values.data(), shapes.data(), states.data());
            set_simd_kernel(SimdKernel::automatic);
            return std::make_tuple(loops, values, shapes, states);
        };
        check(run(SimdKernel::portable) == run(SimdKernel::avx2),
              "speed_loops: the portable and AVX2 kernels give the same digits");
    }

    std::printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
