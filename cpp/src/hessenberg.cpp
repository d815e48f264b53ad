#include "amb_fast/hessenberg.hpp"

#include <cstring>
#include <stdexcept>

#include "amb_fast/inline.hpp"
#include "amb_fast/lanes.hpp"

namespace amb_fast {

using cd = std::complex<double>;

namespace {
constexpr int K = HessenbergLU::lanes;

// One number of every lane (shift). GCC's and Clang's vector type where there is one: whole SIMD
// registers, AVX2 ones in the kernels built for it. Elsewhere four doubles with the same operations.
#if AMB_FAST_LANES_OK
using Shifted = Lanes<K>;
AMB_FAST_ALWAYS_INLINE Shifted where_greater(const Shifted& x, const Shifted& y, const Shifted& a, const Shifted& b) {
    return x > y ? a : b;
}
#else
struct Shifted {
    double v[K];
    double& operator[](int l) { return v[l]; }
    double operator[](int l) const { return v[l]; }
};
#define AMB_FAST_LANEWISE(op)                                        \
    inline Shifted operator op(const Shifted& a, const Shifted& b) { \
        Shifted c;                                                   \
        for (int l = 0; l < K; ++l) c[l] = a[l] op b[l];             \
        return c;                                                    \
    }
AMB_FAST_LANEWISE(+)
AMB_FAST_LANEWISE(-)
AMB_FAST_LANEWISE(*)
AMB_FAST_LANEWISE(/)
#undef AMB_FAST_LANEWISE
inline Shifted operator-(const Shifted& a) { return Shifted{} - a; }
inline Shifted& operator-=(Shifted& a, const Shifted& b) { return a = a - b; }
inline Shifted where_greater(const Shifted& x, const Shifted& y, const Shifted& a, const Shifted& b) {
    Shifted c;
    for (int l = 0; l < K; ++l) c[l] = x[l] > y[l] ? a[l] : b[l];
    return c;
}
#endif

// Loads and stores at any address (a std::vector<double> is not aligned to a whole vector).
AMB_FAST_ALWAYS_INLINE Shifted load(const double* p) {
    Shifted x;
    std::memcpy(&x, p, sizeof x);
    return x;
}
AMB_FAST_ALWAYS_INLINE void store(double* p, const Shifted& x) { std::memcpy(p, &x, sizeof x); }
AMB_FAST_ALWAYS_INLINE Shifted broadcast(double x) {
    Shifted v;
    for (int l = 0; l < K; ++l) v[l] = x;
    return v;
}

// a -= m b, complex, lane by lane (real and imaginary parts apart), a at a_r, a_i.
AMB_FAST_ALWAYS_INLINE void subtract_product(double* a_r, double* a_i, const Shifted& mr, const Shifted& mi,
                                             const Shifted& br, const Shifted& bi) {
    store(a_r, load(a_r) - (mr * br - mi * bi));
    store(a_i, load(a_i) - (mr * bi + mi * br));
}

// Rows a and b exchanged in the lanes where `swapped` is 1 (0 elsewhere).
AMB_FAST_ALWAYS_INLINE void exchange_where(const Shifted& swapped, double* ar, double* ai, double* br, double* bi) {
    const Shifted half = broadcast(0.5);
    const Shifted a_r = load(ar), a_i = load(ai), b_r = load(br), b_i = load(bi);
    store(ar, where_greater(swapped, half, b_r, a_r));
    store(ai, where_greater(swapped, half, b_i, a_i));
    store(br, where_greater(swapped, half, a_r, b_r));
    store(bi, where_greater(swapped, half, a_i, b_i));
}

// x = s d, complex, lane by lane (d: a stored 1 / pivot).
AMB_FAST_ALWAYS_INLINE void set_product(double* xr, double* xi, const Shifted& sr, const Shifted& si, const double* dr,
                                        const double* di) {
    const Shifted d_r = load(dr), d_i = load(di);
    store(xr, sr * d_r - si * d_i);
    store(xi, sr * d_i + si * d_r);
}

// The factors' storage, as HessenbergLU lays it out (see its members): written by the factorisation
// (T = double), read by the solves (T = const double).
template <class T>
struct FactorsOf {
    Eigen::Index n;
    const double* H;  // row-major
    T *ur, *ui, *dr, *di, *mr, *mi, *swapped;
};
using Factors = FactorsOf<double>;
using ConstFactors = FactorsOf<const double>;

// Returns false where a pivot is exactly zero (z a pole of the loop).
AMB_FAST_ALWAYS_INLINE bool factor_kernel(const Factors& f, const cd* z) {
    const Eigen::Index n = f.n;
    const auto U_r = [&](Eigen::Index i, Eigen::Index c) { return f.ur + (i * n + c) * K; };
    const auto U_i = [&](Eigen::Index i, Eigen::Index c) { return f.ui + (i * n + c) * K; };
    const Shifted zero = broadcast(0.0), one = broadcast(1.0);
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index c = 0; c < n; ++c) {
            store(U_r(i, c), broadcast(-f.H[i * n + c]));
            store(U_i(i, c), zero);
        }
    for (Eigen::Index i = 0; i < n; ++i) {
        Shifted zr, zi;
        for (int l = 0; l < K; ++l) zr[l] = z[l].real(), zi[l] = z[l].imag();
        store(U_r(i, i), load(U_r(i, i)) + zr);
        store(U_i(i, i), zi);
    }
    for (Eigen::Index j = 0; j < n; ++j) {
        if (j + 1 < n) {  // pivot: the larger of rows j and j + 1 in column j, lane by lane
            const Shifted below = load(U_r(j + 1, j)) * load(U_r(j + 1, j)) + load(U_i(j + 1, j)) * load(U_i(j + 1, j));
            const Shifted here = load(U_r(j, j)) * load(U_r(j, j)) + load(U_i(j, j)) * load(U_i(j, j));
            const Shifted swap = where_greater(below, here, one, zero);
            store(f.swapped + j * K, swap);
            bool any = false;
            for (int l = 0; l < K; ++l) any = any || swap[l] != 0.0;
            if (any)
                for (Eigen::Index c = j; c < n; ++c)
                    exchange_where(swap, U_r(j, c), U_i(j, c), U_r(j + 1, c), U_i(j + 1, c));
        }
        // 1 / x = conj(x) / |x|^2 (a pivot of a well-conditioned matrix: no scaling)
        const Shifted a = load(U_r(j, j)), b = load(U_i(j, j)), norm = a * a + b * b;
        for (int l = 0; l < K; ++l)
            if (norm[l] == 0.0) return false;
        const Shifted inv_r = a / norm, inv_i = -b / norm;
        store(f.dr + j * K, inv_r);
        store(f.di + j * K, inv_i);
        if (j + 1 == n) break;
        const Shifted lr = load(U_r(j + 1, j)), li = load(U_i(j + 1, j));
        const Shifted m_r = lr * inv_r - li * inv_i, m_i = lr * inv_i + li * inv_r;
        store(f.mr + j * K, m_r);
        store(f.mi + j * K, m_i);
        store(U_r(j + 1, j), zero);
        store(U_i(j + 1, j), zero);
        for (Eigen::Index c = j + 1; c < n; ++c)
            subtract_product(U_r(j + 1, c), U_i(j + 1, c), m_r, m_i, load(U_r(j, c)), load(U_i(j, c)));
    }
    return true;
}

AMB_FAST_ALWAYS_INLINE void solve_kernel(const ConstFactors& f, double* re, double* im) {
    const Eigen::Index n = f.n;
    for (Eigen::Index j = 0; j + 1 < n; ++j) {  // the row operations: swaps and eliminations
        exchange_where(load(f.swapped + j * K), re + j * K, im + j * K, re + (j + 1) * K, im + (j + 1) * K);
        subtract_product(re + (j + 1) * K, im + (j + 1) * K, load(f.mr + j * K), load(f.mi + j * K), load(re + j * K),
                         load(im + j * K));
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {  // back substitution with U
        Shifted sr = load(re + i * K), si = load(im + i * K);
        for (Eigen::Index c = i + 1; c < n; ++c) {
            const Shifted ur = load(f.ur + (i * n + c) * K), ui = load(f.ui + (i * n + c) * K);
            const Shifted xr = load(re + c * K), xi = load(im + c * K);
            sr -= ur * xr - ui * xi;
            si -= ur * xi + ui * xr;
        }
        set_product(re + i * K, im + i * K, sr, si, f.dr + i * K, f.di + i * K);
    }
}

AMB_FAST_ALWAYS_INLINE void solve_transposed_kernel(const ConstFactors& f, double* re, double* im) {
    const Eigen::Index n = f.n;
    for (Eigen::Index i = 0; i < n; ++i) {  // U^T t = b
        Shifted sr = load(re + i * K), si = load(im + i * K);
        for (Eigen::Index k = 0; k < i; ++k) {
            const Shifted ur = load(f.ur + (k * n + i) * K), ui = load(f.ui + (k * n + i) * K);
            const Shifted xr = load(re + k * K), xi = load(im + k * K);
            sr -= ur * xr - ui * xi;
            si -= ur * xi + ui * xr;
        }
        set_product(re + i * K, im + i * K, sr, si, f.dr + i * K, f.di + i * K);
    }
    for (Eigen::Index j = n - 2; j >= 0; --j) {  // then the row operations transposed, last first
        subtract_product(re + j * K, im + j * K, load(f.mr + j * K), load(f.mi + j * K), load(re + (j + 1) * K),
                         load(im + (j + 1) * K));
        exchange_where(load(f.swapped + j * K), re + j * K, im + j * K, re + (j + 1) * K, im + (j + 1) * K);
    }
}

// Each kernel built twice: for any processor of the architecture, and for AVX2 (four lanes in one
// register), chosen at run time (simd_avx2). The same operations in the same order, so the same digits.
bool factor_portable(const Factors& f, const cd* z) { return factor_kernel(f, z); }
void solve_portable(const ConstFactors& f, double* re, double* im) { solve_kernel(f, re, im); }
void solve_transposed_portable(const ConstFactors& f, double* re, double* im) { solve_transposed_kernel(f, re, im); }
#if AMB_FAST_WIDE_LANES
__attribute__((target("avx2"))) bool factor_avx2(const Factors& f, const cd* z) { return factor_kernel(f, z); }
__attribute__((target("avx2"))) void solve_avx2(const ConstFactors& f, double* re, double* im) {
    solve_kernel(f, re, im);
}
__attribute__((target("avx2"))) void solve_transposed_avx2(const ConstFactors& f, double* re, double* im) {
    solve_transposed_kernel(f, re, im);
}
#else  // simd_avx2() is false here: the names only keep the dispatch below free of #if
constexpr auto factor_avx2 = factor_portable;
constexpr auto solve_avx2 = solve_portable;
constexpr auto solve_transposed_avx2 = solve_transposed_portable;
#endif
}  // namespace

HessenbergLU::HessenbergLU(const Eigen::MatrixXd& H)
    : n_(H.rows()),
      H_(H),
      ur_(static_cast<std::size_t>(n_ * n_ * lanes)),
      ui_(ur_.size()),
      dr_(static_cast<std::size_t>(n_ * lanes)),
      di_(dr_.size()),
      mr_(dr_.size()),
      mi_(dr_.size()),
      swapped_(dr_.size()) {}

void HessenbergLU::factor(const cd* z) {
    // clang-format off: a list, not a table
    const Factors f{n_, H_.data(), ur_.data(), ui_.data(), dr_.data(), di_.data(), mr_.data(), mi_.data(),
                    swapped_.data()};
    // clang-format on
    if (!(simd_avx2() ? factor_avx2 : factor_portable)(f, z))
        throw std::invalid_argument("zI - H is singular: z is a pole of the loop");
}

void HessenbergLU::solve(double* re, double* im) const {
    // clang-format off: a list, not a table
    const ConstFactors f{n_, H_.data(), ur_.data(), ui_.data(), dr_.data(), di_.data(), mr_.data(), mi_.data(),
                         swapped_.data()};
    // clang-format on
    (simd_avx2() ? solve_avx2 : solve_portable)(f, re, im);
}

void HessenbergLU::solve_transposed(double* re, double* im) const {
    // clang-format off: a list, not a table
    const ConstFactors f{n_, H_.data(), ur_.data(), ui_.data(), dr_.data(), di_.data(), mr_.data(), mi_.data(),
                         swapped_.data()};
    // clang-format on
    (simd_avx2() ? solve_transposed_avx2 : solve_transposed_portable)(f, re, im);
}

}  // namespace amb_fast
