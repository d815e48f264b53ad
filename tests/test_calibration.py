"""Calibration of the rig to estimates (fit_rig), predictions with error bars, design for the actual k, c."""

from __future__ import annotations

import ctypes
import sys
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import amb_fast as af
from amb_fast.calibration import Design, RigFit, design_controller, fit_rig, read_estimate

SPHS = af.schroeder_multisine(f0=1.0, f_max=200.0)
PID_A = af.PID.paper()
PID_B = replace(PID_A, kp=3000.0, kd=2.0)
# The truth: the paper's lags and noise, with other magnets, a slower amplifier, a dead time.
TRUTH = replace(af.Rig.paper(), kyy=-52e3, kiy=46.0, amp_bandwidth=1500.0, mass_loading=0.05,
                force_coupling_tau=1.5, dead_time=60e-6)  # fmt: skip
FREE = ["kyy", "kiy", "amp_bandwidth", "mass_loading", "force_coupling_tau", "dead_time"]
START = replace(TRUTH, kyy=-50e3, kiy=45.0, amp_bandwidth=2000.0, mass_loading=0.03, force_coupling_tau=1.0,
                dead_time=0.0)  # fmt: skip


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread():  # noqa: ANN201
    """Run this module's many small matrix exponentials and solves on one OpenBLAS thread.

    On a loaded machine OpenBLAS threads make a 7x7 ``expm`` 100-500x slower (8 ms instead of 0.02 ms);
    the fits here make thousands. Restored afterwards; a no-op where the libraries cannot be found.
    """
    restore = []
    if sys.platform.startswith("linux"):
        with open("/proc/self/maps") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower()})
        for path in paths:
            lib = ctypes.CDLL(path)
            for prefix, suffix in (
                ("scipy_openblas", "64_"),
                ("scipy_openblas", ""),
                ("openblas", ""),
                ("openblas", "64_"),
            ):
                get, put = f"{prefix}_get_num_threads{suffix}", f"{prefix}_set_num_threads{suffix}"
                if hasattr(lib, get) and hasattr(lib, put):
                    restore.append((getattr(lib, put), int(getattr(lib, get)())))
                    getattr(lib, put)(1)
                    break
    yield
    for put, threads in restore:
        put(threads)


def measure(rig: af.Rig, seed: int, periods: int = 10) -> list[af.Estimate]:
    return [af.run_experiment(rig, pid, SPHS, periods=periods, seed=seed + j) for j, pid in enumerate((PID_A, PID_B))]


def quiet_fit(*args, **kwargs) -> RigFit:  # noqa: ANN002, ANN003
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return fit_rig(*args, **kwargs)


def test_recovers_the_rig_within_three_standard_errors() -> None:
    fit = fit_rig(measure(TRUTH, 11), START, [PID_A, PID_B], free=FREE)
    for name in FREE:
        assert abs(fit.values[name] - getattr(TRUTH, name)) < 3 * fit.std[name], name
        assert fit.interval[name][0] <= fit.values[name] <= fit.interval[name][1]
        assert getattr(fit.rig, name) == fit.values[name]
    assert 0.9 < fit.chi2 / fit.dof < 1.1 and fit.fits
    assert fit.dof == 2 * 2 * 200 - len(FREE)
    assert np.allclose(np.sqrt(np.diag(fit.covariance)), [fit.std[n] for n in FREE])
    assert np.allclose(np.diag(fit.correlation), 1.0)
    report = fit.report()
    for name in FREE:
        assert name in report
    # An amplifier lag and a dead time act alike on 1-200 Hz: named, not hidden.
    assert ("amp_bandwidth", "dead_time") in {(a, b) for a, b, _ in fit.correlated_pairs()}
    assert "not separately identifiable" in report and "dead time act alike" in report


@pytest.fixture(scope="module")
def monte_carlo() -> dict[str, np.ndarray]:
    """30 seeded repetitions of a two-estimate fit of six parameters (about 5 s)."""
    inside, p_values, ratios, naive = [], [], [], []
    for seed in range(30):
        estimates = measure(TRUTH, 1000 + 2 * seed)
        fit = quiet_fit(estimates, START, [PID_A, PID_B], free=FREE)
        inside.append([fit.interval[n][0] <= getattr(TRUTH, n) <= fit.interval[n][1] for n in FREE])
        p_values.append(fit.p_value)
        ratios.append(fit.chi2 / fit.dof)
        # The plain chi-square of the normalised residuals, as if the weights were known.
        plain = sum(float(np.sum(np.abs(r) ** 2)) for r in fit.normalized_residuals)
        naive.append(stats.chi2.sf(plain, fit.dof))
    return {"inside": np.array(inside), "p": np.array(p_values), "ratio": np.array(ratios), "naive": np.array(naive)}


