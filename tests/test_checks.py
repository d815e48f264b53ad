"""Refuse or warn, never guess: identify, simulate, sweep and the argument checks on inputs that are wrong
in ways a number cannot show by itself."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af

FS = 4000.0


@pytest.fixture(scope="module")
def recording() -> tuple[np.ndarray, np.ndarray]:
    """12 periods of the paper rig under a 1-100 Hz multisine, from rest (a start transient included)."""
    ms = af.schroeder_multisine(f_max=100.0)
    trace = af.simulate(af.Rig.paper(), af.PID.paper(), np.tile(ms.samples, 12), seed=1)
    return trace.force, trace.displacement


def ident(force, displacement, **kwargs):  # noqa: ANN001, ANN003, ANN201
    kwargs.setdefault("settle_periods", 4)
    kwargs.setdefault("mass", 0.92)
    return af.identify(force, displacement, fs=FS, f0=1.0, **kwargs)


def test_a_settled_recording_passes_without_warnings(recording) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        est = ident(*recording)
    assert est.weak is not None and est.weak.dtype == bool and not est.weak.any()


@pytest.mark.parametrize(
    ("force", "kwargs", "message"),
    [
        (lambda f: 0 * f, {}, "it is constant \\(0 N\\)"),
        (lambda f: 0 * f, {"f_max": 100.0}, "it is zero or constant there \\(0 N\\)"),
        (lambda f: 0 * f + 3.0, {"lines": [10.0, 20.0]}, "it is zero or constant there \\(3 N\\)"),
        (lambda f: np.random.default_rng(1).standard_normal(f.size), {}, "no harmonic of f0 stands clearly"),
        (lambda f: np.random.default_rng(2).standard_normal(f.size), {"f_max": 100.0}, "not clearly above the noise"),
        (lambda f: np.random.default_rng(3).standard_normal(f.size), {"f_max": 1999.0}, "not clearly above the noise"),
    ],
    ids=["zero", "zero-f_max", "constant-lines", "noise", "noise-f_max", "noise-every-line"],
)
def test_no_excitation_is_an_error_not_k_equal_m_w2(recording, force, kwargs, message) -> None:
    with pytest.raises(af.NoExcitationError, match=message):
        ident(force(recording[0]), recording[1], **kwargs)


def test_weak_lines_are_flagged_per_line(recording) -> None:
    force, displacement = recording
    ms = af.schroeder_multisine(f_max=100.0)
    # Lines 1-100 Hz excited; the recorded force's 50 Hz component removed (its noise left there).
    t = np.arange(force.size) / FS
    k = int(np.flatnonzero(ms.freq == 50.0)[0])
    line = 2.0 / force.size * np.sum(force * np.exp(-2j * np.pi * 50.0 * t))
    weaker = force - np.real(line * np.exp(2j * np.pi * 50.0 * t))
    est = ident(weaker, displacement, f_max=100.0)
    assert est.weak[k] and est.weak.sum() == 1
    assert not ident(force, displacement, f_max=100.0).weak.any()


def test_a_start_transient_kept_is_warned_about(recording) -> None:
    with pytest.warns(UserWarning, match="the first period differs from the last .* a start transient"):
        ident(*recording, settle_periods=0)


@pytest.mark.parametrize(
    ("change", "kwargs", "message"),
    [
        (lambda f, y: (f, y * 1e3), {}, "displacement amplitude .* is above 10 mm: is the displacement in mm"),
        (lambda f, y: (f, y), {"clearance": 2e-5}, "above the clearance 2e-05 m"),
        (lambda f, y: (y, f), {}, "force and displacement look swapped"),
        (lambda f, y: (f * 1e6, y), {}, "median stiffness .* is outside 100-1e\\+09 N/m"),
        (lambda f, y: (f / 1e3, y), {}, "force is .* of what accelerating the given mass takes.*kN instead of N"),
        (lambda f, y: (f, y), {"mass": 920.0}, "or the mass not in kg"),
    ],
    ids=["millimetres", "clearance", "swapped", "stiffness-range", "kilonewtons", "grams"],
)
def test_plausibility_warnings_for_unit_mistakes(recording, change, kwargs, message) -> None:
    force, displacement = change(*recording)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ident(force, displacement, **kwargs)
    assert any(__import__("re").search(message, str(w.message)) for w in caught), [str(w.message) for w in caught]


def test_nan_positions_count_from_the_start_of_the_recording(recording) -> None:
    force, displacement = recording[0].copy(), recording[1].copy()
    displacement[4 * 4000 + 7] = np.nan  # in the averaged part, after 4 settle periods
    with pytest.raises(ValueError, match="displacement must be finite, got nan at sample 16007"):
        ident(force, displacement)
    force[4 * 4000 + 9] = np.inf  # found while detecting the excited lines
    with pytest.raises(ValueError, match="force must be finite, got inf at sample 16009"):
        ident(force, recording[1])


def test_simulate_refuses_an_unstable_loop_and_flags_the_air_gap_and_saturation() -> None:
    with pytest.raises(af.UnstableLoopError, match="closed loop is unstable"):
        af.simulate(af.Rig(), af.PID(kp=500.0, ki=0.0, kd=5.0), np.ones(4000))
    loud = np.full(4000, 200.0)  # 200 N on a 60 kN/m loop: 3.3 mm, past the 0.575 mm air gap
    with pytest.warns(UserWarning, match="past the air gap 0.000575 m .* the linear force law does not hold"):
        af.simulate(af.Rig(), af.PID.paper(), loud)
    with (
        pytest.warns(UserWarning, match="past the air gap"),
        pytest.warns(UserWarning, match="amplifier saturated: the current reached its limit 0.05 A"),
    ):
        af.simulate(af.Rig(current_limit=0.05), af.PID.paper(), loud)
    with pytest.raises(af.TouchdownError):
        af.simulate(af.Rig(clearance=1e-4), af.PID.paper(), loud)


def test_a_sweep_tells_overflow_from_touchdown_and_saturation() -> None:
    pid = af.PID(kp=2000.0, ki=0.0, kd=5.0)
    ms = af.schroeder_multisine(f0=2.0)
    diverging = af.sweep(af.Rig(current_limit=0.02), pid, ms, kp=[2000.0, 2400.0], periods=3, settle_periods=30)
    assert list(diverging.status) == ["overflow", "overflow"]
    clipped = af.sweep(af.Rig(current_limit=0.02), pid, ms, kp=[2000.0], periods=3, settle_periods=2)
    assert list(clipped.status) == ["saturated"]
    touching = af.sweep(af.Rig(current_limit=0.02, clearance=1e-4), pid, ms, kp=[2000.0], periods=3, settle_periods=2)
    assert list(touching.status) == ["touchdown"]
    mixed = af.sweep(af.Rig(current_limit=0.02), pid, ms, kp=[2000.0], ki=[0.0], periods=3, settle_periods=30)
    assert np.all(np.isnan(mixed.k))


def test_excitation_rms_that_would_overflow_is_refused() -> None:
    with pytest.raises(ValueError, match="rms must be at most 1e12 N"):
        af.schroeder_multisine(rms=1e306)


@pytest.mark.parametrize(
    "call",
    [
        lambda rig, pid, ms: af.run_experiment(pid, rig, ms),
        lambda rig, pid, ms: af.simulate(pid, rig, ms.samples),
        lambda rig, pid, ms: af.sweep(pid, rig, ms, kp=[2000.0]),
        lambda rig, pid, ms: af.predict(pid, rig, [10.0]),
        lambda rig, pid, ms: af.closed_loop(pid, rig),
        lambda rig, pid, ms: af.closed_loop_poles(pid, rig),
        lambda rig, pid, ms: af.sensitivity(pid, rig, [10.0]),
        lambda rig, pid, ms: af.stability_margin(pid, rig),
    ],
    ids=[
        "run_experiment",
        "simulate",
        "sweep",
        "predict",
        "closed_loop",
        "closed_loop_poles",
        "sensitivity",
        "stability_margin",
    ],
)
def test_swapped_rig_and_controller_is_a_type_error_naming_them(call) -> None:
    rig, pid, ms = af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=10.0)
    with pytest.raises(TypeError, match=r"\(rig, pid, \.\.\.\) takes the Rig first and the controller second"):
        call(rig, pid, ms)


def test_the_argument_check_accepts_any_controller() -> None:
    from amb_fast._validate import rig_and_controller

    notch = af.notch(700.0)
    for controller in (af.PID.paper(), af.PID.paper().to_controller(), notch):
        rig_and_controller(af.Rig(), controller, "f")
    with pytest.raises(TypeError, match="got them swapped \\(Controller, Rig\\)"):
        rig_and_controller(notch, af.Rig(), "f")
    with pytest.raises(TypeError, match="pid must be an amb_fast.PID or Controller, got str"):
        rig_and_controller(af.Rig(), "pid", "f")


def test_touchdown_of_the_nonlinear_law_stays_an_error() -> None:
    rig = replace(af.Rig.paper(), force_law="nonlinear")
    with pytest.raises(af.TouchdownError, match="touchdown"):
        af.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(rms=50.0))
