"""Two axes as the N = 2 case of :mod:`amb_fast.system`: simulation, the two experiments, the sweep, and
the 2x2 estimate from recordings of a real two-axis rig."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import system
from .._blas import parked_blas
from .._excitation import Multisine, period_samples
from .._experiment import excited_lines
from .._validate import integer, real, require
from ..system import EstimateN, SweepResultN, TraceN, estimate, experiment_forces, hadamard_signs
from ._model import ControllerMatrix, ControllerSpec, _rig
from ._rig import TwoAxisRig, planar_mechanics

#: Force signs of the two experiments (rows: experiment, columns: axis): x gets +s in both, y +s then
#: -s, so the 2x2 force matrix at every line is s [[1, 1], [1, -1]]: invertible.
SIGNS = hadamard_signs(2)

#: The two-axis names of the N-axis results (every array (lines, 2, 2), axes ``("x", "y")``).
Estimate2, Trace2, SweepResult2 = EstimateN, TraceN, SweepResultN


def simulate(rig: TwoAxisRig, controller: ControllerSpec, force: ArrayLike, *, seed: int | None = None) -> TraceN:
    """Run the two-axis closed loop from rest on forces (n, 2) (N, columns x, y) at the controller's ``fs``
    (:func:`amb_fast.system.simulate`).

    ``controller``: one controller for both axes, a pair ``(cx, cy)``, or a 2x2 matrix of them (cross
    feedback; ``None`` for an absent entry). ``seed`` fixes the noise (one stream per probe and transducer).
    """
    return system.simulate(_rig(rig), controller, force, seed=seed)


def run_experiment(rig: TwoAxisRig, controller: ControllerSpec, excitation: Multisine, **options: Any) -> EstimateN:
    """The two-axis SPHS identification: experiment 1 drives both axes with the multisine ``s``, experiment 2
    x with ``s`` and y with ``-s`` (:data:`SIGNS`), then ``H = F Y^-1`` per line
    (:func:`amb_fast.system.run_experiment`; the same options: ``periods``, ``settle_periods``, ``seed``,
    ``median_window``, ``start``). ``k = Re(H + m w^2 R)``, ``c = Im(H + m w^2 R) / w`` in the probes'
    frame (``R``: their rotation; the identity with aligned probes), as the effective coefficients.
    """
    return system.run_experiment(_rig(rig), controller, excitation, **options)


@parked_blas  # as every sweep (system.sweep parks them too; nested, nothing more happens)
def sweep(rig: TwoAxisRig, controller: ControllerSpec, excitation: Multisine, **options: Any) -> SweepResultN:
    """:func:`run_experiment` over a grid of two-axis points (:func:`amb_fast.system.sweep`), e.g.
    ``sweep(rig, pid, sphs, kxy=np.linspace(0, 2e4, 5), kp=[2000, 2400, 2800])``; names: rig fields
    (``kxy``, ``kyx``, ``cxy``, ``cyx``, ``sensor_angle``), ``x_<Rig field>`` / ``y_<Rig field>`` (or
    ``<Rig field>`` on both), ``kp``, ``ki``, ``kd``, ``derivative_cutoff`` on the diagonal PIDs and
    ``cross_<gain>`` on the off-diagonal ones. Point i reruns alone, bit for bit, with
    ``run_experiment(*point_model2(rig, controller, point), excitation, seed=seeds[i])``."""
    return system.sweep(_rig(rig), controller, excitation, **options)


def point_model2(rig: TwoAxisRig, controller: ControllerSpec, values: dict[str, float]) -> tuple[Any, ControllerMatrix]:
    """The rig and controller of one point of :func:`sweep` (:func:`amb_fast.system.point_model`)."""
    return system.point_model(_rig(rig), controller, values)


def excitation_pair(excitation: Multisine) -> np.ndarray:
    """The two experiments' forces, (2, period, 2): x = +s, +s and y = +s, -s (read-only)."""
    return experiment_forces(excitation, 2)


def identify(
    force: ArrayLike,
    displacement: ArrayLike,
    *,
    fs: float,
    f0: float,
    mass: float,
    f_max: float | None = None,
    lines: ArrayLike | None = None,
    settle_periods: int = 0,
    median_window: int = 5,
) -> EstimateN:
    """The 2x2 estimate from two recorded experiments of a real two-axis rig.

    ``force``, ``displacement``: one (n, 2) recording per experiment (N and m; columns x, y), given as a
    pair or an array of shape (2, n, 2). The two experiments' force matrices must be invertible at
    every line (drive them as :func:`run_experiment` does: x = +s, +s; y = +s, -s). ``mass``: the
    rotor's known mass (kg; ``k = m w^2 I + Re H``). Lines as in :func:`amb_fast.identify` (``lines``,
    ``f_max``, else the harmonics the first experiment's x force excites). Trailing samples short of a
    whole period are dropped with a warning.
    """
    F = np.asarray(force, dtype=np.float64)
    Y = np.asarray(displacement, dtype=np.float64)
    require(F.ndim == 3 and F.shape[0] == 2 and F.shape[2] == 2, "force shape", F.shape,
            "(2 experiments, samples, 2 axes)")  # fmt: skip
    require(Y.shape == F.shape, "displacement shape", Y.shape, f"{F.shape} like force")
    fs = real("fs", fs, "Hz", positive=True)
    f0 = real("f0", f0, "Hz", positive=True)
    mass = real("mass", mass, "kg", positive=True)
    window = integer("median_window", median_window, 1)
    require(window % 2 == 1, "median_window", median_window, "odd")
    settle_periods = integer("settle_periods", settle_periods, 0)
    period = period_samples(fs, f0)
    start = settle_periods * period
    n = F.shape[1]
    whole = start + max(0, n - start) // period * period
    P = (whole - start) // period
    require(P >= 2, "periods after settling", P, ">= 2 (standard errors need at least two)")
    if whole < n:
        warnings.warn(f"recordings are not a whole number of periods of {period} samples: dropped the last "
                      f"{n - whole} samples", stacklevel=2)  # fmt: skip
    F = np.ascontiguousarray(F[:, start:whole].transpose(0, 2, 1))  # (experiment, channel, samples)
    Y = np.ascontiguousarray(Y[:, start:whole].transpose(0, 2, 1))
    for name, x in (("force", F), ("displacement", Y)):
        require(bool(np.all(np.isfinite(x))), name, "non-finite samples", "finite")
    harmonics = excited_lines(F[0, 0], period, f0, fs, f_max, lines)

    def spectra(x: np.ndarray) -> np.ndarray:  # every period's lines: (periods, lines, channel, experiment)
        lines = np.fft.rfft(x.reshape(2, 2, P, period), axis=3)[..., harmonics]
        return np.ascontiguousarray(lines.transpose(2, 3, 1, 0))

    return estimate(spectra(F), spectra(Y), harmonics * f0, planar_mechanics(mass), period, window)
