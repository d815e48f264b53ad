"""Time-domain simulation of the closed loop."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._params import PID, Rig
from ._validate import series


@dataclass(frozen=True)
class Trace:
    """Recorded channels of one run, all sampled at ``fs``.

    Attributes
    ----------
    force : ndarray
        Excitation force f[k] sent to the shaker, N.
    displacement : ndarray
        Displacement sensor output ys(kT), m.
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


def simulate(rig: Rig, pid: PID, force: ArrayLike) -> Trace:
    """Run the closed loop on a force sequence (N) sampled at ``pid.fs``, from rest.

    The force is zero-order held between samples (a DAC). The linear force law is discretised exactly;
    the non-linear one is integrated with RK4, ``rig.substeps`` steps per sample. The GIL is released
    while the core runs.

    Raises
    ------
    ValueError
        For bad parameters or a non-finite force sample (named, with its index).
    OverflowError
        If the state stops being finite (an unstable loop) or the platform leaves the air gap.
    """
    force = np.array(series("force", force))  # our own copy: the trace must not change with the input
    displacement, current = _core.simulate(rig._to_core(), pid._to_core(), force)
    return Trace(force=force, displacement=displacement, current=current, fs=pid.fs)
