"""Sweeps of N axes: :func:`run_experiment` over a grid of points named by parameter paths.

A path names what a point changes: ``speed`` (the rotor's spin, rad/s), ``rotor.<field>`` (a field of the
:class:`RigidRotor`: ``mass``, ``polar_inertia``, ...), ``<Rig field>`` on every axis' chain or
``<axis>.<Rig field>`` on one (``A.x.amp_bandwidth``), and ``kp``, ``ki``, ``kd``, ``derivative_cutoff``
on every diagonal PID of the controller matrix.
"""

from __future__ import annotations

import os
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import dataclass, fields, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._blas import blas_parked
from .._equality import ArrayRecord
from .._errors import UnstableLoopError
from .._excitation import Multisine
from .._params import PID, Rig
from .._sweep import _grid, _progress_bar, point_seeds
from .._validate import integer, require, seed_value
from . import _results
from ._control import ControllerMatrix, ControllerSpec, controller_matrix
from ._experiment import EstimateN, run_experiment
from ._rotor import RotorRig

_AXIS_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps", "mass"))
_ROTOR_FIELDS = ("mass", "transverse_inertia", "polar_inertia", "speed")
_GAINS = ("kp", "ki", "kd", "derivative_cutoff")


@dataclass(frozen=True, eq=False)
class SweepResultN(ArrayRecord):
    """Estimates of N axes over a grid of points; matrices (points, lines, N, N), in grid order (for
    ``grid="product"`` the last name varies fastest).

    Attributes
    ----------
    params : dict of str to ndarray
        Each swept path's value per point, in its unit (``speed`` rad/s, ``kp`` A/m, ...).
    freq : ndarray
        Lines, Hz.
    k, c, k_std, c_std : ndarray
        Actual stiffness (N/m), damping (N s/m) and their standard errors; NaN at unstable points.
    receptance : ndarray
        ``Y F^-1``, complex, m/N; NaN at unstable points.
    stable : ndarray
        Per point, bool (unstable points are not run).
    seeds : ndarray
        Per point, uint64: ``run_experiment(*point_model(rig, controller, point), excitation,
        seed=int(seeds[i]))`` reproduces point i bit for bit.
    axes : tuple of str
        The axes' names.
    """

    params: dict[str, np.ndarray]
    freq: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    receptance: np.ndarray
    stable: np.ndarray
    seeds: np.ndarray
    axes: tuple[str, ...]

    save = _results.save_sweep  # .nc or .npz, checksummed; SweepResultN.load reads it back
    load = staticmethod(_results.load_sweep)
    status = property(_results.sweep_status)
    to_xarray = _results.sweep_to_xarray
    to_dataframe = _results.sweep_to_dataframe


def point_model(rig: RotorRig, controller: ControllerSpec, values: dict[str, float]) -> tuple[RotorRig, Any]:
    """The rig and controller of one point (the paths: see the module's docstring)."""
    names = rig.mechanics().names
    spec = controller_matrix(controller, len(names))
    rotor_changes: dict[str, Any] = {}
    swept = tuple(f for f in _ROTOR_FIELDS if f in {f.name for f in fields(rig.rotor)})  # type: ignore[arg-type]
    axis_changes: list[dict[str, Any]] = [{} for _ in names]
    gains: dict[str, float] = {}
    for path, value in values.items():
        head, _, field = path.rpartition(".")
        if path == "speed" or (head == "rotor" and field in swept):
            rotor_changes["speed" if path == "speed" else field] = value
        elif not head and path in _AXIS_FIELDS:
            for changes in axis_changes:
                changes[path] = value
        elif head in names and field in _AXIS_FIELDS:
            axis_changes[names.index(head)][field] = value
        elif not head and path in _GAINS:
            gains[path] = value
        else:
            require(False, "sweep axis", path, f"speed, rotor.<{'|'.join(swept)}>, a Rig field (every axis) "
                    f"or <axis>.<Rig field> with an axis of {names}, or a PID gain ({', '.join(_GAINS)})")  # fmt: skip
    entries = [list(row) for row in spec.entries]
    if gains:
        diagonal = [entries[i][i] for i in range(len(names))]
        require(all(isinstance(c, PID) for c in diagonal), "sweep axis", next(iter(gains)),
                "a PID gain swept on a controller matrix whose diagonal entries are all PIDs")  # fmt: skip
        for i in range(len(names)):
            entries[i][i] = replace(entries[i][i], **gains)
    axes = tuple(replace(a, **changes) if changes else a for a, changes in zip(rig.axes, axis_changes))
    rotor = replace(rig.rotor, **rotor_changes) if rotor_changes else rig.rotor  # type: ignore[type-var]
    return RotorRig(rotor, axes), ControllerMatrix(tuple(tuple(row) for row in entries), spec.fs)


