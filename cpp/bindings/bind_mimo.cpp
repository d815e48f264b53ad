#include "amb_fast/estimate2x2.hpp"
#include "amb_fast/mimo_lines.hpp"
#include "amb_fast/mimo_sweep.hpp"
#include "bindings.hpp"

#include <pybind11/complex.h>
#include <pybind11/numpy.h>

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

using namespace amb_fast;

namespace {
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Matrix = Eigen::Ref<const Eigen::MatrixXd>;
using Vector = Eigen::Ref<const Eigen::VectorXd>;

MimoModel model_of(const Matrix& M, const Matrix& Bf, const Matrix& Bn, const Matrix& C, const Matrix& Dn,
                   const Vector& transducer_pole, const Vector& sensor_noise, const Vector& force_noise) {
    MimoModel model{M, Bf, Bn, C, Dn, transducer_pole, sensor_noise, force_noise};
    model.validate();
    return model;
}

// The experiments' period forces, (len(seeds), period, p), checked with the seeds and the periods
// asked for; returns one pointer per experiment into the array and the period length. Runs sample by sample
// take one or two experiments in lock step (the loop's lanes); drawn line spectra any number (any_count).
std::vector<const double*> experiment_forces(const InputArray& period_forces, Eigen::Index p,
                                             const std::vector<std::uint64_t>& seeds, Eigen::Index periods,
                                             Eigen::Index& L, bool any_count = false) {
    if (period_forces.ndim() != 3 || period_forces.shape(2) != p ||
        static_cast<std::size_t>(period_forces.shape(0)) != seeds.size())
        throw std::invalid_argument("period_forces must have shape (len(seeds), period, " + std::to_string(p) + ")");
    if (seeds.empty() || (!any_count && seeds.size() > 2))
        throw std::invalid_argument(any_count ? "seeds must hold at least one seed"
                                              : "seeds must hold 1 or 2 seeds (experiments in lock step)");
    if (periods < 2) throw std::invalid_argument("periods must be >= 2, got " + std::to_string(periods));
    L = static_cast<Eigen::Index>(period_forces.shape(1));
    std::vector<const double*> forces;
    for (std::size_t k = 0; k < seeds.size(); ++k)
        forces.push_back(period_forces.data() + static_cast<Eigen::Index>(k) * L * p);
    return forces;
}
}  // namespace

