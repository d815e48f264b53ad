#include "amb_fast/hessenberg.hpp"

#include <stdexcept>

namespace amb_fast {

using cd = std::complex<double>;

namespace {
// One number of every lane (shift): Eigen's fixed-size arrays, which compile to whole SIMD registers.
using Shifted = Eigen::Array<double, HessenbergLU::lanes, 1>;
using ShiftedAt = Eigen::Map<Shifted>;
using ConstShiftedAt = Eigen::Map<const Shifted>;

// a -= m b, complex, lane by lane (real and imaginary parts apart).
template <class A, class M, class B>
void subtract_product(A&& ar, A&& ai, const M& mr, const M& mi, const B& br, const B& bi) {
    ar -= mr * br - mi * bi;
    ai -= mr * bi + mi * br;
}

// x = s d, complex, lane by lane (d: a stored 1 / pivot).
void set_product(ShiftedAt xr, ShiftedAt xi, const Shifted& sr, const Shifted& si, ConstShiftedAt dr, ConstShiftedAt di) {
    xr = sr * dr - si * di;
    xi = sr * di + si * dr;
}

// Rows a and b exchanged in the lanes where `swap` holds.
template <class Mask>
void exchange_where(const Mask& swap, ShiftedAt ar, ShiftedAt ai, ShiftedAt br, ShiftedAt bi) {
    const Shifted r = ar, i = ai;
    ar = swap.select(br, r), ai = swap.select(bi, i);
    br = swap.select(r, br), bi = swap.select(i, bi);
}
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
    const Eigen::Index n = n_;
    const auto U_r = [&](Eigen::Index i, Eigen::Index c) { return ShiftedAt(ur_.data() + (i * n + c) * lanes); };
    const auto U_i = [&](Eigen::Index i, Eigen::Index c) { return ShiftedAt(ui_.data() + (i * n + c) * lanes); };
    Shifted zr, zi;
    for (int l = 0; l < lanes; ++l) zr[l] = z[l].real(), zi[l] = z[l].imag();
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index c = 0; c < n; ++c) {
            U_r(i, c).setConstant(-H_(i, c));
            U_i(i, c).setZero();
        }
    for (Eigen::Index i = 0; i < n; ++i) {
        U_r(i, i) += zr;
        U_i(i, i) = zi;
    }
    for (Eigen::Index j = 0; j < n; ++j) {
        if (j + 1 < n) {  // pivot: the larger of rows j and j + 1 in column j, lane by lane
            const auto swap = (U_r(j + 1, j).square() + U_i(j + 1, j).square() >
                               U_r(j, j).square() + U_i(j, j).square()).eval();
            ShiftedAt(swapped_.data() + j * lanes) = swap.cast<double>();
            for (Eigen::Index c = j; c < n && swap.any(); ++c) exchange_where(swap, U_r(j, c), U_i(j, c), U_r(j + 1, c), U_i(j + 1, c));
        }
        // 1 / x = conj(x) / |x|^2 (a pivot of a well-conditioned matrix: no scaling)
        const Shifted a = U_r(j, j), b = U_i(j, j), norm = a.square() + b.square();
        if ((norm == 0.0).any()) throw std::invalid_argument("zI - H is singular: z is a pole of the loop");
        const Shifted inv_r = a / norm, inv_i = -b / norm;
        ShiftedAt(dr_.data() + j * lanes) = inv_r;
        ShiftedAt(di_.data() + j * lanes) = inv_i;
        if (j + 1 == n) break;
        const Shifted lr = U_r(j + 1, j), li = U_i(j + 1, j);
        const Shifted m_r = lr * inv_r - li * inv_i, m_i = lr * inv_i + li * inv_r;
        ShiftedAt(mr_.data() + j * lanes) = m_r;
        ShiftedAt(mi_.data() + j * lanes) = m_i;
        U_r(j + 1, j).setZero();
        U_i(j + 1, j).setZero();
        for (Eigen::Index c = j + 1; c < n; ++c) subtract_product(U_r(j + 1, c), U_i(j + 1, c), m_r, m_i, U_r(j, c), U_i(j, c));
    }
}

void HessenbergLU::solve(double* re, double* im) const {
    const Eigen::Index n = n_;
    const auto x_r = [&](Eigen::Index i) { return ShiftedAt(re + i * lanes); };
    const auto x_i = [&](Eigen::Index i) { return ShiftedAt(im + i * lanes); };
    for (Eigen::Index j = 0; j + 1 < n; ++j) {  // the row operations: swaps and eliminations
        exchange_where((ConstShiftedAt(swapped_.data() + j * lanes) != 0.0).eval(), x_r(j), x_i(j), x_r(j + 1), x_i(j + 1));
        subtract_product(x_r(j + 1), x_i(j + 1), ConstShiftedAt(mr_.data() + j * lanes), ConstShiftedAt(mi_.data() + j * lanes),
                         x_r(j), x_i(j));
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {  // back substitution with U
        Shifted sr = x_r(i), si = x_i(i);
        for (Eigen::Index c = i + 1; c < n; ++c)
            subtract_product(sr, si, ConstShiftedAt(ur_.data() + (i * n + c) * lanes),
                             ConstShiftedAt(ui_.data() + (i * n + c) * lanes), x_r(c), x_i(c));
        set_product(x_r(i), x_i(i), sr, si, ConstShiftedAt(dr_.data() + i * lanes), ConstShiftedAt(di_.data() + i * lanes));
    }
}

void HessenbergLU::solve_transposed(double* re, double* im) const {
    const Eigen::Index n = n_;
    const auto x_r = [&](Eigen::Index i) { return ShiftedAt(re + i * lanes); };
    const auto x_i = [&](Eigen::Index i) { return ShiftedAt(im + i * lanes); };
    for (Eigen::Index i = 0; i < n; ++i) {  // U^T t = b
        Shifted sr = x_r(i), si = x_i(i);
        for (Eigen::Index k = 0; k < i; ++k)
            subtract_product(sr, si, ConstShiftedAt(ur_.data() + (k * n + i) * lanes),
                             ConstShiftedAt(ui_.data() + (k * n + i) * lanes), x_r(k), x_i(k));
        set_product(x_r(i), x_i(i), sr, si, ConstShiftedAt(dr_.data() + i * lanes), ConstShiftedAt(di_.data() + i * lanes));
    }
    for (Eigen::Index j = n - 2; j >= 0; --j) {  // then the row operations transposed, last first
        subtract_product(x_r(j), x_i(j), ConstShiftedAt(mr_.data() + j * lanes), ConstShiftedAt(mi_.data() + j * lanes),
                         x_r(j + 1), x_i(j + 1));
        exchange_where((ConstShiftedAt(swapped_.data() + j * lanes) != 0.0).eval(), x_r(j), x_i(j), x_r(j + 1), x_i(j + 1));
    }
}

}  // namespace amb_fast