def sweep(
    rig: RotorRig,
    controller: ControllerSpec,
    excitation: Multisine,
    *,
    grid: Literal["product", "zip"] = "product",
    periods: int = 10,
    settle_periods: int | None = None,
    seed: int | None = None,
    median_window: int = 5,
    start: Literal["steady", "rest"] = "steady",
    workers: int | None = None,
    executor: Executor | None = None,
    progress: bool | None = None,
    **axes: ArrayLike,
) -> SweepResultN:
    """:func:`run_experiment` over a grid of points named by parameter paths, e.g. ``sweep(rig, pid, sphs,
    speed=np.linspace(0, 3000, 7), kd=[8.0, 10.0])`` (paths: see :func:`point_model`; a path with a dot is
    passed as ``**{"A.x.amp_bandwidth": [...]}``). Unstable points are flagged and left NaN. Points run on
    ``executor`` (any :class:`concurrent.futures.Executor`: threads, processes, a dask cluster's
    ``client.get_executor()``), by default on ``workers`` threads (one per core; the core releases the GIL).
    Point i runs with ``seeds[i]``, so it reruns alone bit for bit.
    """
    require(isinstance(rig, RotorRig), "rig", type(rig).__name__, "a RotorRig")
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    require(progress in (None, True, False), "progress", progress, "True, False or None")
    require(bool(axes), "sweep axes", "none", "at least one path with its values (speed=[...], kp=[...], ...)")
    periods = integer("periods", periods, 2)
    threads = integer("workers", workers if workers is not None else (os.cpu_count() or 1), 1)
    _, points = _grid(dict(axes), grid)
    count = next(iter(points.values())).size
    models = [point_model(rig, controller, {n: float(v[i]) for n, v in points.items()}) for i in range(count)]
    seeds = point_seeds(seed_value(seed), count)
    N = len(rig.axes)
    shape = (count, excitation.freq.size, N, N)
    k, c, k_std, c_std = (np.full(shape, np.nan) for _ in range(4))
    receptance = np.full(shape, np.nan, dtype=complex)
    stable = np.zeros(count, dtype=bool)
    options = dict(periods=periods, settle_periods=settle_periods, median_window=median_window, start=start)

    def point(i: int) -> EstimateN | None:
        try:
            return run_experiment(*models[i], excitation, seed=int(seeds[i]), **options)  # type: ignore[arg-type]
        except UnstableLoopError:
            return None

    bar = _progress_bar(progress, count)
    own = executor is None
    with blas_parked():  # points on threads: BLAS on one thread, no idle OpenBLAS worker spinning
        pool = ThreadPoolExecutor(threads) if own else executor
        try:
            for i, est in enumerate(pool.map(point, range(count))):  # type: ignore[union-attr]
                if est is not None:
                    stable[i] = True
                    k[i], c[i], k_std[i], c_std[i], receptance[i] = est.k, est.c, est.k_std, est.c_std, est.receptance
                if bar is not None:
                    bar.update(1)
        finally:
            if own:
                pool.shutdown()  # type: ignore[union-attr]
            if bar is not None:
                bar.close()
    return SweepResultN(points, excitation.freq, k, c, k_std, c_std, receptance, stable, seeds, rig.mechanics().names)