void bind_mimo(py::module_& m) {
    m.def(
        "mimo_simulate",
        [](const Matrix& M, const Matrix& Bf, const Matrix& Bn, const Matrix& C, const Matrix& Dn,
           const Vector& transducer_pole, const Vector& sensor_noise, const Vector& force_noise,
           const InputArray& force, std::uint64_t seed) {
            const MimoModel model = model_of(M, Bf, Bn, C, Dn, transducer_pole, sensor_noise, force_noise);
            const auto p = model.forces(), r = model.outputs();
            if (force.ndim() != 2 || force.shape(1) != p)
                throw std::invalid_argument("force must have shape (samples, " + std::to_string(p) + ")");
            const auto n = static_cast<Eigen::Index>(force.shape(0));
            py::array_t<double> recorded({n, p}), out({n, r});
            double *rec = recorded.mutable_data(), *o = out.mutable_data();
            const double* input = force.data();
            interruptible([&] {
                mimo_simulate(model, input, n, seed, rec, o);
                return 0;
            });
            return py::make_tuple(recorded, out);
        },
        py::arg("M"), py::arg("Bf"), py::arg("Bn"), py::arg("C"), py::arg("Dn"), py::arg("transducer_pole"),
        py::arg("sensor_noise"), py::arg("force_noise"), py::arg("force"), py::arg("seed") = 0,
        "Runs the dense MIMO loop z' = M z + Bf f + Bn n, o = C z + Dn n from rest on force (samples, p); returns "
        "the recorded forces (samples, p) and the outputs (samples, r). Releases the GIL; Ctrl-C stops it.");
    m.def(
        "mimo_experiments",
        [](const Matrix& M, const Matrix& Bf, const Matrix& Bn, const Matrix& C, const Matrix& Dn,
           const Vector& transducer_pole, const Vector& sensor_noise, const Vector& force_noise,
           const InputArray& period_forces, Eigen::Index settle_periods, Eigen::Index periods,
           const std::vector<std::uint64_t>& seeds, bool steady_start, bool all_forces) {
            const MimoModel model = model_of(M, Bf, Bn, C, Dn, transducer_pole, sensor_noise, force_noise);
            const auto p = model.forces(), q = model.probes();
            Eigen::Index L = 0;
            const std::vector<const double*> forces = experiment_forces(period_forces, p, seeds, periods, L);
            const auto K = static_cast<Eigen::Index>(forces.size());
            py::array_t<double> recorded({K, p, all_forces ? periods * L : L}), measured({K, q, periods * L});
            double *rec = recorded.mutable_data(), *mea = measured.mutable_data();
            std::vector<double*> recs, meas;
            for (Eigen::Index k = 0; k < K; ++k) {
                recs.push_back(rec + k * (all_forces ? periods : 1) * L * p);
                meas.push_back(mea + k * periods * L * q);
            }
            interruptible([&] {
                mimo_experiments(model, forces.data(), L, settle_periods, periods, seeds, steady_start, recs.data(),
                                 meas.data(), all_forces);
                return 0;
            });
            return py::make_tuple(recorded, measured);
        },
        py::arg("M"), py::arg("Bf"), py::arg("Bn"), py::arg("C"), py::arg("Dn"), py::arg("transducer_pole"),
        py::arg("sensor_noise"), py::arg("force_noise"), py::arg("period_forces"), py::arg("settle_periods"),
        py::arg("periods"), py::arg("seeds"), py::arg("steady_start") = true, py::arg("all_forces") = true,
        "Experiments with the dense MIMO loop in lock step, one per seed (1 or 2): period_forces[k] (period, p) "
        "repeated for "
        "settle_periods + periods from rest or the periodic steady state; returns the recorded forces "
        "(experiments, p, periods * period; only the first period, (experiments, p, period), with all_forces=False) "
        "and "
        "measured displacements (experiments, q, periods * period).");
    m.def(
        "mimo_line_experiments",
        [](const Matrix& M, const Matrix& Bf, const Matrix& Bn, const Matrix& C, const Matrix& Dn,
           const Vector& transducer_pole, const Vector& sensor_noise, const Vector& force_noise,
           const InputArray& period_forces, Eigen::Index settle_periods, Eigen::Index periods,
           const std::vector<std::uint64_t>& seeds, bool steady_start, const std::vector<Eigen::Index>& bins) {
            const MimoModel model = model_of(M, Bf, Bn, C, Dn, transducer_pole, sensor_noise, force_noise);
            const auto p = model.forces(), q = model.probes();
            Eigen::Index L = 0;
            const std::vector<const double*> forces =
                experiment_forces(period_forces, p, seeds, periods, L, steady_start);
            const auto K = static_cast<Eigen::Index>(forces.size());
            const auto B = static_cast<Eigen::Index>(bins.size());
            py::array_t<std::complex<double>> force_lines({periods, B, p, K}), displacement_lines({periods, B, q, K});
            std::complex<double>*fl = force_lines.mutable_data(), *dl = displacement_lines.mutable_data();
            interruptible([&] {
                mimo_line_experiments(model, forces.data(), L, settle_periods, periods, seeds, steady_start, bins, fl,
                                      dl);
                return 0;
            });
            return py::make_tuple(force_lines, displacement_lines);
        },
        py::arg("M"), py::arg("Bf"), py::arg("Bn"), py::arg("C"), py::arg("Dn"), py::arg("transducer_pole"),
        py::arg("sensor_noise"), py::arg("force_noise"), py::arg("period_forces"), py::arg("settle_periods"),
        py::arg("periods"), py::arg("seeds"), py::arg("steady_start"), py::arg("bins"),
        "mimo_experiments reduced to the unscaled DFT of every recorded period at the given bins: returns the force "
        "and displacement line spectra, complex, (periods, bins, channels, experiments). With steady_start the "
        "spectra are drawn directly, exact in distribution (mimo_lines.hpp), for any number of experiments (the "
        "per-line solves made once for all), and the bins must lie strictly between 0 and period / 2; from rest, "
        "1 or 2 experiments. Releases the GIL.");
    m.def(
        "estimate_2x2",
        [](const py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>& force_lines,
           const py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>& displacement_lines) {
            if (force_lines.ndim() != 4 || force_lines.shape(2) != 2 || force_lines.shape(3) != 2)
                throw std::invalid_argument("force_lines must have shape (periods, lines, 2, 2)");
            for (py::ssize_t d = 0; d < 4; ++d)
                if (displacement_lines.ndim() != 4 || displacement_lines.shape(d) != force_lines.shape(d))
                    throw std::invalid_argument("displacement_lines must have the shape of force_lines");
            const auto P = static_cast<Eigen::Index>(force_lines.shape(0));
            const auto B = static_cast<Eigen::Index>(force_lines.shape(1));
            const std::complex<double>*fl = force_lines.data(), *dl = displacement_lines.data();
            const Estimate2x2 est = interruptible([&] { return estimate_2x2(fl, dl, P, B); });
            auto complex_array = [&](const std::vector<std::complex<double>>& x) {
                py::array_t<std::complex<double>> a({B, Eigen::Index{2}, Eigen::Index{2}});
                std::copy(x.begin(), x.end(), a.mutable_data());
                return a;
            };
            auto real_array = [&](const std::vector<double>& x) {
                py::array_t<double> a({B, Eigen::Index{2}, Eigen::Index{2}});
                std::copy(x.begin(), x.end(), a.mutable_data());
                return a;
            };
            return py::make_tuple(complex_array(est.H), complex_array(est.receptance), complex_array(est.force),
                                  complex_array(est.displacement), real_array(est.var_re), real_array(est.var_im));
        },
        py::arg("force_lines"), py::arg("displacement_lines"),
        "The 2x2 estimate from per-period line spectra (periods, lines, channel, experiment): returns H = F Y^-1, its "
        "inverse, the period means F and Y (lines, 2, 2), and the variances of Re H and Im H (lines, 2, 2).");
    m.def(
        "estimate_nxn",
        [](const py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>& force_lines,
           const py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>& displacement_lines,
           const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& readout) {
            if (force_lines.ndim() != 4 || force_lines.shape(2) != force_lines.shape(3))
                throw std::invalid_argument("force_lines must have shape (periods, lines, N, N)");
            if (readout && (readout->ndim() != 2 || readout->shape(0) != force_lines.shape(2) ||
                            readout->shape(1) != force_lines.shape(2)))
                throw std::invalid_argument("readout must have shape (N, N)");
            for (py::ssize_t d = 0; d < 4; ++d)
                if (displacement_lines.ndim() != 4 || displacement_lines.shape(d) != force_lines.shape(d))
                    throw std::invalid_argument("displacement_lines must have the shape of force_lines");
            const auto P = static_cast<Eigen::Index>(force_lines.shape(0));
            const auto B = static_cast<Eigen::Index>(force_lines.shape(1));
            const auto N = static_cast<Eigen::Index>(force_lines.shape(2));
            const std::complex<double>*fl = force_lines.data(), *dl = displacement_lines.data();
            const double* read = readout ? readout->data() : nullptr;
            const Estimate2x2 est = interruptible([&] { return estimate_nxn(fl, dl, P, B, N, read); });
            auto complex_array = [&](const std::vector<std::complex<double>>& x) {
                py::array_t<std::complex<double>> a({B, N, N});
                std::copy(x.begin(), x.end(), a.mutable_data());
                return a;
            };
            auto real_array = [&](const std::vector<double>& x) {
                py::array_t<double> a({B, N, N});
                std::copy(x.begin(), x.end(), a.mutable_data());
                return a;
            };
            return py::make_tuple(complex_array(est.H), complex_array(est.receptance), complex_array(est.force),
                                  complex_array(est.displacement), real_array(est.var_re), real_array(est.var_im));
        },
        py::arg("force_lines"), py::arg("displacement_lines"), py::arg("readout") = py::none(),
        "estimate_2x2 for N axes: from the per-period line spectra (periods, lines, N channels, N experiments) "
        "returns H = F Y^-1, its inverse, the period means F and Y (lines, N, N), and the variances of Re H and "
        "Im H (lines, N, N). readout (N, N): the displacements are readout times the given ones.");
    m.def(
        "mimo_line_sweep",
        [](const std::vector<Eigen::MatrixXd>& M, const std::vector<Eigen::MatrixXd>& Bf,
           const std::vector<Eigen::MatrixXd>& Bn, const std::vector<Eigen::MatrixXd>& C,
           const std::vector<Eigen::MatrixXd>& Dn, const std::vector<Eigen::VectorXd>& transducer_pole,
           const std::vector<Eigen::VectorXd>& sensor_noise, const std::vector<Eigen::VectorXd>& force_noise,
           const InputArray& period_forces, const std::vector<Eigen::Index>& settle_periods, Eigen::Index periods,
           const py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>& seeds, bool steady_start,
           const std::vector<Eigen::Index>& bins, int workers) {
            const std::size_t n = M.size();
            for (const std::size_t size : {Bf.size(), Bn.size(), C.size(), Dn.size(), transducer_pole.size(),
                                           sensor_noise.size(), force_noise.size(), settle_periods.size()})
                if (size != n) throw std::invalid_argument("mimo_line_sweep: one model and settle_periods per point");
            if (seeds.ndim() != 2 || static_cast<std::size_t>(seeds.shape(0)) != n || seeds.shape(1) != 2)
                throw std::invalid_argument("seeds must have shape (points, 2): both experiments' seeds per point");
            std::vector<MimoModel> models;
            std::vector<std::array<std::uint64_t, 2>> pairs;
            for (std::size_t k = 0; k < n; ++k) {
                models.push_back(
                    model_of(M[k], Bf[k], Bn[k], C[k], Dn[k], transducer_pole[k], sensor_noise[k], force_noise[k]));
                if (models.back().forces() != 2 || models.back().probes() != 2)
                    throw std::invalid_argument("mimo_line_sweep: every model has two forces and two probes");
                pairs.push_back({seeds.at(k, 0), seeds.at(k, 1)});
            }
            Eigen::Index L = 0;
            const std::vector<const double*> forces =  // every point's pair: checked as any two experiments' forces
                experiment_forces(period_forces, 2, std::vector<std::uint64_t>(2), periods, L);
            const auto points = static_cast<Eigen::Index>(n), B = static_cast<Eigen::Index>(bins.size());
            const std::vector<py::ssize_t> shape{points, B, 2, 2};
            py::array_t<std::complex<double>> H(shape), receptance(shape);
            py::array_t<double> var_re(shape), var_im(shape);
            const MimoSweepOutput out{H.mutable_data(), receptance.mutable_data(), var_re.mutable_data(),
                                      var_im.mutable_data()};
            interruptible([&] {
                mimo_line_sweep(models, forces.data(), L, settle_periods, periods, pairs, steady_start, bins, workers,
                                out);
                return 0;
            });
            return py::make_tuple(H, receptance, var_re, var_im);
        },
        py::arg("M"), py::arg("Bf"), py::arg("Bn"), py::arg("C"), py::arg("Dn"), py::arg("transducer_pole"),
        py::arg("sensor_noise"), py::arg("force_noise"), py::arg("period_forces"), py::arg("settle_periods"),
        py::arg("periods"), py::arg("seeds"), py::arg("steady_start"), py::arg("bins"), py::arg("workers"),
        "Two-axis sweep: per point (lists of the models' matrices, settle_periods, seeds (points, 2)), "
        "mimo_line_experiments then estimate_2x2, on `workers` threads (<= 0: all cores), GIL released, Ctrl-C "
        "stops it. Returns estimate_2x2's H, receptance, var_re, var_im, each (points, lines, 2, 2).");
}