def test_intervals_cover_the_truth(monte_carlo: dict[str, np.ndarray]) -> None:
    coverage = monte_carlo["inside"].mean()
    assert 0.90 <= coverage <= 0.99, coverage
    assert np.all(monte_carlo["inside"].mean(axis=0) >= 0.8)  # no parameter far off on its own


def test_p_values_of_a_correct_model_are_uniform(monte_carlo: dict[str, np.ndarray]) -> None:
    p = monte_carlo["p"]
    assert stats.kstest(p, "uniform").pvalue > 1e-3
    assert 0.35 < p.mean() < 0.65
    assert np.all(p > 1e-3)
    assert abs(monte_carlo["ratio"].mean() - 1) < 0.05
    # A plain chi-square ignores that the weights come from 10 periods: it rejects a correct model.
    assert np.mean(monte_carlo["naive"] < 0.05) > 0.3  # 0.6 over 300 seeds


def test_a_missing_lag_is_reported_as_a_misfit() -> None:
    truth = replace(TRUTH, eddy_bandwidth=800.0, dead_time=0.0)
    estimates = measure(truth, 21)
    free = FREE[:-1]  # a free dead time would absorb the missing lag (they act alike on 1-200 Hz)
    with pytest.warns(UserWarning, match="cannot fit"):
        wrong = fit_rig(estimates, replace(START, eddy_bandwidth=None), [PID_A, PID_B], free=free)
    assert wrong.p_value < 1e-3 and not wrong.fits
    assert "MISFIT" in wrong.report()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        right = fit_rig(estimates, replace(START, eddy_bandwidth=None), [PID_A, PID_B],
                        free={**{n: getattr(START, n) for n in free}, "eddy_bandwidth": 1000.0})  # fmt: skip
    assert right.p_value > 1e-3 and right.fits
    assert abs(right.values["eddy_bandwidth"] - 800.0) < 3 * right.std["eddy_bandwidth"]


def test_predicts_untried_gains_within_the_combined_errors() -> None:
    fit = fit_rig(measure(TRUTH, 31), START, [PID_A, PID_B], free=FREE)
    untried = replace(PID_A, kp=2000.0, ki=10000.0, kd=4.0)
    run = af.run_experiment(TRUTH, untried, SPHS, periods=10, seed=99)
    k, c, k_std, c_std = fit.coefficients(untried, run.freq)
    # The run's standard errors come from its 10 periods: a 95 % interval takes Student's t with 9 dof
    # (1.96 covers ~92 % then, as measured over seeds 95-109).
    t95 = stats.t.ppf(0.975, 9)
    within_k = np.abs(run.k - k) <= t95 * np.hypot(run.k_std, k_std)
    within_c = np.abs(run.c - c) <= t95 * np.hypot(run.c_std, c_std)
    assert within_k.mean() >= 0.9 and within_c.mean() >= 0.9
    assert np.mean(np.abs(run.k - k) <= 3 * np.hypot(run.k_std, k_std)) >= 0.95
    assert np.mean(np.abs(run.c - c) <= 3 * np.hypot(run.c_std, c_std)) >= 0.95
    R, R_std = fit.predict(untried, run.freq)
    assert np.allclose(R, af.predict(fit.rig, untried, run.freq), rtol=1e-12)
    assert np.all(R_std > 0) and np.all(R_std < 0.05 * np.abs(R))
    # k as an Estimate computes it from the receptance.
    assert np.allclose(k, fit.rig.mass * (2 * np.pi * run.freq) ** 2 + (1 / R).real, rtol=1e-10)
    # The prediction error is the parameters' alone: far below the truth's difference from the start rig.
    k0 = START.mass * (2 * np.pi * run.freq) ** 2 + (1 / af.predict(START, untried, run.freq)).real
    assert np.median(np.abs(k - k0)) > 10 * np.median(k_std)


