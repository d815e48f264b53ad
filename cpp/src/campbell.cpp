// A Campbell diagram's linear algebra (campbell.hpp): one speed per task, on the core's threads.
#include "amb_fast/campbell.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "amb_fast/blocks.hpp"
#include "amb_fast/errors.hpp"
#include "amb_fast/inline.hpp"
#include "amb_fast/lanes.hpp"
#include "amb_fast/steady.hpp"

namespace amb_fast {

using cd = std::complex<double>;

namespace {

// The eigenvalues of the upper Hessenberg matrix a (n x n, row-major, overwritten) by Francis double-shift QR
// steps on the active window only (EISPACK's hqr): no Schur form, no vectors. A complex pair comes as
// (x + j z, x - j z), z > 0. `guess` (n, or null): a nearby matrix's eigenvalues as this function gave them
// (the previous speed's): the first step at each bottom row nn takes guess[nn] and its neighbour as its shifts
// instead of the trailing 2 x 2's, so a pole that barely moved deflates in about one step. A poor guess
// costs one step per row; the standard shifts follow, so convergence is as without. False if a row takes 60 steps
// (the steps stall: the caller solves another way).
AMB_FAST_ALWAYS_INLINE bool hessenberg_eigenvalues_kernel(double* a, Eigen::Index n, cd* values, const cd* guess) {
    const auto at = [&](Eigen::Index i, Eigen::Index j) -> double& { return a[i * n + j]; };
    const auto sign = [](double x, double y) { return y >= 0.0 ? std::abs(x) : -std::abs(x); };
    const double eps = std::numeric_limits<double>::epsilon();
    double norm = 0.0;
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = std::max<Eigen::Index>(i - 1, 0); j < n; ++j) norm += std::abs(at(i, j));
    Eigen::Index warmed = n;  // the last bottom row given the guess's shifts
    Eigen::Index nn = n - 1, l = 0;
    double t = 0.0;  // the exceptional shifts' sum
    while (nn >= 0) {
        int its = 0;
        do {
            for (l = nn; l >= 1; --l) {  // a negligible subdiagonal entry splits the window
                double s = std::abs(at(l - 1, l - 1)) + std::abs(at(l, l));
                if (s == 0.0) s = norm;
                if (std::abs(at(l, l - 1)) <= eps * s) {
                    at(l, l - 1) = 0.0;
                    break;
                }
            }
            if (l < 0) l = 0;
            double x = at(nn, nn);
            if (l == nn) {  // one root
                values[nn--] = x + t;
                continue;
            }
            double y = at(nn - 1, nn - 1), w = at(nn, nn - 1) * at(nn - 1, nn);
            if (l == nn - 1) {  // two roots
                const double p = 0.5 * (y - x), q = p * p + w, z = std::sqrt(std::abs(q));
                x += t;
                if (q >= 0.0) {
                    const double zz = p + sign(z, p);
                    values[nn - 1] = values[nn] = x + zz;
                    if (zz != 0.0) values[nn] = x - w / zz;
                } else {
                    values[nn - 1] = cd(x + p, z);
                    values[nn] = cd(x + p, -z);
                }
                nn -= 2;
                continue;
            }
            if (its == 60) return false;
            if (its > 0 && its % 10 == 0) {  // an exceptional shift
                t += x;
                for (Eigen::Index i = 0; i <= nn; ++i) at(i, i) -= x;
                const double s = std::abs(at(nn, nn - 1)) + std::abs(at(nn - 1, nn - 2));
                y = x = 0.75 * s;
                w = -0.4375 * s * s;
            } else if (guess != nullptr && warmed != nn) {  // the guess's shifts, once per bottom row
                warmed = nn;
                const cd g = guess[nn], h = guess[nn - 1];
                if (g.imag() != 0.0) {  // a complex pair: x = y = Re g, x y - w = |g|^2
                    y = x = g.real() - t;
                    w = -g.imag() * g.imag();
                } else {  // two real shifts: g and its neighbour if real, else g twice
                    x = g.real() - t;
                    y = (h.imag() == 0.0 ? h.real() : g.real()) - t;
                    w = 0.0;
                }
            }
            ++its;
            Eigen::Index m = nn - 2;
            double p = 0.0, q = 0.0, r = 0.0, z = 0.0;
            for (; m >= l; --m) {  // where two small subdiagonal entries let the step start
                z = at(m, m);
                r = x - z;
                double s = y - z;
                p = (r * s - w) / at(m + 1, m) + at(m, m + 1);
                q = at(m + 1, m + 1) - z - r - s;
                r = at(m + 2, m + 1);
                s = std::abs(p) + std::abs(q) + std::abs(r);
                p /= s, q /= s, r /= s;
                if (m == l) break;
                const double u = std::abs(at(m, m - 1)) * (std::abs(q) + std::abs(r));
                const double v = std::abs(p) * (std::abs(at(m - 1, m - 1)) + std::abs(z) + std::abs(at(m + 1, m + 1)));
                if (u <= eps * v) break;
            }
            for (Eigen::Index i = m + 2; i <= nn; ++i) {
                at(i, i - 2) = 0.0;
                if (i != m + 2) at(i, i - 3) = 0.0;
            }
            for (Eigen::Index k = m; k <= nn - 1; ++k) {  // the double-shift step, a 3 x 3 reflector at a time
                if (k != m) {
                    p = at(k, k - 1);
                    q = at(k + 1, k - 1);
                    r = k != nn - 1 ? at(k + 2, k - 1) : 0.0;
                    x = std::abs(p) + std::abs(q) + std::abs(r);
                    if (x != 0.0) p /= x, q /= x, r /= x;
                }
                const double s = sign(std::sqrt(p * p + q * q + r * r), p);
                if (s == 0.0) continue;
                if (k == m) {
                    if (l != m) at(k, k - 1) = -at(k, k - 1);
                } else {
                    at(k, k - 1) = -s * x;
                }
                p += s;
                x = p / s, y = q / s, z = r / s;
                q /= p, r /= p;
                // the rows' update, contiguous (vectorised where the processor can), then the columns'
                double *row0 = &at(k, 0), *row1 = &at(k + 1, 0), *row2 = k != nn - 1 ? &at(k + 2, 0) : nullptr;
                if (row2 != nullptr) {
                    for (Eigen::Index j = k; j <= nn; ++j) {
                        double t3 = row0[j] + q * row1[j];
                        t3 += r * row2[j];
                        row2[j] -= t3 * z;
                        row1[j] -= t3 * y;
                        row0[j] -= t3 * x;
                    }
                } else {
                    for (Eigen::Index j = k; j <= nn; ++j) {
                        const double t2 = row0[j] + q * row1[j];
                        row1[j] -= t2 * y;
                        row0[j] -= t2 * x;
                    }
                }
                const Eigen::Index last = std::min(nn, k + 3);
                for (Eigen::Index i = l; i <= last; ++i) {
                    p = x * at(i, k) + y * at(i, k + 1);
                    if (k != nn - 1) {
                        p += z * at(i, k + 2);
                        at(i, k + 2) -= p * r;
                    }
                    at(i, k + 1) -= p * q;
                    at(i, k) -= p;
                }
            }
        } while (l < nn - 1);
    }
    return true;
}

bool hessenberg_eigenvalues_portable(double* a, Eigen::Index n, cd* values, const cd* guess) {
    return hessenberg_eigenvalues_kernel(a, n, values, guess);
}
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) bool hessenberg_eigenvalues_avx2(double* a, Eigen::Index n, cd* values,
                                                                 const cd* guess) {
    return hessenberg_eigenvalues_kernel(a, n, values, guess);
}
#else
constexpr auto hessenberg_eigenvalues_avx2 = hessenberg_eigenvalues_portable;
#endif

