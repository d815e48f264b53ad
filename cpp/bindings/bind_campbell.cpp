#include "amb_fast/campbell.hpp"
#include "bindings.hpp"

#include <pybind11/complex.h>
#include <pybind11/numpy.h>

using namespace amb_fast;

void bind_campbell(py::module_& m) {
    using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
    m.def(
        "hold_stacks",
        [](const RowMatrixXd& A0, const RowMatrixXd& A1, const RowMatrixXd& B, const std::vector<double>& holds,
           const Array& values, int workers) {
            if (values.ndim() != 1) throw std::invalid_argument("values must be 1-D");
            const auto count = static_cast<Eigen::Index>(values.shape(0));
            py::array_t<double> out({count, static_cast<Eigen::Index>(holds.size()), A0.rows(), A0.rows() + B.cols()});
            double* at = out.mutable_data();
            const double* p = values.data();
            interruptible([&] {
                hold_stacks(A0, A1, B, holds, p, count, workers, at);
                return 0;
            });
            return out;
        },
        py::arg("A0"), py::arg("A1"), py::arg("B"), py::arg("holds"), py::arg("values"), py::arg("workers") = 1,
        "[Phi | Gamma] (count, holds, n, n + k): the exact zero-order hold of A0 + p A1, B over each hold length "
        "(s), for each p of values; on `workers` threads, GIL released.");
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
        "eigenvectors v (zero for eigenvalues on the positive real axis); on `workers` threads, GIL released.");
}
