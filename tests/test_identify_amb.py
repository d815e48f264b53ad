"""system.identify from the bearings as exciters (issue 27 part 2: coil currents and probes per axis), and the
one-axis recording checks (amb_fast.identify's) applied to every experiment and axis of N-axis recordings."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system
from amb_fast.system._experiment import experiment_seeds

SPHS = af.schroeder_multisine(f0=20.0, f_max=200.0)
PID = af.RotorRig.example_controller()
FIELDS = ("H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force", "displacement", "process")


def _quiet(rig: af.RotorRig, **changes: object) -> af.RotorRig:
    return af.RotorRig(rig.rotor, dataclasses.replace(rig.axes[0], sensor_noise=0.0, force_noise=0.0, **changes))


def _amb_recordings(rig: af.RotorRig, periods: int, seeds: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Every experiment simulated from rest with the Hadamard-signed multisine on the current commands: the
    coil currents (A) and the probes (m), (N, samples, N) each."""
    traces = [system.simulate(rig, PID, np.tile(SPHS.samples, periods)[:, None] * row[None, :], seed=s, exciter="amb")
              for row, s in zip(system.hadamard_signs(4), seeds)]  # fmt: skip
    return np.array([t.current for t in traces]), np.array([t.displacement for t in traces])


def _assert_same(est: system.EstimateN, ref: system.EstimateN, tol: float = 1e-9) -> None:
    assert est.axes == ref.axes and est.periods == ref.periods and np.array_equal(est.freq, ref.freq)
    for name in FIELDS:
        a, b = getattr(est, name), getattr(ref, name)
        assert np.max(np.abs(a - b)) <= tol * np.max(np.abs(b)), name


@pytest.mark.parametrize(
    "changes",
    [{}, {"amp_bandwidth": None, "dead_time": 0.0}],  # the coil current a state; the command itself
    ids=["amplifier", "ideal"],
)
def test_currents_and_probes_at_speed_give_the_amb_experiments_estimate(changes: dict) -> None:
    rig = _quiet(af.RotorRig.example(1500.0), **changes)
    settle = 30
    ref = af.run_experiment(rig, PID, SPHS, exciter="amb", start="rest", periods=3, settle_periods=settle, seed=1)
    current, probes = _amb_recordings(rig, settle + 3, experiment_seeds(1, 4))
    est = system.identify(displacement=probes, current=current, fs=SPHS.fs, f0=SPHS.f0, rig=rig,
                          settle_periods=settle)  # fmt: skip
    _assert_same(est, ref)
    assert ref.process is not None and np.abs(ref.process).max() > 0
    # the same as Recordings, each one's "force" channel holding the axis' current
    recordings = [[af.Recording(current[e, :, j], probes[e, :, j], SPHS.fs) for j in range(4)] for e in range(4)]
    _assert_same(system.identify(current=recordings, f0=SPHS.f0, rig=rig, settle_periods=settle), ref)


def test_noisy_currents_with_the_experiments_seeds_give_the_same_estimate() -> None:
    rig = af.RotorRig.example(800.0)
    rig = af.RotorRig(rig.rotor, dataclasses.replace(rig.axes[0], force_coupling_tau=None))
    ref = af.run_experiment(rig, PID, SPHS, exciter="amb", start="rest", periods=4, settle_periods=20, seed=7)
    current, probes = _amb_recordings(rig, 24, experiment_seeds(7, 4))
    est = system.identify(displacement=probes, current=current, fs=SPHS.fs, f0=SPHS.f0, rig=rig, settle_periods=20,
                          lines=SPHS.freq)  # fmt: skip
    _assert_same(est, ref)


def test_a_current_recording_loaded_as_a_force_is_refused(tmp_path) -> None:  # noqa: ANN001
    rig = af.RotorRig.example()
    n = 4 * SPHS.period_samples
    path = tmp_path / "rig.csv"
    af.save_recording(path, force=np.tile(SPHS.samples, 4), displacement=np.ones(n) * 1e-6, fs=SPHS.fs)
    loaded = af.load_recording(path)  # its channel is "force": a force, not a current
    with pytest.raises(ValueError, match=r"recordings\[0\]\[0\] must be a coil current \(A\) in its force channel"):
        system.identify(current=[[loaded] * 4] * 4, f0=SPHS.f0, rig=rig)


ROTOR = af.RotorRig.example()
ZEROS = np.zeros((4, 800, 4))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: system.identify(ZEROS, ZEROS, current=ZEROS, fs=4000.0, f0=20.0, rig=ROTOR),
            r"force, current must be one of them: force= .shakers' forces, N. or current= .*got 'both'",
        ),
        (lambda: system.identify(displacement=ZEROS, fs=4000.0, f0=20.0, rig=ROTOR), r"got 'neither'"),
        (
            lambda: system.identify(current=ZEROS, displacement=ZEROS, fs=4000.0, f0=20.0, rig=ROTOR.rotor),
            r"rig must be a RotorRig or TwoAxisRig with current=: its axes' kyy, kiy .*got 'RigidRotor'",
        ),
        (
            lambda: system.identify(current=ZEROS[:3], displacement=ZEROS[:3], fs=4000.0, f0=20.0, rig=ROTOR),
            r"current shape must be \(4 experiments, samples, 4 axes: A.x, A.y, B.x, B.y\), got \(3, 800, 4\)",
        ),
        (
            lambda: system.identify(
                current=np.tile(np.sin(np.arange(800) * np.pi / 10)[None, :, None], (4, 1, 4)),
                displacement=ZEROS,
                fs=4000.0,
                f0=20.0,
                rig=ROTOR,
            ),
            r"current must tell the 4 axes apart at every line: the experiments' current matrix",
        ),
    ],  # fmt: skip
)
def test_bad_input_is_refused_naming_the_parameter(call, message: str) -> None:  # noqa: ANN001
    with pytest.raises(ValueError, match=message):
        call()


