"""Time-domain simulation of the closed loop."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._dispatch import axes_aware
from ._equality import ArrayRecord
from ._linear import AnyController, core_controller, require_stable
from ._params import Rig
from ._validate import rig_and_controller, seed_value, series


@dataclass(frozen=True, eq=False)
class Channels(ArrayRecord):
    """Recorded channels sampled at ``fs`` (Hz): force (N), displacement (m), current (A); for N axes a column
    per axis (:class:`Trace`, :class:`~amb_fast.system.TraceN`)."""

    force: np.ndarray
    displacement: np.ndarray
    current: np.ndarray
    fs: float

    @cached_property
    def time(self) -> np.ndarray:
        """Sample instants kT, s (computed once, read-only)."""
        t = np.arange(self.force.shape[0]) / self.fs
        t.flags.writeable = False
        return t


@dataclass(frozen=True, eq=False)
class Trace(Channels):
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
    meta : dict
        The rig, the controller and the seed of the run (saved with the recording by :meth:`save`).
    """

    meta: dict = field(default_factory=dict, repr=False, compare=False)

    def save(self, path: str | Path) -> None:
        """Write force and displacement as a recording (``.csv`` or ``.mat``), see :func:`load_recording`."""
        from .io import save_recording

        save_recording(path, force=self.force, displacement=self.displacement, fs=self.fs, meta=self.meta)


@axes_aware
def simulate(rig: Rig, controller: AnyController, force: ArrayLike, *, seed: int | None = None) -> Trace:
    """Run the closed loop on a force sequence (N) sampled at the controller's ``fs``, from rest.

    ``controller``: a :class:`PID` or any :class:`~amb_fast.Controller`.

    The force is zero-order held between samples (a DAC). The linear force law is discretised exactly;
    the non-linear one is integrated with RK4, ``rig.substeps`` steps per sample. The GIL is released
    while the core runs. ``seed`` fixes the measurement noise of a rig that has some.

    Raises
    ------
    UnstableLoopError
        Before simulating, when the linearised loop has a pole on or outside the unit circle (like
        :func:`run_experiment`).
    TouchdownError
        When the platform reaches its clearance (``Rig.clearance``; the air gap with the non-linear law).
    OverflowError
        If the state stops being finite anyway (the message gives the sample and the time).
    ValueError
        For bad parameters or a non-finite force sample (named, with its index).

    Warns (``UserWarning``) when the amplifier clipped the current command (``Rig.current_limit``), and
    when the linear force law carried the platform past the magnets' air gap, where it does not hold.
    """
    rig_and_controller(rig, controller, "simulate")
    force = series("force", force)
    require_stable(rig, controller)
    seed = seed_value(seed)
    recorded, displacement, current = _core.simulate(rig._to_core(), core_controller(controller), force, seed)
    if rig.current_limit is not None and current.size and float(np.max(np.abs(current))) >= rig.current_limit:
        clipped = int(np.count_nonzero(np.abs(current) >= rig.current_limit * (1 - 1e-12)))
        warnings.warn(f"the amplifier saturated: the current reached its limit {rig.current_limit:g} A at {clipped} "
                      "samples, so the loop was not linear there", stacklevel=2)  # fmt: skip
    if rig.force_law == "linear" and rig.clearance is None and displacement.size:
        peak = float(np.max(np.abs(displacement)))
        if peak >= rig.gap:
            warnings.warn(f"the displacement reached {peak:.3g} m, past the air gap {rig.gap:.3g} m of the magnets: "
                          "the linear force law does not hold there (set Rig.clearance, or the non-linear law)",
                          stacklevel=2)  # fmt: skip
    meta = {"source": "simulate", "rig": rig, "controller": controller, "seed": seed}
    return Trace(force=recorded, displacement=displacement, current=current, fs=controller.fs, meta=meta)
