// The sampled-data closed loop: plant between samples, the controller at the samples, noisy measurements.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "amb_fast/controller.hpp"
#include "amb_fast/mimo.hpp"
#include "amb_fast/plant.hpp"
#include "amb_fast/random.hpp"

namespace amb_fast {

// The force transducer: AC coupled (a first-order high-pass of time constant tau, exact for the
// zero-order-held force: q[k+1] = a q[k] + (1 - a) f[k], recorded f[k] - q[k], a = exp(-T/tau)), or
// DC coupled (records the force as it is).
class ForceTransducer {
  public:
    ForceTransducer(const Rig& rig, double T)
        : coupled_(rig.force_coupling_tau.has_value()), a_(coupled_ ? std::exp(-T / *rig.force_coupling_tau) : 0.0) {}

    void record(const double* force, Eigen::Index n, double* recorded) {
        if (!coupled_) {
            std::copy(force, force + n, recorded);
            return;
        }
        // Four samples per step of the recursion: q[k+m] = a^m q[k] + sum_i a^(m-1-i) b f[k+i] (b = 1 - a).
        // The sums do not depend on q, so the serial chain is one multiply-add per four samples instead
        // of one per sample (the recursion's latency, not its arithmetic, set the cost).
        const double a = a_, b = 1.0 - a_, a2 = a * a, a3 = a2 * a, a4 = a3 * a;
        double q = q_;
        Eigen::Index j = 0;
        for (; j + 4 <= n; j += 4) {
            const double f0 = b * force[j], f1 = b * force[j + 1], f2 = b * force[j + 2], f3 = b * force[j + 3];
            const double s2 = a * f0 + f1, s3 = a * s2 + f2, s4 = a * s3 + f3;
            recorded[j] = force[j] - q;
            recorded[j + 1] = force[j + 1] - (a * q + f0);
            recorded[j + 2] = force[j + 2] - (a2 * q + s2);
            recorded[j + 3] = force[j + 3] - (a3 * q + s3);
            q = a4 * q + s4;
        }
        for (; j < n; ++j) {
            recorded[j] = force[j] - q;
            q = a * q + b * force[j];
        }
        q_ = q;
    }

    double pole() const { return a_; }
    double state() const { return q_; }
    void set_state(double q) { q_ = coupled_ ? q : 0.0; }

  private:
    bool coupled_;
    double a_, q_ = 0.0;
};

// One output sample block of the recorded channels, all at fs.
struct Channels {
    double* force;         // N, recorded force: applied force plus transducer noise
    double* displacement;  // m, sensor output ys(kT) plus sensor noise (what the controller reads)
    double* current;       // A, coil current at kT
};

// The loop keeps its state between calls to run(), so a long experiment can be streamed in chunks.
class Loop {
  public:
    // The seed fixes the measurement noise; it is unused when the rig has none.
    // The controller's delay is lengthened by the rig's dead time in whole samples.
    Loop(const Rig& rig, const Controller& controller, std::uint64_t seed = 0);

    // Advances n samples of zero-order-held force (N) and records them. Throws Touchdown when the
    // platform reaches its clearance, std::overflow_error if the state stops being finite.
    void run(const double* force, Eigen::Index n, Channels out);

    // Starts in the periodic steady state of the L-sample period_force repeated forever (steady.hpp):
    // exact for the linear law without noise; with sensor noise, the noise-driven part of the state is
    // drawn from its stationary distribution. The non-linear law starts from the linearised steady state.
    void start_periodic(const double* period_force, Eigen::Index L);
    // The same in two steps, so that many loops' probes can run side by side: the probe (the loop
    // without noise or limits, from rest), then, once it has run one period, the start it gives.
    Loop periodic_probe() const;
    void start_periodic_from(const Loop& probe, Eigen::Index L);
    // The linear loop (the linearised one for the non-linear law) as a MimoModel: the stacked state z of
    // steady.hpp, the shaker force and the sensor noise as inputs, the measured displacement as the one
    // output, with the rig's transducer and noise levels. What the drawn spectra (SteadyLines) run on.
    MimoModel linear_model() const;
    // The state as z of steady.hpp, and setting it (the delay line restarts at its head).
    Eigen::VectorXd stacked_state() const;
    void set_stacked_state(const Eigen::VectorXd& z);
    ForceTransducer& transducer() { return transducer_; }

