"""The rotor (amb_fast.system) against the independent pure-numpy reference (tests/rotor_reference.py):
predict, the experiment from rest and from the steady state, the actual coefficients, the Campbell poles,
with speed, non-collocated probes, lags, fractional dead times, mass loading and a process on."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
import rotor_reference as ref

PID = af.RotorRig.example_controller()
SPHS = af.schroeder_multisine(f0=40.0, f_max=800.0)  # 100-sample periods: the reference is slow
AXES = [
    af.Rig(amp_bandwidth=3000.0, eddy_bandwidth=2000.0, sensor_bandwidth=10_000.0, mass_loading=0.06,
           force_coupling_tau=1.0, dead_time=0.3e-3),
    af.Rig(amp_bandwidth=2500.0, sensor_bandwidth=8000.0, mass_loading=0.04, dead_time=0.1e-3),
    af.Rig(amp_bandwidth=3000.0, eddy_bandwidth=1500.0, dead_time=0.25e-3),
    af.Rig(kyy=-5e4, kiy=45.0, amp_bandwidth=3500.0, sensor_bandwidth=12_000.0, force_coupling_tau=0.5),
]  # fmt: skip


def rigs(speed: float) -> tuple[af.RotorRig, ref.RotorParams]:
    rotor = af.RigidRotor(9.0, 0.25, 0.03, bearings=(-0.18, 0.22), sensors=(-0.21, 0.26), speed=speed,
                          process=[(0.05, 4e3, -4e3, 20.0, -20.0)])  # fmt: skip
    params = ref.RotorParams(9.0, 0.25, 0.03, (-0.18, 0.22), (-0.21, 0.26), speed, [(0.05, 4e3, -4e3, 20.0, -20.0)])
    return af.RotorRig(rotor, AXES), params


@pytest.mark.parametrize("speed", [0.0, 1500.0])
def test_predict_and_poles_equal_the_reference(speed: float) -> None:
    rig, params = rigs(speed)
    freq = SPHS.freq
    R = af.predict(rig, PID, freq)
    expected = ref.receptance(params, AXES, ref.diagonal(PID), freq)
    np.testing.assert_allclose(R, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    ours = af.closed_loop_poles(rig, PID)
    theirs = ref.loop_eigenvalues(params, AXES, ref.diagonal(PID))
    # Every pole of ours among the reference's (which also keeps its delay registers' exact zeros).
    assert np.max(np.min(np.abs(ours[:, None] - theirs[None, :]), axis=1)) < 1e-9
    c = af.campbell(rig, PID, [speed])
    assert np.max(np.min(np.abs(c.z[0][:, None] - theirs[None, :]), axis=1)) < 1e-9
    modes = ref.loop_modes(params, AXES, ref.diagonal(PID))
    for z, w in zip(c.z[0], c.whirl[0]):
        if w != 0 and c.damping[0][list(c.z[0]).index(z)] < 0.9:
            j = int(np.argmin(np.abs(modes[0] - z)))
            if np.sum(np.abs(modes[0] - modes[0][j]) < 1e-8) == 1:  # a simple pole: its whirl is its own
                assert modes[2][j] == w


def test_experiment_from_rest_equals_the_reference() -> None:
    """Noise-free, from rest: the core's four experiments and the reference's sample-by-sample loop give the
    same H = F Y^-1 at the lines (to 1e-9 of its size) and the same actual coefficients."""
    rig, params = rigs(1200.0)
    quiet = af.RotorRig(rig.rotor, [replace(a, force_coupling_tau=None) for a in AXES])
    axes = list(quiet.axes)
    est = af.run_experiment(quiet, PID, SPHS, periods=2, settle_periods=30, start="rest")
    freq, H = ref.experiment(params, axes, ref.diagonal(PID), SPHS.samples, periods=2, settle=30)
    lines = SPHS.harmonics
    np.testing.assert_allclose(freq[lines - 1], est.freq)
    np.testing.assert_allclose(est.H, H[lines - 1], rtol=0, atol=1e-9 * np.abs(est.H).max())
    K, C = ref.actual_coefficients(params, est.freq, H[lines - 1])
    np.testing.assert_allclose(est.k, K, rtol=0, atol=1e-9 * np.abs(est.H).max())
    np.testing.assert_allclose(est.c, C, rtol=0, atol=1e-9 * np.abs(est.H).max() / (2 * np.pi * est.freq[0]))


def test_steady_experiment_equals_the_reference_receptance() -> None:
    rig, params = rigs(800.0)
    est = af.run_experiment(rig, PID, SPHS, periods=2)
    expected = ref.receptance(params, AXES, ref.diagonal(PID), est.freq)
    np.testing.assert_allclose(est.receptance, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
