#include "amb_fast/controller.hpp"
#include "amb_fast/plant.hpp"
#include "bindings.hpp"

using namespace amb_fast;

void bind_params(py::module_& m) {
    py::enum_<ForceLaw>(m, "ForceLaw", "Magnet force law: linearised or the differential magnet pair.")
        .value("linear", ForceLaw::linear)
        .value("nonlinear", ForceLaw::nonlinear);

    py::class_<Rig>(m, "Rig", "Rig parameters in SI units (bandwidths in Hz, None = ideal stage).")
        .def(py::init([](double mass, double kyy, double kiy, double bias_current, ForceLaw force_law,
                         std::optional<double> amp_bandwidth, std::optional<double> eddy_bandwidth,
                         std::optional<double> sensor_bandwidth, int substeps, double sensor_noise, double force_noise,
                         double mass_loading, std::optional<double> force_coupling_tau, std::optional<double> clearance,
                         std::optional<double> current_limit, double dead_time) {
                 Rig rig{mass,
                         kyy,
                         kiy,
                         bias_current,
                         force_law,
                         amp_bandwidth,
                         eddy_bandwidth,
                         sensor_bandwidth,
                         substeps,
                         sensor_noise,
                         force_noise,
                         mass_loading,
                         force_coupling_tau,
                         clearance,
                         current_limit,
                         dead_time};
                 rig.validate();
                 return rig;
             }),
             py::kw_only(), py::arg("mass"), py::arg("kyy"), py::arg("kiy"), py::arg("bias_current"),
             py::arg("force_law"), py::arg("amp_bandwidth"), py::arg("eddy_bandwidth"), py::arg("sensor_bandwidth"),
             py::arg("substeps"), py::arg("sensor_noise") = 0.0, py::arg("force_noise") = 0.0,
             py::arg("mass_loading") = 0.0, py::arg("force_coupling_tau") = std::nullopt,
             py::arg("clearance") = std::nullopt, py::arg("current_limit") = std::nullopt, py::arg("dead_time") = 0.0)
        .def("magnet_force", &Rig::magnet_force, py::arg("y"), py::arg("i"),
             "Non-linear magnet-pair force on the platform (N) at displacement y (m) and current i (A).")
        .def_property_readonly("gap", &Rig::gap, "Nominal air gap of the force law (m).");

    py::class_<Controller>(m, "Controller",
                           "Digital controller: s[k+1] = A s + B e, u = C s + D e (e in m, u in A), at fs (Hz), "
                           "applied `delay` whole samples later.")
        .def(py::init([](const Eigen::MatrixXd& A, const Eigen::VectorXd& B, const Eigen::VectorXd& C, double D,
                         double fs, int delay) {
                 Controller c{A, B, C, D, fs, delay};
                 c.validate();
                 return c;
             }),
             py::kw_only(), py::arg("A"), py::arg("B"), py::arg("C"), py::arg("D"), py::arg("fs"), py::arg("delay"))
        .def_property_readonly("order", &Controller::order, "Number of controller states.")
        .def_readonly("A", &Controller::A)
        .def_readonly("B", &Controller::B)
        .def_readonly("C", &Controller::C)
        .def_readonly("D", &Controller::D)
        .def_readonly("fs", &Controller::fs)
        .def_readonly("delay", &Controller::delay);

    // A sweep's PIDs without a Python object per point: only the assembly, the terms come computed.
    m.def(
        "pid_controllers",
        [](const Eigen::VectorXd& integral_in, const Eigen::VectorXd& derivative_out, const Eigen::VectorXd& direct,
           const Eigen::VectorXd& ki, const Eigen::VectorXd& kd, double pole, double fs, int delay) {
            const Eigen::Index count = direct.size();
            for (const auto* v : {&integral_in, &derivative_out, &ki, &kd})
                if (v->size() != count)
                    throw std::invalid_argument("pid_controllers: one entry per point in every array");
            std::vector<Controller> out;
            out.reserve(static_cast<std::size_t>(count));
            for (Eigen::Index j = 0; j < count; ++j) {
                const bool integral = ki[j] != 0.0, derivative = kd[j] != 0.0;
                const int n = int(integral) + int(derivative);
                Controller c{Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd(n), Eigen::VectorXd(n), direct[j], fs, delay};
                int state = 0;
                if (integral) c.A(state, state) = 1.0, c.B[state] = integral_in[j], c.C[state] = 1.0, ++state;
                if (derivative) c.A(state, state) = pole, c.B[state] = 1.0, c.C[state] = derivative_out[j];
                c.validate();
                out.push_back(std::move(c));
            }
            return out;
        },
        py::arg("integral_in"), py::arg("derivative_out"), py::arg("direct"), py::arg("ki"), py::arg("kd"),
        py::arg("pole"), py::arg("fs"), py::arg("delay"),
        "A digital PID's controllers in modal form (amb_fast.PID.state_space), one per entry of the arrays of its "
        "terms: the integral's state (pole 1, input integral_in) where ki != 0, then the derivative's (pole `pole`, "
        "output derivative_out) where kd != 0, direct term `direct`.");
}