// a -= tau v (v^T a) on rows and columns k + 1.. of a (m x m, row-major): a reflector from the left; w (m): storage
AMB_FAST_ALWAYS_INLINE void reflect_left(double* __restrict a, Eigen::Index m, Eigen::Index k,
                                         const double* __restrict reflector, double tau, double* __restrict w) {
    for (Eigen::Index j = k + 1; j < m; ++j) w[j] = 0.0;
    for (Eigen::Index i = k + 1; i < m; ++i) {
        const double f = reflector[i];
        const double* __restrict row = a + i * m;
        for (Eigen::Index j = k + 1; j < m; ++j) w[j] += f * row[j];
    }
    for (Eigen::Index i = k + 1; i < m; ++i) {
        const double f = tau * reflector[i];
        double* __restrict row = a + i * m;
        for (Eigen::Index j = k + 1; j < m; ++j) row[j] -= f * w[j];
    }
}

// H = Q^T A Q upper Hessenberg by Householder reflections I - tau v v^T (Golub and Van Loan, 7.4.2): h (m x m,
// row-major) holds A and becomes H; q (m x m, row-major, or null) becomes Q. v (m x m: reflector k in row k),
// tau and w (m each): storage. Row-major loops over contiguous rows (vectorised where the processor can; the
// only reductions, the products with v from the right, stay in order, so the same digits either way).
AMB_FAST_ALWAYS_INLINE void hessenberg_kernel(double* __restrict h, Eigen::Index m, double* __restrict q,
                                              double* __restrict v, double* __restrict tau, double* __restrict w) {
    for (Eigen::Index k = 0; k + 2 < m; ++k) {
        double* __restrict reflector = v + k * m;
        double sigma = 0.0;
        for (Eigen::Index i = k + 2; i < m; ++i) sigma += h[i * m + k] * h[i * m + k];
        tau[k] = 0.0;
        if (sigma == 0.0) continue;  // the column is reduced already
        const double x0 = h[(k + 1) * m + k], mu = std::sqrt(x0 * x0 + sigma);
        const double beta = x0 <= 0.0 ? x0 - mu : -sigma / (x0 + mu);  // v = x - mu e1 without cancellation
        tau[k] = 2.0 * beta * beta / (sigma + beta * beta);
        reflector[k + 1] = 1.0;
        for (Eigen::Index i = k + 2; i < m; ++i) reflector[i] = h[i * m + k] / beta;
        const double t = tau[k];
        reflect_left(h, m, k, reflector, t, w);  // column k becomes mu e1 (set below)
        h[(k + 1) * m + k] = mu;
        for (Eigen::Index i = k + 2; i < m; ++i) h[i * m + k] = 0.0;
        // from the right on every row, columns k + 1..: A -= (A v) tau v^T; the sums (A v)_i in order, four rows
        // side by side (independent chains: not one add's latency per term)
        for (Eigen::Index i = 0; i < m; i += 4) {
            const Eigen::Index rows = std::min<Eigen::Index>(4, m - i);
            double sum[4] = {0.0, 0.0, 0.0, 0.0};
            if (rows == 4) {
                const double *r0 = h + i * m, *r1 = r0 + m, *r2 = r1 + m, *r3 = r2 + m;
                for (Eigen::Index j = k + 1; j < m; ++j) {
                    sum[0] += r0[j] * reflector[j];
                    sum[1] += r1[j] * reflector[j];
                    sum[2] += r2[j] * reflector[j];
                    sum[3] += r3[j] * reflector[j];
                }
            } else {
                for (Eigen::Index r = 0; r < rows; ++r)
                    for (Eigen::Index j = k + 1; j < m; ++j) sum[r] += h[(i + r) * m + j] * reflector[j];
            }
            for (Eigen::Index r = 0; r < rows; ++r) {
                const double f = t * sum[r];
                double* __restrict row = h + (i + r) * m;
                for (Eigen::Index j = k + 1; j < m; ++j) row[j] -= f * reflector[j];
            }
        }
    }
    if (q == nullptr) return;
    // Q = H_0 H_1 ... applied to I from the last reflector back (each touches rows and columns k + 1.. only)
    for (Eigen::Index i = 0; i < m * m; ++i) q[i] = 0.0;
    for (Eigen::Index i = 0; i < m; ++i) q[i * m + i] = 1.0;
    for (Eigen::Index k = m - 3; k >= 0; --k) {
        if (tau[k] == 0.0) continue;
        reflect_left(q, m, k, v + k * m, tau[k], w);
    }
}

