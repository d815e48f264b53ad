#include "amb_fast/controller.hpp"

#include <cmath>

#include "amb_fast/errors.hpp"

namespace amb_fast {

void Pid::validate() const {
    require(std::isfinite(kp), "kp", kp, "finite (A/m)");
    require(std::isfinite(ki), "ki", ki, "finite (A/(m s))");
    require(std::isfinite(kd), "kd", kd, "finite (A s/m)");
    require_positive("fs", fs, "Hz");
    if (derivative_cutoff) require_positive("derivative_cutoff", *derivative_cutoff, "Hz");
    require(delay >= 0, "delay", delay, "a whole number of samples >= 0");
}

double Pid::filter_pole() const {
    return derivative_cutoff ? std::exp(-2.0 * M_PI * *derivative_cutoff / fs) : 0.0;
}

DigitalPid::DigitalPid(const Pid& pid)
    : law_(pid),
      delay_line_(static_cast<std::size_t>(pid.delay), 0.0) {}

}  // namespace amb_fast
