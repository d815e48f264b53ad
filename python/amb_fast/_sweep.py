"""Gain sweeps: many experiments in one batched C++ call, on threads or any executor."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import fields, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._blas import blas_on_one_thread, blas_parked
from ._dispatch import axes_aware
from ._excitation import Multisine
from ._experiment import _plan, automatic_settle, run_options
from ._linear import AnyController, _gain_arrays, core_controller, is_controller, loop_poles
from ._linear_poles import _closed_loop_stacks, _radius_of_gains
from ._params import PID, Rig
from ._sweep_result import OVERFLOW, STATUS, STATUS_NAMES, SWEPT, SweepResult, sweep_grid
from ._validate import integer, require, rig_and_controller, seed_value
from .io._results import version

RIG_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps"))
Factory = Callable[..., tuple[Rig, AnyController]]


def point_seeds(seed: int, count: int) -> np.ndarray:
    """One 64-bit seed per point from a base seed (splitmix64 of base + index): the same point gets
    the same noise however the sweep is split across workers."""
    z = np.uint64(seed) + (np.arange(1, count + 1, dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15))
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


#: Estimates per core call of a sweep (one axis or two), bytes.
CALL_BYTES = 2**25


def points_per_call(count: int, threads: int, bytes_per_point: int, progress: bool) -> int:
    """Points per core call of a sweep run here: at most ~32 MB of estimates (a grid of several calls is
    copied out of each, so a larger call would hold them twice), or ~20 calls for a progress bar; at least
    32 points a thread."""
    size = min(count, max(32 * threads, CALL_BYTES // bytes_per_point))
    return min(size, max(32 * threads, -(-count // 20))) if progress else size


def controller_params(controller: AnyController) -> dict[str, float]:
    if isinstance(controller, PID):
        return {"kp": controller.kp, "ki": controller.ki, "kd": controller.kd,
                "derivative_cutoff": controller.derivative_cutoff}  # type: ignore[dict-item]  # fmt: skip
    return dict(getattr(controller, "params", {}))


def _check_names(rig: Rig, controller: AnyController, names: list[str]) -> None:
    known = [*RIG_FIELDS, *controller_params(controller)]
    for name in names:
        require(name in known, "sweep axis", name,
                f"a numeric Rig field or a controller parameter: one of {', '.join(known)}")  # fmt: skip


def point_model(
    rig: Rig, controller: AnyController, values: dict[str, float], factory: Factory | None = None
) -> tuple[Rig, AnyController]:
    """The rig and controller of one sweep point: ``factory(**values)``, or ``rig`` and ``controller``
    with the named fields (rig fields first, then controller parameters) replaced."""
    if factory is not None:
        made = factory(**values)
        require(isinstance(made, tuple) and len(made) == 2 and isinstance(made[0], Rig), "factory result",
                made, "a (Rig, controller) pair")  # fmt: skip
        return made
    on_rig = {k: v for k, v in values.items() if k in RIG_FIELDS}
    on_controller = {k: v for k, v in values.items() if k not in RIG_FIELDS}
    if on_rig:
        rig = replace(rig, **on_rig)  # type: ignore[arg-type]
    if on_controller:
        if isinstance(controller, PID):
            controller = replace(controller, **on_controller)  # type: ignore[arg-type]
        else:
            controller = controller.with_params(**on_controller)
    return rig, controller


def _run_chunk(
    values: dict[str, np.ndarray], seeds: np.ndarray, workers: int, rig: Rig | None, controller: AnyController | None,
    factory: Factory | None, excitation: Multisine, periods: int, settle_periods: int | None, window: int, start: str,
) -> dict[str, np.ndarray]:  # fmt: skip
    """The one-axis sweep's chunk for :func:`run_points`: each point's rig and controller, the stability
    check (an unstable point is flagged, never simulated; made here, or by the core's workers where the
    settling time needs no poles), the settling time, then one batched core call for the stable points."""
    n = len(seeds)
    names = list(values)
    in_core: np.ndarray | None = None  # the points' loop matrices, where the core checks their stability
    radius = None  # the points' spectral radii, where checked here
    if factory is None and isinstance(controller, PID) and set(names) <= set(SWEPT):
        # PID gains only: the closed loop is affine in them, so all loop matrices come from four cached
        # ones, and the core's controllers are made from the gain arrays without a PID (or BLAS) per point.
        assert rig is not None
        gains = _gain_arrays(controller, values.get("kp"), values.get("ki"), values.get("kd"))
        rigs: list[Rig] = [rig] * n
        controllers: list[AnyController] = [controller] * n  # what the settling rule reads
        core_controllers = controller._core_controllers(gains)
        stacks = list(_closed_loop_stacks(rig, controller, gains))
        if len(stacks) == 1 and (settle_periods is not None or (start == "steady" and rig.force_law == "linear")):
            # The settling time does not need the poles: the core's workers check stability as they run
            # the points (the same eigenvalues as spectral_radius), instead of this thread before them.
            in_core = np.ascontiguousarray(stacks[0][1])
        else:
            radius = _radius_of_gains(rig, controller, gains, workers)  # spectral_radius's numbers
    else:
        models = [point_model(rig, controller, {k: float(values[k][j]) for k in names}, factory)  # type: ignore[arg-type]
                  for j in range(n)]  # fmt: skip
        radius = np.array([np.max(np.abs(loop_poles(r, c)), initial=0.0) for r, c in models])
        rigs, controllers = [r for r, _ in models], [c for _, c in models]
        core_controllers = [core_controller(c) for c in controllers]
    for c in {id(c): c for c in controllers}.values():
        require(c.fs == excitation.fs, "controller fs", c.fs, f"equal to the excitation's fs ({excitation.fs} Hz)")
    stable = radius < 1.0 if radius is not None else np.ones(n, dtype=bool)  # in the core: flagged there
    if in_core is not None and settle_periods is None:  # one linear rig from the steady start: none
        settle = np.zeros(n, dtype=np.int64)
    elif settle_periods is None:  # the rule of run_experiment, so every point reruns bit for bit
        assert radius is not None
        period = excitation.period_samples
        settle = np.array([automatic_settle(r, c, float(rad), period, start) if ok else 0
                           for r, c, rad, ok in zip(rigs, controllers, radius, stable)], dtype=np.int64)  # fmt: skip
    else:
        settle = np.full(n, settle_periods, dtype=np.int64)
    plan, unexcited = _plan(excitation.harmonics, excitation.period_samples)
    rows = np.flatnonzero(stable)
    if rigs.count(rigs[0]) == n:  # one rig (a gain sweep): made for the core once
        point_rigs = [rigs[0]._to_core()] * rows.size
    else:
        masses = {rigs[j].mass for j in rows}
        require(len(masses) <= 1, "mass", sorted(masses), "the same at every point of a sweep (kg)")
        core_rigs = {id(r): r._to_core() for r in {id(rigs[j]): rigs[j] for j in rows}.values()}  # once per rig
        point_rigs = [core_rigs[id(rigs[j])] for j in rows]
    point_controllers = core_controllers if rows.size == n else [core_controllers[j] for j in rows]

    def core_call(pick: slice):  # noqa: ANN202  # the points rows[pick]
        at = rows[pick]
        return _core.run_sweep(excitation.samples, point_rigs[pick], point_controllers[pick], settle[at], seeds[at],
                               periods, plan, window, workers, start == "steady",
                               None if in_core is None else in_core[at])  # fmt: skip

    # A point that diverged (e.g. under saturation) fails its call: the points run alone, that one flagged.
    parts, failed = run_or_split(core_call, rows.size, (ValueError, OverflowError))
    taken = [(rows[pick], core.take()) for pick, core in parts]  # numpy arrays that own the core's memory
    out: dict[str, np.ndarray] = {"settle_periods": settle}
    if rows.size == n and len(taken) == 1:  # every point in one call: its arrays are the results
        out.update({name: taken[0][1][name] for name in _CORE_FIELDS})
    else:  # NaN rows and "unstable" wherever the core's rows do not land
        lines = len(excitation.harmonics)
        out.update({name: np.full((n, lines), np.nan) for name in _CORE_FIELDS[1:-2]})
        out["H"] = np.full((n, lines), np.nan + 0j)
        out["unexcited_displacement"] = np.full((n, len(unexcited)), np.nan)
        out["status"] = np.full(n, STATUS.index("unstable"), dtype=np.int32)
        for at, arrays in taken:
            for name in _CORE_FIELDS:
                out[name][at] = arrays[name]
        out["status"][rows[failed]] = STATUS_NAMES.index(OVERFLOW)
    for j in rows[out["status"][rows] == STATUS.index("touchdown")]:
        point_rig = rigs[j]  # no clearance to touch on the linear law: the state overflowed
        if point_rig.force_law == "linear" and point_rig.clearance is None:
            out["status"][j] = STATUS_NAMES.index(OVERFLOW)
    return out


def run_or_split(
    call: Callable[[slice], Any], count: int, errors: type[Exception] | tuple[type[Exception], ...]
) -> tuple[list[tuple[slice, Any]], list[int]]:
    """``call`` over all ``count`` points, or where it raises one of ``errors``, over each point alone: the
    parts that ran, ``(points, result)``, and the points that raised alone."""
    if not count:
        return [], []
    try:
        return [(slice(0, count), call(slice(0, count)))], []
    except errors:
        parts, failed = [], []
        for j in range(count):
            try:
                parts.append((slice(j, j + 1), call(slice(j, j + 1))))
            except errors:
                failed.append(j)
        return parts, failed


_STATUS_NAMES = np.array(STATUS_NAMES)
_CORE_FIELDS = ("H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "unexcited_displacement", "status")


def progress_bar(progress: bool | None, total: int):  # noqa: ANN202
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError as error:
        raise ImportError("progress=True needs tqdm: pip install 'amb_fast[progress]'") from error
    return tqdm(total=total, unit="point", desc="sweep")


def run_points(
    run: Callable[..., dict[str, np.ndarray]], fixed: tuple, points: dict[str, np.ndarray], seeds: np.ndarray, *,
    workers: int | None, executor: Executor | None, progress: bool | None, bytes_per_point: int,
    chunk_size: int | None = None, here: bool = True,
) -> dict[str, np.ndarray]:  # fmt: skip
    """The one sweep driver: a grid's points in chunks, with a progress bar; the chunks' per-point arrays
    in grid order. ``run(values, seeds, core_threads, *fixed)`` runs one chunk (a module-level function
    of picklable arguments, so any executor takes it: threads, processes, dask).

    Without an ``executor``, chunks of :func:`points_per_call` points run here one after another, each on
    ``workers`` core threads (``here``), or chunks of one point on a pool of ``workers`` threads (not
    ``here``). With one, equal chunks (a multiple of ``workers`` of them, up to eight each, of at least
    32 points where there are enough), each with ``workers`` core threads (default one)."""
    n = seeds.size
    threads = integer("workers", workers if workers is not None else (os.cpu_count() or 1), 1)
    require(executor is None or callable(getattr(executor, "submit", None)), "executor", executor,
            "a concurrent.futures.Executor (with submit)")  # fmt: skip
    require(progress in (None, True, False), "progress", progress, "True, False or None")
    size = integer("chunk_size", chunk_size, 1) if chunk_size is not None else 0
    bar = progress_bar(progress, n)
    pool = ThreadPoolExecutor(threads) if executor is None and not here else None
    if not size and pool is not None:
        size = 1
    elif not size and executor is None:
        size = points_per_call(n, threads, bytes_per_point, bar is not None)
    elif not size:
        count = min(8 * threads, max(1, -(-n // 32)))
        size = -(-n // (-(-count // threads) * threads))
    chunks = [slice(i, min(i + size, n)) for i in range(0, n, size)]  # contiguous: views, not copies
    results: dict[str, np.ndarray] = {}

    def chunk(rows: slice, core_threads: int) -> tuple:  # the arguments of one chunk's run
        return ({name: values[rows] for name, values in points.items()}, seeds[rows], core_threads, *fixed)

    def collect(rows: slice, part: dict[str, np.ndarray]) -> None:
        if rows.stop - rows.start == n:  # the one chunk: its arrays (made for it, not shared) are the results
            results.update(part)
        else:
            for name, values in part.items():
                if name not in results:
                    results[name] = np.empty((n, *values.shape[1:]), dtype=values.dtype)
                results[name][rows] = values
        if bar is not None:
            bar.update(rows.stop - rows.start)

    # BLAS on one thread (points made one by one make thousands of small matrix operations); here, also
    # OpenBLAS's idle workers stopped: after the user's own numpy work they spin for ~0.1 s on the cores
    # the core's threads need (a 40-point sweep: 1.2x from one to two threads instead of 1.75x).
    try:
        with blas_parked() if executor is None else blas_on_one_thread():
            if executor is None and pool is None:
                # One chunk after another, each split across `threads` core threads (no Python threads to
                # start, no GIL between the chunks' points); Ctrl-C reaches the core through this thread.
                for rows in chunks:
                    collect(rows, run(*chunk(rows, threads)))
            else:
                runner: Executor = executor or pool  # type: ignore[assignment]
                core_threads = workers if workers is not None and pool is None else 1
                futures = [runner.submit(run, *chunk(rows, core_threads)) for rows in chunks]
                for rows, future in zip(chunks, futures):
                    collect(rows, future.result())
    finally:
        if bar is not None:
            bar.close()
        if pool is not None:
            pool.shutdown()
    return results


@axes_aware
def sweep(
    rig: Rig | Factory,
    controller: AnyController | Multisine,
    excitation: Multisine | None = None,
    *,
    grid: Literal["product", "zip"] = "product",
    periods: int = 10,
    settle_periods: int | None = None,
    workers: int | None = None,
    executor: Executor | None = None,
    progress: bool | None = None,
    seed: int | None = None,
    median_window: int = 5,
    chunk_size: int | None = None,
    start: Literal["steady", "rest"] = "steady",
    **axes: ArrayLike,
) -> SweepResult:
    """Run the experiment of :func:`run_experiment` for many rigs and controllers.

    ``sweep(rig, controller, excitation, kp=[...], amp_bandwidth=[...])``: each keyword names what it
    sweeps: a numeric field of the :class:`Rig` (``kyy``, ``amp_bandwidth``, ``mass_loading``, ...),
    a field of a :class:`PID` (``kp``, ``ki``, ``kd``, ``derivative_cutoff``) or a parameter of a
    :class:`~amb_fast.Controller` (its ``params``: ``kp``, ``notch_freq``, ``low_pass_freq``, ...;
    the names are ``<block>_<parameter>``, see :class:`~amb_fast.Controller`). Everything not swept
    stays as given. ``sweep(factory, excitation, x=[...], y=[...])`` takes any callable
    ``factory(**point) -> (rig, controller)`` instead, for anything else.

    Parameters
    ----------
    rig : Rig, or callable
        The rig every point starts from; or ``factory(**point) -> (rig, controller)``, called for each
        point with its values (then the next argument is the excitation).
    controller : PID or Controller
        The controller every point starts from (with a factory: the :class:`Multisine`).
    excitation : Multisine
        The periodic excitation (N), at the controller's ``fs``.
    grid : {"product", "zip"}
        ``"product"`` crosses the axes (one grid dimension each, the last varying fastest), ``"zip"``
        pairs them (all of one length).
    periods : int
        Periods averaged per point (as in :func:`run_experiment`).
    settle_periods : int, optional
        Periods run before recording, with ``start="rest"`` (default: from the slowest pole, per point).
    workers : int, optional
        Core threads per call (default: all cores here; one per chunk on an ``executor``).
    executor : concurrent.futures.Executor, optional
        Runs the chunks: threads, processes, or a dask cluster's ``client.get_executor()``.
    progress : bool, optional
        A tqdm progress bar (default: when stderr is a terminal).
    seed : int, optional
        Fixes the measurement noise; each point gets its own seed (``SweepResult.seeds``).
    median_window : int
        Odd window (lines) of ``k_smooth``, ``c_smooth``.
    chunk_size : int, optional
        Points per chunk (default: see below).
    start : {"steady", "rest"}
        As in :func:`run_experiment`: from the exact periodic steady state, or from rest.
    **axes : array_like
        The swept values, in each parameter's unit (``kp`` A/m, ``ki`` A/(m s), ``kd`` A s/m, frequencies
        Hz, ``kyy`` N/m, ``mass_loading`` kg, ...).

    Returns
    -------
    SweepResult
        Every point's estimate (``k`` N/m, ``c`` N s/m over ``freq`` Hz) and status, in grid order.

    Notes
    -----
    Points whose linearised loop is unstable are flagged and not simulated; the rest run in a batched
    C++ core, ``workers`` threads per call, with the GIL released: from the steady start of a linear rig
    without limits each point's spectra are drawn (as :func:`run_experiment` does), elsewhere points with
    the same rig and controller shape run side by side in SIMD lanes. Every point equals
    :func:`run_experiment` of that point bit for bit. A sweep of PID gains makes the core's controllers
    from the gain arrays, without a :class:`PID` per point.

    Without an ``executor`` the grid runs here in core calls split across ``workers`` threads: one call
    for up to ~32 MB of estimates (2,300 points of 200 lines), more for larger grids, and about 20 with
    a progress bar (one per update). With one, it is cut into chunks of ``chunk_size``
    points (default: equal chunks, a multiple of the number of workers, up to eight per worker and of at
    least 32 points where there are enough), each run on the executor with ``workers`` core threads
    (default one). ``chunk_size`` sets the calls' size either way. Results come back in grid order.

    See Also
    --------
    SweepResult, run_experiment, load_sweep, amb_fast.two_axis.sweep

    Examples
    --------
    >>> rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine()
    >>> result = af.sweep(rig, pid, sphs, kp=[2000.0, 2400.0, 2800.0], seed=1, progress=False)
    >>> result.status
    array(['ok', 'ok', 'ok'], dtype='<U9')
    >>> one = af.run_experiment(rig, af.PID.paper(), sphs, seed=int(result.seeds[1]))   # kp = 2400
    >>> bool(np.array_equal(one.k, result.k[1]))                                      # bit for bit
    True
    >>> notched = af.sweep(rig, pid.to_controller() * af.notch(700.0), sphs, notch_freq=[500.0, 900.0],
    ...                    seed=1, progress=False)
    >>> notched.points["notch_freq"]
    array([500., 900.])
    """
    options = run_options(periods, settle_periods, median_window, start)
    factory: Factory | None = None
    base_controller: Any
    if callable(rig) and not isinstance(rig, Rig) and not is_controller(rig):
        require(excitation is None, "excitation", excitation, "given once: sweep(factory, excitation, **axes)")
        factory, excitation, base_rig, base_controller = rig, controller, None, None  # type: ignore[assignment]
    else:
        rig_and_controller(rig, controller, "sweep")
        assert isinstance(rig, Rig)
        base_rig, base_controller = rig, controller
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    assert isinstance(excitation, Multisine)
    if base_controller is not None:
        require(excitation.fs == base_controller.fs, "excitation.fs", excitation.fs,
                f"equal to the controller's fs ({base_controller.fs} Hz)")  # fmt: skip
    axes_values, points = sweep_grid(axes, grid)
    if factory is None:
        _check_names(base_rig, base_controller, list(points))  # type: ignore[arg-type]
    base_seed = seed_value(seed)
    seeds = point_seeds(base_seed, len(next(iter(points.values()))))
    fixed = (base_rig, base_controller, factory, excitation, *options.values())
    results = run_points(_run_chunk, fixed, points, seeds, workers=workers, executor=executor, progress=progress,
                         bytes_per_point=72 * excitation.harmonics.size, chunk_size=chunk_size)  # fmt: skip
    described = base_controller.__dict__ if isinstance(base_controller, PID) else repr(factory or base_controller)
    meta = {"rig": None if base_rig is None else base_rig.__dict__, "controller": described, "f0": excitation.f0,
            "fs": excitation.fs, "seed": base_seed, "amb_fast_version": version()}  # fmt: skip
    return SweepResult(
        points=points,
        axes=axes_values,
        grid=grid,
        freq=excitation.freq,
        status=_STATUS_NAMES[results.pop("status")],
        seeds=seeds,
        unexcited_freq=_plan(excitation.harmonics, excitation.period_samples)[1] * excitation.f0,
        periods=options["periods"],
        blocks=options["periods"] // max(1, options["periods"] // 32),
        meta=meta,
        **results,
    )