// z = Q z for hessenberg_kernel's Q = H_0 H_1 ... H_{m-3} (its reflectors v and tau): z m x width (row-major),
// w (width) storage. Each reflector touches rows k + 1.. only; the same loops as Q's.
AMB_FAST_ALWAYS_INLINE void reflect_kernel(const double* __restrict v, const double* __restrict tau, Eigen::Index m,
                                           double* __restrict z, Eigen::Index width, double* __restrict w) {
    for (Eigen::Index k = m - 3; k >= 0; --k) {
        if (tau[k] == 0.0) continue;
        const double* __restrict reflector = v + k * m;
        for (Eigen::Index j = 0; j < width; ++j) w[j] = 0.0;
        for (Eigen::Index i = k + 1; i < m; ++i) {
            const double f = reflector[i];
            const double* __restrict row = z + i * width;
            for (Eigen::Index j = 0; j < width; ++j) w[j] += f * row[j];
        }
        for (Eigen::Index i = k + 1; i < m; ++i) {
            const double f = tau[k] * reflector[i];
            double* __restrict row = z + i * width;
            for (Eigen::Index j = 0; j < width; ++j) row[j] -= f * w[j];
        }
    }
}

void reflect_portable(const double* v, const double* tau, Eigen::Index m, double* z, Eigen::Index width, double* w) {
    reflect_kernel(v, tau, m, z, width, w);
}
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) void reflect_avx2(const double* v, const double* tau, Eigen::Index m, double* z,
                                                  Eigen::Index width, double* w) {
    reflect_kernel(v, tau, m, z, width, w);
}
#else
constexpr auto reflect_avx2 = reflect_portable;
#endif

void hessenberg_portable(double* h, Eigen::Index m, double* q, double* v, double* tau, double* w) {
    hessenberg_kernel(h, m, q, v, tau, w);
}
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) void hessenberg_avx2(double* h, Eigen::Index m, double* q, double* v, double* tau,
                                                     double* w) {
    hessenberg_kernel(h, m, q, v, tau, w);
}
#else
constexpr auto hessenberg_avx2 = hessenberg_portable;
#endif

// Inverse iteration's storage: H - lambda I's LU factors, real and imaginary parts apart (row-major; the
// row operations' multipliers and swaps), and the vector y.
struct InverseIteration {
    explicit InverseIteration(Eigen::Index n)
        : ur(static_cast<std::size_t>(n * n)),
          ui(ur.size()),
          lr(static_cast<std::size_t>(n)),
          li(lr.size()),
          swapped(lr.size()),
          yr(lr.size()),
          yi(lr.size()) {}
    std::vector<double> ur, ui, lr, li, swapped, yr, yi;
};

