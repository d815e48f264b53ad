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
    const bool has_i = ki != 0.0, has_d = kd != 0.0 && a != 0.0, has_e = kd != 0.0;
    const int n = int(has_i) + int(has_d) + int(has_e);
    Controller c;
    c.A = Eigen::MatrixXd::Zero(n, n);
    c.B = Eigen::VectorXd::Zero(n);
    c.C = Eigen::VectorXd::Zero(n);
    c.D = kp + ki * T + kd_gain;
    c.fs = fs;
    c.delay = delay;
    const int I = 0, Dd = int(has_i), E = int(has_i) + int(has_d);
    if (has_i) c.A(I, I) = 1.0, c.B[I] = ki * T, c.C[I] = 1.0;
    if (has_d) c.A(Dd, Dd) = a, c.A(Dd, E) = -kd_gain, c.B[Dd] = kd_gain, c.C[Dd] = a;
    if (has_e) c.B[E] = 1.0, c.C[E] = -kd_gain;
    return c;
}

DigitalController::DigitalController(const Controller& c)
    : controller_(validated(c)),
      capacity_(controller_capacity(c.order())),
      delay_line_(static_cast<std::size_t>(c.delay), 0.0) {
    switch (capacity_) {
        case 4: law4_.emplace(c); break;
        case 8: law8_.emplace(c); break;
        case 16: law16_.emplace(c); break;
        default: law24_.emplace(c); break;
    }
}

double DigitalController::step(double e) {
    switch (capacity_) {
        case 4: return step(*law4_, e);
        case 8: return step(*law8_, e);
        case 16: return step(*law16_, e);
        default: return step(*law24_, e);
    }
}

}  // namespace amb_fast
