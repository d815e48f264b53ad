// A Campbell diagram's linear algebra (campbell.hpp): one speed per task, on the core's threads.
#include "amb_fast/campbell.hpp"

#include <unsupported/Eigen/MatrixFunctions>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "amb_fast/blocks.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

using cd = std::complex<double>;

void sampled_loops(const RowMatrixXd& A0, const RowMatrixXd& A1, const RowMatrixXd& B, double T, const double* values,
                   Eigen::Index count, const RowMatrixXd& feedback, const RowMatrixXd& lower, int workers,
                   double* out) {
    const Eigen::Index n = A0.rows(), k = B.cols(), m = n + lower.rows();
    require(A0.cols() == n && A1.rows() == n && A1.cols() == n && B.rows() == n, "A0, A1, B", n,
            "n x n, n x n and n x k");
    require(feedback.rows() == k && feedback.cols() == m && lower.cols() == m, "feedback, lower", m,
            "k x m and (m - n) x m");
    in_blocks(count, 16, workers, [&] {
        return [&, augmented = Eigen::MatrixXd(n + k, n + k), E = Eigen::MatrixXd(n + k, n + k),
                M = RowMatrixXd(m, m)](Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index s = begin; s < end; ++s) {
                augmented.setZero();
                augmented.topLeftCorner(n, n) = (A0 + values[s] * A1) * T;
                augmented.topRightCorner(n, k) = B * T;
                E = augmented.exp();
                M.topRows(n).setZero();
                M.topLeftCorner(n, n) = E.topLeftCorner(n, n);
                M.topRows(n).noalias() += E.topRightCorner(n, k) * feedback;
                M.bottomRows(m - n) = lower;
                Eigen::Map<RowMatrixXd>(out + s * m * m, m, m) = M;
            }
        };
    });
}

namespace {

// The eigenvalues of the real quasi-triangular Schur form T (EigenSolver's formula for a 2 x 2 block).
void schur_eigenvalues(const Eigen::MatrixXd& T, cd* values) {
    const Eigen::Index n = T.rows();
    for (Eigen::Index i = 0; i < n; ++i) {
        if (i == n - 1 || T(i + 1, i) == 0.0) {
            values[i] = T(i, i);
            continue;
        }
        const double p = 0.5 * (T(i, i) - T(i + 1, i + 1));
        double t0 = T(i + 1, i), t1 = T(i, i + 1);
        const double scale = std::max(std::abs(p), std::max(std::abs(t0), std::abs(t1)));
        t0 /= scale, t1 /= scale;
        const double p0 = p / scale, z = scale * std::sqrt(std::abs(p0 * p0 + t0 * t1));
        values[i] = cd(T(i + 1, i + 1) + p, z);
        values[i + 1] = cd(T(i + 1, i + 1) + p, -z);
        ++i;
    }
}

// y with H y = lambda y, |y| = 1, by two steps of inverse iteration from the start vector y (H upper
// Hessenberg; LU of H - lambda I pivoting between neighbouring rows; a zero pivot made tiny, as LAPACK's hsein).
void inverse_iteration(const Eigen::MatrixXd& H, cd lambda, double tiny, std::vector<cd>& U, std::vector<cd>& lower,
                       std::vector<char>& swapped, std::vector<cd>& y) {
    const Eigen::Index n = H.rows();
    const auto u = [&](Eigen::Index i, Eigen::Index j) -> cd& { return U[static_cast<std::size_t>(i * n + j)]; };
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j) u(i, j) = j >= i - 1 ? cd(H(i, j)) - (i == j ? lambda : 0.0) : 0.0;
    for (Eigen::Index j = 0; j + 1 < n; ++j) {
        const auto J = static_cast<std::size_t>(j);
        swapped[J] = std::norm(u(j + 1, j)) > std::norm(u(j, j));
        if (swapped[J])
            for (Eigen::Index c = j; c < n; ++c) std::swap(u(j, c), u(j + 1, c));
        if (u(j, j) == 0.0) u(j, j) = tiny;
        const cd l = u(j + 1, j) / u(j, j);
        lower[J] = l;
        u(j + 1, j) = 0.0;
        for (Eigen::Index c = j + 1; c < n; ++c) u(j + 1, c) -= l * u(j, c);
    }
    if (u(n - 1, n - 1) == 0.0) u(n - 1, n - 1) = tiny;
    for (int step = 0; step < 2; ++step) {
        for (Eigen::Index j = 0; j + 1 < n; ++j) {
            const auto J = static_cast<std::size_t>(j);
            if (swapped[J]) std::swap(y[J], y[J + 1]);
            y[J + 1] -= lower[J] * y[J];
        }
        for (Eigen::Index i = n - 1; i >= 0; --i) {
            cd sum = y[static_cast<std::size_t>(i)];
            for (Eigen::Index c = i + 1; c < n; ++c) sum -= u(i, c) * y[static_cast<std::size_t>(c)];
            y[static_cast<std::size_t>(i)] = sum / u(i, i);
        }
        double norm = 0.0;
        for (const cd& v : y) norm += std::norm(v);
        norm = std::sqrt(norm);
        for (cd& v : y) v /= norm;
    }
}

}  // namespace

