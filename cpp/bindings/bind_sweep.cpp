#include "amb_fast/batch.hpp"
#include "bindings.hpp"

#include <pybind11/complex.h>
#include <pybind11/numpy.h>

using namespace amb_fast;

namespace {
// A matrix (row-major) or vector moved into a numpy array that owns it: writable, not copied.
template <class Matrix>
py::array owned(Matrix& matrix) {
    using T = typename Matrix::Scalar;
    auto* held = new Matrix(std::move(matrix));
    const py::capsule owner(held, [](void* p) { delete static_cast<Matrix*>(p); });
    const auto size = static_cast<py::ssize_t>(sizeof(T));
    if constexpr (Matrix::ColsAtCompileTime == 1)
        return py::array_t<T>({static_cast<py::ssize_t>(held->size())}, {size}, held->data(), owner);
    else
        return py::array_t<T>({static_cast<py::ssize_t>(held->rows()), static_cast<py::ssize_t>(held->cols())},
                              {static_cast<py::ssize_t>(held->cols()) * size, size}, held->data(), owner);
}
}  // namespace

void bind_sweep(py::module_& m) {
    py::enum_<PointStatus>(m, "PointStatus", "Outcome of one point of a sweep.")
        .value("ok", PointStatus::ok)
        .value("unstable", PointStatus::unstable)
        .value("touchdown", PointStatus::touchdown)
        .value("saturated", PointStatus::saturated);

    py::class_<SweepEstimates>(m, "SweepEstimates", "Estimates of a sweep, one row per point (see amb_fast.sweep).")
        .def_readonly("H", &SweepEstimates::H)
        .def_readonly("k", &SweepEstimates::k)
        .def_readonly("c", &SweepEstimates::c)
        .def_readonly("k_std", &SweepEstimates::k_std)
        .def_readonly("c_std", &SweepEstimates::c_std)
        .def_readonly("k_smooth", &SweepEstimates::k_smooth)
        .def_readonly("c_smooth", &SweepEstimates::c_smooth)
        .def_readonly("unexcited_displacement", &SweepEstimates::unexcited_displacement)
        .def_readonly("status", &SweepEstimates::status)
        .def_readonly("radius", &SweepEstimates::radius)
        .def_readonly("periods", &SweepEstimates::periods)
        .def_readonly("blocks", &SweepEstimates::blocks)
        .def(
            "take",
            [](SweepEstimates& e) {
                py::dict out;
                out["H"] = owned(e.H);
                for (auto [name, matrix] : {std::pair{"k", &e.k},
                                            {"c", &e.c},
                                            {"k_std", &e.k_std},
                                            {"c_std", &e.c_std},
                                            {"k_smooth", &e.k_smooth},
                                            {"c_smooth", &e.c_smooth},
                                            {"unexcited_displacement", &e.unexcited_displacement}})
                    out[name] = owned(*matrix);
                out["status"] = owned(e.status);
                out["radius"] = owned(e.radius);
                return out;
            },
            "The arrays, moved into numpy arrays that own them (writable, not copied): a dict by name. The "
            "attributes are empty afterwards.");

    m.def(
        "run_sweep",
        [](const Eigen::Ref<const Eigen::VectorXd>& period_force, const std::vector<Rig>& rigs,
           const std::vector<Controller>& controllers,
           const Eigen::Ref<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>>& settle_periods,
           const Eigen::Ref<const Eigen::Matrix<std::uint64_t, Eigen::Dynamic, 1>>& seeds, Eigen::Index periods,
           const LinePlan& plan, int median_window, int workers, bool steady_start,
           const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& loop_matrices) {
            const auto n = static_cast<Eigen::Index>(controllers.size());
            if (static_cast<Eigen::Index>(rigs.size()) != n || settle_periods.size() != n || seeds.size() != n)
                throw std::invalid_argument(
                    "rigs, controllers, settle_periods and seeds must have one entry per point");
            LoopMatrices loops;
            if (loop_matrices) {
                const auto& a = *loop_matrices;
                if (a.ndim() != 3 || a.shape(0) != n || a.shape(1) != a.shape(2) || a.shape(1) == 0)
                    throw std::invalid_argument("loop_matrices must have shape (points, m, m)");
                loops = {a.data(), static_cast<Eigen::Index>(a.shape(1))};
            }
            std::vector<SweepPoint> points;
            points.reserve(static_cast<std::size_t>(n));
            for (Eigen::Index g = 0; g < n; ++g) {
                const auto k = static_cast<std::size_t>(g);
                points.push_back({rigs[k], controllers[k], settle_periods[g], seeds[g]});
            }
            return interruptible([&] {
                return run_sweep(period_force, points, periods, plan, median_window, workers, steady_start, loops);
            });
        },
        py::arg("period_force"), py::arg("rigs"), py::arg("controllers"), py::arg("settle_periods"), py::arg("seeds"),
        py::arg("periods"), py::arg("plan"), py::arg("median_window"), py::arg("workers"),
        py::arg("steady_start") = false, py::arg("loop_matrices") = std::nullopt,
        "Runs one experiment per point (rig, controller) on `workers` threads (<= 0: all cores), GIL released; "
        "Ctrl-C stops it. With loop_matrices (points, m, m), each point's closed-loop matrix, the workers check "
        "stability first: a point of spectral radius >= 1 is flagged unstable and not run (radius: every point's).");
    m.def(
        "eigenvalues",
        [](const py::array_t<double, py::array::c_style | py::array::forcecast>& stack, int workers) {
            if (stack.ndim() != 3 || stack.shape(1) != stack.shape(2))
                throw std::invalid_argument("stack must have shape (count, m, m)");
            const auto count = static_cast<Eigen::Index>(stack.shape(0)), m = static_cast<Eigen::Index>(stack.shape(1));
            py::array_t<std::complex<double>> values({count, m});
            std::complex<double>* out = values.mutable_data();
            const double* in = stack.data();
            interruptible([&] {
                eigenvalues(in, count, m, out, workers);
                return 0;
            });
            return values;
        },
        py::arg("stack"), py::arg("workers") = 1,
        "The eigenvalues of a stack of real square matrices (count, m, m) -> (count, m), complex, on `workers` "
        "threads (<= 0: all cores), GIL released.");
}
