"""Records holding arrays compare field by field (a dataclass's own == raised on them)."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import two_axis as ta
from amb_fast._equality import equal_values

RIG, PID = af.Rig.paper(), af.PID.paper()
SPHS = af.schroeder_multisine(f0=10.0, f_max=100.0)


def records() -> dict[str, object]:
    two = ta.TwoAxisRig.paper()
    return {
        "Estimate": af.run_experiment(RIG, PID, SPHS, seed=1),
        "Trace": af.simulate(RIG, PID, np.zeros(50), seed=1),
        # an unstable point: NaN rows, equal to themselves in a copy
        "SweepResult": af.sweep(RIG, PID, SPHS, kp=[2400.0, -1e5], seed=1, progress=False),
        "Multisine": SPHS,
        "Estimate2": ta.run_experiment(two, PID, SPHS, seed=1),
        "Trace2": ta.simulate(two, PID, np.zeros((50, 2)), seed=1),
        "SweepResult2": ta.sweep(two, PID, SPHS, kxy=[0.0, 1e3], seed=1, progress=False),
    }


@pytest.mark.parametrize("name", list(records()))
def test_a_record_equals_its_copy_and_not_a_changed_one(name: str) -> None:
    record = records()[name]
    assert record == copy.deepcopy(record)
    assert not (record != copy.deepcopy(record))
    assert record != "something else"
    # change one element of the first float array field: no longer equal
    field, value = next((f, v) for f, v in vars(record).items() if isinstance(v, np.ndarray) and v.dtype.kind in "fc")
    changed = value.copy()
    changed.flat[0] = changed.flat[0] + 1.0 if np.isfinite(changed.flat[0]) else 0.0
    assert record != replace(record, **{field: changed})  # type: ignore[type-var]
    with pytest.raises(TypeError):
        hash(record)


def test_the_same_seed_gives_an_equal_estimate_and_another_seed_does_not() -> None:
    assert af.run_experiment(RIG, PID, SPHS, seed=3) == af.run_experiment(RIG, PID, SPHS, seed=3)
    assert af.run_experiment(RIG, PID, SPHS, seed=3) != af.run_experiment(RIG, PID, SPHS, seed=4)


def test_fields_declared_not_compared_are_not_compared() -> None:
    """``meta`` (what produced the record) is ``field(compare=False)`` on estimates and traces, as before."""
    estimate = af.run_experiment(RIG, PID, SPHS, seed=3)
    assert replace(estimate, meta={"note": "another run"}) == estimate
    trace = af.simulate(RIG, PID, np.zeros(50), seed=1)
    assert replace(trace, meta={"note": "another run"}) == trace


def test_equal_values() -> None:
    nan = np.array([1.0, np.nan])
    assert equal_values(nan, nan.copy())
    assert not equal_values(nan, np.array([1.0, 2.0]))
    assert not equal_values(np.zeros(2), np.zeros((1, 2)))  # same values, not the same shape
    assert equal_values(np.array(["ok", "unstable"]), np.array(["ok", "unstable"]))
    assert not equal_values(np.array(["ok"]), np.array(["unstable"]))
    assert equal_values({"a": nan, "b": [1, (2, 3)]}, {"a": nan.copy(), "b": [1, (2, 3)]})
    assert not equal_values({"a": 1}, {"a": 1, "b": 2})
    assert not equal_values([1, 2], (1, 2))
    assert equal_values(float("nan"), float("nan"))
    assert not equal_values(1.0, 2.0)
