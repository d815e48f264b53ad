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
            double* channels[3] = {recorded.mutable_data(), displacement.mutable_data(), current.mutable_data()};
            const double* input = force.data();
            interruptible([&] {
                simulate(rig, controller, input, n, {channels[0], channels[1], channels[2]}, seed);
                return 0;
            });
            return py::make_tuple(recorded, displacement, current);
        },
        py::arg("rig"), py::arg("controller"), py::arg("force"), py::arg("seed") = 0,
        "Runs the closed loop from rest on a force sequence (N) at fs; returns the recorded force (N), sensor "
        "displacement (m) and coil current (A). Releases the GIL while it runs; Ctrl-C stops it.");

    m.def(
        "loop_model",
        [](const Rig& rig, const Controller& controller) {
            const MimoModel model = Loop(rig, controller).linear_model();
            py::dict out;
            out["M"] = model.M;
            out["Bf"] = model.Bf;
            out["Bn"] = model.Bn;
            out["C"] = model.C;
            out["Dn"] = model.Dn;
            out["transducer_pole"] = model.transducer_pole;
            out["sensor_noise"] = model.sensor_noise;
            out["force_noise"] = model.force_noise;
            return out;
        },
        py::arg("rig"), py::arg("controller"),
        "The linear loop as the MIMO model that run_experiment draws its spectra from (Loop::linear_model): "
        "the arguments of mimo_line_experiments, by name.");
    m.def(
        "normal_noise",
        [](std::uint64_t seed, const std::vector<Eigen::Index>& chunks, double sigma) {
            Eigen::Index n = 0;
            for (Eigen::Index c : chunks) {
                if (c < 0) throw std::invalid_argument("chunks must be >= 0");
                n += c;
            }
            py::array_t<double> out(n);
            NormalStream stream(seed);
            double* at = out.mutable_data();
            for (Eigen::Index c : chunks) {
                stream.fill(at, c, sigma);
                at += c;
            }
            return out;
        },
        py::arg("seed"), py::arg("chunks"), py::arg("sigma") = 1.0,
        "The loop's noise stream of this seed (the sensor's; the force's is seed ^ 0x9e3779b97f4a7c15): "
        "sum(chunks) deviates of N(0, sigma^2), drawn in calls of the given sizes.");
    m.def(
        "xoshiro256pp",
        [](std::uint64_t seed, Eigen::Index n) {
            if (n < 0) throw std::invalid_argument("n must be >= 0");
            py::array_t<std::uint64_t> out(n);
            Xoshiro256pp rng(seed);
            for (Eigen::Index j = 0; j < n; ++j) out.mutable_data()[j] = rng();
            return out;
        },
        py::arg("seed"), py::arg("n"), "The first n outputs of the noise generator for this seed (tests).");
}
