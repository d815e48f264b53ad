"""The two-axis model shares the one-axis pieces: the dead-time command line, the frequency response and the
message of an unstable loop (same numbers, same words)."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import two_axis as ta
from amb_fast._linear import state_response

QUIET = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)


@pytest.mark.parametrize("dead_x, dead_y", [(0.0, 0.0), (2 / 4000, 0.0), (0.3e-3, 1 / 4000), (0.1e-3, 0.55e-3)])
def test_uncoupled_two_axis_plant_holds_each_one_axis_plant(dead_x: float, dead_y: float) -> None:
    x = replace(QUIET, dead_time=dead_x)
    y = replace(QUIET, amp_bandwidth=2500.0, eddy_bandwidth=None, dead_time=dead_y)
    Phi2, Gamma2, names = ta.discrete_plant2(ta.TwoAxisRig(x=x, y=y), 4000.0)
    for axis, (name, rig) in enumerate((("x", x), ("y", y))):
        Phi, Gamma, states = af._linear.discrete_plant(rig, 4000.0)
        # The N-axis plant names a coordinate's position and velocity "x", "x'"; the chain "x.i", "x.dead1".
        rows = [names.index({"y": name, "v": f"{name}'"}.get(s, f"{name}.{s}")) for s in states]
        # The N-axis plant is the core's (nd_loop), the one-axis plant scipy's expm: equal to rounding, 1e-14 of
        # the largest entry in each entry's row or column (an exact zero may come out as 1e-17).
        one, two = (
            np.hstack([Phi, Gamma]),
            np.hstack([Phi2[np.ix_(rows, rows)], Gamma2[np.ix_(rows, [axis, 2 + axis])]]),
        )
        scale = np.maximum(np.abs(one).max(axis=1, keepdims=True), np.abs(one).max(axis=0, keepdims=True))
        np.testing.assert_array_less(np.abs(two - one), 1e-14 * scale + 1e-300)
        others = np.setdiff1d(np.arange(len(names)), rows)
        assert not np.any(Phi2[np.ix_(rows, others)]) and not np.any(Phi2[np.ix_(others, rows)])


def test_response_frequency_first_is_the_same_numbers() -> None:
    rng = np.random.default_rng(1)
    A, B, C = rng.normal(size=(9, 9)), rng.normal(size=(9, 2)), rng.normal(size=(4, 9))
    z = np.exp(2j * np.pi * rng.uniform(0.0, 0.5, 50))
    stacked = state_response(A, B, C, z, frequency_first=True)
    assert stacked.shape == (50, 4, 2) and stacked.flags.c_contiguous
    np.testing.assert_array_equal(stacked, np.moveaxis(state_response(A, B, C, z), -1, 0))


def test_unstable_messages_of_one_and_two_axes() -> None:
    pid = replace(af.PID.paper(), kp=500.0)
    shown = r"(-?[0-9.e+-]+[+-][0-9.e+-]+j \(\|z\|=[0-9.e+-]+\)(, |$))+"
    with pytest.raises(af.UnstableLoopError) as one:
        af._linear.require_stable(QUIET, pid)
    with pytest.raises(af.UnstableLoopError) as two:
        ta._model.require_stable(ta.TwoAxisRig(x=QUIET, y=QUIET), pid)
    assert re.fullmatch(rf"the closed loop is unstable with kp=500\.0 A/m, ki=20000\.0 A/\(m s\), kd=3\.0 A s/m, "
                        rf"delay=0: pole\(s\) on or outside the unit circle: {shown}", str(one.value))  # fmt: skip
    assert re.fullmatch(rf"the two-axis closed loop is unstable: pole\(s\) on or outside the unit circle: {shown}",
                        str(two.value))  # fmt: skip
    for error in (one.value, two.value):
        assert error.poles.size and np.all(np.abs(error.poles) >= 1.0)


def test_a_cached_loop_model_cannot_be_changed_through_closed_loop() -> None:
    # Before: system.closed_loop handed out the cached LoopModel's arrays writable; writing into A changed
    # every later closed loop, prediction and pole of that (system, controller).
    pid = af.PID.paper()
    for A, B, C, _ in (af.system.closed_loop(QUIET, pid), af.closed_loop(QUIET, pid)):
        for array in (A, B, C):
            with pytest.raises(ValueError, match="read-only"):
                array[0, 0] = 1.0
    np.testing.assert_array_equal(af.system.loop_model(QUIET, pid).M, af.closed_loop(QUIET, pid)[0])
