// One way to reject bad input: the parameter, the value, what was expected.
#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace amb_fast {

template <class T>
void require(bool ok, const char* name, T value, const char* expected) {
    if (ok) return;
    std::ostringstream msg;
    msg.precision(17);
    msg << name << " must be " << expected << ", got " << value;
    throw std::invalid_argument(msg.str());
}

inline void require_positive(const char* name, double value, const char* unit) {
    require(std::isfinite(value) && value > 0.0, name, value,
            (std::string("a finite number > 0 (") + unit + ")").c_str());
}

// The platform reached its mechanical clearance: an event that ends the run.
struct Touchdown : std::runtime_error {
    Touchdown(double time_, double position_, long sample_)
        : std::runtime_error(message(time_, position_, sample_)), time(time_), position(position_), sample(sample_) {}
    double time;      // s
    double position;  // m
    long sample;

  private:
    static std::string message(double t, double y, long k) {
        std::ostringstream msg;
        msg.precision(6);
        msg << "touchdown: the platform reached its clearance at t = " << t << " s (sample " << k << "), y = " << y
            << " m";
        return msg.str();
    }
};

// Names the first non-finite sample of a series; `first` is the index of values[0] in the record.
inline void require_finite_samples(const char* name, const double* values, long n, long first = 0) {
    for (long k = 0; k < n; ++k) {
        if (!std::isfinite(values[k])) {
            std::ostringstream msg;
            msg << name << " must be finite, got " << values[k] << " at sample " << first + k;
            throw std::invalid_argument(msg.str());
        }
    }
}

// For member initialisers: validates, then passes the parameters on.
template <class Params>
const Params& validated(const Params& params) {
    params.validate();
    return params;
}

}  // namespace amb_fast
