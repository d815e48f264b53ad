#include "amb_fast/estimate2x2.hpp"

#include <Eigen/LU>

#include <array>
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "amb_fast/errors.hpp"

namespace amb_fast {

using cd = std::complex<double>;

namespace {
using Matrix22 = std::array<cd, 4>;  // row-major 2x2: (0, 0), (0, 1), (1, 0), (1, 1)

// 1 / x without the library's scaled division (x: a determinant of well-conditioned line spectra).
cd reciprocal(cd x) { return std::conj(x) / std::norm(x); }

Matrix22 product(const Matrix22& a, const Matrix22& b) {
    return {a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2], a[2] * b[1] + a[3] * b[3]};
}
Matrix22 inverse(const Matrix22& a) {
    const cd inv = reciprocal(a[0] * a[3] - a[1] * a[2]);
    return {a[3] * inv, -a[1] * inv, -a[2] * inv, a[0] * inv};
}
}  // namespace

Estimate2x2 estimate_2x2(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines,
                         Eigen::Index periods, Eigen::Index lines) {
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    Estimate2x2 est;
    est.lines = lines;
    est.periods = periods;
    const auto n = static_cast<std::size_t>(4 * lines);
    for (auto* v : {&est.H, &est.receptance, &est.force, &est.displacement}) v->resize(n);
    est.var_re.resize(n);
    est.var_im.resize(n);
    // [period][line][channel][experiment]: one 2x2 matrix (row: channel, column: experiment), row-major.
    const auto at = [&](const cd* x, Eigen::Index period, Eigen::Index j) {
        const cd* m = x + (period * lines + j) * 4;
        return Matrix22{m[0], m[1], m[2], m[3]};
    };
    const double mean = 1.0 / static_cast<double>(periods), scale = 1.0 / static_cast<double>(periods * (periods - 1));
    for (Eigen::Index j = 0; j < lines; ++j) {
        Matrix22 F{}, Y{};  // the period means
        for (Eigen::Index period = 0; period < periods; ++period) {
            const Matrix22 f = at(force_lines, period, j), y = at(displacement_lines, period, j);
            for (int e = 0; e < 4; ++e) F[e] += f[e], Y[e] += y[e];
        }
        for (int e = 0; e < 4; ++e) {
            F[e] *= mean, Y[e] *= mean;
            if (!std::isfinite(F[e].real() + F[e].imag() + Y[e].real() + Y[e].imag()))
                throw std::invalid_argument("force and displacement must be finite");
        }
        const Matrix22 Yinv = inverse(Y), H = product(F, Yinv), receptance = inverse(H);
        // Linearised: dH = (dF - H dY) Y^-1 per period; the variance of Re H and Im H is the sum of the
        // squares / (P (P - 1)).
        double re[4] = {0, 0, 0, 0}, im[4] = {0, 0, 0, 0};
        for (Eigen::Index period = 0; period < periods; ++period) {
            Matrix22 dF = at(force_lines, period, j), dY = at(displacement_lines, period, j);
            for (int e = 0; e < 4; ++e) dF[e] -= F[e], dY[e] -= Y[e];
            const Matrix22 HdY = product(H, dY);
            for (int e = 0; e < 4; ++e) dF[e] -= HdY[e];
            const Matrix22 dH = product(dF, Yinv);
            for (int e = 0; e < 4; ++e) re[e] += dH[e].real() * dH[e].real(), im[e] += dH[e].imag() * dH[e].imag();
        }
        for (int e = 0; e < 4; ++e) {
            const auto k = static_cast<std::size_t>(4 * j + e);
            est.H[k] = H[e], est.receptance[k] = receptance[e], est.force[k] = F[e], est.displacement[k] = Y[e];
            est.var_re[k] = re[e] * scale, est.var_im[k] = im[e] * scale;
        }
    }
    return est;
}

