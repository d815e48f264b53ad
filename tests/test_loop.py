"""The compiled loop against the pure-numpy reference and an independent state-space simulation."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from scipy import signal

import amb_fast as af
from amb_fast import _core, reference
from conftest import ALL_LAGS, GAINS

TOL = 1e-10  # relative to the largest value of each channel

LAG_SETS = [
    {name: ALL_LAGS[name] for name, on in zip(ALL_LAGS, switches) if on}
    for switches in itertools.product([False, True], repeat=3)
]
CONFIGS = list(itertools.product(range(len(LAG_SETS)), [0, 1, 2], [None, 1000.0], [0.0, GAINS["ki"]]))


def relative_error(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(actual - expected)) / np.max(np.abs(expected)))


@pytest.mark.parametrize(("lags", "delay", "cutoff", "ki"), CONFIGS)
def test_core_matches_numpy_reference(lags: int, delay: int, cutoff: float | None, ki: float, rng) -> None:
    rig = af.Rig(**LAG_SETS[lags])
    pid = af.PID(kp=GAINS["kp"], ki=ki, kd=GAINS["kd"], derivative_cutoff=cutoff, delay=delay)
    force = rng.standard_normal(1500)

    trace = af.simulate(rig, pid, force)
    displacement, current = reference.simulate(rig, pid, force)

    assert relative_error(trace.displacement, displacement) < TOL
    assert relative_error(trace.current, current) < TOL
    np.testing.assert_array_equal(trace.force, force)
    # The configuration is a stable loop: the response stays bounded (no quiet growth hidden by the
    # relative measure).
    A, *_ = af.closed_loop(rig, pid)
    assert np.max(np.abs(np.linalg.eigvals(A))) <= 1.0 + 1e-12


def test_core_matches_closed_loop_state_space(lagged_rig, pid, rng) -> None:
    """A third route: the whole loop as one discrete state space, run by scipy.signal.dlsim."""
    force = rng.standard_normal(4000)
    trace = af.simulate(lagged_rig, pid, force)
    _, outputs, _ = signal.dlsim(af.closed_loop(lagged_rig, pid) + (1 / pid.fs,), force)
    assert relative_error(trace.displacement, outputs[:, 0]) < TOL
    assert relative_error(trace.current, outputs[:, 1]) < TOL


def test_static_stiffness_is_exact(pid) -> None:
    """Under a constant force the integral drives the displacement back to exactly zero, and the
    steady current balances the force: Kiy i = f (the magnets' own Kyy y term vanishes with y)."""
    rig = af.Rig()
    trace = af.simulate(rig, pid, np.full(8000, 2.0))
    assert abs(trace.displacement[-1]) < 1e-12
    assert trace.current[-1] == pytest.approx(2.0 / rig.kiy, rel=1e-9)


def test_threads_give_the_serial_result(lagged_rig, pid, rng) -> None:
    """The same loop from two threads at once gives exactly the serial result (GIL released)."""
    from concurrent.futures import ThreadPoolExecutor

    force = rng.standard_normal(50_000)
    serial = af.simulate(lagged_rig, pid, force).displacement
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda _: af.simulate(lagged_rig, pid, force).displacement, range(4)))
    for result in results:
        np.testing.assert_array_equal(result, serial)


def test_unstable_loop_raises_instead_of_returning_inf(lagged_rig) -> None:
    too_soft = af.PID(kp=500.0, ki=0.0, kd=5.0)  # Kiy kp < -Kyy: negative net stiffness
    with pytest.raises(af.UnstableLoopError, match="closed loop is unstable with kp=500.0"):
        af.simulate(lagged_rig, too_soft, np.ones(40_000))  # refused before simulating, like run_experiment
    with pytest.raises(OverflowError, match="non-finite.*unstable.*at sample"):  # the core's own check stays
        _core.simulate(lagged_rig._to_core(), too_soft._to_core(), np.ones(40_000), 0)


@pytest.mark.parametrize("n", [1, 3, 4, 7, 4001])
def test_the_force_transducer_records_the_ac_coupled_force(n) -> None:
    """The recorded force is f - q with q[k+1] = a q[k] + (1 - a) f[k], a = exp(-T/tau) (scipy's lfilter as
    the reference), at lengths that are and are not multiples of the core's four-sample step."""
    rig = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0, force_coupling_tau=0.01)
    force = np.random.default_rng(n).standard_normal(n)
    trace = af.simulate(rig, af.PID.paper(), force)
    a = np.exp(-1.0 / (af.PID.paper().fs * 0.01))
    q = signal.lfilter([0.0, 1.0 - a], [1.0, -a], force)
    np.testing.assert_allclose(trace.force, force - q, rtol=0, atol=1e-13 * np.max(np.abs(force)))
