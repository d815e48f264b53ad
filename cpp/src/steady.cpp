#include "amb_fast/steady.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

namespace amb_fast {

ClosedLoopMap::ClosedLoopMap(const SampleMap& P, int sensed, const Controller& c, double fraction) {
    const int np = state::size, n = c.order(), d = c.delay, prev = int(fraction > 0.0), size = np + n + d + prev;
    M = Eigen::MatrixXd::Zero(size, size);
    noise_in = Eigen::VectorXd::Zero(size);
    // e = x[sensed] (+ noise); u = C s + D e; the applied command is line[0] (or u without a delay).
    Eigen::RowVectorXd u_row = Eigen::RowVectorXd::Zero(size);
    u_row[sensed] = c.D;
    u_row.segment(np, n) = c.C.transpose();
    Eigen::RowVectorXd applied = u_row;
    double applied_noise = c.D;
    if (d > 0) {
        applied.setZero();
        applied[np + n] = 1.0;
        applied_noise = 0.0;
    }
    M.topLeftCorner(np, np) = P.Phi;
    M.topRows(np) += P.G0 * applied;
    noise_in.head(np) = P.G0 * applied_noise;
    if (prev) {  // x gets G1 u_prev; u_prev' = the applied command
        M.block(0, size - 1, np, 1) += P.G1;
        M.row(size - 1) = applied;
        noise_in[size - 1] = applied_noise;
    }
    M.block(np, np, n, n) = c.A;
    M.block(np, sensed, n, 1) += c.B;
    noise_in.segment(np, n) = c.B;
    for (int j = 0; j + 1 < d; ++j) M(np + n + j, np + n + j + 1) = 1.0;
    if (d > 0) {
        M.row(np + n + d - 1) = u_row;
        noise_in[np + n + d - 1] = c.D;
    }
}

Eigen::MatrixXd matrix_power(const Eigen::MatrixXd& M, Eigen::Index N) {
    Eigen::MatrixXd power = Eigen::MatrixXd::Identity(M.rows(), M.cols()), square = M;
    for (Eigen::Index k = N; k > 0; k >>= 1) {
        if (k & 1) power = power * square;
        square = square * square;
    }
    return power;
}

Eigen::VectorXd periodic_start(const Eigen::MatrixXd& M, Eigen::Index N, const Eigen::VectorXd& zN) {
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(M.rows(), M.cols());
    return (I - matrix_power(M, N)).partialPivLu().solve(zN);
}

Eigen::MatrixXd stationary_covariance(const Eigen::MatrixXd& M, const Eigen::MatrixXd& G,
                                      const Eigen::VectorXd& sigma) {
    // P = sum_k M^k Q M^kT; doubling: P <- P + A P A^T, A <- A A.
    Eigen::MatrixXd P = G * sigma.cwiseAbs2().asDiagonal() * G.transpose(), A = M, next(M.rows(), M.cols());
    for (int it = 0; it < 80; ++it) {
        next.noalias() = A * P * A.transpose();
        next += P;
        A = A * A;
        const bool done = (next - P).cwiseAbs().maxCoeff() <= 1e-16 * next.cwiseAbs().maxCoeff();
        P.swap(next);
        if (done && A.cwiseAbs().maxCoeff() < 1e-12) break;
    }
    return 0.5 * (P + P.transpose());
}

Eigen::MatrixXd covariance_root(const Eigen::MatrixXd& P) {
    const Eigen::Index n = P.rows();
    Eigen::VectorXd scale(n);
    for (Eigen::Index i = 0; i < n; ++i) scale[i] = P(i, i) > 0.0 ? std::sqrt(P(i, i)) : 1.0;
    const Eigen::MatrixXd C = scale.cwiseInverse().asDiagonal() * P * scale.cwiseInverse().asDiagonal();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(C);  // C = Pi^T L D L^T Pi
    const Eigen::MatrixXd L = ldlt.matrixL();
    const Eigen::VectorXd d = ldlt.vectorD().cwiseMax(0.0).cwiseSqrt();
    return scale.asDiagonal() * (ldlt.transpositionsP().transpose() * (L * d.asDiagonal()));
}

void balance(Eigen::MatrixXd& B, Eigen::VectorXd& d) {
    const Eigen::Index n = B.rows();
    d.setOnes(n);
    for (bool changed = true; changed;) {
        changed = false;
        for (Eigen::Index i = 0; i < n; ++i) {
            const double c = B.col(i).cwiseAbs().sum() - std::abs(B(i, i)),
                         r = B.row(i).cwiseAbs().sum() - std::abs(B(i, i));
            if (c == 0.0 || r == 0.0) continue;
            double f = 1.0;
            const double total = c + r;
            double cs = c, rs = r;
            while (cs < rs / 2.0) cs *= 2.0, rs /= 2.0, f *= 2.0;
            while (cs >= rs * 2.0) cs /= 2.0, rs *= 2.0, f /= 2.0;
            if (cs + rs >= 0.95 * total) continue;
            changed = true;
            d[i] *= f;
            B.col(i) *= f;
            B.row(i) /= f;
        }
    }
}

Eigen::VectorXd balancing(const Eigen::MatrixXd& M) {
    Eigen::MatrixXd B = M;
    Eigen::VectorXd d;
    balance(B, d);
    return d;
}

}  // namespace amb_fast