// y with H y = lambda y by one step of inverse iteration from the start vector y (H upper Hessenberg,
// row-major; LU of H - lambda I pivoting between neighbouring rows; a zero pivot made tiny, as LAPACK's hsein):
// y becomes (H - lambda I)^-1 y, not normalised. One step suffices for an eigenvalue from QR (accurate to
// rounding: the other vectors' parts shrink by eps |H| / gap), as in LAPACK's hsein; the solves of the steady
// states are the same step. `Complex` false: lambda and y real (lambda_i, y's imaginary part ignored), the same
// operations without their zero imaginary parts. Elementwise loops over real arrays (vectorised where the
// processor can; no reduction is reordered, so the same digits either way).
template <bool Complex>
AMB_FAST_ALWAYS_INLINE void inverse_iteration_kernel(const double* H, Eigen::Index n, double lambda_r, double lambda_i,
                                                     double tiny, InverseIteration& w) {
    double *ur = w.ur.data(), *ui = w.ui.data(), *yr = w.yr.data(), *yi = w.yi.data();
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = std::max<Eigen::Index>(i - 1, 0); j < n; ++j) {
            ur[i * n + j] = H[i * n + j];
            if (Complex) ui[i * n + j] = 0.0;
        }
        ur[i * n + i] -= lambda_r;
        if (Complex) ui[i * n + i] = -lambda_i;
    }
    for (Eigen::Index j = 0; j + 1 < n; ++j) {
        double *ar = ur + j * n, *ai = ui + j * n, *br = ur + (j + 1) * n, *bi = ui + (j + 1) * n;
        const bool swap =
            Complex ? br[j] * br[j] + bi[j] * bi[j] > ar[j] * ar[j] + ai[j] * ai[j] : br[j] * br[j] > ar[j] * ar[j];
        w.swapped[static_cast<std::size_t>(j)] = swap;
        if (swap)
            for (Eigen::Index c = j; c < n; ++c) {
                std::swap(ar[c], br[c]);
                if (Complex) std::swap(ai[c], bi[c]);
            }
        if (Complex ? ar[j] == 0.0 && ai[j] == 0.0 : ar[j] == 0.0) ar[j] = tiny;
        if (Complex) {
            const double norm = ar[j] * ar[j] + ai[j] * ai[j];
            const double mr = (br[j] * ar[j] + bi[j] * ai[j]) / norm, mi = (bi[j] * ar[j] - br[j] * ai[j]) / norm;
            w.lr[static_cast<std::size_t>(j)] = mr, w.li[static_cast<std::size_t>(j)] = mi;
            for (Eigen::Index c = j + 1; c < n; ++c) {
                const double xr = ar[c], xi = ai[c];
                br[c] -= mr * xr - mi * xi;
                bi[c] -= mr * xi + mi * xr;
            }
        } else {
            const double mr = br[j] * ar[j] / (ar[j] * ar[j]);
            w.lr[static_cast<std::size_t>(j)] = mr;
            for (Eigen::Index c = j + 1; c < n; ++c) br[c] -= mr * ar[c];
        }
    }
    if (Complex ? ur[n * n - 1] == 0.0 && ui[n * n - 1] == 0.0 : ur[n * n - 1] == 0.0) ur[n * n - 1] = tiny;
    for (Eigen::Index j = 0; j + 1 < n; ++j) {
        const auto J = static_cast<std::size_t>(j);
        if (!Complex) {
            if (w.swapped[J] != 0.0) std::swap(yr[j], yr[j + 1]);
            yr[j + 1] -= w.lr[J] * yr[j];
            continue;
        }
        if (w.swapped[J] != 0.0) std::swap(yr[j], yr[j + 1]), std::swap(yi[j], yi[j + 1]);
        yr[j + 1] -= w.lr[J] * yr[j] - w.li[J] * yi[j];
        yi[j + 1] -= w.lr[J] * yi[j] + w.li[J] * yr[j];
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {
        const double *rr = ur + i * n, *ri = ui + i * n;
        double sr = yr[i], si = Complex ? yi[i] : 0.0;
        if (!Complex) {
            for (Eigen::Index c = i + 1; c < n; ++c) sr -= rr[c] * yr[c];
            yr[i] = sr * rr[i] / (rr[i] * rr[i]);
            continue;
        }
        for (Eigen::Index c = i + 1; c < n; ++c) {
            sr -= rr[c] * yr[c] - ri[c] * yi[c];
            si -= rr[c] * yi[c] + ri[c] * yr[c];
        }
        const double norm = rr[i] * rr[i] + ri[i] * ri[i];
        yr[i] = (sr * rr[i] + si * ri[i]) / norm;
        yi[i] = (si * rr[i] - sr * ri[i]) / norm;
    }
    if (!Complex)
        for (Eigen::Index i = 0; i < n; ++i) yi[i] = 0.0;
}

// `real`: lambda and y real (the real kernel), else the complex one.
void inverse_iteration_portable(const double* H, Eigen::Index n, cd lambda, bool real, double tiny,
                                InverseIteration& w) {
    if (real) inverse_iteration_kernel<false>(H, n, lambda.real(), 0.0, tiny, w);
    else inverse_iteration_kernel<true>(H, n, lambda.real(), lambda.imag(), tiny, w);
}
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) void inverse_iteration_avx2(const double* H, Eigen::Index n, cd lambda, bool real,
                                                            double tiny, InverseIteration& w) {
    if (real) inverse_iteration_kernel<false>(H, n, lambda.real(), 0.0, tiny, w);
    else inverse_iteration_kernel<true>(H, n, lambda.real(), lambda.imag(), tiny, w);
}
#else
constexpr auto inverse_iteration_avx2 = inverse_iteration_portable;
#endif

// exp(X) for X = [[A, C], [0, S]] (e x e, row-major: A n x n, S the small block of the last e - n states, zero
// for a hold's commands, the force's oscillator) by scaling and squaring with the Pade degree Higham (2005)
// picks from X's 1-norm, as Eigen's MatrixFunctions does, on storage kept from one call to the next. Every
// power and the quotient keep X's zero block, which the products and the solve skip (with any zero entry):
// the squarings cost n^2 e + (e - n)^3, not e^3. Row-major loops over contiguous rows (vectorised where the
// processor can; no reduction is reordered, so the same digits either way).
struct Exponential {
    explicit Exponential(Eigen::Index size)
        : x(static_cast<std::size_t>(size * size)),
          x2(x.size()),
          x4(x.size()),
          x6(x.size()),
          x8(x.size()),
          u(x.size()),
          v(x.size()),
          t(x.size()),
          pivots(static_cast<std::size_t>(size)) {}
    std::vector<double> x, x2, x4, x6, x8, u, v, t;
    std::vector<Eigen::Index> pivots;
};

