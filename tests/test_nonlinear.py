"""The non-linear force law: linearises to the linear loop, and its integrator converges at order 4."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import reference


def rel(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(actual - expected)) / np.max(np.abs(expected)))


def test_magnet_force_linearises_to_kyy_and_kiy() -> None:
    rig = af.Rig(force_law="nonlinear")
    core = rig._to_core()
    h = 1e-9
    assert core.magnet_force(0.0, 0.0) == 0.0
    assert (core.magnet_force(h, 0) - core.magnet_force(-h, 0)) / (2 * h) == pytest.approx(-rig.kyy, rel=1e-6)
    assert (core.magnet_force(0, h) - core.magnet_force(0, -h)) / (2 * h) == pytest.approx(-rig.kiy, rel=1e-6)
    assert core.magnet_force(1e-4, 0.1) == pytest.approx(reference.magnet_force(rig, 1e-4, 0.1), rel=1e-14)


def test_small_amplitude_agrees_with_linear_and_difference_shrinks(lagged_rig, pid, rng) -> None:
    nonlinear = replace(lagged_rig, force_law="nonlinear")
    force = rng.standard_normal(4000)
    differences = []
    for scale in (0.1, 1.0, 10.0):
        linear = af.simulate(lagged_rig, pid, scale * force).displacement
        differences.append(rel(af.simulate(nonlinear, pid, scale * force).displacement, linear))
    assert differences[0] < 1e-5
    # The pair's force law is odd, so the leading distortion is cubic: relative difference ~ amplitude^2.
    assert differences[1] / differences[0] > 50
    assert differences[2] / differences[1] > 50


def test_integrator_converges_at_fourth_order(lagged_rig, pid, rng) -> None:
    rig = replace(lagged_rig, force_law="nonlinear")
    force = 10 * rng.standard_normal(800)  # about 25 % of the air gap: strongly non-linear
    fine = af.simulate(replace(rig, substeps=64), pid, force).displacement
    errors = [rel(af.simulate(replace(rig, substeps=n), pid, force).displacement, fine) for n in (2, 4, 8)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 3.6) & (orders < 4.4)), orders


def test_converged_core_matches_reference_rk4(lagged_rig, pid, rng) -> None:
    """The core's integrating-factor RK4 and the reference's classical RK4 converge to one solution."""
    rig = replace(lagged_rig, force_law="nonlinear", substeps=64)
    force = 10 * rng.standard_normal(400)
    core = af.simulate(rig, pid, force)
    displacement, current = reference.simulate(rig, pid, force)
    assert rel(core.displacement, displacement) < 1e-9
    assert rel(core.current, current) < 1e-9


def test_reaching_the_air_gap_is_a_touchdown(pid) -> None:
    rig = af.Rig(force_law="nonlinear")
    with pytest.raises(af.TouchdownError, match="touchdown") as info:
        af.simulate(rig, pid, np.full(400, 200.0))  # 200 N: far beyond what the pair can hold
    assert abs(info.value.position) >= rig.gap
    assert 0 < info.value.time < 400 / pid.fs
