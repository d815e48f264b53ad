"""The compiled two-axis paths (issue 14, speed): the MIMO kernels, the per-period line spectra and the
2x2 estimate of the core, each against numpy computing the same thing."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import _core
from amb_fast import two_axis as ta
from amb_fast.system._experiment import core_args as _core_args
from amb_fast.two_axis import excitation_pair, loop_model
from moments import assert_same_moments

PID = af.PID.paper()


def numpy_estimate(Fp: np.ndarray, Yp: np.ndarray) -> tuple[np.ndarray, ...]:
    """H = F Y^-1 per line and the variances of Re H, Im H from dH = (dF - H dY) Y^-1, in numpy."""
    P = Fp.shape[0]
    F, Y = Fp.mean(axis=0), Yp.mean(axis=0)
    Yinv = np.linalg.inv(Y)
    H = F @ Yinv
    dH = ((Fp - F) - H @ (Yp - Y)) @ Yinv
    var_re = np.sum(dH.real**2, axis=0) / (P * (P - 1))
    var_im = np.sum(dH.imag**2, axis=0) / (P * (P - 1))
    return H, np.linalg.inv(H), F, Y, var_re, var_im


def test_estimate_2x2_equals_numpy(rng) -> None:
    periods, lines = 7, 31
    shape = (periods, lines, 2, 2)
    Fp = rng.normal(size=shape) + 1j * rng.normal(size=shape) + 3 * np.eye(2)
    Yp = 1e-5 * (rng.normal(size=shape) + 1j * rng.normal(size=shape) + 4 * np.eye(2))
    for got, want in zip(_core.estimate_2x2(Fp, Yp), numpy_estimate(Fp, Yp)):
        assert got.shape == (lines, 2, 2)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15 * np.max(np.abs(want)))
    with pytest.raises(ValueError, match="finite"):
        _core.estimate_2x2(np.where(np.arange(lines)[None, :, None, None] == 3, np.nan, Fp), Yp)
    with pytest.raises(ValueError):
        _core.estimate_2x2(Fp[:, :, :1], Yp[:, :, :1])


@pytest.mark.parametrize("start", ["steady", "rest"])
def test_line_experiments_are_the_spectra_of_the_experiments(start: str) -> None:
    """Noise-free: the line spectra equal numpy's rfft of every recorded period of mimo_experiments."""
    quiet = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0, force_coupling_tau=0.02)
    rig = ta.TwoAxisRig(x=quiet, y=replace(quiet, dead_time=0.1e-3), kxy=3e3, kyx=-3e3, sensor_angle=0.02)
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    model = loop_model(rig, PID)
    args = _core_args(model, rig, outputs=2)
    steady, settle, periods, L = start == "steady", (0 if start == "steady" else 30), 3, sphs.period_samples
    common = dict(period_forces=excitation_pair(sphs), settle_periods=settle, periods=periods, seeds=[5, 6],
                  steady_start=steady)  # fmt: skip
    Fp, Yp = _core.mimo_line_experiments(**args, **common, bins=sphs.harmonics)
    force, displacement = _core.mimo_experiments(**args, **common, all_forces=True)
    for lines, x in ((Fp, force), (Yp, displacement)):
        want = np.fft.rfft(x.reshape(2, 2, periods, L), axis=3)[..., sphs.harmonics].transpose(2, 3, 1, 0)
        assert lines.shape == (periods, sphs.harmonics.size, 2, 2)
        assert np.max(np.abs(lines - want)) < 1e-12 * np.max(np.abs(want))


