#include "amb_fast/nd_loop.hpp"
#include "bindings.hpp"

#include <stdexcept>
#include <string>

using namespace amb_fast;

namespace {
template <class T>
T item(const py::dict& d, const char* key) {
    if (!d.contains(key)) throw std::invalid_argument(std::string("nd_loop: missing argument ") + key);
    return py::cast<T>(d[key]);
}

// One point's arguments (nd_loop's keywords), converted while the GIL is held.
NdPoint point_of(const py::dict& d) {
    using Eigen::MatrixXd, Eigen::VectorXd;
    NdPoint p;
    p.structure = {item<MatrixXd>(d, "mass"),      item<MatrixXd>(d, "gyroscopic"), item<MatrixXd>(d, "stiffness"),
                   item<MatrixXd>(d, "damping"),   item<MatrixXd>(d, "actuators"),  item<MatrixXd>(d, "probes"),
                   item<double>(d, "speed")};
    p.chains = {item<VectorXd>(d, "kyy"),          item<VectorXd>(d, "kiy"),
                item<VectorXd>(d, "amp_bandwidth"), item<VectorXd>(d, "eddy_bandwidth"),
                item<VectorXd>(d, "sensor_bandwidth"), item<VectorXd>(d, "mass_loading"),
                item<VectorXd>(d, "dead_time"),     item<VectorXd>(d, "force_coupling_tau")};
    p.fs = d.contains("fs") ? py::cast<double>(d["fs"]) : 0.0;
    p.closed = d.contains("Ac");
    if (p.closed)
        p.controller = {item<MatrixXd>(d, "Ac"), item<MatrixXd>(d, "Bc"), item<MatrixXd>(d, "Cc"),
                        item<MatrixXd>(d, "Dc")};
    return p;
}

// The pieces assembled: the plant, with fs its discrete form, with a controller the loop.
py::dict result(NdLoop&& r) {
    py::dict out;
    for (auto [name, v] : {std::pair{"position", &r.position}, {"velocity", &r.velocity}, {"coil", &r.coil},
                           {"eddy", &r.eddy}, {"sensor", &r.sensor}, {"lines", &r.lines}})
        out[name] = py::tuple(py::cast(*v));
    for (auto [name, m] : {std::pair{"A", &r.A}, {"B", &r.B}, {"S", &r.S}, {"Phi", &r.Phi}, {"Gamma", &r.Gamma},
                           {"M", &r.M}, {"Bf", &r.Bf}, {"Bn", &r.Bn}, {"C", &r.C}, {"Dn", &r.Dn}})
        if (m->size()) out[name] = py::cast(std::move(*m));
    if (r.poles.size()) out["poles"] = py::cast(std::move(r.poles));
    return out;
}
}  // namespace

void bind_nd_loop(py::module_& m) {
    m.def(
        "nd_loop",
        [](const py::kwargs& kwargs) {
            const NdPoint p = point_of(kwargs);
            NdLoop r = interruptible([&] { return nd_loop(p.structure, p.chains, p.fs, p.closed ? &p.controller : nullptr); });
            return result(std::move(r));
        },
        "The linear loop of N axes (amb_fast.system._model), keywords: the structure's mass, gyroscopic, stiffness, "
        "damping (n x n), actuators, probes (N x n), speed (rad/s); per axis (N) kyy, kiy, amp_bandwidth, "
        "eddy_bandwidth, sensor_bandwidth (Hz, NaN: ideal), mass_loading (kg), dead_time (s), force_coupling_tau "
        "(s, NaN: DC); optional fs (Hz: the discrete plant) and the controller matrix's Ac, Bc, Cc, Dc (the loop). "
        "Returns a dict: the layout (position, velocity, coil, eddy, sensor, lines), A, B, S, and with fs Phi, Gamma, "
        "with the controller M, Bf, Bn, C, Dn, poles. Releases the GIL.");
    m.def(
        "nd_loops",
        [](const py::list& points, int workers) {
            std::vector<NdPoint> given;
            given.reserve(points.size());
            for (const auto& p : points) given.push_back(point_of(py::cast<py::dict>(p)));
            std::vector<NdLoop> loops = interruptible([&] { return nd_loops(given, workers); });
            py::list out;
            for (auto& r : loops) out.append(result(std::move(r)));
            return out;
        },
        py::arg("points"), py::arg("workers") = 1,
        "nd_loop for each point (a dict of nd_loop's keywords), on `workers` threads (<= 0: all cores), GIL "
        "released; a list of nd_loop's dicts.");
}