def test_design_recovers_known_gains() -> None:
    rig = replace(TRUTH, sensor_noise=0.0, force_noise=0.0)
    known = replace(PID_A, kp=2800.0, ki=15000.0, kd=2.5)
    f = np.arange(20.0, 151.0)
    w = 2 * np.pi * f
    H = 1 / af.predict(rig, known, f)
    k, c = rig.mass * w**2 + H.real, H.imag / w
    design = design_controller(rig, PID_A, freq=f, stiffness=k, damping=c, free=("kp", "ki", "kd"))
    assert isinstance(design, Design) and design.exact and not design.constrained
    for name in ("kp", "ki", "kd"):
        assert design.params[name] == pytest.approx(getattr(known, name), rel=1e-3)
        assert getattr(design.controller, name) == design.params[name]
    assert np.allclose(design.k, k, rtol=1e-6) and design.residual < 1e-6
    # A free filter corner makes it non-linear: least squares still finds it.
    free = ("kp", "ki", "kd", "derivative_cutoff")
    other = design_controller(rig, replace(PID_A, derivative_cutoff=700.0), freq=f, stiffness=k, damping=c, free=free)
    assert not other.exact
    assert other.params["derivative_cutoff"] == pytest.approx(1000.0, rel=1e-3)


def test_designing_for_the_actual_coefficients_differs_from_the_naive_design() -> None:
    f = np.arange(20.0, 151.0)
    actual = design_controller(TRUTH, PID_A, freq=f, stiffness=6e4, damping=150.0)
    naive = design_controller(TRUTH, PID_A, freq=f, stiffness=6e4, damping=150.0, basis="effective")
    assert abs(actual.params["kd"] / naive.params["kd"] - 1) > 0.1
    # On the rig, the naive design misses the targets by more (the objective: rms relative miss).
    naive_on_rig = np.sqrt(np.mean(np.concatenate([naive.k / 6e4 - 1, naive.c / 150.0 - 1]) ** 2))
    assert actual.residual < 0.8 * naive_on_rig
    # The naive design meets its targets in the effective coefficients, not in the actual ones.
    assert np.sqrt(np.mean((naive.c_effective - 150.0) ** 2)) < naive.c_miss
    assert "misses by" in actual.report()


def test_design_respects_the_sensitivity_limit() -> None:
    rig = replace(TRUTH, dead_time=0.0)
    f = np.arange(20.0, 151.0)
    start = replace(PID_A, kd=6.0)
    assert af.stability_margin(rig, start).peak < 3.0
    free_design = design_controller(rig, start, freq=f, stiffness=8e4, damping=20.0)
    assert free_design.peak_sensitivity > 3.0
    limited = design_controller(rig, start, freq=f, stiffness=8e4, damping=20.0, max_sensitivity=3.0)
    assert limited.constrained and limited.stable
    assert limited.peak_sensitivity <= 3.0  # before: 3.00011, the search grid missing the peak
    assert limited.residual >= free_design.residual
    assert "not feasible" in limited.report()


def test_bad_input_names_the_argument() -> None:
    estimates = measure(replace(TRUTH, dead_time=0.0), 41)
    pids = [PID_A, PID_B]
    cases = [
        (dict(free=["kyy", "stiffness"]), "free"),
        (dict(free=["sensor_noise"]), "free"),
        (dict(free=[]), "free"),
        (dict(free=["kyy", "kyy"]), "free"),
        (dict(free=["eddy_bandwidth"], rig=replace(START, eddy_bandwidth=None)), "free.*eddy_bandwidth.*None"),
        (dict(controllers=[PID_A]), "controllers"),
        (dict(controllers=[PID_A, replace(PID_B, fs=8000.0)]), "controllers.*fs"),
        (dict(controllers=[PID_A, "pid"]), "controllers"),
        (dict(bounds={"kyy": (-40e3, -30e3)}), "bounds"),
        (dict(bounds={"kiy": (1.0, 100.0)}), "bounds"),
        (dict(rig="paper"), "rig"),
        (dict(estimates=[estimates[0], "estimate"]), r"estimates\[1\]"),
        (dict(estimates=[measure(TRUTH, 5, periods=3)[0], estimates[1]]), r"estimates\[0\].*blocks"),
    ]
    for change, match in cases:
        arguments = dict(estimates=estimates, rig=START, controllers=pids, free=["kyy"]) | change
        with pytest.raises(ValueError, match=match):
            fit_rig(arguments.pop("estimates"), arguments.pop("rig"), arguments.pop("controllers"), **arguments)
    f = np.arange(20.0, 151.0)
    design_cases = [
        (dict(free=("kp", "gain")), "free"),
        (dict(free=("kp", "kyy")), "free.*rig field"),
        (dict(stiffness=None, damping=None), "stiffness and damping"),
        (dict(stiffness=[1.0, 2.0]), "stiffness"),
        (dict(freq=[10.0, 3000.0]), "freq"),
        (dict(max_sensitivity=0.5), "max_sensitivity"),
        (dict(weights=(1.0,)), "weights"),
    ]
    for change, match in design_cases:
        arguments = dict(freq=f, stiffness=6e4, damping=150.0) | change
        with pytest.raises(ValueError, match=match):
            design_controller(TRUTH, PID_A, **arguments)