void loop_modes(const double* stack, Eigen::Index count, Eigen::Index m, const RowMatrixXd& R, int workers,
                cd* values, cd* shapes) {
    require(R.cols() == m, "R", R.cols(), "m columns (one per state)");
    const Eigen::Index r = R.rows();
    const auto M = static_cast<std::size_t>(m);
    in_blocks(count, 8, workers, [&] {
        return [&, hessenberg = Eigen::HessenbergDecomposition<Eigen::MatrixXd>(m),
                schur = Eigen::RealSchur<Eigen::MatrixXd>(m), U = std::vector<cd>(M * M), lower = std::vector<cd>(M),
                swapped = std::vector<char>(M), y = std::vector<cd>(M), v = std::vector<cd>(M),
                Q = Eigen::MatrixXd(m, m)](Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index s = begin; s < end; ++s) {
                const Eigen::MatrixXd A = Eigen::Map<const RowMatrixXd>(stack + s * m * m, m, m);
                const Eigen::VectorXd d = balancing(A);
                hessenberg.compute(d.cwiseInverse().asDiagonal() * A * d.asDiagonal());
                const Eigen::MatrixXd H = hessenberg.matrixH();
                Q = hessenberg.matrixQ();
                schur.computeFromHessenberg(H, Q, false);
                if (schur.info() != Eigen::Success) throw std::runtime_error("eigenvalues did not converge");
                cd* value = values + s * m;
                schur_eigenvalues(schur.matrixT(), value);
                const double tiny = std::numeric_limits<double>::epsilon() * std::max(H.cwiseAbs().maxCoeff(), 1e-300);
                for (Eigen::Index i = 0; i < m; ++i) {
                    cd* shape = shapes + s * r * m + i;  // shape[j * m]: row j
                    const bool conjugate = value[i].imag() < 0.0 && i > 0 && value[i - 1] == std::conj(value[i]);
                    if (conjugate) {  // the conjugate eigenvalue's vector is the conjugate vector
                        for (Eigen::Index j = 0; j < r; ++j) shape[j * m] = std::conj(shape[j * m - 1]);
                        continue;
                    }
                    if (value[i].imag() == 0.0 && value[i].real() > 0.0) {
                        for (Eigen::Index j = 0; j < r; ++j) shape[j * m] = 0.0;
                        continue;
                    }
                    for (Eigen::Index j = 0; j < m; ++j)  // a start vector of its own per index
                        y[static_cast<std::size_t>(j)] = 1.0 + 0.5 * std::sin(static_cast<double>((i + 1) * (j + 1)));
                    inverse_iteration(H, value[i], tiny, U, lower, swapped, y);
                    double norm = 0.0;  // v = D Q y, of unit norm
                    for (Eigen::Index a = 0; a < m; ++a) {
                        cd sum = 0.0;
                        for (Eigen::Index b = 0; b < m; ++b) sum += Q(a, b) * y[static_cast<std::size_t>(b)];
                        v[static_cast<std::size_t>(a)] = d[a] * sum;
                        norm += std::norm(v[static_cast<std::size_t>(a)]);
                    }
                    norm = std::sqrt(norm);
                    for (Eigen::Index j = 0; j < r; ++j) {
                        cd sum = 0.0;
                        for (Eigen::Index a = 0; a < m; ++a) sum += R(j, a) * v[static_cast<std::size_t>(a)];
                        shape[j * m] = sum / norm;
                    }
                }
            }
        };
    });
}

}  // namespace amb_fast
