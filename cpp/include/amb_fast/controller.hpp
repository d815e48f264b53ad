// The digital PID of MODEL.md section 2, with its derivative filter and computation delay.
#pragma once

#include <optional>
#include <vector>

namespace amb_fast {

struct Pid {
    double kp = 0.0;   // A/m
    double ki = 0.0;   // A/(m s)
    double kd = 0.0;   // A s/m
    std::optional<double> derivative_cutoff;  // Hz; empty = unfiltered difference
    double fs = 4000.0;  // Hz
    int delay = 1;       // whole samples of computation delay

    void validate() const;  // throws std::invalid_argument naming the parameter and the value
    double period() const { return 1.0 / fs; }
    double filter_pole() const;  // a = exp(-2 pi fd T), 0 without a filter
};

// Controller state: backward-Euler integral, filtered difference derivative, a delay line of u.
class DigitalPid {
public:
    explicit DigitalPid(const Pid& pid);

    // Reads e[k] (m) and returns the current command held over [kT, (k+1)T): u[k - delay] (A).
    double step(double e) {
        integral_ += ki_T_ * e;
        derivative_ = a_ * derivative_ + kd_gain_ * (e - e_prev_);
        e_prev_ = e;
        const double u = kp_ * e + integral_ + derivative_;
        if (delay_line_.empty()) return u;
        const double held = delay_line_[head_];
        delay_line_[head_] = u;
        if (++head_ == delay_line_.size()) head_ = 0;
        return held;
    }

private:
    double kp_, ki_T_, kd_gain_, a_;
    double integral_ = 0.0, derivative_ = 0.0, e_prev_ = 0.0;
    std::vector<double> delay_line_;
    std::size_t head_ = 0;
};

}  // namespace amb_fast
