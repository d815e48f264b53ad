// The exact periodic steady state of the linear loop, and the stationary distribution of its noise:
// a run can start where an infinitely long settling would have left it, however slow its poles.
#pragma once

#include <Eigen/Dense>

#include "amb_fast/controller.hpp"
#include "amb_fast/plant.hpp"

namespace amb_fast {

// The loop's state stacked as z = [x (the plant's 5 states), s (the controller's n), line (the delay
// line, oldest command first), u_prev (the previous applied command, with a fractional dead time)].
// The controller's delay here includes the dead time's whole samples. Without noise or limits, z[k+1] = M z[k] + (force
// term); white sensor noise n[k] adds noise_in * n[k] (it enters through the measurement e).
struct ClosedLoopMap {
    ClosedLoopMap(const Rig& rig, const Controller& controller, double fraction)
        : ClosedLoopMap(sample_map(rig, controller.period()), rig.sensor_bandwidth ? state::ys : state::y, controller,
                        fraction) {}
    // From the plant's one-sample map (shared by many controllers) and the state the sensor reads.
    ClosedLoopMap(const SampleMap& plant, int sensed, const Controller& controller, double fraction);
    Eigen::MatrixXd M;
    Eigen::VectorXd noise_in;
};

// Powers of two d with D^-1 M D balanced (each state's row and column of similar size; Parlett and
// Reinsch, as LAPACK's gebal): exact in floating point. Without it, orthogonal reductions (Hessenberg,
// QR) mix states of very different scales (m, m/s, A) and lose their small digits.
Eigen::VectorXd balancing(const Eigen::MatrixXd& M);
// The same in place: B becomes D^-1 B D, d the powers of two (no allocation once d has B's size).
void balance(Eigen::MatrixXd& B, Eigen::VectorXd& d);

// M^N by repeated squaring (log2 N products).
Eigen::MatrixXd matrix_power(const Eigen::MatrixXd& M, Eigen::Index N);

// The z0 with z0 = M^N z0 + zN, where zN is the state one period of N samples after rest: the state at
// the start of a period in periodic steady state. M^N by repeated squaring.
Eigen::VectorXd periodic_start(const Eigen::MatrixXd& M, Eigen::Index N, const Eigen::VectorXd& zN);

// The stationary covariance P = M P M^T + G diag(sigma^2) G^T of z driven by independent white noises
// of rms sigma_j through the columns of G, by the doubling algorithm (converging quadratically in
// samples, however slow the slowest pole).
Eigen::MatrixXd stationary_covariance(const Eigen::MatrixXd& M, const Eigen::MatrixXd& G, const Eigen::VectorXd& sigma);

// A square root R (P = R R^T) of a covariance P: LDL^T with diagonal pivoting of P scaled to a unit
// diagonal (states in m, m/s and A keep their own digits); rounding's negative pivots count as 0.
// z = R w, w ~ N(0, I), draws from N(0, P).
Eigen::MatrixXd covariance_root(const Eigen::MatrixXd& P);

// The force transducer's AC-coupling state q at a period's start in steady state, from q after one
// period from rest (q[k+1] = a q[k] + (1 - a) f[k], so q0 = qN / (1 - a^N)).
inline double periodic_transducer_start(double a, Eigen::Index N, double qN) {
    return qN / (1.0 - std::pow(a, static_cast<double>(N)));
}

// Seed of the stream that draws the stationary noise state (neither the sensor's nor the force's).
inline std::uint64_t start_noise_seed(std::uint64_t seed) { return seed ^ 0x5851f42d4c957f2dULL; }

}  // namespace amb_fast