// c = a b for a, b zero in rows >= n, columns < n (e x e, row-major; c apart from a and b).
AMB_FAST_ALWAYS_INLINE void block_product(const double* __restrict a, const double* __restrict b, double* __restrict c,
                                          Eigen::Index e, Eigen::Index n) {
    for (Eigen::Index i = 0; i < e; ++i) {
        double* __restrict row = c + i * e;
        for (Eigen::Index j = 0; j < e; ++j) row[j] = 0.0;
        for (Eigen::Index k = i < n ? 0 : n; k < e; ++k) {
            const double f = a[i * e + k];
            if (f == 0.0) continue;
            const double* __restrict from = b + k * e;
            for (Eigen::Index j = k < n ? 0 : n; j < e; ++j) row[j] += f * from[j];
        }
    }
}

// out = sum_j w[j] p[j] + w0 I (count terms, e x e).
AMB_FAST_ALWAYS_INLINE void combine(const double* const* p, const double* w, int count, double w0, double* out,
                                    Eigen::Index e) {
    for (Eigen::Index i = 0; i < e * e; ++i) {
        double sum = w[0] * p[0][i];
        for (int j = 1; j < count; ++j) sum += w[j] * p[j][i];
        out[i] = sum;
    }
    for (Eigen::Index i = 0; i < e; ++i) out[i * e + i] += w0;
}

// E = exp(X): X in w.x (e x e, row-major, overwritten), E (e x e, row-major).
AMB_FAST_ALWAYS_INLINE void exponential_kernel(Exponential& w, Eigen::Index e, Eigen::Index n, double* E) {
    double *X = w.x.data(), *X2 = w.x2.data(), *X4 = w.x4.data(), *X6 = w.x6.data(), *X8 = w.x8.data();
    double *U = w.u.data(), *V = w.v.data(), *T = w.t.data();
    double norm = 0.0;
    for (Eigen::Index j = 0; j < e; ++j) {
        double sum = 0.0;
        for (Eigen::Index i = 0; i < e; ++i) sum += std::abs(X[i * e + j]);
        norm = std::max(norm, sum);
    }
    int squarings = 0;
    if (norm >= 2.097847961257068) {  // [13/13] on X / 2^s, ||X / 2^s|| <= theta_13
        std::frexp(norm / 5.371920351148152, &squarings);
        squarings = std::max(squarings, 0);
        for (Eigen::Index i = 0; i < e * e; ++i) X[i] = std::ldexp(X[i], -squarings);
    }
    block_product(X, X, X2, e, n);
    if (norm < 1.495585217958292e-2) {  // [3/3]
        static constexpr double b[] = {120.0, 60.0, 12.0, 1.0};
        const double* p[] = {X2};
        combine(p, b + 3, 1, b[1], T, e);
        combine(p, b + 2, 1, b[0], V, e);
    } else if (norm < 2.539398330063230e-1) {  // [5/5]
        static constexpr double b[] = {30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0};
        block_product(X2, X2, X4, e, n);
        const double* p[] = {X4, X2};
        const double odd[] = {b[5], b[3]}, even[] = {b[4], b[2]};
        combine(p, odd, 2, b[1], T, e);
        combine(p, even, 2, b[0], V, e);
    } else if (norm < 9.504178996162932e-1) {  // [7/7]
        static constexpr double b[] = {17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0};
        block_product(X2, X2, X4, e, n);
        block_product(X4, X2, X6, e, n);
        const double* p[] = {X6, X4, X2};
        const double odd[] = {b[7], b[5], b[3]}, even[] = {b[6], b[4], b[2]};
        combine(p, odd, 3, b[1], T, e);
        combine(p, even, 3, b[0], V, e);
    } else if (norm < 2.097847961257068) {  // [9/9]
        static constexpr double b[] = {17643225600.0, 8821612800.0, 2075673600.0, 302702400.0, 30270240.0,
                                       2162160.0,     110880.0,     3960.0,       90.0,        1.0};
        block_product(X2, X2, X4, e, n);
        block_product(X4, X2, X6, e, n);
        block_product(X6, X2, X8, e, n);
        const double* p[] = {X8, X6, X4, X2};
        const double odd[] = {b[9], b[7], b[5], b[3]}, even[] = {b[8], b[6], b[4], b[2]};
        combine(p, odd, 4, b[1], T, e);
        combine(p, even, 4, b[0], V, e);
    } else {  // [13/13]
        constexpr const auto& b = pade13;
        block_product(X2, X2, X4, e, n);
        block_product(X4, X2, X6, e, n);
        const double* p[] = {X6, X4, X2};
        const double high_odd[] = {b[13], b[11], b[9]}, odd[] = {b[7], b[5], b[3]};
        const double high_even[] = {b[12], b[10], b[8]}, even[] = {b[6], b[4], b[2]};
        combine(p, high_odd, 3, 0.0, V, e);  // X6 (b13 X6 + b11 X4 + b9 X2) + b7 X6 + ... + b1 I
        block_product(X6, V, X8, e, n);
        combine(p, odd, 3, b[1], T, e);
        for (Eigen::Index i = 0; i < e * e; ++i) T[i] += X8[i];
        combine(p, high_even, 3, 0.0, U, e);  // X6 (b12 X6 + b10 X4 + b8 X2) + b6 X6 + ... + b0 I
        block_product(X6, U, X8, e, n);
        combine(p, even, 3, b[0], V, e);
        for (Eigen::Index i = 0; i < e * e; ++i) V[i] += X8[i];
    }
    block_product(X, T, U, e, n);  // U = X (odd part / X)
    // (V - U) E = V + U by LU with partial pivoting (row operations on E's rows)
    for (Eigen::Index i = 0; i < e * e; ++i) {
        const double denominator = V[i] - U[i];
        E[i] = V[i] + U[i];
        V[i] = denominator;
    }
    Eigen::Index* pivots = w.pivots.data();
    for (Eigen::Index j = 0; j < e; ++j) {
        Eigen::Index best = j;
        for (Eigen::Index i = j + 1; i < e; ++i)
            if (std::abs(V[i * e + j]) > std::abs(V[best * e + j])) best = i;
        pivots[j] = best;
        if (best != j)
            for (Eigen::Index c = 0; c < e; ++c)
                std::swap(V[j * e + c], V[best * e + c]), std::swap(E[j * e + c], E[best * e + c]);
        const double pivot = V[j * e + j];
        if (pivot == 0.0) throw std::runtime_error("matrix exponential: singular Pade denominator");
        for (Eigen::Index i = j + 1; i < e; ++i) {
            const double f = V[i * e + j] / pivot;
            if (f == 0.0) continue;
            for (Eigen::Index c = j + 1; c < e; ++c) V[i * e + c] -= f * V[j * e + c];
            for (Eigen::Index c = 0; c < e; ++c) E[i * e + c] -= f * E[j * e + c];
        }
    }
    for (Eigen::Index i = e - 1; i >= 0; --i) {
        double* __restrict row = E + i * e;
        for (Eigen::Index k = i + 1; k < e; ++k) {
            const double f = V[i * e + k];
            if (f == 0.0) continue;
            const double* __restrict from = E + k * e;
            for (Eigen::Index c = 0; c < e; ++c) row[c] -= f * from[c];
        }
        const double pivot = V[i * e + i];
        for (Eigen::Index c = 0; c < e; ++c) row[c] /= pivot;
    }
    for (int k = 0; k < squarings; ++k) {
        block_product(E, E, T, e, n);
        std::copy(T, T + e * e, E);
    }
}

