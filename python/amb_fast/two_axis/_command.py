"""The ``run --two-axis`` command: its options, the run, the estimate's table and file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from .._excitation import Multisine, schroeder_multisine
from .._linear import AnyController
from .._params import PID, Rig
from ..io import atomic_write, figure_metadata
from ..plots import plot_coefficients2
from ..system import EstimateN
from ._experiment import run_experiment
from ._model import effective_coefficients, require_stable, stability_margin
from ._rig import TwoAxisRig

#: A text table of every entry of K and C at the lines nearest ``at`` (Hz): :meth:`EstimateN.summary`.
summary2 = EstimateN.summary


def add_two_axis_options(parser: argparse.ArgumentParser) -> None:
    """The options of ``amb-fast run --two-axis`` (the lead adds them to the ``run`` parser)."""
    group = parser.add_argument_group("two axes (with --two-axis)")
    group.add_argument("--two-axis", action="store_true", help="identify the 2x2 K, C of a two-axis rig")
    for name, unit in (("kxy", "N/m"), ("kyx", "N/m"), ("cxy", "N s/m"), ("cyx", "N s/m")):
        group.add_argument(f"--{name}", type=float, default=0.0, help=f"process cross coefficient, {unit}")
    group.add_argument("--sensor-angle", type=float, default=0.0, help="probe rotation, rad")
    group.add_argument("--cross-kp", type=float, default=0.0, help="cross-feedback kp (A/m) on both off-diagonals")


def two_axis_model(args: argparse.Namespace, rig: Rig, pid: AnyController) -> tuple[TwoAxisRig, list[list[Any]]]:
    """The two-axis rig (both axes ``rig``, the process and probe angle of the options) and its 2x2 controller
    (``pid`` on the diagonal, a ``--cross-kp`` PID off it), checked stable: the command calls it before the run,
    so that an unstable loop is a mistake in the options (exit status 2), not a failed run.

    Raises
    ------
    UnstableLoopError
        The two-axis closed loop has poles on or outside the unit circle.
    """
    two = TwoAxisRig(x=rig, y=rig, kxy=args.kxy, kyx=args.kyx, cxy=args.cxy, cyx=args.cyx,
                     sensor_angle=args.sensor_angle)  # fmt: skip
    controller: list[list[Any]] = [[pid, None], [None, pid]]
    if args.cross_kp:
        cross = PID(kp=args.cross_kp, ki=0.0, kd=0.0, fs=pid.fs, delay=pid.delay)
        controller = [[pid, cross], [cross, pid]]
    require_stable(two, controller)
    return two, controller


def run_two_axis(
    args: argparse.Namespace, rig: Rig, pid: AnyController, excitation: Multisine | None = None
) -> EstimateN:
    """``amb-fast run --two-axis``: both axes ``rig`` under ``pid`` (cross feedback ``--cross-kp``), the
    process and probe angle from the options; prints the margins and the 2x2 K and C at ``--at``, and
    writes ``--save`` (:meth:`EstimateN.save`: .csv, .nc or .npz, which :func:`amb_fast.load_estimate` reads
    back) and ``--figure`` (.png, .pdf or .svg) when the run parser has them. Without ``excitation``: the
    1-200 Hz multisine, up to the highest line below ``fs/2`` when that is lower."""
    two, controller = two_axis_model(args, rig, pid)
    sphs = excitation or schroeder_multisine(f0=1.0, f_max=min(200.0, np.ceil(pid.fs / 2) - 1), fs=pid.fs)
    options = {name: getattr(args, name) for name in ("periods", "settle_periods", "seed") if hasattr(args, name)}
    est = run_experiment(two, controller, sphs, **options)
    margin = stability_margin(two, controller)
    print(f"stability margin    largest singular value of S: {margin.peak:.3f} ({margin.peak_db:.1f} dB) at "
          f"{margin.frequency:.1f} Hz, zone {margin.zone}; per axis |S_xx| {margin.x.peak:.3f} (zone {margin.x.zone}), "
          f"|S_yy| {margin.y.peak:.3f} (zone {margin.y.zone})")  # fmt: skip
    print(est.summary(getattr(args, "at", (10.0, 40.0, 100.0, 200.0))))
    if getattr(args, "save", None):
        est.save(args.save)  # the N-axis estimate's own file: amb_fast.load_estimate reads it back
        print(f"wrote {args.save}")
    if getattr(args, "figure", None):
        figure = plot_coefficients2(est, effective=effective_coefficients(two, controller, est.freq))
        kind = Path(args.figure).suffix.lstrip(".").lower()
        meta = {"command": "run --two-axis", "rig": two, "controller": repr(controller), "seed": options.get("seed"),
                "periods": est.periods}  # fmt: skip
        png = figure_metadata(meta) if kind == "png" else None  # what drew it, as the one-axis figure records
        atomic_write(args.figure, lambda p: figure.savefig(p, dpi=120, format=kind, metadata=png))
        print(f"wrote {args.figure}")
    return est


def save_estimate2(est: EstimateN, path: Path) -> None:
    """An estimate of N axes as a wide table for other tools: CSV (one row per line, units in the header:
    ``kxy_N_per_m``, ``cyx_std_Ns_per_m``, ... over the axes' names) or .npz. :func:`amb_fast.load_estimate`
    does not read it back; :meth:`EstimateN.save` writes the files it reads (``amb-fast run --two-axis --save``
    writes those)."""
    columns: dict[str, Any] = {"freq_Hz": est.freq}
    for name, values, unit in (("k", est.k, "N_per_m"), ("c", est.c, "Ns_per_m"), ("k_std", est.k_std, "N_per_m"),
                               ("c_std", est.c_std, "Ns_per_m")):  # fmt: skip
        for i, a in enumerate(est.axes):
            for j, b in enumerate(est.axes):
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
