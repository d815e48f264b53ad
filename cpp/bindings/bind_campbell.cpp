#include "amb_fast/campbell.hpp"
#include "bindings.hpp"

#include <pybind11/complex.h>
#include <pybind11/numpy.h>

#include <optional>

using namespace amb_fast;

void bind_campbell(py::module_& m) {
    using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
    m.def(
        "speed_loops",
        [](const RowMatrixXd& A0, const RowMatrixXd& A1, const RowMatrixXd& B, const std::vector<double>& holds,
           const RowMatrixXd& P, const RowMatrixXd& L, const Array& speeds, const std::optional<RowMatrixXd>& R,
           const std::optional<Eigen::VectorXcd>& drive, bool loops, int workers) {
            if (speeds.ndim() != 1) throw std::invalid_argument("speeds must be 1-D");
            SpeedLoops in{A0, A1, B, holds, P, L, drive.value_or(Eigen::VectorXcd()), R.value_or(RowMatrixXd())};
            const auto count = static_cast<Eigen::Index>(speeds.shape(0));
            const Eigen::Index m = L.rows(), r = in.R.rows();
            py::array_t<std::complex<double>> values({count, m});
            py::object shapes = py::none(), states = py::none(), stack = py::none();
            std::complex<double>*s = nullptr, *x = nullptr;
            double* at = nullptr;
            if (R) {
                py::array_t<std::complex<double>> a({count, r, m});
                s = a.mutable_data(), shapes = a;
            }
            if (drive) {
                py::array_t<std::complex<double>> a({count, m});
                x = a.mutable_data(), states = a;
            }
            if (loops) {
                py::array_t<double> a({count, m, m});
                at = a.mutable_data(), stack = a;
            }
            std::complex<double>* v = values.mutable_data();
            const double* p = speeds.data();
            interruptible([&] {
                speed_loops(in, p, count, workers, at, v, s, x);
                return 0;
            });
            return py::make_tuple(values, shapes, states, stack);
        },
        py::arg("A0"), py::arg("A1"), py::arg("B"), py::arg("holds"), py::arg("P"), py::arg("L"), py::arg("speeds"),
        py::arg("R") = py::none(), py::arg("drive") = py::none(), py::arg("loops") = false, py::arg("workers") = 1,
        "Per speed p the sampled loop L + [Phi | Gamma(holds[0]) | Gamma(holds[1]) ...] P (top rows) of the plant "
        "A0 + p A1, B: (eigenvalues (count, m), R v of their unit eigenvectors (count, r, m) or None, the steady "
        "state at z = e^{j p T} driven by the force Re(p^2 drive e^{j p t}) (count, m) or None, the loops "
        "(count, m, m) or None); on `workers` threads, GIL released.");
    m.def(
        "loop_modes",
        [](const Array& stack, const RowMatrixXd& R, int workers) {
            if (stack.ndim() != 3 || stack.shape(1) != stack.shape(2))
                throw std::invalid_argument("stack must have shape (count, m, m)");
            const auto count = static_cast<Eigen::Index>(stack.shape(0)),
                       size = static_cast<Eigen::Index>(stack.shape(1));
            py::array_t<std::complex<double>> values({count, size}), shapes({count, R.rows(), size});
            std::complex<double>*v = values.mutable_data(), *s = shapes.mutable_data();
            const double* in = stack.data();
            interruptible([&] {
                loop_modes(in, count, size, R, workers, v, s);
                return 0;
            });
            return py::make_tuple(values, shapes);
        },
        py::arg("stack"), py::arg("R"), py::arg("workers") = 1,
        "Eigenvalues (count, m) of each matrix of a stack (count, m, m) and R v (count, r, m) for their unit "
        "eigenvectors v (zero for real eigenvalues); on `workers` threads, GIL released.");
}
