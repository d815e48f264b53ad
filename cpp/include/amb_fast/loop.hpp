// The sampled-data closed loop: plant between samples, PID at the samples.
#pragma once

#include <Eigen/Dense>

#include "amb_fast/controller.hpp"
#include "amb_fast/plant.hpp"

namespace amb_fast {

// The loop keeps its state between calls to run(), so a long experiment can be streamed in chunks.
class Loop {
public:
    Loop(const Rig& rig, const Pid& pid);

    // Advances n samples of zero-order-held force (N). Writes the sensor output ys(kT) (m) and the
    // coil current at kT (A). Throws std::overflow_error if the state stops being finite, and, for the
    // non-linear force law, if the platform reaches the air gap.
    void run(const double* force, Eigen::Index n, double* displacement, double* current);

    Eigen::Index samples_done() const { return k_; }

private:
    void run_linear(const double* force, Eigen::Index n, double* displacement, double* current);
    template <int sensed, bool has_amp>
    void run_linear_kernel(const double* force, Eigen::Index n, double* displacement, double* current);
    void run_nonlinear(const double* force, Eigen::Index n, double* displacement, double* current);
    void advance_nonlinear(AugmentedVector& X) const;
    [[noreturn]] void fail(Eigen::Index sample, const char* what) const;

    Rig rig_;
    DigitalPid pid_;
    double T_;
    int sensed_;        // state read by the sensor: ys, or y itself
    bool has_amp_;      // coil current is a state, or the command itself
    Propagator P_;      // over one sample (linear law) or one substep (non-linear law)
    Propagator P_half_; // over half a substep (non-linear law)
    int drive_;         // augmented index of the force-producing current
    MagnetPair magnets_;
    StateVector x_ = StateVector::Zero();
    Eigen::Index k_ = 0;
};

// Runs the loop from rest on n force samples (N); writes the sensor displacement (m) and the coil
// current (A) at every sample. Throws std::invalid_argument on a non-finite force sample.
void simulate(const Rig& rig, const Pid& pid, const double* force, Eigen::Index n, double* displacement,
              double* current);

}  // namespace amb_fast
