"""Short reprs of the records (shapes and a summary, not thousands of numbers) and ``dir(amb_fast)`` with the
names loaded on first use (issue 25, case 15)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import amb_fast as af
import amb_fast.two_axis as ta
from amb_fast._equality import ArrayRecord

SPHS = af.schroeder_multisine()


@pytest.fixture(scope="module")
def estimate() -> af.Estimate:
    return af.run_experiment(af.Rig.paper(), af.PID.paper(), SPHS, periods=2, seed=1)


def test_an_estimate_shows_its_lines_band_and_shapes(estimate) -> None:
    text = repr(estimate)
    assert len(text) < 1000  # a dataclass's own repr: ~60,000 characters
    assert text.startswith("Estimate(lines=200, 1-200 Hz, freq: (200,) Hz, H: (200,) complex128 N/m,")
    assert "k: (200,) N/m, c: (200,) N s/m" in text and "periods=2, blocks=2" in text
    assert "unexcited: UnexcitedLines(" in text and "meta: {source, rig, controller" in text


def test_a_sweep_shows_its_grid_axes_and_status() -> None:
    result = af.sweep(af.Rig.paper(), af.PID.paper(), SPHS, kp=[2000.0, 2400.0], kd=[0.0, 2.0, 3.0], periods=2,
                      seed=1, progress=False)  # fmt: skip
    text = repr(result)
    assert len(text) < 1000
    assert text.startswith("SweepResult(points=6 (product 2 x 3), kp: [2000, 2400] A/m, kd: [0, 2, 3] A s/m, ok=4, "
                           "unstable=2, lines=200, 1-200 Hz,")  # fmt: skip
    assert "k: (6, 200) N/m" in text and "H: (6, 200) complex128 N/m" in text


def test_a_design_shows_its_parameters() -> None:
    freq = np.linspace(20.0, 100.0, 9)
    design = af.design_controller(af.Rig.paper(), af.PID.paper(), freq=freq, stiffness=6e4, damping=150.0)
    text = repr(design)
    # Design keeps its own summary (a record with its own __repr__ keeps it): the parameters, the misses of
    # the targets set, the peak sensitivity.
    kp, kd = design.params["kp"], design.params["kd"]
    assert len(text) < 1000 and f"kp={kp:.6g}, kd={kd:.6g}" in text and "peak |S|" in text
    assert "stiffness misses by" in text and "nan" not in text


def test_every_record_is_short() -> None:
    est2 = ta.run_experiment(ta.TwoAxisRig.paper(), af.PID.paper(), SPHS, periods=2, seed=1)
    trace = af.simulate(af.Rig.paper(), af.PID.paper(), SPHS.samples)
    for record in (est2, trace, SPHS):
        text = repr(record)
        assert len(text) < 1000 and text.startswith(type(record).__name__ + "("), text
    assert "k: (200, 2, 2) N/m" in repr(est2)


def test_a_record_with_its_own_repr_keeps_it() -> None:
    @dataclass(frozen=True, eq=False)
    class Own(ArrayRecord):
        x: np.ndarray

        def __repr__(self) -> str:
            return "own"

    @dataclass(frozen=True, eq=False)
    class Plain(ArrayRecord):
        x: np.ndarray
        n: int = 3

    assert repr(Own(np.zeros(5))) == "own"
    assert repr(Plain(np.zeros((5, 2)))) == "Plain(x: (5, 2), n=3)"
    assert repr(Plain(np.array([1.0, 2.5]))) == "Plain(x: [1. , 2.5], n=3)"


def test_dir_lists_the_names_loaded_on_first_use() -> None:
    names = dir(af)
    for name in ("plot_family", "plot_estimate", "design_controller", "fit_rig", "Design", "RigFit", "sweep"):
        assert name in names
    assert names == sorted(names)
