"""Sweeps of N axes: :func:`run_experiment` over a grid of points named by parameter paths.

A path names what a point changes: a number of the rig or of a part of it (``kxy``, ``sensor_angle`` of a
:class:`~amb_fast.TwoAxisRig`; ``rotor.mass``, ``rotor.polar_inertia``, ``speed`` (the rotor's spin,
rad/s) of a :class:`RotorRig`), ``<Rig field>`` on every axis' chain or ``<axis>.<Rig field>`` on one
(``A.x.amp_bandwidth``; ``x.amp_bandwidth`` or ``x_amp_bandwidth`` on two axes), ``kp``, ``ki``, ``kd``,
``derivative_cutoff`` on every diagonal PID of the controller matrix and ``cross_<gain>`` on every
off-diagonal one.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import dataclass, fields, is_dataclass, replace
from numbers import Real
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._blas import parked_blas
from .._equality import ArrayRecord
from .._errors import UnstableLoopError
from .._excitation import Multisine
from .._linear import checked_poles, eigenvalues
from .._params import PID, Rig
from .._sweep import point_seeds, points_per_call, progress_bar, sweep_grid
from .._validate import integer, require, seed_value
from . import _results
from ._control import ControllerMatrix, ControllerSpec, controller_matrix
from ._experiment import (
    coefficients,
    core_args,
    experiment_forces,
    experiment_seeds,
    run_experiment,
    settle_for,
)
from ._model import System, loop_models

_AXIS_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps", "mass"))
_GAINS = ("kp", "ki", "kd", "derivative_cutoff")


@dataclass(frozen=True, eq=False)
class SweepResultN(ArrayRecord):
    """Estimates of N axes over a grid of points; matrices (points, lines, N, N), in grid order (for
    ``grid="product"`` the last name varies fastest).

    Attributes
    ----------
    params : dict of str to ndarray
        Each swept path's value per point, in its unit (``speed`` rad/s, ``kxy`` N/m, ``kp`` A/m, ...).
    freq : ndarray
        Lines, Hz.
    k, c, k_std, c_std : ndarray
        Actual stiffness (N/m), damping (N s/m) and their standard errors; ``k[p, :, i, j]`` is ROSS's
        ``k_ij`` at point p. NaN at unstable points.
    receptance : ndarray
        ``Y F^-1``, complex, m/N; NaN at unstable points.
    stable : ndarray
        Per point, bool (unstable points are not run).
    seeds : ndarray
        Per point, uint64: ``run_experiment(*point_model(rig, controller, point), excitation,
        seed=int(seeds[i]))`` reproduces point i bit for bit.
    axes : tuple of str
        The axes' names.

    Examples
    --------
    >>> rig, pid, sphs = af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine()
    >>> kxy = np.array([0.0, 1e4, 3e4])                                          # N/m
    >>> result = af.two_axis.sweep(rig, pid, sphs, grid="zip", kxy=kxy, kyx=-kxy, seed=1)
    >>> result.k.shape, result.stable                    # the circulatory 3e4 N/m destabilises the loop
    ((3, 200, 2, 2), array([ True,  True, False]))
    >>> bool(np.isnan(result.k[2]).all())
    True
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


def _with(part: Any, path: str, value: float, whole: str, expected: str) -> Any:
    """``part`` with the number at ``path`` (``a.b``: field ``b`` of its field ``a``) set to ``value``."""
    head, _, rest = path.partition(".")
    known = is_dataclass(part) and head in {f.name for f in fields(part)}
    current = getattr(part, head, None) if known else None
    leaf = isinstance(current, Real) and not isinstance(current, bool)
    require(known and (leaf if not rest else is_dataclass(current)), "sweep axis", whole, expected)
    return replace(part, **{head: _with(current, rest, value, whole, expected) if rest else value})


