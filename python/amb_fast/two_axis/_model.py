"""The two-axis loop in closed form: the N-axis model (:mod:`amb_fast.system`) of a :class:`TwoAxisRig`.

The functions are the N-axis ones under the one-axis API's names, with 2x2 results; they refuse any rig
but a :class:`TwoAxisRig` (a one-axis :class:`~amb_fast.Rig` is an N-axis system too, of one axis).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from .. import system
from .._linear import StabilityMargin
from .._validate import require
from ..system import ControllerMatrix, ControllerSpec
from ._rig import TwoAxisRig

F = TypeVar("F", bound=Callable[..., Any])


def two_axes(function: F) -> F:
    """``function`` of :mod:`amb_fast.system` for a :class:`TwoAxisRig` (its first argument) only."""

    @functools.wraps(function)
    def wrapper(rig: Any, *args: Any, **kwargs: Any) -> Any:
        require(isinstance(rig, TwoAxisRig), "rig", type(rig).__name__, "a TwoAxisRig")
        return function(rig, *args, **kwargs)

    return wrapper  # type: ignore[return-value]


loop_model = two_axes(system.loop_model)
closed_loop = two_axes(system.closed_loop)
closed_loop_poles = two_axes(system.closed_loop_poles)
predict = two_axes(system.predict)
sensitivity = two_axes(system.sensitivity)
effective_coefficients = two_axes(system.effective_coefficients)


def controller_matrix(controller: ControllerSpec) -> ControllerMatrix:
    """Reads a controller spec (:data:`~amb_fast.system.ControllerSpec`) into a 2x2 :class:`ControllerMatrix`."""
    return system.controller_matrix(controller, 2)


@two_axes
def plant_matrices2(rig: TwoAxisRig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` of the coupled plant; inputs ``(fx, fy, ux, uy)`` (N, N, A, A).

    States: ``x, x'``, then axis x's chain (``x.i``, ``x.i_f``, ``x.ys`` as present), then y's likewise.
    """
    A, B, layout = system.plant(rig)
    return A, B, list(layout.names)


@two_axes
def discrete_plant2(rig: TwoAxisRig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs ``fx, fy, ux, uy``) with each axis' dead time
    (:func:`amb_fast.system.discrete_plant`)."""
    Phi, Gamma, names = system.discrete_plant(rig, float(fs))
    return Phi, Gamma, list(names)


@two_axes
def require_stable(rig: TwoAxisRig, controller: ControllerSpec) -> np.ndarray:
    """The closed-loop poles (read-only), or :class:`UnstableLoopError` naming the unstable ones."""
    return system.require_stable(rig, controller, "the two-axis closed loop")


@dataclass(frozen=True)
class StabilityMargin2(StabilityMargin):
    """Peak sensitivity of the two-axis loop: MIMO (largest singular value) and per axis (ISO 14839-3).

    Attributes
    ----------
    peak, peak_db, frequency, zone, stable
        As :class:`amb_fast.StabilityMargin`, for ``max sigma_max(S)``.
    x, y : StabilityMargin
        Per axis: the peak of the diagonal entry ``|S_ii|`` (the loop of that axis opened with the
        other closed).
    """

    x: StabilityMargin
    y: StabilityMargin


@two_axes
def stability_margin(rig: TwoAxisRig, controller: ControllerSpec, points: int = 20_000) -> StabilityMargin2:
    """Peaks of the sensitivity over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    m = system.stability_margin(rig, controller, points)
    return StabilityMargin2(m.peak, m.peak_db, m.frequency, m.zone, m.stable, *m.axes)
