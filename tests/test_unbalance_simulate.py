"""``simulate`` of a rotor with rotating unbalances at constant speed: the record settles on the exact
synchronous response (``unbalance_response``), starts from rest with the force rotating from ``t = 0``,
and leaves the noise of the run unchanged."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast.system import _model

PID = af.RotorRig.example_controller()
W = 900.0  # rad/s, between the rigid modes' critical speeds
UNBALANCE = [(2e-4, 0.1, 0.3), (1e-4, -0.15, 2.0)]


def quiet(speed: float = W, dead_time: float = 0.0) -> af.RotorRig:
    """The example rotor without noise; every axis the paper's chain (amplifier, eddy-current and probe lags,
    mass loading, AC-coupled transducer), with ``dead_time`` (s)."""
    rig = af.RotorRig.example(speed=speed)
    return af.RotorRig(rig.rotor, replace(rig.axes[0], sensor_noise=0.0, force_noise=0.0, dead_time=dead_time))


def synchronous(amplitude: np.ndarray, samples: int) -> np.ndarray:
    """``Re(amplitude e^{jWkT})`` at the samples k, (samples, 4)."""
    return np.real(amplitude[None, :] * np.exp(1j * W * np.arange(samples) / PID.fs)[:, None])


@pytest.mark.parametrize("dead_time", [0.0, 0.3e-3])  # 0.3 ms: 1.2 samples, the fraction by the modified z
def test_a_simulated_record_settles_on_the_exact_unbalance_response(dead_time: float) -> None:
    """The slowest pole (the integrator, |z| = 0.99937) decays below 1e-12 in 44000 samples; after 60000 the
    record's probes and coil currents are the synchronous response to 1e-9 of its amplitude, and its fitted
    amplitude and phase (least squares on cos, sin over the last 20000 samples) likewise."""
    rig = quiet(dead_time=dead_time)
    n = 80_000
    trace = af.simulate(rig, PID, np.zeros((n, 4)), unbalance=UNBALANCE)
    exact = af.unbalance_response(rig, PID, [W], UNBALANCE)
    tail = slice(60_000, None)
    for recorded, amplitude in ((trace.displacement, exact.probes[0]), (trace.current, exact.currents[0])):
        scale = np.abs(amplitude).max()
        assert np.abs(recorded - synchronous(amplitude, n))[tail].max() < 1e-9 * scale
        k = np.arange(n)[tail]
        basis = np.c_[np.cos(W * k / PID.fs), -np.sin(W * k / PID.fs)]
        re, im = np.linalg.lstsq(basis, recorded[tail], rcond=None)[0]
        np.testing.assert_allclose(np.abs(re + 1j * im), np.abs(amplitude), rtol=1e-9)
        np.testing.assert_allclose(np.angle(re + 1j * im), np.angle(amplitude), rtol=0, atol=1e-9)
    assert np.abs(trace.force).max() == 0.0  # the shakers' transducers do not see the unbalance
    # Not settled yet, the record is far from it: the comparison can tell.
    assert np.abs(trace.displacement - synchronous(exact.probes[0], n))[1000].max() > 1e-3 * np.abs(exact.probes).max()


def test_the_record_starts_from_rest_with_the_force_rotating_from_time_zero() -> None:
    """From rest, the loop's state is the synchronous orbit minus the free response from its start:
    ``z[k] = Re(X e^{jWkT}) - M^k Re(X)`` (X: the orbit's state at the samples), sample by sample from the
    first. An oscillator started one sample late (the force from t = T) misses this by its whole size."""
    rig = quiet()
    n = 400
    trace = af.simulate(rig, PID, np.zeros((n, 4)), unbalance=UNBALANCE)
    X = af.unbalance_response(rig, PID, [W], UNBALANCE).states[0]
    model = _model.loop_model(rig, PID)
    free, expected = np.real(X), np.zeros((n, 4))
    for k in range(n):
        expected[k] = model.C[:4] @ (np.real(X * np.exp(1j * W * k / PID.fs)) - free)
        free = model.M @ free
    assert trace.displacement[0].tolist() == [0.0] * 4
    np.testing.assert_allclose(trace.displacement, expected, rtol=0, atol=1e-10 * np.abs(expected).max())


def test_the_unbalance_adds_to_the_run_without_changing_its_noise() -> None:
    """With noise and shaker forces, the record minus the same seed's record without unbalance is the
    noise-free record of the unbalance alone (the loop is linear; the oscillator's channel draws no noise)."""
    rig = af.RotorRig.example(speed=W)
    force = np.random.default_rng(3).standard_normal((2000, 4))
    with_u = af.simulate(rig, PID, force, unbalance=UNBALANCE, seed=7)
    without = af.simulate(rig, PID, force, seed=7)
    alone = af.simulate(af.RotorRig(rig.rotor, replace(rig.axes[0], sensor_noise=0.0, force_noise=0.0)), PID,
                        np.zeros_like(force), unbalance=UNBALANCE)  # fmt: skip
    np.testing.assert_array_equal(with_u.force, without.force)
    scale = np.abs(alone.displacement).max()
    assert scale > 10 * rig.axes[0].sensor_noise  # the unbalance is well above the noise: the check can tell
    np.testing.assert_allclose(with_u.displacement - without.displacement, alone.displacement, rtol=0,
                               atol=1e-9 * scale)  # fmt: skip


def test_unbalance_in_simulate_bad_input_names_the_value() -> None:
    rig, force = af.RotorRig.example(speed=W), np.zeros((10, 4))
    with pytest.raises(ValueError, match=r"unbalance\[0\] plane must be within the rotor's model.*got 5.0"):
        af.simulate(rig, PID, force, unbalance=[(1e-4, 5.0, 0.0)])
    with pytest.raises(ValueError, match=r"unbalance\[0\]\[0\] must be a finite number \(kg m\), got nan"):
        af.simulate(rig, PID, force, unbalance=[(np.nan, 0.0, 0.0)])
    with pytest.raises(ValueError, match=r"unbalance\[1\]\[2\] must be a finite number \(rad\), got inf"):
        af.simulate(rig, PID, force, unbalance=[(1e-4, 0.0, 0.0), (1e-4, 0.0, np.inf)])
    with pytest.raises(ValueError, match="the rotor's speed must be non-zero with an unbalance"):
        af.simulate(rig.at_speed(0.0), PID, force, unbalance=UNBALANCE)
    with pytest.raises(ValueError, match="unbalance must be a list"):
        af.simulate(rig, PID, force, unbalance=[])
    unstable = replace(rig, rotor=replace(rig.rotor, process=((0.0, 3e5, -3e5, 0.0, 0.0),)))
    with pytest.raises(af.UnstableLoopError, match="the closed loop at speed 900 rad/s is unstable"):
        af.simulate(unstable, PID, force, unbalance=UNBALANCE)
    with pytest.raises(ValueError, match=r"rig must be a RotorRig \(an unbalance needs a rotor\), got 'TwoAxisRig'"):
        af.simulate(af.TwoAxisRig(af.Rig.paper()), af.PID.paper(), np.zeros((10, 2)), unbalance=UNBALANCE)