def point_model(rig: System, controller: ControllerSpec, values: dict[str, float]) -> tuple[Any, ControllerMatrix]:
    """The rig and controller of one point (the paths: see the module's docstring)."""
    names = rig.mechanics().names
    N = len(names)
    spec = controller_matrix(controller, N)
    entries = [list(row) for row in spec.entries]
    axis_changes: list[dict[str, Any]] = [{} for _ in names]
    expected = (f"a number of the rig (kxy, rotor.mass, speed, ...), a Rig field (every axis) or <axis>.<Rig field> "
                f"with an axis of {names}, or a PID gain ([cross_]{'|'.join(_GAINS)})")  # fmt: skip
    for path, value in values.items():
        head, _, field = path.rpartition(".")
        for axis in names:  # <axis>_<field>: the two-axis spelling
            if path.startswith(axis + "_") and path[len(axis) + 1 :] in _AXIS_FIELDS:
                head, field = axis, path[len(axis) + 1 :]
        if head in names and field in _AXIS_FIELDS:
            axis_changes[names.index(head)][field] = value
        elif not head and path in _AXIS_FIELDS:
            for changes in axis_changes:
                changes[path] = value
        elif path in _GAINS:
            require(all(isinstance(entries[i][i], PID) for i in range(N)), "sweep axis", path,
                    "a PID gain swept on a controller matrix whose diagonal entries are all PIDs")  # fmt: skip
            for i in range(N):
                entries[i][i] = replace(entries[i][i], **{path: value})
        elif path.startswith("cross_") and path[6:] in _GAINS:  # the off-diagonal PIDs (absent ones stay absent)
            for i, j in np.ndindex(N, N):
                if i != j and isinstance(entries[i][j], PID):
                    entries[i][j] = replace(entries[i][j], **{path[6:]: value})
        else:
            rotor_speed = path == "speed" and hasattr(rig, "rotor")
            rig = _with(rig, "rotor.speed" if rotor_speed else path, value, path, expected)
    if any(axis_changes):
        axes = tuple(replace(a, **changes) if changes else a for a, changes in zip(rig.axes, axis_changes))
        # A rig holds its chains as a tuple ``axes`` (a rotor), one field per axis named as the axis (x, y),
        # or is its own one chain (a Rig).
        if tuple(rig.axes) == (rig,):
            rig = axes[0]
        else:
            given = {"axes": axes} if "axes" in {f.name for f in fields(rig)} else dict(zip(names, axes))  # type: ignore[arg-type]
            rig = replace(rig, **given)  # type: ignore[type-var]
    return rig, ControllerMatrix(tuple(tuple(row) for row in entries), spec.fs)


