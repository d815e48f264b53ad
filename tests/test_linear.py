"""Closed-form answers: effective coefficients, sensitivity and its zones, poles."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import cont2discrete

import amb_fast as af
from amb_fast._linear import iso_zone, plant_matrices


def test_effective_coefficients_of_an_unfiltered_pid_are_analytic() -> None:
    rig, pid = af.Rig(), af.PID(kp=2000.0, ki=20000.0, kd=5.0)
    f = np.array([1.0, 10.0, 100.0])
    w = 2 * np.pi * f
    k, c = af.effective_coefficients(rig, pid, f)
    np.testing.assert_allclose(k, rig.kyy + rig.kiy * pid.kp, rtol=1e-14)
    np.testing.assert_allclose(c, rig.kiy * (pid.kd * w - pid.ki / w) / w, rtol=1e-13)


def test_controller_forms_agree() -> None:
    rig, pid = af.Rig(), af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0)
    f = np.geomspace(1, 200, 50)
    wd = 2 * np.pi * 1000.0
    # G(s) = kp + ki/s + kd s/(1 + s/wd) over a common denominator s (1 + s/wd).
    num = np.polyadd(np.polyadd(np.polymul([pid.kp, 0], [1 / wd, 1]), np.polymul([pid.ki], [1 / wd, 1])),
                     [pid.kd, 0, 0])  # fmt: skip
    den = np.polymul([1, 0], [1 / wd, 1])
    expected = af.effective_coefficients(rig, pid, f)
    for controller in ((num, den), lambda s: pid.kp + pid.ki / s + pid.kd * s / (1 + s / wd)):
        for got, want in zip(af.effective_coefficients(rig, controller, f), expected):
            np.testing.assert_allclose(got, want, rtol=1e-10)


def test_discrete_effective_coefficients_include_the_delay() -> None:
    rig, pid = af.Rig(), af.PID(kp=2000.0, ki=0.0, kd=0.0, delay=2)
    f = np.array([50.0, 200.0])
    k, c = af.effective_coefficients(rig, pid, f, discrete=True)
    G = pid.kp * np.exp(-2j * np.pi * f * 2 / pid.fs)
    np.testing.assert_allclose(k, rig.kyy + rig.kiy * G.real, rtol=1e-12)
    np.testing.assert_allclose(c, rig.kiy * G.imag / (2 * np.pi * f), rtol=1e-12)
    with pytest.raises(ValueError, match="discrete must be False"):
        af.effective_coefficients(rig, ([1.0], [1.0]), f, discrete=True)


def test_sensitivity_links_prediction_to_the_open_plant(lagged_rig, pid) -> None:
    """Y/F = P_f S: the closed loop is the open plant's force response times the sensitivity."""
    f = np.geomspace(0.5, 1900, 40)
    A, B, states = plant_matrices(lagged_rig)
    Phi, Gamma, *_ = cont2discrete((A, B, np.eye(len(states)), np.zeros((len(states), 2))), 1 / pid.fs)
    z = np.exp(2j * np.pi * f / pid.fs)
    Pf = np.array([np.linalg.solve(zk * np.eye(len(states)) - Phi, Gamma[:, 0])[states.index("ys")] for zk in z])
    np.testing.assert_allclose(af.predict(lagged_rig, pid, f), Pf * af.sensitivity(lagged_rig, pid, f), rtol=1e-9)


def test_stability_margin_zones() -> None:
    assert [iso_zone(p) for p in (2.99, 3.0, 3.99, 4.0, 4.99, 5.0)] == ["A", "B", "B", "C", "C", "D"]
    rig = af.Rig(amp_bandwidth=1500.0, sensor_bandwidth=5000.0)
    margin = af.stability_margin(rig, af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0))
    assert margin.stable and margin.zone == iso_zone(margin.peak) and margin.peak > 1
    f = np.geomspace(0.01, 1999.9, 200_000)
    dense = np.abs(af.sensitivity(rig, af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0), f)).max()
    assert margin.peak == pytest.approx(dense, rel=1e-3)
    unstable = af.stability_margin(rig, af.PID(kp=500.0, ki=0.0, kd=5.0))
    assert not unstable.stable and unstable.zone == "D" and unstable.peak == np.inf


def test_poles_of_a_lightly_damped_loop_are_inside_the_unit_circle(lagged_rig, pid) -> None:
    poles = af.closed_loop_poles(lagged_rig, pid)
    assert poles.size == 5 + 2 + 1  # plant, PID (integral, filtered derivative), one delay
    assert np.all(np.abs(poles) < 1)
    with pytest.raises(ValueError, match="freq must be"):
        af.predict(lagged_rig, pid, [10.0, 2500.0])


def test_core_eigenvalues_equal_numpy_and_do_not_depend_on_threads(rng) -> None:
    """The stability checks of runs and sweeps take their poles from the core (one function, the same
    digits for both): against numpy's LAPACK eigenvalues to 1e-12 of the spectral radius, closed loops
    and random matrices with complex pairs alike, and bit for bit the same on 1 or 2 threads."""
    from amb_fast import _core
    from amb_fast._linear import _closed_loop_stacks, _gain_arrays

    pid = af.PID.paper()
    ((_, loops),) = _closed_loop_stacks(af.Rig.paper(), pid, _gain_arrays(pid, np.linspace(1e3, 5e3, 150), None, None))
    stack = np.concatenate([loops, rng.standard_normal((150, 7, 7))])
    ours = _core.eigenvalues(stack, 1)
    np.testing.assert_array_equal(ours, _core.eigenvalues(stack, 2))
    for mine, theirs in zip(ours, np.linalg.eigvals(stack)):
        # eigenvalues as a multiset: match each of numpy's to the nearest of ours
        gap = np.abs(theirs[:, None] - mine[None, :]).min(axis=1)
        assert gap.max() <= 1e-12 * np.abs(theirs).max()
