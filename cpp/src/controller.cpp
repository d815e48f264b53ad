#include "amb_fast/controller.hpp"

#include <cmath>

#include "amb_fast/errors.hpp"

namespace amb_fast {

void Controller::validate() const {
    const auto n = A.rows();
    require(n <= max_controller_order, "controller order", n, "at most 24 states");
    require(A.cols() == n, "controller A columns", A.cols(), "equal to its rows (square)");
    require(B.size() == n, "controller B length", B.size(), "the order of A");
    require(C.size() == n, "controller C length", C.size(), "the order of A");
    require(A.allFinite() && B.allFinite() && C.allFinite(), "controller matrices", "A, B or C",
            "finite (no NaN or infinity)");
    require(std::isfinite(D), "controller D", D, "finite");
    require_positive("fs", fs, "Hz");
    require(delay >= 0, "delay", delay, "a whole number of samples >= 0");
}

Controller pid_controller(double kp, double ki, double kd, std::optional<double> derivative_cutoff, double fs,
                          int delay) {
    const double T = 1.0 / fs;
    const double a = derivative_cutoff ? std::exp(-2.0 * M_PI * *derivative_cutoff * T) : 0.0;
    const double kd_gain = kd * (1.0 - a) / T;
    const bool has_i = ki != 0.0, has_d = kd != 0.0;
    const int n = int(has_i) + int(has_d);
    Controller c;
    c.A = Eigen::MatrixXd::Zero(n, n);
    c.B = Eigen::VectorXd::Zero(n);
    c.C = Eigen::VectorXd::Zero(n);
    c.D = kp + ki * T + kd_gain;
    c.fs = fs;
    c.delay = delay;
    if (has_i) c.A(0, 0) = 1.0, c.B[0] = ki * T, c.C[0] = 1.0;
    const int d = int(has_i);
    if (has_d) c.A(d, d) = a, c.B[d] = 1.0, c.C[d] = kd_gain * (a - 1.0);
    return c;
}

DigitalController::DigitalController(const Controller& c)
    : controller_(validated(c)),
      capacity_(controller_capacity(c.order())),
      delay_line_(static_cast<std::size_t>(c.delay), 0.0) {
    with_capacity(capacity_, [&](auto N) {
        if constexpr (N == 2) law2_.emplace(c);
        else if constexpr (N == 4) law4_.emplace(c);
        else if constexpr (N == 6) law6_.emplace(c);
        else if constexpr (N == 8) law8_.emplace(c);
        else if constexpr (N == 16) law16_.emplace(c);
        else law24_.emplace(c);
    });
}

double DigitalController::step(double e) {
    return with_capacity(capacity_, [&](auto N) { return step(law<N>(), e); });
}

}  // namespace amb_fast
