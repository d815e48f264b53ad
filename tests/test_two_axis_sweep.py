"""Two-axis sweeps: a point that fails for another reason than instability ends the call and its threads."""

from __future__ import annotations

import threading

import pytest

import amb_fast as af
from amb_fast.two_axis import _sweep


def test_a_failing_point_raises_and_leaves_no_threads_behind(monkeypatch) -> None:
    calls = []

    def failing(model, seed, **options):  # noqa: ANN001, ANN003, ANN202
        calls.append(seed)
        raise ValueError("disk full")

    monkeypatch.setattr(_sweep, "_point", failing)
    before = threading.active_count()
    sphs = af.schroeder_multisine(f0=1.0, f_max=20.0)
    with pytest.raises(ValueError, match="disk full"):
        _sweep.sweep(af.TwoAxisRig.paper(), af.PID.paper(), sphs, workers=2, kxy=[0.0, 1e3, 2e3, 3e3])
    assert calls
    assert threading.active_count() == before