    // Samples at which the amplifier clipped the current command, since the start.
    Eigen::Index saturated_samples() const { return saturated_; }

    // Runs count loops over the same n force samples, side by side in SIMD lanes (lanes.hpp) when they
    // can share them (can_run_beside), else one after the other. Each loop gets exactly the numbers
    // that its own run() would give it, except that a loop reaching its clearance does not throw: it
    // is marked touched_down() and runs on.
    static void run_side_by_side(Loop* const* loops, int count, const double* force, Eigen::Index n,
                                 const Channels* out);
    // Linear, with the same rig and a controller of the same capacity and delay.
    bool can_run_beside(const Loop& other) const;
    // The same test on what the loops would be made of (their controllers' own delays).
    static bool can_share_lanes(const Rig& a, const Controller& ca, const Rig& b, const Controller& cb);
    bool touched_down() const { return touched_down_; }
    // Throws Touchdown if |y| (m) has reached the clearance at this sample.
    void check_clearance(double y, Eigen::Index sample) const;

  private:
    friend struct LoopState;                     // loop_kernel.hpp: the state into and out of the kernel's registers
    static constexpr Eigen::Index chunk = 1024;  // noise is drawn a chunk at a time

    // force_noise: where the loop draws the force transducer's noise of these samples, or null.
    void run_linear(const double* force, Eigen::Index n, Channels out, const double* noise, double* force_noise);
    bool checked() const;  // a current limit or a clearance to watch
    // run_side_by_side's work in K lanes.
    template <int K>
    static void run_lanes(Loop* const* loops, int count, const double* force, Eigen::Index n, const Channels* out);
    void run_nonlinear(const double* force, Eigen::Index n, Channels out, const double* noise);
    // Integrator steps over one stretch of a sample with constant inputs (steps of h).
    struct Stretch {
        double h = 0.0;
        Propagator full, half;
    };
    void advance_nonlinear(AugmentedVector& X, const Stretch& stretch) const;
    [[noreturn]] void fail(Eigen::Index sample, const char* what) const;

    Rig rig_;
    DigitalController controller_;
    double T_;
    int sensed_;                      // state read by the sensor: ys, or y itself
    bool has_amp_;                    // coil current is a state, or the command itself
    std::optional<SampleMap> plant_;  // linear law: the one-sample map
    std::optional<CascadeMap> map_;   // the same, written out for the kernel
    Stretch early_, late_;            // non-linear law: [0, fraction) with the previous command, then the rest
    double fraction_;                 // the dead time's fraction of a sample (s)
    double u_prev_ = 0.0;             // the previous applied command, felt over that fraction (A)
    int drive_;                       // augmented index of the force-producing current
    MagnetPair magnets_;
    StateVector x_ = StateVector::Zero();
    Eigen::Index k_ = 0;
    double limit_;      // amplifier limit on |i_cmd| (A), may be infinite
    double touchdown_;  // |y| of touchdown (m), may be infinite
    Eigen::Index saturated_ = 0;
    bool touched_down_ = false;
    // One stream per noise source, so the draws do not depend on how a run is cut into chunks.
    std::uint64_t seed_;
    NormalStream sensor_rng_, force_rng_;
    Eigen::VectorXd sensor_noise_ = Eigen::VectorXd::Zero(chunk), force_noise_ = Eigen::VectorXd::Zero(chunk);
    ForceTransducer transducer_;
};

// Runs the loop from rest on n force samples (N) and records the channels. Throws
// std::invalid_argument on a non-finite force sample.
void simulate(const Rig& rig, const Controller& controller, const double* force, Eigen::Index n, Channels out,
              std::uint64_t seed = 0);

}  // namespace amb_fast