void exponential_portable(Exponential& w, Eigen::Index e, Eigen::Index n, double* E) { exponential_kernel(w, e, n, E); }
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) void exponential_avx2(Exponential& w, Eigen::Index e, Eigen::Index n, double* E) {
    exponential_kernel(w, e, n, E);
}
#else
constexpr auto exponential_avx2 = exponential_portable;
#endif

// One matrix's eigenvalues and shapes (loop_modes), with its storage kept from one matrix to the next.
class Modes {
  public:
    explicit Modes(Eigen::Index m)
        : A(m, m),
          d(m),
          reflectors(m, m),
          tau(m),
          row(2 * m),
          H(m, m),
          work(m, m),
          Q(m, m),
          start(m, m),
          Y(static_cast<std::size_t>(2 * m * m)),
          iteration(m) {
        // a start vector of its own per index i (column i), so that a repeated eigenvalue's copies differ
        for (Eigen::Index i = 0; i < m; ++i)
            for (Eigen::Index j = 0; j < m; ++j)
                start(j, i) = 1.0 + 0.5 * std::sin(static_cast<double>(static_cast<std::size_t>((i + 1) * (j + 1))));
    }

    // A: the matrix (m x m, overwritten by its balanced form). shapes: R v for each eigenvalue (shape[j * m + i]),
    // or null for the eigenvalues only; `solvable`: keep what `solve` needs; guess: the previous (nearby)
    // matrix's values, or null (hessenberg_eigenvalues_kernel).
    void compute(const RowMatrixXd* R, cd* values, cd* shapes, bool solvable, const cd* guess) {
        const Eigen::Index m = A.rows();
        balance(A, d);
        H = A;
        (simd_avx2() ? hessenberg_avx2 : hessenberg_portable)(H.data(), m, solvable ? Q.data() : nullptr,
                                                              reflectors.data(), tau.data(), row.data());
        work = H;
        if (!(simd_avx2() ? hessenberg_eigenvalues_avx2 : hessenberg_eigenvalues_portable)(work.data(), m, values,
                                                                                           guess)) {
            // Francis steps can stall (a flexible rotor at standstill: pairs of equal poles): Eigen's solver, its
            // own reduction and shifts and more steps, instead; rare, so its allocations do not matter
            const Eigen::EigenSolver<Eigen::MatrixXd> solver(H, false);
            if (solver.info() != Eigen::Success) throw std::runtime_error("eigenvalues did not converge");
            for (Eigen::Index i = 0; i < m; ++i) values[i] = solver.eigenvalues()[i];
        }
        if (shapes == nullptr && !solvable) return;
        tiny = std::numeric_limits<double>::epsilon() * std::max(H.cwiseAbs().maxCoeff(), 1e-300);
        if (shapes == nullptr) return;
        const auto step = simd_avx2() ? inverse_iteration_avx2 : inverse_iteration_portable;
        // A shape for each eigenvalue off the real axis (a real one does not whirl), but not the conjugate's
        const auto wanted = [&](Eigen::Index i) {
            const bool conjugate = values[i].imag() < 0.0 && i > 0 && values[i - 1] == std::conj(values[i]);
            return values[i].imag() != 0.0 && !conjugate;
        };
        Eigen::Index c = 0;  // how many are wanted
        for (Eigen::Index i = 0; i < m; ++i) c += wanted(i);
        // Y (m x 2c, row-major): column c' the c'-th wanted eigenvalue's vector of H, real part, and column c + c'
        // its imaginary part; then V = D Q Y by the reflectors (only these columns: m^2 c, no m x m Q)
        const Eigen::Index width = 2 * c;
        c = 0;
        for (Eigen::Index i = 0; i < m; ++i) {
            if (!wanted(i)) continue;
            Eigen::Map<Eigen::VectorXd>(iteration.yr.data(), m) = start.col(i);
            Eigen::Map<Eigen::VectorXd>(iteration.yi.data(), m).setZero();
            step(H.data(), m, values[i], false, tiny, iteration);
            for (Eigen::Index a = 0; a < m; ++a) {
                Y[static_cast<std::size_t>(a * width + c)] = iteration.yr[static_cast<std::size_t>(a)];
                Y[static_cast<std::size_t>(a * width + width / 2 + c)] = iteration.yi[static_cast<std::size_t>(a)];
            }
            ++c;
        }
        (simd_avx2() ? reflect_avx2 : reflect_portable)(reflectors.data(), tau.data(), m, Y.data(), width, row.data());
        Eigen::Map<RowMatrixXd> V(Y.data(), m, width);
        V = d.asDiagonal() * V;
        const Eigen::Index r = R->rows();
        if (S.size() < static_cast<std::size_t>(r * width)) S.resize(static_cast<std::size_t>(r * width));
        Eigen::Map<RowMatrixXd> RV(S.data(), r, width);
        RV.noalias() = *R * V;
        c = 0;
        for (Eigen::Index i = 0; i < m; ++i) {
            cd* shape = shapes + i;  // shape[j * m]: row j
            if (wanted(i)) {
                const double norm = std::sqrt(V.col(c).squaredNorm() + V.col(c + width / 2).squaredNorm());
                for (Eigen::Index j = 0; j < r; ++j) shape[j * m] = cd(RV(j, c), RV(j, c + width / 2)) / norm;
                ++c;
            } else if (values[i].imag() < 0.0) {  // the conjugate eigenvalue's vector is the conjugate vector
                for (Eigen::Index j = 0; j < r; ++j) shape[j * m] = std::conj(shape[j * m - 1]);
            } else {
                for (Eigen::Index j = 0; j < r; ++j) shape[j * m] = 0.0;
            }
        }
    }