def test_steady_force_line_noise_has_the_transducer_variance() -> None:
    """With steady_start the transducer noise is drawn per period and line: complex normal, variance L sigma^2,
    independent across periods, lines, channels and experiments; the probe noise enters the loop."""
    rig = ta.TwoAxisRig.paper()
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    model = loop_model(rig, PID)
    args = _core_args(model, rig, outputs=2)
    periods, L = 40, sphs.period_samples
    common = dict(period_forces=excitation_pair(sphs), settle_periods=0, periods=periods, seeds=[11, 12],
                  steady_start=True, bins=sphs.harmonics)  # fmt: skip
    Fp, Yp = _core.mimo_line_experiments(**args, **common)
    quiet = dict(args, force_noise=np.zeros(2), sensor_noise=np.zeros(2))
    F0, _ = _core.mimo_line_experiments(**quiet, **common)
    np.testing.assert_allclose(F0, np.broadcast_to(F0[:1], F0.shape), rtol=0, atol=1e-9 * np.abs(F0).max())
    noise = Fp - Fp.mean(axis=0)  # the deterministic part is the same every period (to rounding)
    sigma = np.array([a.force_noise for a in rig.axes])
    for part in (noise.real, noise.imag):
        variance = np.mean(part**2, axis=(0, 1, 3)) * periods / (periods - 1)
        np.testing.assert_allclose(variance, L * sigma**2 / 2, rtol=0.05)  # 16000 draws per channel: 1.1 % rms
    corr = np.corrcoef(noise[:, :, 0, 0].real.ravel(), noise[:, :, 0, 1].real.ravel())[0, 1]
    assert abs(corr) < 0.05  # the two experiments' streams are independent
    # ... and independent of the probes' noise: every force channel against every probe's displacement
    # (8,000 pairs each: rms 0.011; one stream for force channel 0 and probe 1 gave 0.41)
    wobble = Yp - Yp.mean(axis=0)
    for channel, probe, experiment in np.ndindex(2, 2, 2):
        f, y = noise[:, :, channel, experiment].ravel(), wobble[:, :, probe, experiment].ravel()
        for a, b in ((f.real, y.real), (f.imag, y.imag), (f.real, y.imag)):
            assert abs(np.corrcoef(a, b)[0, 1]) < 0.05, (channel, probe, experiment)
    assert not np.allclose(Yp, _core.mimo_line_experiments(**quiet, **common)[1])
    again = _core.mimo_line_experiments(**args, **common)
    np.testing.assert_array_equal(again[0], Fp)  # reproducible per seed
    np.testing.assert_array_equal(again[1], Yp)


def test_mimo_simulate_is_independent_of_the_kernel_layout(rng) -> None:
    """The blocked kernel equals the recursion z' = M z + Bf f, o = C z written out (noise-free), on a
    loop with cross coupling and cross feedback (rows in several passes)."""
    rig = replace(ta.TwoAxisRig.paper(), kxy=8e3, kyx=-8e3)
    controller = [[PID, PID], [None, PID]]
    model = loop_model(rig, controller)
    force = rng.normal(size=(500, 2))
    args = _core_args(model, rig)
    args.update(sensor_noise=np.zeros(2), force_noise=np.zeros(2))
    _, out = _core.mimo_simulate(**args, force=force)
    z = np.zeros(model.M.shape[0])
    want = np.empty((500, 4))
    for k in range(500):
        want[k] = model.C @ z
        z = model.M @ z + model.Bf @ force[k]
    assert np.max(np.abs(out - want)) <= 1e-12 * np.max(np.abs(want))


@pytest.mark.parametrize("coupled", [True, False], ids=["coupled", "uncoupled"])
def test_steady_line_spectra_have_the_statistics_of_the_time_domain_loop(coupled: bool) -> None:
    """From the steady state the probe noise's line spectra are drawn directly (mimo_lines.hpp); from
    the same stationary start the loop run sample by sample and transformed period by period must give
    the same second moments: each line's variance, its covariance with the next period (the state
    carried over), between the two probes, and the pseudo-covariance E[Y Y]. Each compared within 4.5
    standard errors of the difference (seeded; 30,000 periods per side). Five lines in a hundred bins:
    the state's change over a period is then mostly what the lines do not explain (leaving that part
    out of the draws fails this test at 6.5 standard errors). Uncoupled, the axes are drawn part by part
    (independent_parts in mimo.hpp), each with its own solves and streams."""
    noisy = replace(af.Rig.paper(), sensor_noise=2e-6)
    coupling = dict(kxy=3e3, kyx=-3e3, sensor_angle=0.05) if coupled else {}
    rig = ta.TwoAxisRig(x=noisy, y=replace(noisy, dead_time=0.1e-3, sensor_noise=1e-6), **coupling)
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    model = loop_model(rig, PID)
    args = dict(_core_args(model, rig, outputs=2), force_noise=np.zeros(2))
    L, bins, periods = sphs.period_samples, sphs.harmonics, 50
    common = dict(period_forces=np.zeros((2, L, 2)), settle_periods=0, periods=periods, steady_start=True)

    drawn, looped = [], []
    for run in range(300):
        seeds = [2 * run + 1, 2 * run + 2]
        _, Yp = _core.mimo_line_experiments(**args, **common, seeds=seeds, bins=bins)
        drawn += [Yp[..., 0], Yp[..., 1]]
        _, y = _core.mimo_experiments(**args, **common, seeds=[s + 10**6 for s in seeds])
        spectra = np.fft.rfft(y.reshape(2, 2, periods, L), axis=3)[..., bins]  # (experiment, probe, period, line)
        looped += list(spectra.transpose(0, 2, 3, 1))
    assert_same_moments(np.array(drawn), np.array(looped))


