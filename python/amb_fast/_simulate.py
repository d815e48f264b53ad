"""Time-domain simulation of the closed loop."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._linear import AnyController, core_controller
from ._params import Rig
from ._validate import seed_value, series


@dataclass(frozen=True)
class Trace:
    """Recorded channels of one run, all sampled at ``fs``.

    Attributes
    ----------
    force : ndarray
        Recorded force, N: the force f[k] sent to the shaker plus the transducer noise, if any.
    displacement : ndarray
        Displacement sensor output ys(kT) plus sensor noise, if any, m.
    current : ndarray
        Coil control current at kT, A.
    fs : float
        Sampling frequency, Hz.
    """

    force: np.ndarray
    displacement: np.ndarray
    current: np.ndarray
    fs: float

    @property
    def time(self) -> np.ndarray:
        """Sample instants kT, s."""
        return np.arange(self.force.size) / self.fs

    def save(self, path: str | Path) -> None:
        """Write force and displacement as a recording (``.csv`` or ``.mat``), see :func:`load_recording`."""
        from ._recording import save_recording

        save_recording(path, force=self.force, displacement=self.displacement, fs=self.fs)


def simulate(rig: Rig, controller: AnyController, force: ArrayLike, *, seed: int | None = None) -> Trace:
    """Run the closed loop on a force sequence (N) sampled at the controller's ``fs``, from rest.

    ``controller``: a :class:`PID` or any :class:`~amb_fast.Controller`.

    The force is zero-order held between samples (a DAC). The linear force law is discretised exactly;
    the non-linear one is integrated with RK4, ``rig.substeps`` steps per sample. The GIL is released
    while the core runs. ``seed`` fixes the measurement noise of a rig that has some.

    Raises
    ------
    ValueError
        For bad parameters or a non-finite force sample (named, with its index).
    OverflowError
        If the state stops being finite (an unstable loop) or the platform leaves the air gap.
    """
    force = series("force", force)
    recorded, displacement, current = _core.simulate(rig._to_core(), core_controller(controller), force,
                                                     seed_value(seed))  # fmt: skip
    return Trace(force=recorded, displacement=displacement, current=current, fs=controller.fs)
