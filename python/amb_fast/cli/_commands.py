"""The sub-commands ``run``, ``sweep``, ``identify`` and ``paper``."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._experiment import Estimate, identify, run_experiment
from .._linear import AnyController, closed_loop_poles, require_stable, stability_margin
from .._params import Rig
from .._sweep import sweep
from .._validate import integer
from ..claims import natural_frequency
from ..io import atomic_path, load_recording
from ..two_axis import run_two_axis
from ._options import (
    ESTIMATE_SUFFIXES,
    FIGURE_SUFFIXES,
    SWEEP_SUFFIXES,
    TWO_AXIS_SUFFIXES,
    UsageError,
    _excitation,
    _model,
    _needs,
    _save_figure,
    _started,
    check_output,
    check_output_dir,
)


def _summary(estimate: Estimate, rig: Rig, pid: AnyController, at: Sequence[float]) -> str:
    margin = stability_margin(rig, pid)
    fn = natural_frequency(estimate.freq, estimate.H)
    peak = int(np.argmax(np.abs(estimate.receptance)))
    lines = [
        f"natural frequency   {fn:.3f} Hz (where Re F/Y = 0)",
        f"peak |Y/F|          {abs(estimate.receptance[peak]):.4g} m/N at {estimate.freq[peak]:g} Hz",
        f"stability margin    peak |S| = {margin.peak:.3f} ({margin.peak_db:.1f} dB) at {margin.frequency:.1f} Hz, "
        f"ISO 14839-3 zone {margin.zone}",
        f"slowest pole        |z| = {np.abs(closed_loop_poles(rig, pid)).max():.6f}",
        f"periods averaged    {estimate.periods}",
        "",
        f"{'f (Hz)':>8} {'k (N/m)':>12} {'+-k (N/m)':>10} {'c (N s/m)':>12} {'+-c (N s/m)':>11} {'|Y/F| (m/N)':>12}",
    ]
    for f in at:
        i = int(np.argmin(np.abs(estimate.freq - f)))
        lines.append(f"{estimate.freq[i]:8g} {estimate.k[i]:12.6g} {estimate.k_std[i]:10.3g} {estimate.c[i]:12.6g} "
                     f"{estimate.c_std[i]:11.3g} {abs(estimate.receptance[i]):12.4g}")  # fmt: skip
    return "\n".join(lines)


def cmd_run(args: argparse.Namespace) -> None:
    if args.save:
        check_output(args.save, "--save", TWO_AXIS_SUFFIXES if args.two_axis else ESTIMATE_SUFFIXES, args.overwrite)
    if args.figure:
        check_output(args.figure, "--figure", FIGURE_SUFFIXES, args.overwrite)
        _needs("matplotlib", "plot", "--figure")
    if args.save and args.figure and args.save.resolve() == args.figure.resolve():
        raise UsageError("--save and --figure must be different files")
    if args.save and args.save.suffix.lower() == ".nc":
        _needs("h5netcdf", "xarray", "--save .nc")
    rig, pid = _model(args)
    excitation = _excitation(args, pid)
    outside = [float(f) for f in args.at if not excitation.freq[0] <= f <= excitation.freq[-1]]
    if outside:
        raise UsageError(f"--at must be within the excited band {excitation.freq[0]:g}-{excitation.freq[-1]:g} Hz, "
                         f"got {outside}")  # fmt: skip
    integer("--periods", args.periods, 2)
    if args.settle_periods is not None:
        integer("--settle-periods", args.settle_periods, 0)
    if args.two_axis:
        _started(args)
        run_two_axis(args, rig, pid, excitation)
        return
    if any(getattr(args, name) for name in ("kxy", "kyx", "cxy", "cyx", "sensor_angle", "cross_kp")):
        raise UsageError("--kxy, --kyx, --cxy, --cyx, --sensor-angle and --cross-kp need --two-axis")
    require_stable(rig, pid)
    _started(args)
    estimate = run_experiment(
        rig, pid, excitation, periods=args.periods, settle_periods=args.settle_periods, seed=args.seed
    )
    print(_summary(estimate, rig, pid, args.at))
    if args.save:
        estimate.save(args.save)
        print(f"wrote {args.save}")
    if args.figure:
        from ..plots import plot_estimate

        _save_figure(plot_estimate(estimate), args.figure, estimate.meta)
        print(f"wrote {args.figure}")


def _sweep_csv(result, out: Path) -> None:  # noqa: ANN001
    """One row per point and line; the metadata (version, rig, controller, seed) in trailing ``#`` lines."""
    from ..io._results import trailer

    names = list(result.points)
    header = ",".join([*names, "status", "freq_Hz", "k_N_per_m", "c_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m",
                       "receptance_abs_m_per_N"])  # fmt: skip
    with atomic_path(out) as target, target.open("w") as handle:
        handle.write(header + "\n")
        for i in range(result.status.size):
            for j, f in enumerate(result.freq):
                row = [*[result.points[n][i] for n in names], result.status[i], f, result.k[i, j], result.c[i, j],
                       result.k_std[i, j], result.c_std[i, j], abs(1 / result.H[i, j])]  # fmt: skip
                handle.write(",".join(str(v) for v in row) + "\n")
        handle.write(trailer(result.meta))


