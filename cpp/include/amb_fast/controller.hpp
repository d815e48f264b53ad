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

// The PID law of MODEL.md in the form every loop evaluates it (single runs and batched sweeps alike,
// so they agree bit for bit): coefficients ki T and kd (1 - a) / T, state I, D and e[k-1].
struct PidLaw {
    explicit PidLaw(const Pid& pid)
        : kp(pid.kp), ki_T(pid.ki * pid.period()), kd_gain(pid.kd * (1.0 - pid.filter_pole()) / pid.period()),
          a(pid.filter_pole()) {}

    // u[k] (A) from e[k] (m), updating the state.
    double operator()(double e, double& integral, double& derivative, double& e_prev) const {
        return apply(kp, ki_T, kd_gain, a, e, integral, derivative, e_prev);
    }
    static double apply(double kp, double ki_T, double kd_gain, double a, double e, double& integral,
                        double& derivative, double& e_prev) {
        integral += ki_T * e;
        derivative = a * derivative + kd_gain * (e - e_prev);
        e_prev = e;
        return kp * e + integral + derivative;
    }

    double kp, ki_T, kd_gain, a;
};

// Controller state: backward-Euler integral, filtered difference derivative, a delay line of u.
class DigitalPid {
public:
    explicit DigitalPid(const Pid& pid);

    // Reads e[k] (m) and returns the current command held over [kT, (k+1)T): u[k - delay] (A).
    double step(double e) {
        const double u = law_(e, integral_, derivative_, e_prev_);
        if (delay_line_.empty()) return u;
        const double held = delay_line_[head_];
        delay_line_[head_] = u;
        if (++head_ == delay_line_.size()) head_ = 0;
        return held;
    }

private:
    PidLaw law_;
    double integral_ = 0.0, derivative_ = 0.0, e_prev_ = 0.0;
    std::vector<double> delay_line_;
    std::size_t head_ = 0;
};

}  // namespace amb_fast
