"""Property tests: random rigs, gains, excitations and recordings give results or documented errors,
never a crash or a quiet NaN; results do not depend on what should not matter."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import amb_fast as af

DOCUMENTED = (ValueError, af.TouchdownError)  # UnstableLoopError is a ValueError

bandwidths = st.one_of(st.none(), st.floats(500.0, 30_000.0))
rigs = st.builds(
    af.Rig,
    mass=st.floats(0.05, 20.0),
    kyy=st.floats(-2e5, -1e2),
    kiy=st.floats(1.0, 500.0),
    bias_current=st.floats(0.1, 3.0),
    force_law=st.sampled_from(["linear", "nonlinear"]),
    amp_bandwidth=bandwidths,
    eddy_bandwidth=bandwidths,
    sensor_bandwidth=bandwidths,
    sensor_noise=st.sampled_from([0.0, 1e-9, 1e-6]),
    force_noise=st.sampled_from([0.0, 1e-3]),
    mass_loading=st.sampled_from([0.0, 0.05]),
    force_coupling_tau=st.one_of(st.none(), st.floats(0.05, 5.0)),
)
pids = st.builds(
    af.PID,
    kp=st.floats(0.0, 3e4),
    ki=st.floats(0.0, 2e5),
    kd=st.floats(0.0, 30.0),
    derivative_cutoff=st.one_of(st.none(), st.floats(20.0, 1900.0)),
    fs=st.just(4000.0),
    delay=st.integers(0, 2),
)
excitations = st.builds(
    lambda f0, top, rms, lines: af.schroeder_multisine(f0=f0, f_max=f0 * top, rms=rms, lines=lines, seed=1),
    f0=st.sampled_from([10.0, 20.0, 40.0]),
    top=st.integers(1, 40),
    rms=st.floats(1e-3, 50.0),
    lines=st.sampled_from(["all", "odd", "random-odd"]),
)
fast = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def finite(est: af.Estimate) -> bool:
    return all(np.all(np.isfinite(getattr(est, n))) for n in ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth"))


@st.composite
def loops(draw) -> tuple[af.Rig, af.PID]:  # noqa: ANN001
    """A rig and gains that are mostly, not always, a working loop: stiffness 1.05-5x what the
    magnets take away, a damping ratio 0.02-1.5, an integral corner up to 10 Hz; or any gains at all."""
    rig = draw(rigs)
    if draw(st.integers(0, 4)) == 0:
        return rig, draw(pids)
    kp = -rig.kyy / rig.kiy * draw(st.floats(1.05, 5.0))
    k = rig.kiy * kp + rig.kyy
    kd = 2 * draw(st.floats(0.02, 1.5)) * np.sqrt(k * rig.moving_mass) / rig.kiy
    ki = kp * 2 * np.pi * draw(st.floats(0.0, 10.0))
    cutoff = draw(st.one_of(st.none(), st.floats(300.0, 1900.0)))
    return rig, af.PID(kp=kp, ki=ki, kd=kd, derivative_cutoff=cutoff, delay=draw(st.integers(0, 2)))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(loop=loops(), excitation=excitations, seed=st.integers(0, 2**32))
def test_experiments_give_finite_estimates_or_documented_errors(loop, excitation, seed) -> None:
    rig, pid = loop
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            est = af.run_experiment(rig, pid, excitation, periods=3, settle_periods=2, seed=seed)
        except DOCUMENTED as error:
            event(type(error).__name__)
            return
    event("estimate")
    assert finite(est)
    assert all(issubclass(w.category, UserWarning) and "saturated" in str(w.message) for w in caught)
    assert est.saturated == bool(caught)


@fast
@given(
    periods=st.integers(0, 6),
    extra=st.integers(0, 150),
    f0=st.sampled_from([10.0, 20.0, 25.0]),
    settle=st.integers(0, 3),
    bad=st.one_of(st.none(), st.tuples(st.sampled_from([np.nan, np.inf, -np.inf]), st.floats(0.0, 1.0))),
    shorter=st.booleans(),
)
def test_identify_on_arbitrary_recordings(periods, extra, f0, settle, bad, shorter) -> None:
    period = int(4000.0 / f0)
    n = periods * period + extra
    rng = np.random.default_rng(n)
    # An excited force (every line to f_max) and a displacement of noise at a plausible size (m).
    one = af.schroeder_multisine(f0=f0, f_max=100.0).samples
    force, displacement = np.resize(one, n), 1e-6 * rng.standard_normal(n)
    kept = n - (n - settle * period) % period if n >= settle * period else n  # whole periods are used
    if bad is not None and n:
        where = int(bad[1] * (n - 1))
        displacement[where] = bad[0]
        bad = bad if settle * period <= where < kept else None  # outside the averaged periods: unused
    if shorter and n:
        displacement = displacement[:-1]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            est = af.identify(force, displacement, fs=4000.0, f0=f0, mass=1.0, f_max=100.0, settle_periods=settle)
        except ValueError as error:
            assert str(error)  # a reason, always
            return
    assert finite(est)
    assert bad is None and not shorter
    # The displacement is noise: every line is weak, and identify says so.
    assert all("dropped the last" in str(w.message) or w.category is af.WeakLinesWarning for w in caught)


@fast
@given(pid=pids, scale=st.floats(1e-3, 1e3))
def test_scaling_the_excitation_leaves_H_unchanged_on_a_linear_rig(pid, scale) -> None:
    rig = af.Rig(amp_bandwidth=2000.0, sensor_bandwidth=8000.0)
    excitation = af.schroeder_multisine(f0=20.0, f_max=400.0)
    try:
        base = af.run_experiment(rig, pid, excitation, periods=2, settle_periods=2)
    except af.UnstableLoopError:
        return
    scaled = af.run_experiment(rig, pid, replace(excitation, samples=excitation.samples * scale), periods=2,
                               settle_periods=2)  # fmt: skip
    np.testing.assert_allclose(scaled.H, base.H, rtol=1e-9)


@fast
@given(shift=st.integers(0, 4), seed=st.integers(0, 1000))
def test_shifting_a_recording_by_whole_periods_after_settling_changes_nothing(shift, seed) -> None:
    rig = af.Rig(amp_bandwidth=2000.0, sensor_noise=1e-8, force_noise=1e-3)
    pid = af.PID(kp=2400.0, ki=10000.0, kd=3.0)
    excitation = af.schroeder_multisine(f0=20.0, f_max=400.0)
    period = excitation.period_samples
    trace = af.simulate(rig, pid, np.tile(excitation.samples, 12), seed=seed)
    whole = af.identify(trace.force, trace.displacement, fs=4000.0, f0=20.0, mass=0.92, settle_periods=6)
    cut = slice(shift * period, None)
    shifted = af.identify(trace.force[cut], trace.displacement[cut], fs=4000.0, f0=20.0, mass=0.92,
                          settle_periods=6 - shift)  # fmt: skip
    for name in ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth"):
        np.testing.assert_array_equal(getattr(shifted, name), getattr(whole, name))