def test_bounds_and_a_single_estimate() -> None:
    (estimate,) = measure(replace(TRUTH, dead_time=0.0), 51)[:1]
    fit = quiet_fit(
        estimate, START, PID_A, free={"kyy": -5e4, "mass_loading": 0.01}, bounds={"mass_loading": (0, 0.02)}
    )
    assert fit.estimates == 1 and fit.values["mass_loading"] <= 0.02 + 1e-12
    assert fit.interval["mass_loading"][1] <= 0.02 + 1e-12


def test_cli_fit_and_design(tmp_path, capsys) -> None:  # noqa: ANN001
    from amb_fast.cli import main

    truth = replace(TRUTH, dead_time=0.0)
    estimates = measure(truth, 61)
    paths = [tmp_path / "est0.csv", tmp_path / "est1.nc"]
    for estimate, path in zip(estimates, paths):
        estimate.save(path)
    for estimate, path in zip(estimates, paths):
        back = read_estimate(path, blocks=10, mass=truth.mass)
        np.testing.assert_array_equal(back.H, estimate.H)
        assert back.blocks == estimate.blocks
    # A plain table with the saved file's columns (no checksum line) is read too.
    plain = tmp_path / "plain.csv"
    e = estimates[0]
    columns = np.c_[e.freq, e.H.real, e.H.imag, e.k_std, e.c_std]
    np.savetxt(plain, columns, delimiter=",", comments="",
               header="freq_Hz,H_real_N_per_m,H_imag_N_per_m,k_std_N_per_m,c_std_Ns_per_m")  # fmt: skip
    back = read_estimate(plain, blocks=10, mass=truth.mass)
    np.testing.assert_allclose(back.H, e.H, rtol=1e-15)
    assert back.blocks == 10

    free = "kyy,kiy,amp_bandwidth,mass_loading,force_coupling_tau"
    options = ["--free", free, "--kp", "2400,3000", "--kd", "3,2", "--set", "kyy=-50000,force_coupling_tau=1"]
    assert main(["fit", *map(str, paths), *options]) == 0
    out = capsys.readouterr().out
    assert "amp_bandwidth" in out and "consistent with the data" in out
    assert main(["design", "--stiffness", "6e4", "--damping", "150", "--band", "20:150"]) == 0
    out = capsys.readouterr().out
    assert "kp" in out and "naive design" in out
    assert main(["design", "--stiffness", "6e4", "--set", "stiffness=1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("amb-fast: error:") and "--set" in err and len(err.strip().splitlines()) == 1


def test_general_controllers() -> None:
    """A Controller (here the PID with a notch) works wherever a PID does: fit, prediction, design."""
    from amb_fast.controllers import notch, pid_controller, series

    controller = series(pid_controller(PID_A), notch(500.0, 0.5, fs=4000.0))
    rig = replace(TRUTH, dead_time=0.0)
    estimate = af.run_experiment(rig, controller, SPHS, periods=10, seed=71)
    fit = fit_rig(estimate, replace(rig, kyy=-5e4, mass_loading=0.03), controller, free=["kyy", "mass_loading"])
    assert abs(fit.values["kyy"] - rig.kyy) < 3 * fit.std["kyy"]
    R, _ = fit.predict(controller, estimate.freq)
    assert np.allclose(R, af.predict(fit.rig, controller, estimate.freq), rtol=1e-12)
    f = np.arange(20.0, 151.0)
    w = 2 * np.pi * f
    known = controller.with_params(kp=2800.0, kd=2.5, notch_freq=450.0)
    H = 1 / af.predict(rig, known, f)
    design = design_controller(rig, controller, freq=f, stiffness=rig.mass * w**2 + H.real, damping=H.imag / w,
                               free=("kp", "kd", "notch_freq"))  # fmt: skip
    assert not design.exact
    for name, value in (("kp", 2800.0), ("kd", 2.5), ("notch_freq", 450.0)):
        assert design.params[name] == pytest.approx(value, rel=1e-3)
    assert design.controller.params["notch_freq"] == pytest.approx(450.0, rel=1e-3)