namespace {
// estimate_nxn with N x N matrices of a fixed size (1 to 4: no allocation, unrolled) or N = Dynamic.
template <int N>
void estimate_lines(const cd* force_lines, const cd* displacement_lines, const double* readout, Eigen::Index periods,
                    Eigen::Index lines, Eigen::Index axes, Estimate2x2& est) {
    const Eigen::Index n = N == Eigen::Dynamic ? axes : N;  // a constant for a fixed size: loops unrolled
    using Matrix = Eigen::Matrix<cd, N, N, N == 1 ? Eigen::ColMajor : Eigen::RowMajor>;
    using Map = Eigen::Map<const Matrix>;
    const double mean = 1.0 / static_cast<double>(periods), scale = 1.0 / static_cast<double>(periods * (periods - 1));
    // [period][line][channel][experiment]: one N x N matrix per period and line, row-major.
    const auto at = [&](const cd* x, Eigen::Index period, Eigen::Index j) {
        return Map(x + (period * lines + j) * n * n, n, n);
    };
    // The displacements read through `readout` (row-major, real), per period of the line.
    std::vector<Matrix> read(readout ? static_cast<std::size_t>(periods) : 0, Matrix(n, n));
    const auto displacement = [&](Eigen::Index period, Eigen::Index j) {
        return readout ? Map(read[static_cast<std::size_t>(period)].data(), n, n) : at(displacement_lines, period, j);
    };
    // out = a b with every sum in order (the digits of Eigen's lazy product of dynamic size), the complex
    // products written out (finite numbers: the library's product adds a NaN check to each).
    const auto product = [n](const auto& a, const auto& b, Matrix& out) {
        const auto times = [](cd x, cd y) {
            return cd(x.real() * y.real() - x.imag() * y.imag(), x.real() * y.imag() + x.imag() * y.real());
        };
        for (Eigen::Index r = 0; r < n; ++r)
            for (Eigen::Index c = 0; c < n; ++c) {
                cd sum = times(a(r, 0), b(0, c));
                for (Eigen::Index s = 1; s < n; ++s) sum += times(a(r, s), b(s, c));
                out(r, c) = sum;
            }
    };
    Matrix F(n, n), Y(n, n), H(n, n), dY(n, n), HdY(n, n), dF(n, n), dH(n, n);
    Eigen::Matrix<double, N, N> re(n, n), im(n, n);
    for (Eigen::Index j = 0; j < lines; ++j) {
        for (Eigen::Index period = 0; readout && period < periods; ++period) {
            const Map y = at(displacement_lines, period, j);
            Matrix& out = read[static_cast<std::size_t>(period)];
            for (Eigen::Index r = 0; r < n; ++r)
                for (Eigen::Index c = 0; c < n; ++c) {
                    cd sum = 0.0;
                    for (Eigen::Index s = 0; s < n; ++s) sum += readout[r * n + s] * y(s, c);
                    out(r, c) = sum;
                }
        }
        F.setZero();
        Y.setZero();
        for (Eigen::Index period = 0; period < periods; ++period) {
            F += at(force_lines, period, j);
            Y += displacement(period, j);
        }
        F *= mean;
        Y *= mean;
        if (!F.allFinite() || !Y.allFinite()) throw std::invalid_argument("force and displacement must be finite");
        const Eigen::PartialPivLU<Matrix> lu(Y);
        const Matrix Yinv = lu.inverse();
        product(F, Yinv, H);
        const Matrix receptance = Eigen::PartialPivLU<Matrix>(H).inverse();
        re.setZero();
        im.setZero();
        for (Eigen::Index period = 0; period < periods; ++period) {
            dY = displacement(period, j) - Y;
            product(H, dY, HdY);
            dF = (at(force_lines, period, j) - F) - HdY;
            product(dF, Yinv, dH);
            re += dH.real().cwiseAbs2();
            im += dH.imag().cwiseAbs2();
        }
        for (Eigen::Index r = 0; r < n; ++r)
            for (Eigen::Index c = 0; c < n; ++c) {
                const auto k = static_cast<std::size_t>((j * n + r) * n + c);
                est.H[k] = H(r, c), est.receptance[k] = receptance(r, c), est.force[k] = F(r, c);
                est.displacement[k] = Y(r, c), est.var_re[k] = re(r, c) * scale, est.var_im[k] = im(r, c) * scale;
            }
    }
}
}  // namespace

Estimate2x2 estimate_nxn(const std::complex<double>* force_lines, const std::complex<double>* displacement_lines,
                         Eigen::Index periods, Eigen::Index lines, Eigen::Index n, const double* readout) {
    require(periods >= 2, "periods", periods, ">= 2 (standard errors need at least two)");
    require(n >= 1, "axes", n, ">= 1");
    Estimate2x2 est;
    est.lines = lines;
    est.periods = periods;
    const auto size = static_cast<std::size_t>(n * n * lines);
    for (auto* v : {&est.H, &est.receptance, &est.force, &est.displacement}) v->resize(size);
    est.var_re.resize(size);
    est.var_im.resize(size);
    const auto run = [&](auto fixed) {
        estimate_lines<decltype(fixed)::value>(force_lines, displacement_lines, readout, periods, lines, n, est);
    };
    switch (n) {
        case 1:
            run(std::integral_constant<int, 1>{});
            break;
        case 2:
            run(std::integral_constant<int, 2>{});
            break;
        case 3:
            run(std::integral_constant<int, 3>{});
            break;
        case 4:
            run(std::integral_constant<int, 4>{});
            break;
        default:
            run(std::integral_constant<int, Eigen::Dynamic>{});
    }
    return est;
}

}  // namespace amb_fast
