#include "amb_fast/loop.hpp"
#include "bindings.hpp"

using namespace amb_fast;

namespace {
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
}

void bind_loop(py::module_& m) {
    m.def(
        "simulate",
        [](const Rig& rig, const Pid& pid, const InputArray& force) {
            if (force.ndim() != 1) throw std::invalid_argument("force must be one-dimensional (samples,)");
            const auto n = static_cast<Eigen::Index>(force.size());
            // Outputs are numpy's own arrays (numpy asks the kernel for huge pages on large ones).
            py::array_t<double> displacement(n), current(n);
            {
                py::gil_scoped_release release;
                simulate(rig, pid, force.data(), n, displacement.mutable_data(), current.mutable_data());
            }
            return py::make_tuple(displacement, current);
        },
        py::arg("rig"), py::arg("pid"), py::arg("force"),
        "Runs the closed loop from rest on a force sequence (N) at fs; returns (sensor displacement m, coil "
        "current A). Releases the GIL while it runs.");
}