    // x (m) with (z I - A) x = g (m) for the matrix last computed (solvable): through its Hessenberg form,
    // A = D Q H Q^T D^-1, in O(m^2) beyond it ((H - z I) w = -Q^T D^-1 g, x = D Q w).
    void solve(cd z, const cd* g, cd* x) {
        const Eigen::Index m = A.rows();
        for (Eigen::Index b = 0; b < m; ++b) {
            cd sum = 0.0;
            for (Eigen::Index a = 0; a < m; ++a) sum += Q(a, b) * (g[a] / d[a]);
            iteration.yr[static_cast<std::size_t>(b)] = -sum.real();
            iteration.yi[static_cast<std::size_t>(b)] = -sum.imag();
        }
        (simd_avx2() ? inverse_iteration_avx2 : inverse_iteration_portable)(H.data(), m, z, false, tiny, iteration);
        for (Eigen::Index a = 0; a < m; ++a) {
            cd sum = 0.0;
            for (Eigen::Index b = 0; b < m; ++b)
                sum +=
                    Q(a, b) * cd(iteration.yr[static_cast<std::size_t>(b)], iteration.yi[static_cast<std::size_t>(b)]);
            x[a] = d[a] * sum;
        }
    }

    Eigen::MatrixXd A;

  private:
    double tiny = 0.0;
    Eigen::VectorXd d;
    RowMatrixXd reflectors;  // the Hessenberg reduction's reflectors (one per row), their tau, a row's storage
    Eigen::VectorXd tau, row;
    RowMatrixXd H, work;
    RowMatrixXd Q;  // for `solve` only
    Eigen::MatrixXd start;
    std::vector<double> Y, S;  // the wanted vectors of H, then of A (m x 2c), and R times them (r x 2c)
    InverseIteration iteration;
};

}  // namespace

void loop_modes(const double* stack, Eigen::Index count, Eigen::Index m, const RowMatrixXd& R, int workers, cd* values,
                cd* shapes) {
    require(R.cols() == m, "R", R.cols(), "m columns (one per state)");
    in_blocks(count, 8, workers, [&] {
        return [&, modes = Modes(m)](Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index s = begin; s < end; ++s) {
                modes.A = Eigen::Map<const RowMatrixXd>(stack + s * m * m, m, m);
                modes.compute(&R, values + s * m, shapes + s * R.rows() * m, false,
                              s > begin ? values + (s - 1) * m : nullptr);
            }
        };
    });
}