@parked_blas  # points on threads: BLAS on one thread, no idle OpenBLAS worker spinning
def sweep(
    rig: System,
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
    passed as ``**{"A.x.amp_bandwidth": [...]}``). Unstable points are flagged and left NaN. Point i runs
    with ``seeds[i]``, so it reruns alone bit for bit.

    Points run on ``executor`` (any :class:`concurrent.futures.Executor`: threads, processes, a dask
    cluster's ``client.get_executor()``), each a :func:`run_experiment`, by default on ``workers`` threads
    (one per core). Two axes without an executor run in calls of the compiled core: the points' loops are
    made here and the core's threads claim the points in turn with the GIL released; a call takes up to
    ~32 MB of estimates (about 500 points of 200 lines), so a large grid is never held twice, and ~20
    calls with a progress bar (``progress``: a tqdm bar; default when stderr is a terminal).
    """
    require(callable(getattr(rig, "mechanics", None)), "rig", type(rig).__name__, "a rig of N axes (TwoAxisRig, ...)")
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    require(start in ("steady", "rest"), "start", start, "'steady' or 'rest'")
    require(progress in (None, True, False), "progress", progress, "True, False or None")
    require(bool(axes), "sweep axes", "none", "at least one path with its values (kxy=[...], kp=[...], ...)")
    periods = integer("periods", periods, 2)
    window = integer("median_window", median_window, 1)
    require(window % 2 == 1, "median_window", median_window, "odd")
    if settle_periods is not None:
        settle_periods = integer("settle_periods", settle_periods, 0)
    threads = integer("workers", workers if workers is not None else (os.cpu_count() or 1), 1)
    _, points = sweep_grid(dict(axes), grid)
    count = next(iter(points.values())).size
    seeds = point_seeds(seed_value(seed), count)
    names = rig.mechanics().names
    N = len(names)
    shape = (count, excitation.freq.size, N, N)
    k, c, k_std, c_std = (np.full(shape, np.nan) for _ in range(4))
    receptance = np.full(shape, np.nan, dtype=complex)
    stable = np.zeros(count, dtype=bool)
    options = dict(periods=periods, settle_periods=settle_periods, median_window=window, start=start)

    def model(i: int) -> tuple[Any, ControllerMatrix]:
        return point_model(rig, controller, {n: float(v[i]) for n, v in points.items()})

    def point(i: int) -> tuple[bool, tuple[np.ndarray, ...] | None]:
        """Whether point i is stable, and its (k, c, k_std, c_std, receptance); None where it is unstable or
        its spectra overflowed (a pole within rounding of |z| = 1: stable, its rows stay NaN)."""
        try:
            est = run_experiment(*model(i), excitation, seed=int(seeds[i]), **options)  # type: ignore[arg-type]
        except UnstableLoopError:
            return False, None
        except OverflowError:
            return True, None
        return True, (est.k, est.c, est.k_std, est.c_std, est.receptance)

    def keep(i: int, values: tuple[np.ndarray, ...] | None) -> None:
        stable[i] = True  # its poles are inside the unit circle; None: its spectra overflowed (rows stay NaN)
        if values is not None:
            k[i], c[i], k_std[i], c_std[i], receptance[i] = values

    bar = progress_bar(progress, count)
    try:
        if executor is None and N == 2:  # the core's two-axis sweep: 4 x 80 bytes of estimates a line
            size = points_per_call(count, threads, 320 * excitation.freq.size, bar is not None)
            for first in range(0, count, size):
                rows = np.arange(first, min(first + size, count))
                models = [model(i) for i in rows]
                for j, values in _core_sweep(models, excitation, settle_periods, seeds[rows], start, periods, threads):
                    keep(rows[j], values)
                if bar is not None:
                    bar.update(rows.size)
        else:
            pool = ThreadPoolExecutor(threads) if executor is None else executor
            try:
                for i, (ok, values) in enumerate(pool.map(point, range(count))):
                    if ok:
                        keep(i, values)
                    if bar is not None:
                        bar.update(1)
            finally:
                if executor is None:
                    pool.shutdown()
    finally:
        if bar is not None:
            bar.close()
    return SweepResultN(points, excitation.freq, k, c, k_std, c_std, receptance, stable, seeds, names)


def _core_sweep(
    models: list[tuple[Any, ControllerMatrix]], excitation: Multisine, settle_periods: int | None, seeds: np.ndarray,
    start: str, periods: int, workers: int,
) -> Iterator[tuple[int, tuple[np.ndarray, ...] | None]]:  # fmt: skip
    """Two-axis points in one call of the core on ``workers`` threads: each stable point's index and its
    (k, c, k_std, c_std, receptance) as :func:`run_experiment` makes them, bit for bit (an unstable point
    is not run; None for a point whose spectra overflowed). The loops are assembled here, each once, in one call
    of the core on ``workers`` threads (a call's points outnumber loop_model's cache); their poles come from
    the core in a stack per loop size, the numbers with which run_experiment checks one."""
    loops = loop_models(models, workers)
    poles: list[np.ndarray] = [np.empty(0)] * len(models)
    sizes: dict[int, list[int]] = {}
    for j, loop in enumerate(loops):
        sizes.setdefault(loop.M.shape[0], []).append(j)
    for same in sizes.values():
        for j, values in zip(same, eigenvalues(np.stack([loops[j].M for j in same]), workers)):
            poles[j] = values
    given = []  # (index, rig, core arguments, settle periods, the two experiments' seeds) per stable point
    for j, ((system, spec), seed, loop, p) in enumerate(zip(models, seeds, loops, poles)):
        try:
            checked_poles(p, str)  # run_experiment's stability test
        except UnstableLoopError:
            continue
        require(excitation.fs == spec.fs, "excitation.fs", excitation.fs, f"the controller's fs ({spec.fs} Hz)")
        settle = settle_periods
        if settle is None:
            settle = 0 if start == "steady" else settle_for(system, spec.fs, p, excitation.period_samples)
        given.append((j, system, core_args(loop, system, outputs=2), settle, experiment_seeds(int(seed), 2)))
    if not given:
        return
    freq = excitation.harmonics * excitation.f0  # as run_experiment computes them, to the bit

    def run(part: list) -> tuple[np.ndarray, ...]:
        args: dict[str, Any] = {name: [g[2][name] for g in part] for name in part[0][2]}  # a list per matrix
        return _core.mimo_line_sweep(
            **args, period_forces=experiment_forces(excitation, 2), settle_periods=[g[3] for g in part],
            periods=periods, seeds=np.array([g[4] for g in part], dtype=np.uint64), steady_start=start == "steady",
            bins=excitation.harmonics, workers=workers)  # fmt: skip

    try:
        results = [(given, run(given))]
    except OverflowError:  # a point within rounding of |z| = 1: run them one by one, and flag that one
        results = []
        for g in given:
            try:
                results.append(([g], run([g])))
            except OverflowError:
                yield g[0], None
    for part, (H, receptance, var_re, var_im) in results:
        for at, (j, system, *_) in enumerate(part):
            yield j, (*coefficients(H[at], var_re[at], var_im[at], freq, system.mechanics()), receptance[at])
