// MimoLoop's start in the periodic steady state, with the noise-driven part of the state drawn from its
// stationary distribution.
#include "amb_fast/mimo.hpp"

#include <vector>

#include "amb_fast/steady.hpp"

namespace amb_fast {

void MimoLoop::start_periodic(const double* const* period_force, Eigen::Index L) {
    const Eigen::Index ns = model_.states(), p = model_.forces(), r = model_.outputs();
    MimoModel quiet = model_;
    quiet.sensor_noise.setZero();
    quiet.force_noise.setZero();
    MimoLoop probe(quiet, std::vector<std::uint64_t>(static_cast<std::size_t>(lanes_), 0));
    std::vector<Eigen::MatrixXd> recorded(static_cast<std::size_t>(lanes_), Eigen::MatrixXd(p, L)),
        out(static_cast<std::size_t>(lanes_), Eigen::MatrixXd(r, L));  // column k = sample k: sample-major
    std::vector<double*> rec_ptr, out_ptr;
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        rec_ptr.push_back(recorded[l].data());
        out_ptr.push_back(out[l].data());
    }
    probe.run(period_force, L, rec_ptr.data(), out_ptr.data());
    // M^L once for every lane (the solve is cheap beside it).
    const auto lu = (Eigen::MatrixXd::Identity(ns, ns) - matrix_power(model_.M, L)).partialPivLu();
    const Eigen::MatrixXd root = covariance_root(stationary_noise_covariance(model_));
    for (Eigen::Index l = 0; l < lanes_; ++l) {
        Eigen::VectorXd z = lu.solve(probe.state(l));
        add_stationary_noise(root, seeds_[l], z);
        for (Eigen::Index i = 0; i < ns; ++i) set_state(i, l, z[i]);
        for (Eigen::Index j = 0; j < p; ++j) {
            const double a = model_.transducer_pole[j];
            q_(j, l) = a > 0.0 ? periodic_transducer_start(a, L, probe.q_(j, l)) : 0.0;
        }
    }
}

Eigen::MatrixXd stationary_noise_covariance(const MimoModel& model) {
    return stationary_covariance(model.M, model.Bn, model.sensor_noise);
}

void add_stationary_noise(const Eigen::MatrixXd& root, std::uint64_t seed, Eigen::VectorXd& z) {
    NormalStream draws(start_noise_seed(seed));
    Eigen::VectorXd v(z.size());
    draws.fill(v.data(), z.size(), 1.0);
    z += root * v;
}

}  // namespace amb_fast
