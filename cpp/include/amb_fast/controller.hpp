// The digital controller: any SISO discrete state space at the sample rate, from measured displacement
// e (m) to current command u (A), plus a whole-sample computation delay. The loops know nothing else
// about it: a PID, a notch, a lead-lag or their combination all arrive here as (A, B, C, D, delay).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <optional>
#include <type_traits>
#include <vector>

#include "amb_fast/inline.hpp"

namespace amb_fast {

constexpr int max_controller_order = 24;

// s[k+1] = A s[k] + B e[k],  u[k] = C s[k] + D e[k],  applied `delay` samples later.
struct Controller {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(0, 0);  // n x n
    Eigen::VectorXd B = Eigen::VectorXd::Zero(0);     // n
    Eigen::VectorXd C = Eigen::VectorXd::Zero(0);     // n
    double D = 0.0;
    double fs = 4000.0;  // Hz
    int delay = 0;       // whole samples of computation delay

    void validate() const;  // throws std::invalid_argument naming the parameter and the value
    int order() const { return static_cast<int>(A.rows()); }
    double period() const { return 1.0 / fs; }
};

// The digital PID of MODEL.md section 2 (backward-Euler integral, filtered difference derivative) as a
// Controller in modal form: the integral's state (pole 1) and the derivative's (pole a), each only
// where its gain is non-zero. The Python layer builds
// the same matrices (amb_fast.PID.to_controller); this one serves the C++ test driver.
Controller pid_controller(double kp, double ki, double kd, std::optional<double> derivative_cutoff, double fs,
                          int delay);

// Controllers are evaluated at a compile-time capacity N >= order, padded with zero coefficients: the
// padding adds exact zeros, so the numbers do not depend on N, and small controllers stay in registers.
inline int controller_capacity(int order) {
    return order <= 2 ? 2 : order <= 4 ? 4 : order <= 6 ? 6 : order <= 8 ? 8 : order <= 16 ? 16 : 24;
}

// Calls f(std::integral_constant<int, N>{}) with the capacity N as a compile-time constant.
template <class F>
decltype(auto) with_capacity(int capacity, F&& f) {
    switch (capacity) {
        case 2:
            return f(std::integral_constant<int, 2>{});
        case 4:
            return f(std::integral_constant<int, 4>{});
        case 6:
            return f(std::integral_constant<int, 6>{});
        case 8:
            return f(std::integral_constant<int, 8>{});
        case 16:
            return f(std::integral_constant<int, 16>{});
        default:
            return f(std::integral_constant<int, 24>{});
    }
}

// The coefficients padded to capacity N, A by columns (At[j N + i] = A(i, j)) so that the state update
// runs down whole columns, which vectorises. T is double for one loop, or a SIMD vector of doubles
// (lanes.hpp) holding the coefficients of several loops run side by side, one per lane.
template <int N, class T = double>
struct ControlLaw {
    ControlLaw() = default;
    explicit ControlLaw(const Controller& c) {
        At.fill(0.0), B.fill(0.0), C.fill(0.0);
        const int n = c.order();
        for (int i = 0; i < n; ++i) {
            B[i] = c.B[i], C[i] = c.C[i];
            for (int j = 0; j < n; ++j) At[j * N + i] = c.A(i, j);
        }
        D = c.D;
    }

    // u[k] from e[k], advancing the state s. The output's sum over the state does not wait for e, so
    // only one product and one sum stand between the measurement and the command. Every loop (single
    // runs and each lane of a sweep) performs these operations in this order, so all agree bit for bit.
    // Each state's new value is ((A(i,0) s0 + A(i,1) s1) + ...) + B(i) e, summed in that order.
    AMB_FAST_ALWAYS_INLINE T operator()(T e, T* s) const {
        T cs = C[0] * s[0];
        for (int j = 1; j < N; ++j) cs += C[j] * s[j];
        std::array<T, N> next;
        for (int i = 0; i < N; ++i) next[i] = At[i] * s[0];
        for (int j = 1; j < N; ++j)
            for (int i = 0; i < N; ++i) next[i] += At[j * N + i] * s[j];
        for (int i = 0; i < N; ++i) s[i] = next[i] + B[i] * e;
        return cs + D * e;
    }

    std::array<T, N * N> At;
    std::array<T, N> B, C;
    T D;
};

// A delay line of d > 0 entries, a ring from head: puts u[k] in and returns u[k - d]. T is double for
// one loop, or a SIMD vector for loops side by side (lanes.hpp).
template <class T>
AMB_FAST_ALWAYS_INLINE T pass_through_delay(T* line, std::size_t d, std::size_t& head, T u) {
    const T held = line[head];
    line[head] = u;
    if (++head == d) head = 0;
    return held;
}

// The controller with its state and its delay line, for single runs.
class DigitalController {
  public:
    explicit DigitalController(const Controller& c);

    // Reads e[k] (m) and returns the command held over [kT, (k+1)T): u[k - delay] (A).
    template <int N>
    double step(const ControlLaw<N>& law, double e) {
        return delayed(law(e, state_.data()));
    }
    // The same for any capacity, chosen per call (the non-linear loop, where it costs nothing).
    double step(double e);

    template <int N>
    const ControlLaw<N>& law() const {
        if constexpr (N == 2) return *law2_;
        else if constexpr (N == 4) return *law4_;
        else if constexpr (N == 6) return *law6_;
        else if constexpr (N == 8) return *law8_;
        else if constexpr (N == 16) return *law16_;
        else return *law24_;
    }
    int capacity() const { return capacity_; }
    const Controller& controller() const { return controller_; }
    double* state() { return state_.data(); }
    const double* state() const { return state_.data(); }

    // The delay line, oldest command first (the next one applied), and setting it and the state.
    double line(int j) const { return delay_line_[(head_ + static_cast<std::size_t>(j)) % delay_line_.size()]; }
    void set_line(int j, double u) {
        head_ = 0;
        delay_line_[static_cast<std::size_t>(j)] = u;
    }

    // Puts u[k] (A) into the delay line and returns u[k - delay].
    double delayed(double u) {
        return delay_line_.empty() ? u : pass_through_delay(delay_line_.data(), delay_line_.size(), head_, u);
    }

  private:
    Controller controller_;
    int capacity_;
    std::array<double, max_controller_order> state_{};
    std::vector<double> delay_line_;
    std::size_t head_ = 0;
    std::optional<ControlLaw<2>> law2_;
    std::optional<ControlLaw<4>> law4_;
    std::optional<ControlLaw<6>> law6_;
    std::optional<ControlLaw<8>> law8_;
    std::optional<ControlLaw<16>> law16_;
    std::optional<ControlLaw<24>> law24_;
};

}  // namespace amb_fast
