"""Two axes (issue 14): the coupled loop, the two-experiment 2x2 identification, effective matrices, ROSS."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
import two_axis_reference as reference
from amb_fast import two_axis as ta


def worst(actual: np.ndarray, expected: np.ndarray) -> float:
    """Largest relative error at any line and any entry (each entry relative to itself)."""
    return float(np.max(np.abs(actual - expected) / np.abs(expected)))


QUIET = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)
PID = af.PID.paper()


@pytest.fixture(scope="module")
def coupled() -> tuple[ta.TwoAxisRig, list]:
    """Everything on: different lags, dead times (fractional), mass loading and transducers per axis, a
    process with cross stiffness and damping, rotated probes, a 2x2 controller with cross feedback."""
    x = replace(QUIET, dead_time=0.3e-3, force_coupling_tau=0.02)
    y = replace(x, amp_bandwidth=2500.0, eddy_bandwidth=None, sensor_bandwidth=8000.0, dead_time=0.1e-3,
                mass_loading=0.03)  # fmt: skip
    rig = ta.TwoAxisRig(x=x, y=y, kxy=8000.0, kyx=-8000.0, cxy=5.0, cyx=-3.0, sensor_angle=0.05)
    cross = replace(PID, kp=150.0, ki=0.0, kd=0.2, delay=1)
    return rig, [[PID, cross], [None, replace(PID, kp=2600.0)]]


def test_simulate_equals_the_numpy_reference(coupled, rng) -> None:
    rig, controller = coupled
    force = rng.normal(size=(2000, 2))
    noise = 1e-7 * rng.normal(size=(2000, 2))
    core = ta.simulate(rig, controller, force)
    ref = reference.simulate(rig, controller, force)
    np.testing.assert_array_equal(core.force, ref[0])
    for a, b in zip((core.displacement, core.current), ref[1:]):
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))
    # The probe noise enters the loop (the controllers see it): same answer with the draws given.
    noisy_rig = replace(rig, x=replace(rig.x, sensor_noise=1e-7))
    assert not np.allclose(ta.simulate(noisy_rig, controller, force, seed=1).displacement, core.displacement)
    ref_noisy = reference.simulate(rig, controller, force, sensor_noise=noise)
    assert np.max(np.abs(ref_noisy[1] - ref[1])) > 1e-8


def test_noise_free_experiment_equals_predict_and_the_reference(coupled) -> None:
    rig, controller = coupled
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    est = ta.run_experiment(rig, controller, sphs, periods=3, seed=0)
    R = ta.predict(rig, controller, sphs.freq)
    assert R.shape == (sphs.freq.size, 2, 2)
    assert np.all(np.abs(R[:, 0, 1]) > 1e-2 * np.abs(R[:, 0, 0]))  # the coupling is really on
    assert worst(est.receptance, R) < 1e-9
    _, H = reference.run_experiment(rig, controller, sphs.samples, settle_periods=80, periods=3)
    assert worst(est.H, H[sphs.harmonics - 1]) < 1e-9
    assert worst(np.linalg.inv(R), H[sphs.harmonics - 1]) < 1e-9
    assert np.all(est.k_std < 1e-9 * np.abs(est.k).max())
    rest = ta.run_experiment(rig, controller, sphs, periods=3, start="rest")
    assert worst(rest.receptance, R) < 1e-8  # settled to 1e-9 of the slowest pole


def test_uncoupled_axes_are_the_one_axis_results() -> None:
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    y = replace(QUIET, amp_bandwidth=2000.0, mass_loading=0.02)
    rig = ta.TwoAxisRig(x=QUIET, y=y)
    pid_y = replace(PID, kp=2600.0)
    est = ta.run_experiment(rig, (PID, pid_y), sphs, periods=2, seed=3)
    for axis, (one_rig, one_pid) in enumerate(((QUIET, PID), (y, pid_y))):
        one = af.run_experiment(one_rig, one_pid, sphs, periods=2, seed=3)
        assert np.max(np.abs(est.receptance[:, axis, axis] / one.receptance - 1)) < 1e-9
        assert np.max(np.abs(est.k[:, axis, axis] - one.k) / np.abs(one.k)) < 1e-9
        assert np.max(np.abs(ta.predict(rig, (PID, pid_y), sphs.freq)[:, axis, axis] /
                             af.predict(one_rig, one_pid, sphs.freq) - 1)) < 1e-12  # fmt: skip
    scale = np.max(np.abs(est.receptance))
    assert np.max(np.abs(est.receptance[:, 0, 1])) < 1e-12 * scale
    assert np.max(np.abs(est.receptance[:, 1, 0])) < 1e-12 * scale
    margin = ta.stability_margin(rig, (PID, pid_y))
    one_x, one_y = af.stability_margin(QUIET, PID), af.stability_margin(y, pid_y)
    assert margin.x.peak == pytest.approx(one_x.peak, rel=1e-12)
    assert margin.y.peak == pytest.approx(one_y.peak, rel=1e-12)
    assert margin.peak == pytest.approx(max(one_x.peak, one_y.peak), rel=1e-12)


def test_process_is_recovered_with_honest_standard_errors() -> None:
    """A seal-like process kxy = -kyx, identified on the noisy paper rig over 12 seeds."""
    rig = replace(ta.TwoAxisRig.paper(), kxy=10e3, kyx=-10e3)
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    R = ta.predict(rig, PID, sphs.freq)
    w = 2 * np.pi * sphs.freq[:, None, None]
    H = np.linalg.inv(R)
    k_pred, c_pred = rig.mass * w**2 * np.eye(2) + H.real, H.imag / w
    # predict's cross stiffness is kxy through the hold and the lags: within 1 % up to 170 Hz (1.14 % at
    # 200 Hz), but at the lowest line, where the transducer's 1 s AC coupling adds 2.5 %
    band = (sphs.freq >= 2) & (sphs.freq <= 170)
    assert np.max(np.abs(k_pred[band, 0, 1] / 10e3 - 1)) < 0.01
    assert np.max(np.abs(k_pred[band, 1, 0] / -10e3 - 1)) < 0.01
    assert np.max(np.abs(k_pred[1:, 0, 1] / 10e3 - 1)) < 0.012
    z_k, z_c = [], []
    for seed in range(12):
        est = ta.run_experiment(rig, PID, sphs, periods=10, seed=seed)
        z_k.append((est.k - k_pred) / est.k_std)
        z_c.append((est.c - c_pred) / est.c_std)
        # kxy over the band, weighted by its errors: within 3 standard errors of predict's
        weights = 1 / est.k_std[:, 0, 1] ** 2
        fitted = np.sum(weights * est.k[:, 0, 1]) / np.sum(weights)
        expected = np.sum(weights * k_pred[:, 0, 1]) / np.sum(weights)
        assert abs(fitted - expected) < 3 / np.sqrt(np.sum(weights))
    # Student's t with 9 degrees of freedom has rms sqrt(9/7) = 1.134
    for z in (np.array(z_k), np.array(z_c)):
        rms = np.sqrt(np.mean(z**2, axis=(0, 1)))
        assert np.all((rms > 1.0) & (rms < 1.27)), rms


def test_identify_recovers_the_experiment_from_recordings(coupled) -> None:
    rig, controller = coupled
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    settle, periods = 80, 4
    forces, displacements = [], []
    for signs in ta.SIGNS:
        trace = ta.simulate(rig, controller, np.tile(np.outer(sphs.samples, signs), (settle + periods, 1)))
        forces.append(trace.force)
        displacements.append(trace.displacement)
    est = ta.identify(forces, displacements, fs=4000.0, f0=20.0, mass=rig.mass, settle_periods=settle)
    np.testing.assert_array_equal(est.freq, sphs.freq)
    assert worst(est.receptance, ta.predict(rig, controller, sphs.freq)) < 1e-8
    with pytest.raises(ValueError, match="force shape"):
        ta.identify(forces[0], displacements[0], fs=4000.0, f0=20.0, mass=rig.mass)


def test_effective_matrices() -> None:
    freq = np.array([5.0, 50.0, 150.0])
    rig = ta.TwoAxisRig(x=QUIET, y=QUIET, kxy=1e3, kyx=-1e3, cxy=2.0, sensor_angle=0.0)
    K, C = ta.effective_coefficients(rig, PID, freq)
    k1, c1 = af.effective_coefficients(QUIET, PID, freq)
    np.testing.assert_allclose(K[:, 0, 0], k1, rtol=1e-13)
    np.testing.assert_allclose(C[:, 1, 1], c1, rtol=1e-13)
    np.testing.assert_allclose(K[:, 0, 1], 1e3)
    np.testing.assert_allclose(C[:, 0, 1], 2.0)
    K0, _ = ta.effective_coefficients(rig, PID, freq, process=False)
    np.testing.assert_allclose(K0[:, 0, 1], 0.0, atol=1e-9)
    # Rotated probes: the controller acts on R^T q, so at the bearing the force couples the axes by
    # kiy G R^T; the estimate F Y^-1 reads Y = R^T q, so in its frame that is (diag(kyy) + kiy G R^T) R =
    # diag(kyy) R + kiy G: the magnets' negative stiffness turns with the probes, the controller's does not.
    turned = replace(rig, sensor_angle=0.1)
    Kt, Ct = ta.effective_coefficients(turned, PID, freq, process=False)
    g = af.effective_coefficients(af.Rig(kyy=1e-300, kiy=1.0), PID, freq)
    np.testing.assert_allclose(Kt[:, 0, 1], -QUIET.kyy * np.sin(0.1), rtol=1e-12)
    np.testing.assert_allclose(Kt[:, 1, 0], QUIET.kyy * np.sin(0.1), rtol=1e-12)
    np.testing.assert_allclose(Kt[:, 0, 0], QUIET.kyy * np.cos(0.1) + QUIET.kiy * g[0], rtol=1e-12)
    np.testing.assert_allclose(Ct[:, 1, 1], QUIET.kiy * g[1], rtol=1e-12)
    # The same through a noise-free experiment's frame: F Y^-1 of the exact receptance, with the actual
    # minus effective difference the same as with aligned probes (the lags act per axis, before R).


def test_controller_specs_and_validation() -> None:
    rig = ta.TwoAxisRig(x=QUIET, y=QUIET)
    freq = np.array([10.0, 100.0])
    one = ta.predict(rig, PID, freq)
    np.testing.assert_allclose(ta.predict(rig, (PID, PID), freq), one, rtol=1e-14)
    np.testing.assert_allclose(ta.predict(rig, [[PID, None], [0, PID]], freq), one, rtol=1e-14)
    with pytest.raises(ValueError, match="fs"):
        ta.predict(rig, (PID, replace(PID, fs=2000.0)), freq)
    with pytest.raises(ValueError, match="y.mass"):
        ta.TwoAxisRig(x=QUIET, y=replace(QUIET, mass=1.0))
    with pytest.raises(ValueError, match="force_law"):
        ta.TwoAxisRig(x=replace(QUIET, force_law="nonlinear"), y=QUIET)
    with pytest.raises(af.UnstableLoopError):
        ta.run_experiment(rig, replace(PID, kp=500.0), af.schroeder_multisine(f0=20.0, f_max=100.0))
    poles = ta.closed_loop_poles(rig, PID)
    one = af.closed_loop_poles(QUIET, PID)
    assert poles.size == 2 * one.size
    assert max(np.min(np.abs(poles - p)) for p in one) < 1e-9


def _ross():  # noqa: ANN202 - ROSS is optional; its import warns about an unrelated optional library
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pytest.importorskip("ross")


def test_to_ross_holds_the_estimate_and_runs_a_rotor() -> None:
    rs = _ross()
    rig = replace(ta.TwoAxisRig.paper(), kxy=10e3, kyx=-10e3)
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    est = ta.run_experiment(rig, PID, sphs, periods=4, seed=5)
    for smoothed in (False, True):
        element = est.to_ross(0, smoothed=smoothed)
        k = est.k_smooth if smoothed else est.k
        c = est.c_smooth if smoothed else est.c
        omega = 2 * np.pi * est.freq
        np.testing.assert_array_equal(element.frequency, omega)
        for j, speed in enumerate(omega):
            K, C = element.K(speed), element.C(speed)
            np.testing.assert_allclose(K[:2, :2], k[j], rtol=1e-12, atol=1e-9)
            np.testing.assert_allclose(C[:2, :2], c[j], rtol=1e-12, atol=1e-12)
    one = af.run_experiment(af.Rig.paper(), PID, sphs, periods=4, seed=5)
    element = ta.to_ross(one, 1)
    np.testing.assert_allclose(element.K(omega[10])[:2, :2], np.diag([one.k[10]] * 2))
    # A small rotor: a steel shaft on two identified bearings; its frequency response runs.
    steel = rs.Material(name="Steel", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [rs.ShaftElement(L=0.1, idl=0.0, odl=0.03, material=steel) for _ in range(4)]
    disk = rs.DiskElement.from_geometry(n=2, material=steel, width=0.03, i_d=0.03, o_d=0.12)
    rotor = rs.Rotor(shaft, [disk], [est.to_ross(0), est.to_ross(4)])
    response = rotor.run_freq_response(speed_range=omega[5:50:5])
    assert np.all(np.isfinite(np.abs(response.freq_resp)))


def test_sweep_over_the_process_and_a_gain() -> None:
    rig = ta.TwoAxisRig.paper()
    sphs = af.schroeder_multisine(f0=20.0, f_max=200.0)
    result = ta.sweep(rig, PID, sphs, kxy=[0.0, 5e3], kp=[1000.0, 2400.0], periods=3, seed=7)
    assert result.k.shape == (4, sphs.freq.size, 2, 2)
    np.testing.assert_array_equal(result.stable, [False, True, False, True])  # kp = 1000 A/m is unstable
    assert np.all(np.isnan(result.k[0]))
    point = {"kxy": 5e3, "kp": 2400.0}
    again = ta.run_experiment(*ta.point_model2(rig, PID, point), sphs, periods=3, seed=int(result.seeds[3]))
    np.testing.assert_array_equal(result.k[3], again.k)
    threaded = ta.sweep(rig, PID, sphs, kxy=[0.0, 5e3], kp=[1000.0, 2400.0], periods=3, seed=7, workers=2)
    np.testing.assert_array_equal(threaded.k, result.k)
    A, B, C, D = ta.closed_loop(rig, PID)
    assert A.shape[0] == B.shape[0] == C.shape[1] and B.shape[1] == 2 and C.shape[0] == 4 and D.shape == (4, 2)
    assert abs(np.median(result.k[3, :, 0, 1] - result.k[1, :, 0, 1]) - 5e3) < 100
    model_rig, model_controller = ta.point_model2(rig, PID, {"y_amp_bandwidth": 1000.0, "cross_kp": 10.0})
    assert model_rig.y.amp_bandwidth == 1000.0 and model_rig.x.amp_bandwidth == rig.x.amp_bandwidth
    assert model_controller.entries[0][1] is None  # no cross entry to change
    with pytest.raises(ValueError, match="sweep axis"):
        ta.point_model2(rig, PID, {"nonsense": 1.0})


def test_plot_and_command_helpers(capsys, tmp_path) -> None:
    pytest.importorskip("matplotlib")
    import argparse

    import matplotlib

    matplotlib.use("Agg")
    rig = replace(ta.TwoAxisRig.paper(), kxy=1e4, kyx=-1e4)
    sphs = af.schroeder_multisine(f0=20.0, f_max=200.0)
    est = ta.run_experiment(rig, PID, sphs, periods=3, seed=1)
    fig = ta.plot_coefficients2(est, effective=ta.effective_coefficients(rig, PID, est.freq))
    assert len(fig.axes) == 8
    parser = argparse.ArgumentParser()
    ta.add_two_axis_options(parser)
    args = parser.parse_args(["--two-axis", "--kxy", "1e4", "--kyx=-1e4", "--cross-kp", "20"])
    args.save, args.figure = tmp_path / "est.csv", tmp_path / "est.png"
    out = ta.run_two_axis(args, af.Rig.paper(), PID, sphs)
    assert out.k.shape == (sphs.freq.size, 2, 2)
    printed = capsys.readouterr().out
    assert "kxy (N/m)" in printed and "singular value" in printed
    assert af.load_estimate(args.save) == out  # the N-axis estimate's own file (was a wide table it could not read)
    assert args.figure.stat().st_size > 0


def test_noise_in_the_time_domain_from_rest_matches_the_steady_draws() -> None:
    """From rest the transducer noise is added sample by sample; in the steady state its line spectra are
    drawn directly. Both give standard errors of the same size, and honest ones."""
    rig = replace(ta.TwoAxisRig.paper(), kxy=5e3, kyx=-5e3, x=replace(af.Rig.paper(), force_noise=0.05))
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    R = ta.predict(rig, PID, sphs.freq)
    w = 2 * np.pi * sphs.freq[:, None, None]
    k_pred = rig.mass * w**2 * np.eye(2) + np.linalg.inv(R).real
    spreads, z = {}, []
    for start in ("steady", "rest"):
        runs = [ta.run_experiment(rig, PID, sphs, periods=20, seed=s, start=start) for s in range(6)]
        spreads[start] = np.median([r.k_std for r in runs], axis=0)
        z += [(r.k - k_pred) / r.k_std for r in runs]
    ratio = spreads["rest"] / spreads["steady"]
    assert 0.85 < np.median(ratio) < 1.15
    rms = np.sqrt(np.mean(np.array(z) ** 2))
    assert 0.9 < rms < 1.2  # Student's t with 19 degrees of freedom: rms 1.054


def test_the_one_axis_api_takes_a_two_axis_rig(coupled) -> None:
    """af.<function>(TwoAxisRig, ...) is amb_fast.two_axis.<function>, result for result."""
    rig, controller = coupled
    sphs = af.schroeder_multisine(f0=20.0, f_max=200.0)
    freq = sphs.freq
    np.testing.assert_array_equal(af.predict(rig, controller, freq), ta.predict(rig, controller, freq))
    np.testing.assert_array_equal(af.closed_loop_poles(rig, controller), ta.closed_loop_poles(rig, controller))
    for a, b in zip(af.closed_loop(rig, controller), ta.closed_loop(rig, controller)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(af.sensitivity(rig, controller, freq), ta.sensitivity(rig, controller, freq))
    assert af.stability_margin(rig, controller).peak == ta.stability_margin(rig, controller).peak
    for a, b in zip(af.effective_coefficients(rig, controller, freq), ta.effective_coefficients(rig, controller, freq)):
        np.testing.assert_array_equal(a, b)
    force = np.random.default_rng(3).normal(size=(500, 2))
    np.testing.assert_array_equal(af.simulate(rig, controller, force).displacement,
                                  ta.simulate(rig, controller, force).displacement)  # fmt: skip
    est = af.run_experiment(rig, controller, sphs, periods=3, seed=4)
    assert isinstance(est, af.Estimate2)
    np.testing.assert_array_equal(est.k, ta.run_experiment(rig, controller, sphs, periods=3, seed=4).k)
    swept = af.sweep(rig, PID, sphs, kxy=[0.0, 5e3], periods=3, seed=7)
    np.testing.assert_array_equal(swept.k, ta.sweep(rig, PID, sphs, kxy=[0.0, 5e3], periods=3, seed=7).k)
    # Two recorded experiments, shape (2, n, 2), identify as two axes.
    L = sphs.period_samples
    drive = np.tile(ta.excitation_pair(sphs), (1, 4, 1))
    runs = [ta.simulate(rig, controller, drive[e]) for e in range(2)]
    forces = np.stack([r.force for r in runs])
    displacements = np.stack([r.displacement for r in runs])
    kwargs = dict(fs=4000.0, f0=20.0, mass=rig.mass, settle_periods=2)
    np.testing.assert_array_equal(af.identify(forces, displacements, **kwargs).k,
                                  ta.identify(forces, displacements, **kwargs).k)  # fmt: skip
    assert forces.shape == (2, 4 * L, 2)
    # The one-axis functions still refuse a swapped pair with a TypeError naming the arguments.
    with pytest.raises(TypeError, match="takes the Rig first"):
        af.predict(PID, af.Rig.paper(), freq)


def test_command_line_two_axis_run(tmp_path, capsys) -> None:
    pytest.importorskip("matplotlib")
    from amb_fast.cli import main

    save, figure = tmp_path / "two.npz", tmp_path / "two.png"
    argv = ["run", "--two-axis", "--kxy", "1e4", "--kyx=-1e4", "--f-max", "200", "--periods", "3",
            "--save", str(save), "--figure", str(figure)]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "kxy (N/m)" in out and save.stat().st_size > 0 and figure.stat().st_size > 0
    assert af.load_estimate(save).k.shape == (200, 2, 2)  # EstimateN.save's file (was a wide table)
    assert main(argv) == 2  # exists: refused without --overwrite, before any work
    assert "exists" in capsys.readouterr().err
    assert main(["run", "--kxy", "1e4"]) == 2
    assert "need --two-axis" in capsys.readouterr().err
    assert main(["run", "--two-axis", "--save", str(tmp_path / "two.xlsx")]) == 2


def test_to_ross_keeps_the_callers_standard_output_clean() -> None:
    """Importing ROSS prints a REFPROP banner from a C library (CoolProp, through ccp); to_ross silences it."""
    import subprocess
    import sys

    pytest.importorskip("ross")
    code = (
        "import amb_fast as af\n"
        "est = af.run_experiment(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), periods=3)\n"
        "print(type(est.to_ross(0)).__name__)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out == "BearingElement\n"
