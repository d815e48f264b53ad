"""Two axes as the N = 2 case of :mod:`amb_fast.system`: simulation, the two experiments, the sweep, and
the 2x2 estimate from recordings of a real two-axis rig."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import system
from .._excitation import Multisine
from .._validate import real
from ..system import EstimateN, SweepResultN, TraceN, experiment_forces, hadamard_signs
from ._model import two_axes
from ._rig import planar_mechanics

#: Force signs of the two experiments (rows: experiment, columns: axis): x gets +s in both, y +s then
#: -s, so the 2x2 force matrix at every line is s [[1, 1], [1, -1]]: invertible.
SIGNS = hadamard_signs(2)

#: The two-axis names of the N-axis results (every array (lines, 2, 2), axes ``("x", "y")``).
Estimate2, Trace2, SweepResult2 = EstimateN, TraceN, SweepResultN

simulate = two_axes(system.simulate)
run_experiment = two_axes(system.run_experiment)
sweep = two_axes(system.sweep)
point_model2 = two_axes(system.point_model)


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
    """The 2x2 estimate from two recorded experiments of a real two-axis rig
    (:func:`amb_fast.system.identify` of a rotor of ``mass`` on two aligned axes).

    ``force``, ``displacement``: one (n, 2) recording per experiment (N and m; columns x, y), given as a
    pair or an array of shape (2, n, 2). The two experiments' force matrices must be invertible at
    every line (drive them as :func:`run_experiment` does: x = +s, +s; y = +s, -s). ``mass``: the
    rotor's known mass (kg; ``k = m w^2 I + Re H``). Lines as in :func:`amb_fast.identify` (``lines``,
    ``f_max``, else the harmonics the first experiment's x force excites). Trailing samples short of a
    whole period are dropped with a warning; the recordings get :func:`amb_fast.identify`'s checks.
    """
    structure = planar_mechanics(real("mass", mass, "kg", positive=True))
    return system.identify(force, displacement, f0=f0, rig=structure, fs=fs, f_max=f_max, lines=lines,
                           settle_periods=settle_periods, median_window=median_window)  # fmt: skip