def cmd_sweep(args: argparse.Namespace) -> None:
    out = check_output(Path(args.out), "--out", SWEEP_SUFFIXES, args.overwrite)
    if out.suffix.lower() == ".nc":
        _needs("h5netcdf", "xarray", "--out .nc")
        if args.grid == "zip":  # written through xarray (product grids are written directly)
            _needs("xarray", "xarray", "--out .nc with --grid zip")
    rig, pid = _model(args, gains=False)
    if args.kp is None and args.ki is None and args.kd is None:
        raise UsageError("give at least one of --kp, --ki, --kd (e.g. --kp 2000:3000:11)")
    given = {name: len(getattr(args, name)) for name in ("kp", "ki", "kd") if getattr(args, name) is not None}
    if args.grid == "zip" and len(set(given.values())) > 1:
        raise UsageError(f"--grid zip needs as many values of each gain, got {given}")
    if any(n == 0 for n in given.values()):
        raise UsageError("every gain given needs at least one value")
    if args.workers is not None:
        integer("--workers", args.workers, 1)
    integer("--periods", args.periods, 2)
    excitation = _excitation(args, pid)
    _started(args)
    gains = {name: getattr(args, name) for name in ("kp", "ki", "kd") if getattr(args, name) is not None}
    result = sweep(rig, pid, excitation, **gains, grid=args.grid, periods=args.periods,
                   settle_periods=args.settle_periods, workers=args.workers, seed=args.seed,
                   progress=None if not args.no_progress else False)  # fmt: skip
    counts = {s: int(np.sum(result.status == s)) for s in np.unique(result.status)}
    print(f"{result.status.size} points: " + ", ".join(f"{n} {s}" for s, n in counts.items()))
    if out.suffix.lower() == ".csv":
        _sweep_csv(result, out)
    else:
        result.save(out)
    print(f"wrote {out}")


def _channel(text: str) -> str | int:
    """A channel by name, or by 0-based column index when all digits."""
    return int(text) if text.isdigit() else text


def cmd_identify(args: argparse.Namespace) -> None:
    names = ("estimate.csv", "estimate.png")
    check_output_dir(args.out, "--out", names, args.overwrite)
    integer("--settle-periods", args.settle_periods, 0)
    integer("--median-window", args.median_window, 1)
    for option, value in (("--f0", args.f0), ("--mass", args.mass), ("--f-max", args.f_max), ("--fs", args.fs),
                          ("--clearance", args.clearance)):  # fmt: skip
        if value is not None and not (np.isfinite(value) and value > 0):
            raise UsageError(f"{option} must be a finite number > 0, got {value}")
    _needs("matplotlib", "plot", "identify (it draws estimate.png)")
    if not args.file.is_file():
        raise UsageError(f"path must be an existing file, got {str(args.file)!r}")
    rec = load_recording(args.file, force=_channel(args.force), displacement=_channel(args.displacement), fs=args.fs,
                         recording=args.recording)  # fmt: skip
    _started(args)
    try:
        estimate = identify(rec.force, rec.displacement, fs=rec.fs, f0=args.f0, mass=args.mass, f_max=args.f_max,
                            settle_periods=args.settle_periods, median_window=args.median_window,
                            clearance=args.clearance)  # fmt: skip
    except ValueError as error:  # a refused fs says where it came from (the file's clock, or --fs)
        if "fs" not in str(error):
            raise
        error.args = (f"{error}; {rec.fs_note()}",)
        raise
    print(f"{args.file}: {rec.force.size} samples at {rec.fs:g} Hz, {estimate.periods} periods, "
          f"{estimate.freq.size} lines from {estimate.freq[0]:g} to {estimate.freq[-1]:g} Hz")  # fmt: skip
    if estimate.weak is not None and estimate.weak.any():
        print(f"{int(estimate.weak.sum())} weak lines (force or displacement under 10x the unexcited level)")
    print(f"natural frequency {natural_frequency(estimate.freq, estimate.H):.3f} Hz (where Re F/Y = 0)")
    args.out.mkdir(exist_ok=True)
    estimate.save(args.out / "estimate.csv")
    from ..plots import plot_estimate

    title = f"Identified from {Path(args.file).name}"
    _save_figure(
        plot_estimate(estimate, title=title), args.out / "estimate.png", {**estimate.meta, "file": str(args.file)}
    )
    print(f"wrote {args.out / 'estimate.csv'} and {args.out / 'estimate.png'}")


def cmd_paper(args: argparse.Namespace) -> None:
    from ..paper import output_names, write_paper

    check_output_dir(args.out, "--out", output_names(), args.overwrite)
    _needs("matplotlib", "plot", "paper (it draws the figures)")
    _started(args)
    write_paper(args.out, seed=args.seed, progress=not args.no_progress)