void speed_loops(const SpeedLoops& in, const double* values_p, Eigen::Index count, int workers, double* loops,
                 cd* values, cd* shapes, cd* states) {
    const Eigen::Index n = in.A0.rows(), k = in.B.cols(), H = static_cast<Eigen::Index>(in.holds.size());
    const Eigen::Index m = in.L.rows(), r = in.R.rows();
    const bool driven = in.drive.size() > 0, shaped = r > 0;
    require(in.A0.cols() == n && in.A1.rows() == n && in.A1.cols() == n && in.B.rows() == n, "A0, A1, B", n,
            "n x n, n x n and n x k");
    require(H >= 1, "holds", H, "at least the sample period");
    for (const double h : in.holds) require(std::isfinite(h) && h > 0.0, "hold", h, "> 0 (s)");
    require(in.P.rows() == n + k * H && in.P.cols() == m && in.L.cols() == m && m >= n, "P, L", m,
            "(n + k holds) x m and m x m");
    require(!driven || in.drive.size() == n, "drive", in.drive.size(), "n entries (one per plant state)");
    require(!shaped || in.R.cols() == m, "R", in.R.cols(), "m columns (one per state)");
    require(!shaped || shapes != nullptr, "shapes", 0, "storage for the shapes");
    require(!driven || states != nullptr, "states", 0, "storage for the steady states");
    const double T = in.holds[0];
    const Eigen::Index size = n + k + (driven ? 2 : 0);
    // The exponentials of D^-1 X D = D^-1 e^X D, D the powers of two balancing the plant at p = 0 (exact in
    // floating point): the balanced matrix's smaller norm takes fewer squarings. scaled(i, j) = d_j / d_i.
    Eigen::MatrixXd scaled = Eigen::MatrixXd::Ones(size, size);
    {
        Eigen::MatrixXd X = Eigen::MatrixXd::Zero(n + k, n + k);
        X.topLeftCorner(n, n) = in.A0 * T;
        X.topRightCorner(n, k) = in.B * T;
        Eigen::VectorXd d;
        balance(X, d);
        for (Eigen::Index i = 0; i < n + k; ++i)
            for (Eigen::Index j = 0; j < size; ++j) scaled(i, j) = (j < n + k ? d[j] : 1.0) / d[i];
    }
    const auto exponential = simd_avx2() ? exponential_avx2 : exponential_portable;
    in_blocks(count, 8, workers, [&] {
        return [&, size, work = Exponential(size), E = RowMatrixXd(size, size), X = RowMatrixXd(n, n + k * H),
                M = RowMatrixXd(m, m), modes = Modes(m),
                x = Eigen::VectorXcd(m)](Eigen::Index begin, Eigen::Index end) mutable {
            for (Eigen::Index s = begin; s < end; ++s) {
                const double p = values_p[s];
                for (Eigen::Index j = 0; j < H; ++j) {
                    const double h = in.holds[static_cast<std::size_t>(j)];
                    const bool drives = driven && j == 0;  // the force over the sample only
                    const Eigen::Index e = drives ? size : n + k;
                    Eigen::Map<RowMatrixXd> aug(work.x.data(), e, e), exp(E.data(), e, e);
                    aug.setZero();
                    aug.topLeftCorner(n, n) = (in.A0 + p * in.A1) * h;
                    aug.block(0, n, n, k) = in.B * h;
                    if (drives) {  // the force's phasor as a 2-state oscillator (cos p t, sin p t): Re G, -Im G
                        aug.col(n + k).head(n) = (p * p * h) * in.drive.real();
                        aug.col(n + k + 1).head(n) = -(p * p * h) * in.drive.imag();
                        aug(n + k, n + k + 1) = -p * h;
                        aug(n + k + 1, n + k) = p * h;
                    }
                    aug.array() *= scaled.topLeftCorner(e, e).array();
                    double force = 1.0;  // the force's columns scaled (a power of two) to no more than unit size
                    if (drives) {
                        const double size = aug.block(0, n + k, n, 2).cwiseAbs().colwise().sum().maxCoeff();
                        if (size > 1.0) force = std::exp2(std::ceil(std::log2(size)));
                        aug.block(0, n + k, n, 2) /= force;
                    }
                    exponential(work, e, n, exp.data());
                    exp.array() /= scaled.topLeftCorner(e, e).array();
                    if (drives) exp.block(0, n + k, n, 2) *= force;
                    if (j == 0) X.leftCols(n) = exp.topLeftCorner(n, n);
                    if (drives) {  // G_p = Re G + j Im G, and the loop's drive [G_p; 0]
                        x.setZero();
                        for (Eigen::Index i = 0; i < n; ++i) x[i] = cd(exp(i, n + k), -exp(i, n + k + 1));
                    }
                    X.middleCols(n + j * k, k) = exp.block(0, n, n, k);
                }
                M = in.L;
                M.topRows(n).noalias() += X * in.P;
                if (loops != nullptr) Eigen::Map<RowMatrixXd>(loops + s * m * m, m, m) = M;
                modes.A = M;
                modes.compute(&in.R, values + s * m, shaped ? shapes + s * r * m : nullptr, driven,
                              s > begin ? values + (s - 1) * m : nullptr);
                if (driven) modes.solve(std::polar(1.0, p * T), x.data(), states + s * m);
            }
        };
    });
}

}  // namespace amb_fast
