#include "amb_fast/batch.hpp"
#include "amb_fast/experiment.hpp"
#include "bindings.hpp"

using namespace amb_fast;

namespace {
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
}

void bind_spectrum(py::module_& m) {
    py::class_<LinePlan>(m, "LinePlan", "Period length (samples) and the harmonic numbers of excited/unexcited lines.")
        .def(py::init([](Eigen::Index period,
                         const Eigen::Ref<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>>& excited,
                         const Eigen::Ref<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>>& unexcited) {
                 LinePlan plan{period, {excited.begin(), excited.end()}, {unexcited.begin(), unexcited.end()}, 1};
                 plan.validate();
                 return plan;
             }),
             py::kw_only(), py::arg("period"), py::arg("excited"), py::arg("unexcited"));

    py::class_<LineEstimate>(m, "LineEstimate", "Raw estimator output (see amb_fast.Estimate for units).")
        .def_readonly("force", &LineEstimate::force)
        .def_readonly("displacement", &LineEstimate::displacement)
        .def_readonly("H", &LineEstimate::H)
        .def_readonly("k", &LineEstimate::k)
        .def_readonly("c", &LineEstimate::c)
        .def_readonly("k_std", &LineEstimate::k_std)
        .def_readonly("c_std", &LineEstimate::c_std)
        .def_readonly("k_smooth", &LineEstimate::k_smooth)
        .def_readonly("c_smooth", &LineEstimate::c_smooth)
        .def_readonly("unexcited_force", &LineEstimate::unexcited_force)
        .def_readonly("unexcited_displacement", &LineEstimate::unexcited_displacement)
        .def_readonly("periods", &LineEstimate::periods)
        .def_readonly("blocks", &LineEstimate::blocks)
        .def_readonly("saturated_samples", &LineEstimate::saturated_samples);

    m.def(
        "median_filter",
        [](const InputArray& x, int window) {
            if (x.ndim() != 2) throw std::invalid_argument("x must be 2-D: (lines, columns)");
            if (window < 1 || window % 2 == 0)
                throw std::invalid_argument("window must be an odd number >= 1, got " + std::to_string(window));
            const auto n = static_cast<Eigen::Index>(x.shape(0)), columns = static_cast<Eigen::Index>(x.shape(1));
            py::array_t<double> out({n, columns});
            const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> in(
                x.data(), n, columns);
            Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> to(out.mutable_data(), n,
                                                                                                  columns);
            for (Eigen::Index c = 0; c < columns; ++c) to.col(c) = median_filter(in.col(c), window);
            return out;
        },
        py::arg("x"), py::arg("window"),
        "Running median of each column across the rows (odd window; the ends repeat the edge value).");
    m.def(
        "line_spectrum",
        [](const InputArray& x, const std::vector<Eigen::Index>& bins, const std::string& method) -> py::tuple {
            if (x.ndim() != 1 && x.ndim() != 2) throw std::invalid_argument("x must be one period or rows of periods");
            const auto how = method == "fft"      ? LineTransform::Method::fft
                             : method == "direct" ? LineTransform::Method::direct
                             : method == "auto"   ? LineTransform::Method::automatic
                                                  : throw std::invalid_argument("method must be auto, fft or direct");
            const Eigen::Index rows = x.ndim() == 1 ? 1 : static_cast<Eigen::Index>(x.shape(0));
            const auto L = static_cast<Eigen::Index>(x.shape(x.ndim() - 1));
            const auto n = static_cast<Eigen::Index>(bins.size());
            RowMatrixXcd lines(rows, n);
            auto used = how;
            {
                py::gil_scoped_release release;
                LineTransform transform(L, bins, how);
                for (Eigen::Index r = 0; r < rows; ++r) transform(x.data() + r * L, lines.row(r).data());
                used = transform.method();
            }
            const char* name = used == LineTransform::Method::fft ? "fft" : "direct";
            if (x.ndim() == 1) return py::make_tuple(Eigen::VectorXcd(lines.row(0).transpose()), name);
            return py::make_tuple(lines, name);
        },
        py::arg("x"), py::arg("bins"), py::arg("method") = "auto",
        "The estimator's transform: unscaled DFT bins of one period, or of each row of periods "
        "(numpy.fft.rfft(x, axis=-1)[..., bins]), and the method used.");

    m.def(
        "run_experiment",
        [](const Rig& rig, const Controller& controller, const Eigen::Ref<const Eigen::VectorXd>& period_force,
           Eigen::Index settle_periods, Eigen::Index periods, const LinePlan& plan, std::uint64_t seed,
           int median_window, bool steady_start) {
            return interruptible([&] {
                return run_experiment(rig, controller, period_force, settle_periods, periods, plan, seed, median_window,
                                      steady_start);
            });
        },
        py::arg("rig"), py::arg("controller"), py::arg("period_force"), py::arg("settle_periods"), py::arg("periods"),
        py::arg("plan"), py::arg("seed"), py::arg("median_window"), py::arg("steady_start") = false,
        "Simulates settle + periods of the repeated excitation and estimates, keeping no time series.");

    m.def(
        "identify",
        [](const InputArray& force, const InputArray& displacement, Eigen::Index settle_periods, const LinePlan& plan,
           double mass, double fs, int median_window) {
            if (force.ndim() != 1 || displacement.ndim() != 1 || force.size() != displacement.size())
                throw std::invalid_argument("force and displacement must be one-dimensional and of equal length");
            return interruptible([&] {
                return identify(force.data(), displacement.data(), static_cast<Eigen::Index>(force.size()),
                                settle_periods, plan, mass, fs, median_window);
            });
        },
        py::arg("force"), py::arg("displacement"), py::arg("settle_periods"), py::arg("plan"), py::arg("mass"),
        py::arg("fs"), py::arg("median_window"), "The estimator over recorded arrays (whole periods).");
}
