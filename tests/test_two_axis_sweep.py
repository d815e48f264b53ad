"""Two-axis sweeps: every point equals run_experiment of that point bit for bit, on any number of threads
and on an executor; a point that fails for another reason than instability ends the call."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
import amb_fast.two_axis as ta
from amb_fast import _sweep as one_axis_sweep
from amb_fast.system import _experiment, _sweep

FIELDS = ("k", "c", "k_std", "c_std", "receptance")


@pytest.mark.parametrize("start", ["steady", "rest"])
def test_every_point_equals_its_own_experiment_on_threads_and_executors(start, monkeypatch) -> None:
    """On one thread and two, in one core call and in several, and on an executor."""
    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=2e3, kyx=-2e3)  # drawn whole, not by axis
    sphs = af.schroeder_multisine(f0=20.0, f_max=200.0)
    settle = 3 if start == "rest" else None
    axes = dict(kxy=np.linspace(0.0, 4e3, 12), kp=[900.0, 2200.0, 2600.0])  # kp = 900 A/m is unstable
    options = dict(periods=3, seed=5, start=start, settle_periods=settle, progress=False)
    results = [ta.sweep(coupled, af.PID.paper(), sphs, workers=w, **options, **axes) for w in (1, 2)]
    monkeypatch.setattr(one_axis_sweep, "CALL_BYTES", 1)  # calls of 32 points a thread: 36 points in two calls
    results.append(ta.sweep(coupled, af.PID.paper(), sphs, workers=1, **options, **axes))
    with ThreadPoolExecutor(2) as pool:
        results.append(ta.sweep(coupled, af.PID.paper(), sphs, executor=pool, **options, **axes))
    first = results[0]
    np.testing.assert_array_equal(first.stable, [False, True, True] * 12)
    for i in range(first.stable.size):
        point = {name: values[i] for name, values in first.params.items()}
        if not first.stable[i]:
            for result in results:
                assert not result.stable[i] and all(np.isnan(getattr(result, name)[i]).all() for name in FIELDS)
            continue
        alone = ta.run_experiment(*ta.point_model2(coupled, af.PID.paper(), point), sphs, periods=3,
                                  seed=int(first.seeds[i]), start=start, settle_periods=settle)  # fmt: skip
        for result in results:
            for name in FIELDS:
                np.testing.assert_array_equal(getattr(result, name)[i], getattr(alone, name), err_msg=f"{name} at {i}")


def test_a_failing_point_raises(monkeypatch) -> None:
    """On the executor's threads and in the core's call: an error that is not instability is not a NaN point."""
    sphs = af.schroeder_multisine(f0=10.0, f_max=50.0)
    real = _experiment.core_args
    calls = []

    def failing(loop, rig, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        calls.append(rig.kxy)
        if rig.kxy == 2e3:
            raise ValueError("disk full")
        return real(loop, rig, *args, **kwargs)

    monkeypatch.setattr(_sweep, "core_args", failing)
    monkeypatch.setattr(_experiment, "core_args", failing)
    with pytest.raises(ValueError, match="disk full"):
        ta.sweep(ta.TwoAxisRig.paper(), af.PID.paper(), sphs, periods=2, kxy=[0.0, 1e3, 2e3, 3e3])
    with ThreadPoolExecutor(2) as pool, pytest.raises(ValueError, match="disk full"):
        ta.sweep(ta.TwoAxisRig.paper(), af.PID.paper(), sphs, periods=2, executor=pool, kxy=[0.0, 1e3, 2e3, 3e3])
    assert 2e3 in calls


def test_progress_bar_when_asked_and_the_one_axis_call_takes_the_same_arguments(capsys) -> None:
    pytest.importorskip("tqdm")
    sphs = af.schroeder_multisine(f0=10.0, f_max=50.0)
    rig = ta.TwoAxisRig.paper()
    result = af.sweep(rig, af.PID.paper(), sphs, periods=2, seed=1, progress=True, kxy=[0.0, 1e3])
    assert "2/2" in capsys.readouterr().err
    quiet = af.sweep(rig, af.PID.paper(), sphs, periods=2, seed=1, progress=False, kxy=[0.0, 1e3])
    assert capsys.readouterr().err == ""
    np.testing.assert_array_equal(result.k, quiet.k)
    with pytest.raises(ValueError, match="progress"):
        ta.sweep(rig, af.PID.paper(), sphs, progress="yes", kxy=[0.0])


def test_points_at_the_stability_boundary_are_classified_as_run_experiment_does() -> None:
    """The sweep takes its points' poles in one stack on the core's threads; run_experiment checks one loop
    with closed_loop_poles. Both are the core's solver (against numpy's LAPACK to 1e-12 of the spectral
    radius), so points within rounding of the boundary fall on the same side in both."""
    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=5e3, kyx=-5e3, sensor_angle=0.05)
    pid = af.PID.paper()

    def radius(kp: float) -> float:
        return float(np.abs(ta.closed_loop_poles(coupled, replace(pid, kp=kp))).max())

    low, high = 500.0, 2400.0  # unstable, stable
    assert radius(low) >= 1.0 > radius(high)
    for _ in range(60):  # bisect to the last digits of kp
        middle = 0.5 * (low + high)
        low, high = (middle, high) if radius(middle) >= 1.0 else (low, middle)
    kp = np.array([low, high, *np.nextafter(low, [0.0, np.inf]), *np.nextafter(high, [0.0, np.inf])])
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    result = ta.sweep(coupled, pid, sphs, kp=kp, periods=2, seed=1, progress=False)
    expected = [radius(k) < 1.0 for k in kp]
    assert True in expected and False in expected
    np.testing.assert_array_equal(result.stable, expected)
    loop = ta.closed_loop(coupled, pid)[0]
    ours, theirs = ta.closed_loop_poles(coupled, pid), np.linalg.eigvals(loop)
    gap = np.abs(theirs[:, None] - ours[None, :]).min(axis=1)
    assert gap.max() <= 1e-12 * np.abs(theirs).max()


def test_each_point_loop_is_built_once() -> None:
    """A core call takes hundreds of points, more than loop_model's cache holds: the sweep hands each
    point's checked loop on instead of asking the cache again (which rebuilt most of them)."""
    from amb_fast import _linear_loop as _model  # where the loop models are cached

    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=2e3, kyx=-2e3)
    kxy = np.linspace(0.0, 4e3, 100) + 0.123  # fresh points
    _model._loop_model.cache_clear()
    real, assembled = af._core.nd_loops, []
    af._core.nd_loops = lambda points, workers: assembled.append(len(points)) or real(points, workers)
    try:
        result = ta.sweep(coupled, af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=100.0), grid="zip",
                          kxy=kxy, kyx=-kxy, periods=2, seed=1, progress=False)  # fmt: skip
    finally:
        af._core.nd_loops = real
    assert result.stable.all()
    assert sum(assembled) == kxy.size  # each point's loop assembled once, in the core's batched calls
    assert _model._loop_model.cache_info().misses == 0  # and not again one by one


