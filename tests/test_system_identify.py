"""system.identify: the N x N estimate from recordings of N experiments gives run_experiment's estimate, and
refuses wrong shapes, experiment counts and force patterns naming the parameter."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system
from amb_fast.system._control import controller_matrix
from amb_fast.system._experiment import experiment_seeds, settle_for
from amb_fast.system._model import require_stable

SPHS = af.schroeder_multisine(f0=20.0, f_max=200.0)
PID = af.RotorRig.example_controller()
FIELDS = ("H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force", "displacement")


def _quiet(rig: af.RotorRig) -> af.RotorRig:
    return af.RotorRig(rig.rotor, dataclasses.replace(rig.axes[0], sensor_noise=0.0, force_noise=0.0))


def _recordings(rig, controller, periods: int, seeds: list[int]) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    """Every experiment simulated from rest with the Hadamard-signed multisine: (N, samples, N) each."""
    signs = system.hadamard_signs(len(rig.axes))
    traces = [system.simulate(rig, controller, np.tile(SPHS.samples, periods)[:, None] * row[None, :], seed=s)
              for row, s in zip(signs, seeds)]  # fmt: skip
    return np.array([t.force for t in traces]), np.array([t.displacement for t in traces])


def _assert_same(est: system.EstimateN, ref: system.EstimateN, tol: float = 1e-9) -> None:
    assert est.axes == ref.axes and est.periods == ref.periods
    assert np.array_equal(est.freq, ref.freq)
    for name in FIELDS:
        a, b = getattr(est, name), getattr(ref, name)
        assert np.max(np.abs(a - b)) <= tol * np.max(np.abs(b)), name


@pytest.mark.parametrize("speed", [0.0, 2000.0])  # at speed the gyroscopic matrix is removed from k, c
def test_noise_free_recordings_give_run_experiments_estimate(speed: float) -> None:
    rig = _quiet(af.RotorRig.example(speed))
    settle = 30
    ref = af.run_experiment(rig, PID, SPHS, periods=3, start="rest", settle_periods=settle, seed=1)
    F, Y = _recordings(rig, PID, settle + 3, [1, 2, 3, 4])
    est = system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=settle, lines=SPHS.freq)
    _assert_same(est, ref)
    # the rotor alone (its RigidRotor or its Mechanics) is structure enough, and the lines are found
    _assert_same(system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig.rotor, settle_periods=settle), ref)
    _assert_same(system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig.mechanics(), settle_periods=settle), ref)
    _assert_same(af.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=settle), ref)  # routed by shape


def test_automatic_settling_and_recordings_as_recording_objects() -> None:
    rig = _quiet(af.RotorRig.example())
    ref = af.run_experiment(rig, PID, SPHS, periods=3, start="rest", seed=1)  # settles as long as it needs
    settle = settle_for(rig, SPHS.fs, require_stable(rig, controller_matrix(PID, 4)), SPHS.period_samples)
    F, Y = _recordings(rig, PID, settle + 3, [1, 2, 3, 4])
    recordings = [[af.Recording(F[e, :, j], Y[e, :, j], SPHS.fs) for j in range(4)] for e in range(4)]
    _assert_same(system.identify(recordings, f0=SPHS.f0, rig=rig, settle_periods=settle), ref)


def test_noisy_recordings_with_the_experiments_seeds_give_the_same_estimate() -> None:
    rig = af.RotorRig.example()
    ref = af.run_experiment(rig, PID, SPHS, periods=4, start="rest", settle_periods=20, seed=7)
    F, Y = _recordings(rig, PID, 24, experiment_seeds(7, 4))
    _assert_same(system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=20, lines=SPHS.freq), ref)


def test_two_axes() -> None:
    rig = af.TwoAxisRig.paper()
    ms = af.schroeder_multisine(f0=20.0, f_max=100.0)
    ref = system.run_experiment(rig, af.PID.paper(), ms, periods=3, start="rest", settle_periods=20, seed=5)
    signs = system.hadamard_signs(2)
    traces = [system.simulate(rig, af.PID.paper(), np.tile(ms.samples, 23)[:, None] * row, seed=s)
              for row, s in zip(signs, experiment_seeds(5, 2))]  # fmt: skip
    F, Y = np.array([t.force for t in traces]), np.array([t.displacement for t in traces])
    _assert_same(system.identify(F, Y, fs=ms.fs, f0=ms.f0, rig=rig, settle_periods=20, lines=ms.freq), ref)


def test_trailing_samples_are_dropped_with_a_warning() -> None:
    rig = _quiet(af.RotorRig.example())
    F, Y = _recordings(rig, PID, 33, [1, 2, 3, 4])
    ref = system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=30)
    with pytest.warns(af.IdentificationWarning, match="dropped 600 samples .over the 4 experiments."):
        est = system.identify(F[:, :-50], Y[:, :-50], fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=30)
    assert est.periods == 2 and np.array_equal(est.freq, ref.freq)


# -- refusals -----------------------------------------------------------------------------------------------------

ROTOR = af.RotorRig.example()
ZEROS = np.zeros((4, 800, 4))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: system.identify(np.zeros((3, 800, 4)), np.zeros((3, 800, 4)), fs=4000.0, f0=20.0, rig=ROTOR),
         r"force shape must be \(4 experiments, samples, 4 axes: A.x, A.y, B.x, B.y\), got \(3, 800, 4\)"),
        (lambda: system.identify(ZEROS, ZEROS[:, :400], fs=4000.0, f0=20.0, rig=ROTOR),
         r"displacement shape must be \(4, 800, 4\) like force, got \(4, 400, 4\)"),
        (lambda: system.identify(ZEROS, ZEROS, f0=20.0, rig=ROTOR), "fs must be the sampling frequency"),
        (lambda: system.identify(ZEROS, ZEROS, fs=4000.0, f0=20.0, rig=af.PID.paper()),
         "rig must be a RotorRig, a RigidRotor, a TwoAxisRig or their Mechanics"),
        (lambda: system.identify([[None] * 4] * 3, f0=20.0, rig=ROTOR),
         r"recordings must be 4 experiments \(one per axis\), each a list of 4 Recordings .*, got '3 experiments'"),
        (lambda: system.identify([[af.Recording(np.ones(800), np.ones(800), 4000.0)] * 3] * 4, f0=20.0, rig=ROTOR),
         r"recordings\[0\] must be a list of 4 amb_fast.Recording \(axes A.x, A.y, B.x, B.y\), got \['Recording'"),
        (lambda: system.identify([[af.Recording(np.ones(800), np.ones(800), 4000.0)] * 4] * 4, f0=20.0, rig=ROTOR,
                                 fs=5000.0), r"fs must be the recordings' fs 4000 Hz within 0.1 %, got 5000.0"),
        (lambda: system.identify([[af.Recording(np.ones(800), np.ones(800), 4000.0)] * 3
                                  + [af.Recording(np.ones(800), np.ones(800), 4001.0)]] * 4, f0=20.0, rig=ROTOR),
         r"recordings\[0\]\[3\].fs must be 4000.0 Hz like recordings\[0\]\[0\]"),
        (lambda: system.identify(ZEROS[:, :300], ZEROS[:, :300], fs=4000.0, f0=20.0, rig=ROTOR),
         r"periods after settling must be >= 2"),
        (lambda: system.identify(np.tile(np.sin(np.arange(800) * np.pi / 10)[None, :, None], (4, 1, 4)), ZEROS + 1,
                                 fs=4000.0, f0=20.0, rig=ROTOR),
         r"force must tell the 4 axes apart at every line: .* at 200 Hz .*hadamard_signs\(4\)\[e, j\]"),
    ],
)  # fmt: skip
def test_refusals_name_the_parameter(call, message: str) -> None:  # noqa: ANN001
    with pytest.raises(ValueError, match=message):
        call()


def test_non_finite_sample_is_named() -> None:
    F = np.tile(np.sin(np.arange(800) * np.pi / 10)[None, :, None], (4, 1, 4)) * system.hadamard_signs(4)[:, None, :]
    Y = F * 1e-7  # |F/Y| 1e7 N/m: above what moving the rotor takes (1e5 would warn: too light)
    Y[2, 500, 3] = np.nan
    with pytest.raises(ValueError, match=r"displacement must be finite, got nan in experiment 2, axis B.y, sample 500"):
        system.identify(F, Y, fs=4000.0, f0=20.0, rig=ROTOR)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        est = system.identify(F, F * 1e-7, fs=4000.0, f0=20.0, rig=ROTOR)  # the same without the NaN
    assert est.freq.tolist() == [200.0]