# -- the one-axis checks on N axes --------------------------------------------------------------------------------


def _shaker_recordings(rig: af.RotorRig, periods: int, seeds: list[int]) -> tuple[np.ndarray, np.ndarray]:
    traces = [system.simulate(rig, PID, np.tile(SPHS.samples, periods)[:, None] * row[None, :], seed=s)
              for row, s in zip(system.hadamard_signs(4), seeds)]  # fmt: skip
    return np.array([t.force for t in traces]), np.array([t.displacement for t in traces])


F, Y = _shaker_recordings(af.RotorRig.example(), 24, [1, 2, 3, 4])


def test_the_noisy_experiment_passes_every_check() -> None:
    est = system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=ROTOR, settle_periods=20)  # warnings are errors
    assert est.periods == 4


@pytest.mark.filterwarnings("ignore:recordings are not a whole number of periods")
def test_a_wrong_fs_warns_non_periodic() -> None:
    """fs given 5 % high: the force no longer repeats with fs/f0 samples (before: no warning at all)."""
    with pytest.warns(af.NonPeriodicExcitationWarning, match=r"experiment 0, axis A.x: the force does not repeat"):
        system.identify(F, Y, fs=1.05 * SPHS.fs, f0=SPHS.f0, rig=ROTOR, settle_periods=20, lines=SPHS.freq[:5])


def test_a_displacement_of_pure_noise_warns_weak_lines() -> None:
    noise = np.random.default_rng(3).normal(0.0, 1e-6, Y.shape)
    with pytest.warns(af.WeakLinesWarning, match=r"4 experiments: 10 of 10 excited lines are weak: their force or "
                                                 r"displacement"):  # fmt: skip
        system.identify(F, noise, fs=SPHS.fs, f0=SPHS.f0, rig=ROTOR, settle_periods=20)


def test_a_kept_start_transient_warns() -> None:
    with pytest.warns(af.IdentificationWarning, match=r"experiment 0, axis A.x: the first period differs from the "):
        system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0, rig=ROTOR)  # the start from rest kept


def test_a_period_of_half_fs_over_f0_warns_short_period() -> None:
    """f0 given half the multisine's: every excited harmonic is even."""
    with pytest.warns(af.ShortPeriodWarning, match=r"experiment 0, axis A.x: every harmonic the force excites"):
        system.identify(F, Y, fs=SPHS.fs, f0=SPHS.f0 / 2, rig=ROTOR, settle_periods=10)


def test_displacement_in_um_warns_implausible() -> None:
    with pytest.warns(af.IdentificationWarning) as caught:
        system.identify(F, Y * 1e6, fs=SPHS.fs, f0=SPHS.f0, rig=ROTOR, settle_periods=20)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2, messages  # once each, not once per axis
    assert messages[0].startswith("axis A.x: the force is 9.3e-07 of what accelerating the given mass takes")
    assert messages[1].startswith("axis A.x: the displacement amplitude") and "is above 10 mm" in messages[1]


def test_a_noisy_current_warns_in_amperes() -> None:
    current, probes = _amb_recordings(_quiet(ROTOR), 24, [1, 2, 3, 4])
    noise = np.random.default_rng(4).normal(0.0, 1e-6, probes.shape)
    with pytest.warns(af.WeakLinesWarning, match=r"their current or displacement .*\(current [0-9.e-]+ A, "):
        system.identify(current=current, displacement=noise, fs=SPHS.fs, f0=SPHS.f0, rig=ROTOR, settle_periods=20)


def test_simulate_with_the_bearings_as_exciters_records_the_injection() -> None:
    """simulate(..., exciter="amb"): the columns are current (A) on the commands; TraceN.force is the injection
    and, with an ideal amplifier and no dead time, the coil current is the command with the injection in it."""
    rig = _quiet(ROTOR, amp_bandwidth=None, dead_time=0.0)
    injection = np.tile(SPHS.samples, 2)[:, None] * system.hadamard_signs(4)[1]
    trace = system.simulate(rig, PID, injection, exciter="amb")
    assert np.array_equal(trace.force, injection)
    shaken = system.simulate(rig, PID, injection)  # the same samples as forces: another loop input
    assert np.max(np.abs(trace.current - shaken.current)) > 0.1 * np.max(np.abs(injection))
    with pytest.raises(ValueError, match=r"exciter must be 'shaker' .* or 'amb' .*, got 'coil'"):
        system.simulate(rig, PID, injection, exciter="coil")  # type: ignore[arg-type]