def test_a_stable_point_whose_spectra_overflow_is_flagged_not_fatal() -> None:
    """A point within rounding of |z| = 1 (radius 1 - 3e-15) passed the stability test and then its stationary
    state overflowed in the core: the whole batched sweep raised OverflowError and lost every point. Now the
    points run one by one after such a failure, the failing one is stable with NaN rows and status "overflow"."""
    from dataclasses import replace as swap

    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=5e3, kyx=-5e3, sensor_angle=0.05)
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    result = ta.sweep(coupled, af.PID.paper(), sphs, kp=[3000.0, 3500.0], periods=2, seed=1, progress=False)
    assert result.status.tolist() == ["ok", "ok"]
    k = result.k.copy()
    k[1] = np.nan
    assert swap(result, k=k).status.tolist() == ["ok", "overflow"]
    assert swap(result, stable=np.array([True, False])).status.tolist() == ["ok", "unstable"]


def test_the_batch_falls_back_to_single_points_on_overflow(monkeypatch: pytest.MonkeyPatch) -> None:
    from amb_fast import _core

    real, calls = _core.mimo_line_sweep, []

    def failing(**kwargs):  # noqa: ANN003, ANN202 - the core's signature
        calls.append(len(kwargs["seeds"]))
        if len(kwargs["seeds"]) > 1 or len(calls) == 3:  # the batch, then the second point alone
            raise OverflowError("the line spectra became non-finite")
        return real(**kwargs)

    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=5e3, kyx=-5e3)
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    expected = ta.sweep(coupled, af.PID.paper(), sphs, kp=[3000.0, 3500.0], periods=2, seed=1, progress=False)
    monkeypatch.setattr(_core, "mimo_line_sweep", failing)
    result = ta.sweep(coupled, af.PID.paper(), sphs, kp=[3000.0, 3500.0], periods=2, seed=1, progress=False)
    assert calls == [2, 1, 1] and result.status.tolist() == ["ok", "overflow"] and result.stable.all()
    np.testing.assert_array_equal(result.k[0], expected.k[0])
    assert np.isnan(result.k[1]).all()


def test_a_marginal_loop_that_overflows_says_how_close_its_pole_is() -> None:
    """At the stability boundary (|z| = 1 - 3e-15) the stationary state may overflow in the core; the error said
    "the loop is unstable" of a loop whose poles passed the test. It now names the pole's distance."""
    coupled = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=5e3, kyx=-5e3, sensor_angle=0.05)
    pid = af.PID.paper()

    def radius(kp: float) -> float:
        return float(np.abs(ta.closed_loop_poles(coupled, replace(pid, kp=kp))).max())

    low, high = 500.0, 2400.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if radius(middle) >= 1.0 else (low, middle)
    overflowed = 0
    for kp in (high, np.nextafter(high, np.inf)):
        try:
            ta.run_experiment(coupled, replace(pid, kp=kp), af.schroeder_multisine(f0=20.0, f_max=100.0), periods=2)
        except OverflowError as error:
            overflowed += 1
            assert "slowest pole at |z| = 1 - " in str(error) and "within rounding of the unit circle" in str(error)
    if not overflowed:
        pytest.skip("this build's rounding computed the marginal loop's stationary state")


@pytest.mark.parametrize("rig", ["two axes", "rotor"])
def test_a_process_pool_and_chunks_give_the_same_sweep(rig) -> None:
    """Before: the N-axis sweep handed the executor a closure, which a process pool cannot pickle
    ("Can't pickle local object"), and took no chunk_size. Now each chunk is a module-level function of
    picklable arguments (the one-axis sweep's driver), so processes (and dask) run it; same bits."""
    from concurrent.futures import ProcessPoolExecutor

    if rig == "rotor":
        system, controller, axes = (
            af.RotorRig.example(),
            af.RotorRig.example_controller(),
            dict(speed=[0.0, 500.0, 900.0]),
        )
    else:
        system, controller, axes = ta.TwoAxisRig.paper(), af.PID.paper(), dict(kxy=[0.0, 1e3, 2e3], kp=[900.0, 2400.0])
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    options = dict(periods=2, seed=4, progress=False, **axes)
    here = af.sweep(system, controller, sphs, **options)
    assert af.sweep(system, controller, sphs, chunk_size=2, workers=2, **options) == here
    with ProcessPoolExecutor(2) as pool:
        assert af.sweep(system, controller, sphs, executor=pool, chunk_size=2, **options) == here
