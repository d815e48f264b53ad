"""Bad input: a ValueError naming the parameter and the value, from Python and again from C++."""

from __future__ import annotations

import math

import numpy as np
import pytest

import amb_fast as af
from amb_fast import _core

BAD_RIGS = [
    ("mass", 0.0),
    ("mass", -1.0),
    ("mass", math.nan),
    ("kyy", 0.0),
    ("kyy", math.inf),
    ("kiy", -47.19),
    ("bias_current", 0.0),
    ("amp_bandwidth", 0.0),
    ("eddy_bandwidth", -5.0),
    ("sensor_bandwidth", math.nan),
    ("substeps", 0),
    ("substeps", 2.5),
    ("force_law", "cubic"),
]
BAD_PIDS = [
    ("kp", math.nan),
    ("ki", math.inf),
    ("kd", "5"),
    ("fs", 0.0),
    ("fs", -4000.0),
    ("derivative_cutoff", 0.0),
    ("delay", -1),
    ("delay", 1.5),
]
CORE_RIG = dict(
    mass=0.92, kyy=-53.3e3, kiy=47.19, bias_current=0.65, force_law=_core.ForceLaw.linear,
    amp_bandwidth=None, eddy_bandwidth=None, sensor_bandwidth=None, substeps=2,
)  # fmt: skip
CORE_PID = dict(kp=2000.0, ki=0.0, kd=5.0, derivative_cutoff=None, fs=4000.0, delay=1)


@pytest.mark.parametrize(("name", "value"), BAD_RIGS)
def test_rig_rejects(name, value) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must be .*got {value!r}"):
        af.Rig(**{name: value})


@pytest.mark.parametrize(("name", "value"), BAD_PIDS)
def test_pid_rejects(name, value) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must be .*got {value!r}"):
        af.PID(**{**CORE_PID, name: value})


def test_nonlinear_law_needs_negative_kyy() -> None:
    with pytest.raises(ValueError, match="kyy must be < 0"):
        af.Rig(kyy=1e3, force_law="nonlinear")


@pytest.mark.parametrize(("name", "value"), [b for b in BAD_RIGS if b[0] != "substeps" and isinstance(b[1], float)])
def test_core_rig_rejects_as_second_line_of_defence(name, value) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must be .*got"):
        _core.Rig(**{**CORE_RIG, name: value})


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [("fs", 0.0, "fs must be"), ("D", math.nan, "controller D must be finite"), ("delay", -1, "delay must be"),
     ("A", np.full((1, 1), np.inf), "controller matrices must be finite"),
     ("A", np.zeros((25, 25)), "controller order must be at most 24")],
)  # fmt: skip
def test_core_controller_rejects_as_second_line_of_defence(name, value, message) -> None:
    fields = dict(A=np.eye(1), B=np.ones(1), C=np.ones(1), D=1.0, fs=4000.0, delay=0)
    with pytest.raises(ValueError, match=rf"^{message}.*got"):
        _core.Controller(**{**fields, name: value})


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_force_is_named_with_its_sample(bad) -> None:
    force = np.zeros(100)
    force[37] = bad
    rig, pid = af.Rig(), af.PID(**CORE_PID)
    with pytest.raises(ValueError, match=r"force must be finite, got .* at sample 37"):
        af.simulate(rig, pid, force)
    with pytest.raises(ValueError, match=r"force must be finite, got .* at sample 37"):
        _core.simulate(rig._to_core(), pid._to_core(), force)


def test_force_must_be_one_dimensional() -> None:
    rig, pid = af.Rig(), af.PID(**CORE_PID)
    with pytest.raises(ValueError, match=r"force shape must be one-dimensional.*got \(10, 2\)"):
        af.simulate(rig, pid, np.zeros((10, 2)))
    with pytest.raises(ValueError, match="force must be one-dimensional"):
        _core.simulate(rig._to_core(), pid._to_core(), np.zeros((10, 2)))
