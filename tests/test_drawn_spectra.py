"""The one-axis experiment from the periodic steady state of a linear rig draws its periods' line spectra
(experiment.hpp, draws_spectra) instead of running the loop: the drawn spectra against the loop run
sample by sample, and the estimate from them against numpy computing it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import ndimage

import amb_fast as af
from amb_fast import _core
from amb_fast._experiment import _plan
from amb_fast._linear import core_controller
from moments import assert_same_moments

PID = af.PID.paper()


def drawn_spectra(rig: af.Rig, pid: af.PID, period_force: np.ndarray, periods: int, seed: int, bins) -> tuple:
    """The per-period force and displacement line spectra (periods, lines) that run_experiment draws."""
    model = _core.loop_model(rig._to_core(), core_controller(pid))
    F, Y = _core.mimo_line_experiments(**model, period_forces=period_force[None, :, None], settle_periods=0,
                                       periods=periods, seeds=[seed], steady_start=True, bins=list(bins))  # fmt: skip
    return F[:, :, 0, 0], Y[:, :, 0, 0]


def test_drawn_spectra_have_the_statistics_of_the_loop_run_sample_by_sample() -> None:
    """Noise only (no excitation), on a rig with lags, a fractional dead time (0.4 samples) and both noise
    sources: the drawn displacement and force spectra against af.simulate's time series (from rest,
    settled far past the slowest pole) transformed by numpy, period by period. Compared: each line's
    variance, its covariance with the next period, and E[Y Y], within 4.5 standard errors of the
    difference (seeded; 15,000 periods per side, five lines in a hundred bins, so the state's change
    over a period, which the lines do not explain, matters)."""
    rig = replace(af.Rig.paper(), sensor_noise=2e-6, force_noise=1e-3, dead_time=0.1e-3)
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    L, bins = sphs.period_samples, sphs.harmonics
    drawn_f, drawn_y = [], []
    for run in range(300):
        F, Y = drawn_spectra(rig, PID, np.zeros(L), 50, run + 1, bins)
        drawn_f.append(F[..., None])
        drawn_y.append(Y[..., None])
    radius = float(np.max(np.abs(af.closed_loop_poles(rig, PID))))
    settle = int(np.ceil(np.log(1e-8) / np.log(radius) / L)) + 1  # the start's trace decays below 1e-8
    looped_f, looped_y = [], []
    for run in range(5):
        trace = af.simulate(rig, PID, np.zeros((settle + 3000) * L), seed=10**6 + run)
        for channel, into in ((trace.displacement, looped_y), (trace.force, looped_f)):
            spectra = np.fft.rfft(channel[settle * L :].reshape(-1, L), axis=1)[:, bins]
            into.append(spectra.reshape(60, 50, -1)[..., None])
    assert_same_moments(np.array(drawn_y), np.concatenate(looped_y))
    assert_same_moments(np.array(drawn_f), np.concatenate(looped_f))


def test_run_experiment_estimates_from_the_drawn_spectra() -> None:
    """run_experiment on the paper rig (noise on) equals numpy's estimate from the drawn spectra of the same
    seed, settle periods dropped: 71 periods, so the variance comes from 35 batch means of 2 periods and
    the last period enters the means only. k, c, their standard errors, the median-filtered curves and
    the unexcited levels, to 1e-9 relative."""
    rig, sphs = af.Rig.paper(), af.schroeder_multisine(f0=2.0, f_max=100.0, lines="odd")
    settle, periods, seed, G = 2, 71, 7, 2
    est = af.run_experiment(rig, PID, sphs, periods=periods, settle_periods=settle, seed=seed)
    plan, unexcited = _plan(sphs.harmonics, sphs.period_samples)
    n = sphs.harmonics.size
    F, Y = drawn_spectra(rig, PID, sphs.samples, settle + periods, seed, [*sphs.harmonics, *unexcited])
    F, Y = F[settle:], Y[settle:]
    L, blocks = sphs.period_samples, periods // G
    scale = 2.0 / (L * periods)
    Fm, Ym = F.sum(axis=0) * scale, Y.sum(axis=0) * scale
    H = Fm[:n] / Ym[:n]
    w = 2 * np.pi * sphs.harmonics * sphs.f0
    Fb = F[: blocks * G, :n].reshape(blocks, G, n).mean(axis=1)
    Yb = Y[: blocks * G, :n].reshape(blocks, G, n).mean(axis=1)
    dH = ((Fb - Fb.mean(axis=0)) - H * (Yb - Yb.mean(axis=0))) / Yb.mean(axis=0)
    to_mean = G / ((blocks - 1) * periods)
    k = rig.mass * w**2 + H.real
    c = H.imag / w
    want = {
        "k": k,
        "c": c,
        "k_std": np.sqrt(to_mean * np.sum(dH.real**2, axis=0)),
        "c_std": np.sqrt(to_mean * np.sum(dH.imag**2, axis=0)) / w,
        "k_smooth": ndimage.median_filter(k, 5, mode="nearest"),
        "c_smooth": ndimage.median_filter(c, 5, mode="nearest"),
    }
    assert est.blocks == blocks and est.periods == periods
    for name, value in want.items():
        np.testing.assert_allclose(getattr(est, name), value, rtol=1e-9, err_msg=name)
    np.testing.assert_allclose(est.unexcited.displacement, np.abs(Ym[n:]), rtol=1e-9)
    np.testing.assert_allclose(est.unexcited.force, np.abs(Fm[n:]), rtol=1e-9)


def test_rigs_with_something_to_watch_still_run_the_loop() -> None:
    """A current limit the loop reaches is seen only sample by sample: with one, the steady-start experiment
    of a linear rig still runs the loop and counts the saturated samples (drawn spectra would show none)."""
    rig = af.Rig.paper()
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)  # peaks at 0.145 A
    limited = replace(rig, current_limit=0.13)
    with pytest.warns(UserWarning, match="saturated"):
        clipped = af.run_experiment(limited, PID, sphs, seed=3)
    assert clipped.saturated_samples > 0
