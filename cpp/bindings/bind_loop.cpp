#include "amb_fast/loop.hpp"
#include "bindings.hpp"

using namespace amb_fast;

namespace {
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
}

void bind_loop(py::module_& m) {
    m.def(
        "simulate",
        [](const Rig& rig, const Controller& controller, const InputArray& force, std::uint64_t seed) {
            if (force.ndim() != 1) throw std::invalid_argument("force must be one-dimensional (samples,)");
            const auto n = static_cast<Eigen::Index>(force.size());
            // Outputs are numpy's own arrays (numpy asks the kernel for huge pages on large ones).
            py::array_t<double> recorded(n), displacement(n), current(n);
            {
                py::gil_scoped_release release;
                simulate(rig, controller, force.data(), n,
                         {recorded.mutable_data(), displacement.mutable_data(), current.mutable_data()}, seed);
            }
            return py::make_tuple(recorded, displacement, current);
        },
        py::arg("rig"), py::arg("controller"), py::arg("force"), py::arg("seed") = 0,
        "Runs the closed loop from rest on a force sequence (N) at fs; returns the recorded force (N), sensor "
        "displacement (m) and coil current (A). Releases the GIL while it runs.");
}