@pytest.mark.parametrize("window", [1, 3, 5, 7])
def test_median_across_lines_equals_numpy(rng, window: int) -> None:
    """The two-axis estimate's running median (the core's, per entry) against numpy's sliding window."""
    from amb_fast.system._experiment import median_lines as _median

    x = np.round(rng.normal(size=(23, 2, 2)), 1)  # rounded: ties
    half = window // 2
    padded = np.concatenate([np.repeat(x[:1], half, axis=0), x, np.repeat(x[-1:], half, axis=0)])
    want = np.median(np.lib.stride_tricks.sliding_window_view(padded, window, axis=0), axis=-1)
    np.testing.assert_array_equal(_median(x, window), want)


def test_drawn_spectra_refuse_an_unstable_loop() -> None:
    """The steady-state draw has no loop to blow up: an unstable M overflows M^L or the stationary
    covariance instead, and the core raises rather than return numbers."""
    rig = ta.TwoAxisRig.paper()
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    args = _core_args(loop_model(rig, PID), rig, outputs=2)
    args["M"] = 1.02 * args["M"]
    assert np.max(np.abs(np.linalg.eigvals(args["M"]))) > 1.01
    with pytest.raises(OverflowError, match="unstable"):
        _core.mimo_line_experiments(**args, period_forces=excitation_pair(sphs), settle_periods=0, periods=3,
                                    seeds=[1, 2], steady_start=True, bins=sphs.harmonics)  # fmt: skip


@pytest.mark.parametrize("n", [1, 3, 4, 5])
def test_estimate_nxn_with_a_readout_equals_numpy(rng, n: int) -> None:
    """The N x N estimate with the structure's readout applied in the core (fixed-size matrices up to 4
    axes, dynamic beyond) equals numpy's estimate of ``readout @ Y``."""
    periods, lines = 6, 23
    shape = (periods, lines, n, n)
    Fp = rng.normal(size=shape) + 1j * rng.normal(size=shape) + 3 * np.eye(n)
    Yp = 1e-5 * (rng.normal(size=shape) + 1j * rng.normal(size=shape) + 4 * np.eye(n))
    readout = np.eye(n) + 0.1 * rng.normal(size=(n, n))
    for got, want in zip(_core.estimate_nxn(Fp, Yp, readout), numpy_estimate(Fp, readout @ Yp)):
        assert got.shape == (lines, n, n)
        np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-14 * np.max(np.abs(want)))
    with pytest.raises(ValueError, match="readout"):
        _core.estimate_nxn(Fp, Yp, np.eye(n + 1))


def test_drawn_rotor_lines_do_not_depend_on_the_shared_solves() -> None:
    """The N experiments drawn in lock step from one set of per-line solves (kept for the next call with
    a bitwise equal model) equal each experiment drawn alone, call after call; a model differing only in
    its probe noise is solved afresh (other lines), and its lines are the same after the cache moved on."""
    from amb_fast.system._control import controller_matrix
    from amb_fast.system._experiment import core_args, experiment_forces
    from amb_fast.system._model import loop_model as system_loop

    rig, sphs = af.RotorRig.example(speed=1000.0), af.schroeder_multisine(f0=20.0, f_max=400.0)
    args = core_args(system_loop(rig, controller_matrix(af.RotorRig.example_controller(), 4)), rig, outputs=4)
    forces = experiment_forces(sphs, 4)

    def lines(model: dict, first: int = 0, count: int = 4) -> tuple[np.ndarray, np.ndarray]:
        return _core.mimo_line_experiments(**model, period_forces=np.ascontiguousarray(forces[first : first + count]),
                                           settle_periods=0, periods=3, seeds=[11, 12, 13, 14][first : first + count],
                                           steady_start=True, bins=sphs.harmonics)  # fmt: skip

    together = lines(args)
    for got, want in zip(lines(args), together):
        np.testing.assert_array_equal(got, want)
    for e in range(4):
        for got, want in zip(lines(args, e, 1), together):
            np.testing.assert_array_equal(got[..., 0], want[..., e])
    noisier = dict(args, sensor_noise=2 * args["sensor_noise"])
    first = lines(noisier)
    assert not np.array_equal(first[1], together[1])
    for scale in (1.1, 1.2, 1.3, 1.4, 1.5):  # more models than the cache keeps
        lines(dict(args, force_noise=scale * args["force_noise"]), 0, 1)
    for got, want in zip(lines(noisier), first):
        np.testing.assert_array_equal(got, want)
