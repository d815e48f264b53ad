// Gaussian measurement noise, drawn in blocks from one stream per noise source.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <random>

namespace amb_fast {

// A sequential stream of N(0, sigma^2) draws: the numbers do not depend on how they are cut into blocks.
class NormalStream {
public:
    explicit NormalStream(std::uint64_t seed) : rng_(seed) {}

    void fill(double* out, Eigen::Index n, double sigma) {
        for (Eigen::Index j = 0; j < n; ++j) out[j] = sigma * normal_(rng_);
    }

private:
    std::mt19937_64 rng_;
    std::normal_distribution<double> normal_;
};

}  // namespace amb_fast
