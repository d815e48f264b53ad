"""Sweeps over two-axis rigs and controllers, plots of the 2x2 coefficients, the ``run --two-axis`` command."""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, fields, replace
from functools import partial
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._blas import parked_blas
from .._equality import ArrayRecord
from .._errors import UnstableLoopError
from .._excitation import Multisine, schroeder_multisine
from .._linear import AnyController, _unstable_poles, eigenvalues
from .._params import PID, Rig
from .._sweep import _grid, _progress_bar, point_seeds, points_per_call
from .._validate import integer, require, seed_value
from ..io._atomic import atomic_write
from ..plots import _damping_scale, _pyplot, _tight_layout
from ._experiment import Estimate2, _core_pair, _point_args, _window, coefficients2, run_experiment
from ._model import (
    ControllerMatrix,
    ControllerSpec,
    controller_matrix,
    effective_coefficients,
    loop_model,
    stability_margin,
)
from ._rig import TwoAxisRig

_RIG_FIELDS = ("kxy", "kyx", "cxy", "cyx", "sensor_angle")
_AXIS_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps", "mass"))
_GAINS = ("kp", "ki", "kd", "derivative_cutoff")


@dataclass(frozen=True, eq=False)
class SweepResult2(ArrayRecord):
    """Two-axis estimates over a grid of points, what :func:`sweep` returns; matrices have shape
    (points, lines, 2, 2), in grid order (for ``grid="product"`` the last name varies fastest).

    Attributes
    ----------
    params : dict of str to ndarray
        Each swept name's value per point, in its unit (``kxy``, ``kyx`` N/m; ``cxy``, ``cyx`` N s/m;
        ``sensor_angle`` rad; ``kp`` A/m, ...; see :func:`point_model2`).
    freq : ndarray
        Lines, Hz.
    k, c, k_std, c_std : ndarray
        Stiffness (N/m), damping (N s/m) and their standard errors; ``k[p, :, i, j]`` is ROSS's
        ``k_ij`` at point p. NaN at unstable points.
    receptance : ndarray
        ``Y F^-1``, complex, m/N; NaN at unstable points.
    stable : ndarray
        Per point, bool: whether the loop was stable (unstable points are not run).
    seeds : ndarray
        Per point, uint64: ``run_experiment(*point_model2(rig, controller, point), excitation,
        seed=int(seeds[i]))`` reproduces point i bit for bit.

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


def point_model2(rig: TwoAxisRig, controller: ControllerSpec, values: dict[str, float]) -> tuple[TwoAxisRig, Any]:
    """The rig and controller of one point: ``kxy``, ``kyx``, ``cxy``, ``cyx``, ``sensor_angle`` set on the
    rig; ``x_<field>`` / ``y_<field>`` on that axis' :class:`Rig` (``<field>`` alone: on both); ``kp``,
    ``ki``, ``kd``, ``derivative_cutoff`` on the diagonal PID entries, ``cross_<gain>`` on the off-diagonal
    ones."""
    spec = controller_matrix(controller)
    entries = [list(row) for row in spec.entries]
    changes: dict[str, Any] = {}
    axis_changes: list[dict[str, Any]] = [{}, {}]
    for name, value in values.items():
        if name in _RIG_FIELDS:
            changes[name] = value
        elif name in _AXIS_FIELDS:
            axis_changes[0][name] = axis_changes[1][name] = value
        elif name[:2] in ("x_", "y_") and name[2:] in _AXIS_FIELDS:
            axis_changes["xy".index(name[0])][name[2:]] = value
        else:
            cross = name.startswith("cross_")
            gain = name[6:] if cross else name
            require(gain in _GAINS, "sweep axis", name, "a TwoAxisRig field (kxy, ...), [x_|y_]<Rig field> or "
                    "[cross_]<PID gain>")  # fmt: skip
            for i in range(2):
                for j in range(2):
                    if (i != j) == cross and isinstance(entries[i][j], PID):
                        entries[i][j] = replace(entries[i][j], **{gain: value})
    x = replace(rig.x, **axis_changes[0]) if axis_changes[0] else rig.x
    y = replace(rig.y, **axis_changes[1]) if axis_changes[1] else rig.y
    return replace(rig, x=x, y=y, **changes), ControllerMatrix((tuple(entries[0]), tuple(entries[1])), spec.fs)  # type: ignore[arg-type]


@parked_blas  # BLAS on one thread, OpenBLAS's idle workers stopped (issue 25 case 11)
def sweep(
    rig: TwoAxisRig,
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
) -> SweepResult2:
    """:func:`run_experiment` over a grid of two-axis points (names: see :func:`point_model2`), e.g.
    ``sweep(rig, pid, sphs, kxy=np.linspace(0, 2e4, 5), kp=[2000, 2400, 2800])``. Unstable points are
    flagged and left NaN. Point i runs with ``SweepResult2.seeds[i]``, so it reruns alone bit for bit
    with ``run_experiment(*point_model2(rig, controller, point), excitation, seed=seeds[i])``.

    Without an ``executor`` the points' loops are made here and run in calls of the compiled core on
    ``workers`` threads (``None``: one per core), which claim the points in turn, with the GIL released;
    a call takes up to ~32 MB of estimates (about 500 points of 200 lines) and its points' loops, so a
    large grid is never held twice, and ~20 calls with a progress bar (``progress``: a tqdm bar; default
    when stderr is a terminal). With an ``executor`` (any :class:`concurrent.futures.Executor`: threads,
    processes, a dask cluster), each point is a :func:`run_experiment` on it. ``settle_periods``: as in
    :func:`run_experiment` (from rest; default from the slowest pole, per point).
    """
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    require(start in ("steady", "rest"), "start", start, "'steady' or 'rest'")
    require(progress in (None, True, False), "progress", progress, "True, False or None")
    periods = integer("periods", periods, 2)
    if settle_periods is not None:
        settle_periods = integer("settle_periods", settle_periods, 0)
    _window(median_window)
    threads = integer("workers", workers if workers is not None else (os.cpu_count() or 1), 1)
    _, points = _grid(dict(axes), grid)
    count = next(iter(points.values())).size
    seeds = point_seeds(seed_value(seed), count)
    shape = (count, excitation.freq.size, 2, 2)
    k, c, k_std, c_std = (np.full(shape, np.nan) for _ in range(4))
    receptance = np.full(shape, np.nan, dtype=complex)
    stable = np.zeros(count, dtype=bool)

    def model(i: int) -> tuple[TwoAxisRig, Any]:
        return point_model2(rig, controller, {n: float(v[i]) for n, v in points.items()})

    def keep(i: int, est: Estimate2) -> None:
        stable[i] = True
        k[i], c[i], k_std[i], c_std[i], receptance[i] = est.k, est.c, est.k_std, est.c_std, est.receptance

    bar = _progress_bar(progress, count)
    try:
        if executor is not None:
            run = partial(_point, excitation=excitation, periods=periods, settle_periods=settle_periods,
                          median_window=median_window, start=start)  # fmt: skip
            for i, est in enumerate(executor.map(run, (model(i) for i in range(count)), seeds.tolist())):
                if est is not None:
                    keep(i, est)
                if bar is not None:
                    bar.update(1)
        else:
            # 4 x 80 bytes of estimates per line and point
            size = points_per_call(count, threads, 320 * excitation.freq.size, bar is not None)
            freq = excitation.harmonics * excitation.f0  # as run_experiment computes them, to the bit
            for first in range(0, count, size):
                rows = np.arange(first, min(first + size, count))
                prepared = _prepared([model(i) for i in rows], excitation, settle_periods, seeds[rows], start, threads)
                ran = rows[[p is not None for p in prepared]]
                stable[ran] = True
                given = [p for p in prepared if p is not None]
                if given:
                    args = {name: [a[name] for a, _, _ in given] for name in given[0][0]}  # a list per model matrix
                    H, receptance[ran], var_re, var_im = _core.mimo_line_sweep(
                        **args, period_forces=_core_pair(excitation), settle_periods=[settle for _, settle, _ in given],
                        periods=periods, seeds=np.array([pair for _, _, pair in given], dtype=np.uint64),
                        steady_start=start == "steady", bins=excitation.harmonics, workers=threads)  # fmt: skip
                    k[ran], c[ran], k_std[ran], c_std[ran] = coefficients2(H, var_re, var_im, freq, rig.mass)
                if bar is not None:
                    bar.update(rows.size)
    finally:
        if bar is not None:
            bar.close()
    return SweepResult2(points, excitation.freq, k, c, k_std, c_std, receptance, stable, seeds)


def _prepared(
    models: list[tuple[TwoAxisRig, Any]], excitation: Multisine, settle_periods: int | None, seeds: np.ndarray,
    start: str, workers: int,
) -> list[tuple | None]:  # fmt: skip
    """The points' core arguments (two_axis.run_experiment's), None where a loop is unstable. The loops are
    built here; their poles come from the core on ``workers`` threads, a stack per loop size, the numbers
    with which run_experiment checks a loop."""
    loops = [loop_model(*model) for model in models]
    poles: list[np.ndarray] = [np.empty(0)] * len(models)
    sizes: dict[int, list[int]] = {}
    for j, loop in enumerate(loops):
        sizes.setdefault(loop.M.shape[0], []).append(j)
    for same in sizes.values():
        for j, values in zip(same, eigenvalues(np.stack([loops[j].M for j in same]), workers)):
            poles[j] = values
    stable = [not _unstable_poles(p).size for p in poles]  # require_stable's test
    return [_point_args(*model, excitation, settle_periods, int(seed), start, (loop, p)) if ok else None
            for model, seed, loop, p, ok in zip(models, seeds, loops, poles, stable)]  # fmt: skip


def _point(model: tuple[TwoAxisRig, Any], seed: int, **options: Any) -> Estimate2 | None:
    try:
        return run_experiment(*model, seed=int(seed), **options)
    except UnstableLoopError:
        return None


def plot_coefficients2(estimate: Estimate2, *, smoothed: bool = False, effective: tuple | None = None) -> Any:
    """The four stiffness and four damping coefficients over frequency, in a 2x4 grid of axes.

    Parameters
    ----------
    estimate : Estimate2
        A two-axis estimate (:func:`run_experiment`, :func:`identify`).
    smoothed : bool
        Plot the median-filtered ``k_smooth``, ``c_smooth`` instead of the raw ``k``, ``c``. The bands
        are always +-1.96 standard errors of the raw estimate.
    effective : (K_eff, C_eff), optional
        Effective matrices at ``estimate.freq`` (N/m, N s/m; shape (lines, 2, 2)), as
        :func:`effective_coefficients` returns them: drawn as dashed lines.

    Returns
    -------
    matplotlib.figure.Figure
        Top row ``kxx, kxy, kyx, kyy`` (N/m), bottom row ``cxx, cxy, cyx, cyy`` (N s/m), against
        frequency (Hz). Needs matplotlib (the ``plot`` extra).

    Examples
    --------
    >>> rig = af.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=1e4, kyx=-1e4)
    >>> est = af.two_axis.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(), seed=1)
    >>> fig = af.plot_coefficients2(est, effective=af.two_axis.effective_coefficients(rig, af.PID.paper(), est.freq))
    >>> [ax.get_title() for ax in fig.axes[4:]]
    ['cxx (N s/m)', 'cxy (N s/m)', 'cyx (N s/m)', 'cyy (N s/m)']
    """
    k = estimate.k_smooth if smoothed else estimate.k
    c = estimate.c_smooth if smoothed else estimate.c
    fig, axes = _pyplot().subplots(2, 4, figsize=(14, 6), sharex=True)
    for col, (i, j) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
        label = "xy"[i] + "xy"[j]
        for row, (values, std, unit, name) in enumerate(((k, estimate.k_std, "N/m", "k"),
                                                         (c, estimate.c_std, "N s/m", "c"))):  # fmt: skip
            ax = axes[row, col]
            ax.plot(estimate.freq, values[:, i, j], label="actual")
            ax.fill_between(estimate.freq, values[:, i, j] - 1.96 * std[:, i, j],
                            values[:, i, j] + 1.96 * std[:, i, j], alpha=0.3)  # fmt: skip
            if effective is not None:
                ax.plot(estimate.freq, effective[row][:, i, j], "--", label="effective")
            ax.set_title(f"{name}{label} ({unit})")
            ax.set_xscale("log")  # as every other coefficient figure
            ax.grid(True, which="both", alpha=0.3)
            if row == 1:
                ax.set_xlabel("frequency (Hz)")
                _damping_scale(ax, estimate.freq, [values[:, i, j]])
    axes[0, 0].legend()
    _tight_layout(fig)
    return fig


def add_two_axis_options(parser: argparse.ArgumentParser) -> None:
    """The options of ``amb-fast run --two-axis`` (the lead adds them to the ``run`` parser)."""
    group = parser.add_argument_group("two axes (with --two-axis)")
    group.add_argument("--two-axis", action="store_true", help="identify the 2x2 K, C of a two-axis rig")
    for name, unit in (("kxy", "N/m"), ("kyx", "N/m"), ("cxy", "N s/m"), ("cyx", "N s/m")):
        group.add_argument(f"--{name}", type=float, default=0.0, help=f"process cross coefficient, {unit}")
    group.add_argument("--sensor-angle", type=float, default=0.0, help="probe rotation, rad")
    group.add_argument("--cross-kp", type=float, default=0.0, help="cross-feedback kp (A/m) on both off-diagonals")


def run_two_axis(
    args: argparse.Namespace, rig: Rig, pid: AnyController, excitation: Multisine | None = None
) -> Estimate2:
    """``amb-fast run --two-axis``: both axes ``rig`` under ``pid`` (cross feedback ``--cross-kp``), the
    process and probe angle from the options; prints the margins and the 2x2 K and C at ``--at``, and
    writes ``--save`` (.csv or .npz) and ``--figure`` (.png) when the run parser has them."""
    two = TwoAxisRig(x=rig, y=rig, kxy=args.kxy, kyx=args.kyx, cxy=args.cxy, cyx=args.cyx,
                     sensor_angle=args.sensor_angle)  # fmt: skip
    controller: Sequence[Any] = [[pid, None], [None, pid]]
    if args.cross_kp:
        cross = PID(kp=args.cross_kp, ki=0.0, kd=0.0, fs=pid.fs, delay=pid.delay)
        controller = [[pid, cross], [cross, pid]]
    sphs = excitation or schroeder_multisine(f0=1.0, f_max=200.0, fs=pid.fs)
    options = {name: getattr(args, name) for name in ("periods", "settle_periods", "seed") if hasattr(args, name)}
    est = run_experiment(two, controller, sphs, **options)
    margin = stability_margin(two, controller)
    print(f"stability margin    largest singular value of S: {margin.peak:.3f} ({margin.peak_db:.1f} dB) at "
          f"{margin.frequency:.1f} Hz, zone {margin.zone}; per axis |S_xx| {margin.x.peak:.3f} (zone {margin.x.zone}), "
          f"|S_yy| {margin.y.peak:.3f} (zone {margin.y.zone})")  # fmt: skip
    print(summary2(est, getattr(args, "at", (10.0, 40.0, 100.0, 200.0))))
    if getattr(args, "save", None):
        save_estimate2(est, args.save)
        print(f"wrote {args.save}")
    if getattr(args, "figure", None):
        figure = plot_coefficients2(est, effective=effective_coefficients(two, controller, est.freq))
        atomic_write(args.figure, lambda p: figure.savefig(p, dpi=120, format=Path(args.figure).suffix.lstrip(".")))
        print(f"wrote {args.figure}")
    return est


def save_estimate2(est: Estimate2, path: Path) -> None:
    """A two-axis estimate as CSV (one row per line, units in the header) or .npz."""
    columns: dict[str, Any] = {"freq_Hz": est.freq}
    for name, values, unit in (("k", est.k, "N_per_m"), ("c", est.c, "Ns_per_m"), ("k_std", est.k_std, "N_per_m"),
                               ("c_std", est.c_std, "Ns_per_m")):  # fmt: skip
        for i, a in enumerate("xy"):
            for j, b in enumerate("xy"):
                columns[f"{name.replace('_std', '')}{a}{b}{'_std' if 'std' in name else ''}_{unit}"] = values[:, i, j]
    path = Path(path)
    if path.suffix.lower() == ".csv":
        table = np.column_stack(list(columns.values()))
        atomic_write(path, lambda p: np.savetxt(p, table, delimiter=",", header=",".join(columns), comments="",
                                                fmt="%.10g"))  # fmt: skip
    elif path.suffix.lower() == ".npz":
        atomic_write(path, lambda p: np.savez(p, **columns))
    else:
        raise ValueError(f"save path must end in .csv or .npz, got {str(path)!r}")


def summary2(est: Estimate2, at: Sequence[float] = (10.0, 40.0, 100.0, 200.0)) -> str:
    """A text table of the 2x2 K and C at the lines nearest ``at`` (Hz)."""
    out = [f"{'f (Hz)':>8} " + " ".join(f"{'k' + a + b + ' (N/m)':>14}" for a in "xy" for b in "xy")
           + " " + " ".join(f"{'c' + a + b + ' (Ns/m)':>14}" for a in "xy" for b in "xy")]  # fmt: skip
    for f in at:
        j = int(np.argmin(np.abs(est.freq - f)))
        out.append(f"{est.freq[j]:8.1f} " + " ".join(f"{v:14.6g}" for v in est.k[j].ravel()) + " "
                   + " ".join(f"{v:14.6g}" for v in est.c[j].ravel()))  # fmt: skip
    return "\n".join(out)
