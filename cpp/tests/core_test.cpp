// The C++ core on its own, for the sanitizer build (AMB_FAST_SANITIZE): every path once, with checks
// against independent answers. The Python test suite is the full one; this driver exists so that
// AddressSanitizer and UndefinedBehaviorSanitizer see the core without an interpreter around it.
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "amb_fast/batch.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/experiment.hpp"
#include "amb_fast/loop.hpp"
#include "amb_fast/spectrum.hpp"

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
            f[static_cast<std::size_t>(k)] += 0.1 * std::cos(2.0 * M_PI * n * static_cast<double>(k) / static_cast<double>(L) -
                                                             M_PI * n * (n - 1) / lines);
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
            const LineEstimate e = run_experiment(noisy, points[g].controller, period_force, points[g].settle_periods, 3,
                                                  plan, points[g].seed, 5);
            same = same && (s.H.row(g).transpose() - e.H).cwiseAbs().maxCoeff() == 0.0 && s.status[g] == 0;
        }
        check(same, "sweep rows equal single runs bit for bit");
        const SweepEstimates steady = run_sweep(period_force, points, 3, plan, 5, 2, true);
        bool steady_same = true;
        for (int g : {0, 17, 36}) {
            const LineEstimate e = run_experiment(noisy, points[g].controller, period_force, points[g].settle_periods, 3,
                                                  plan, points[g].seed, 5, true);
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
        for (std::size_t k = 0; k < yl.size(); ++k) diff = std::max(diff, std::abs(yl[k] - yn[k])), peak = std::max(peak, std::abs(yl[k]));
        check(diff < 1e-6 * peak, "non-linear law is linear at small amplitude");
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
        check_throws<std::overflow_error>([&] { simulate(rig, soft.controller(), ones.data(), 40000, {r.data(), y.data(), i.data()}); },
                                          "unstable loop stops at a non-finite state");
    }

    std::printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
