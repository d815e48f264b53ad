#include "amb_fast/nd_loop.hpp"
#include "bindings.hpp"

#include <stdexcept>
#include <string>

using namespace amb_fast;

namespace {
using Eigen::MatrixXd, Eigen::VectorXd;

// d[key] as a float64 array of `ndim` dimensions (viewed where it is one already: the Eigen caster's copy
// through a second numpy array costs more than the assembly of a small loop).
py::array_t<double, py::array::c_style | py::array::forcecast> array(const py::dict& d, const char* key, int ndim) {
    PyObject* value = PyDict_GetItemString(d.ptr(), key);  // borrowed
    if (!value) throw std::invalid_argument(std::string("nd_loop: missing argument ") + key);
    auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a || a.ndim() != ndim)
        throw std::invalid_argument(std::string(key) + " must be a " + (ndim == 2 ? "matrix" : "vector") +
                                    " of numbers");
    return a;
}
MatrixXd matrix(const py::dict& d, const char* key) {
    const auto a = array(d, key, 2);
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        a.data(), a.shape(0), a.shape(1));
}
VectorXd vector(const py::dict& d, const char* key) {
    const auto a = array(d, key, 1);
    return Eigen::Map<const VectorXd>(a.data(), a.shape(0));
}
double number(const py::dict& d, const char* key, double absent) {
    PyObject* value = PyDict_GetItemString(d.ptr(), key);
    return value ? py::cast<double>(py::handle(value)) : absent;
}

// One point's arguments (nd_loop's keywords), converted while the GIL is held.
NdPoint point_of(const py::dict& d) {
    NdPoint p;
    p.structure = {matrix(d, "mass"),      matrix(d, "gyroscopic"), matrix(d, "stiffness"), matrix(d, "damping"),
                   matrix(d, "actuators"), matrix(d, "probes"),     number(d, "speed", 0.0)};
    p.chains = {vector(d, "kyy"),
                vector(d, "kiy"),
                vector(d, "amp_bandwidth"),
                vector(d, "eddy_bandwidth"),
                vector(d, "sensor_bandwidth"),
                vector(d, "mass_loading"),
                vector(d, "dead_time"),
                vector(d, "force_coupling_tau")};
    p.fs = number(d, "fs", 0.0);
    p.closed = PyDict_GetItemString(d.ptr(), "Ac") != nullptr;
    if (p.closed) p.controller = {matrix(d, "Ac"), matrix(d, "Bc"), matrix(d, "Cc"), matrix(d, "Dc")};
    return p;
}

// The pieces assembled: the plant, with fs its discrete form, with a controller the loop.
py::dict result(NdLoop&& r) {
    py::dict out;
    for (auto [name, v] : {std::pair{"position", &r.position},
                           {"velocity", &r.velocity},
                           {"coil", &r.coil},
                           {"eddy", &r.eddy},
                           {"sensor", &r.sensor},
                           {"lines", &r.lines}})
        out[name] = py::tuple(py::cast(*v));
    for (auto [name, m] : {std::pair{"A", &r.A},
                           {"B", &r.B},
                           {"S", &r.S},
                           {"Phi", &r.Phi},
                           {"Gamma", &r.Gamma},
                           {"M", &r.M},
                           {"Bf", &r.Bf},
                           {"Bn", &r.Bn},
                           {"C", &r.C},
                           {"Dn", &r.Dn}})
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
            NdLoop r =
                interruptible([&] { return nd_loop(p.structure, p.chains, p.fs, p.closed ? &p.controller : nullptr); });
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
