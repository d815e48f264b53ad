"""The ``amb-fast`` command (also ``python -m amb_fast``).

SI units on every option: forces in N, displacements in m, gains in A/m (kp), A/(m s) (ki) and
A s/m (kd), bandwidths and frequencies in Hz, masses in kg, time constants in s.

Every expected error is one line on stderr, ``amb-fast: error: ...``, with exit status 2 for a
mistake in the command line or its input files (found before any work starts: options, output
paths, the recording) and 1 for a run that failed (touchdown, overflow, a failed write); a traceback
only with ``--debug``. Warnings are one line each, ``amb-fast: warning: ...``. No output file is
overwritten without ``--overwrite``, and every file is written atomically.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import traceback
import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import NoReturn

import numpy as np

from ._errors import TouchdownError
from ._excitation import schroeder_multisine
from ._experiment import Estimate, identify, run_experiment
from ._linear import AnyController, closed_loop_poles, require_stable, stability_margin
from ._params import PID, Rig
from ._sweep import sweep
from ._validate import integer
from .claims import natural_frequency
from .controllers import load_controller
from .io import atomic_path, load_recording
from .two_axis import add_two_axis_options, run_two_axis

RIG_OPTIONS = {  # option -> (Rig field, unit, help)
    "mass": ("mass", "kg", "known moving mass m of eq. 9"),
    "kyy": ("kyy", "N/m", "position stiffness of the magnet pair (negative)"),
    "kiy": ("kiy", "N/A", "current stiffness"),
    "bias-current": ("bias_current", "A", "bias current of the magnet pair"),
    "amp-bandwidth": ("amp_bandwidth", "Hz", "amplifier current-loop bandwidth, or 'none'"),
    "eddy-bandwidth": ("eddy_bandwidth", "Hz", "eddy-current force lag corner, or 'none'"),
    "sensor-bandwidth": ("sensor_bandwidth", "Hz", "displacement sensor bandwidth, or 'none'"),
    "sensor-noise": ("sensor_noise", "m rms", "displacement sensor noise"),
    "force-noise": ("force_noise", "N rms", "force transducer noise"),
    "mass-loading": ("mass_loading", "kg", "extra mass moving with the platform"),
    "force-coupling-tau": ("force_coupling_tau", "s", "AC-coupling time constant of the force transducer, or 'none'"),
    "dead-time": ("dead_time", "s", "transport delay from the current command to the amplifier (DSP latency)"),
}
PID_OPTIONS = {
    "kp": ("kp", "A/m", "proportional gain"),
    "ki": ("ki", "A/(m s)", "integral gain"),
    "kd": ("kd", "A s/m", "derivative gain"),
    "derivative-cutoff": ("derivative_cutoff", "Hz", "derivative filter corner, or 'none'"),
    "fs": ("fs", "Hz", "sampling frequency"),
}


class UsageError(Exception):
    """A mistake in the command line or its files: reported in one line, without a traceback."""


class _Parser(argparse.ArgumentParser):
    """argparse with its errors in the command's one-line form (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        print(f"amb-fast: error: {message} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)


ESTIMATE_SUFFIXES = (".csv", ".nc")
TWO_AXIS_SUFFIXES = (".csv", ".npz")  # amb-fast run --two-axis --save
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
SWEEP_SUFFIXES = (".nc", ".npz", ".csv")


def check_output(path: Path, option: str, suffixes: Sequence[str], overwrite: bool) -> Path:
    """Refuse an output path before any work: its suffix, its directory, an existing file (without --overwrite)."""
    if path.suffix.lower() not in suffixes:
        raise UsageError(f"{option} must end in {', '.join(suffixes)}, got {str(path)!r}")
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise UsageError(f"{option}: the directory {str(directory)!r} does not exist")
    if path.is_dir():
        raise UsageError(f"{option}: {str(path)!r} is a directory")
    if path.exists() and not overwrite:
        raise UsageError(f"{option}: {str(path)!r} exists; pass --overwrite to replace it")
    return path


def check_output_dir(directory: Path, option: str, names: Sequence[str], overwrite: bool) -> Path:
    """An output folder: it may not exist yet (its parent must); files in it are not overwritten without --overwrite."""
    if directory.exists() and not directory.is_dir():
        raise UsageError(f"{option}: {str(directory)!r} exists and is not a directory")
    parent = directory.parent if str(directory.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"{option}: the directory {str(parent)!r} does not exist")
    existing = [name for name in names if (directory / name).exists()]
    if existing and not overwrite:
        shown = ", ".join(existing[:4]) + (" ..." if len(existing) > 4 else "")
        raise UsageError(f"{option}: {str(directory)!r} already holds {shown}; pass --overwrite to replace them")
    return directory


def _needs(module: str, extra: str, what: str) -> None:
    try:
        __import__(module)
    except ImportError:
        raise UsageError(f"{what} needs {module}: pip install 'amb_fast[{extra}]'") from None


def _started(args: argparse.Namespace) -> None:
    """Every check passed: errors from here on are failed runs (exit status 1)."""
    args.phase = "run"


def _save_figure(fig, path: Path, meta: dict) -> None:  # noqa: ANN001
    """Atomically; a PNG records the version, rig, controller and seed in its text chunks."""
    import matplotlib.pyplot as plt

    from .io._results import figure_metadata

    kind = path.suffix.lstrip(".").lower()
    with atomic_path(path) as target:
        fig.savefig(target, dpi=120, format=kind, metadata=figure_metadata(meta) if kind == "png" else None)
    plt.close(fig)


def _number_or_none(text: str) -> float | None:
    if text.lower() == "none":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or 'none', got {text!r}") from None


def _values(text: str) -> np.ndarray:
    """'1,2,3' or 'start:stop:count' (inclusive, evenly spaced)."""
    try:
        if ":" in text:
            start, stop, count = text.split(":")
            return np.linspace(float(start), float(stop), int(count))
        return np.array([float(v) for v in text.split(",") if v.strip()])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'a,b,c' or 'start:stop:count', got {text!r}") from None


def _add_model_options(parser: argparse.ArgumentParser, gains: bool = True) -> None:
    rig = parser.add_argument_group("rig (defaults: Rig.paper())")
    for option, (_, unit, text) in RIG_OPTIONS.items():
        rig.add_argument(f"--{option}", type=_number_or_none, default=argparse.SUPPRESS, metavar="X",
                         help=f"{text} ({unit})")  # fmt: skip
    rig.add_argument("--force-law", choices=["linear", "nonlinear"], default=argparse.SUPPRESS, help="magnet force law")
    pid = parser.add_argument_group("controller (defaults: PID.paper())")
    for option, (_, unit, text) in PID_OPTIONS.items():
        if gains or option not in ("kp", "ki", "kd"):
            pid.add_argument(f"--{option}", type=_number_or_none, default=argparse.SUPPRESS, metavar="X",
                             help=f"{text} ({unit})")  # fmt: skip
    pid.add_argument("--delay", type=int, default=argparse.SUPPRESS, help="computation delay (whole samples)")
    text = ("any digital controller from a TOML or JSON file (PID, notch, low-pass, lead-lag, second-order, "
            "transfer-function blocks in series; docs/controllers.md) instead of the PID")  # fmt: skip
    pid.add_argument("--controller", type=Path, metavar="FILE", help=text)
    ex = parser.add_argument_group("excitation and experiment")
    ex.add_argument("--f0", type=float, default=1.0, help="fundamental of the SPHS (Hz; default 1)")
    ex.add_argument("--f-max", type=float, default=200.0, help="highest line (Hz; default 200)")
    ex.add_argument("--rms", type=float, default=1.0, help="excitation rms (N; default 1)")
    ex.add_argument("--lines", choices=["all", "odd", "random-odd"], default="all", help="which harmonics to excite")
    ex.add_argument("--periods", type=int, default=10, help="periods averaged (default 10)")
    ex.add_argument("--settle-periods", type=int, help="periods before recording (default: from the slowest pole)")
    ex.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")


def _model(args: argparse.Namespace, *, gains: bool = True) -> tuple[Rig, AnyController]:
    """The paper's rig and controller with the options that were given (the others are absent); the
    controller of ``--controller FILE`` instead of the PID when given."""
    rig_changes = {field: getattr(args, o.replace("-", "_")) for o, (field, _, _) in RIG_OPTIONS.items()
                   if hasattr(args, o.replace("-", "_"))}  # fmt: skip
    if hasattr(args, "force_law"):
        rig_changes["force_law"] = args.force_law
    pid_changes = {field: getattr(args, o.replace("-", "_")) for o, (field, _, _) in PID_OPTIONS.items()
                   if hasattr(args, o.replace("-", "_")) and (gains or field not in ("kp", "ki", "kd"))}  # fmt: skip
    if hasattr(args, "delay"):
        pid_changes["delay"] = args.delay
    rig = replace(Rig.paper(), **rig_changes)
    if getattr(args, "controller", None) is None:
        return rig, replace(PID.paper(), **pid_changes)
    if pid_changes:
        given = ", ".join("--" + name.replace("_", "-") for name in pid_changes)
        raise UsageError(f"{given} cannot go with --controller (the file sets the controller, its fs and delay)")
    if not args.controller.is_file():
        raise UsageError(f"--controller: {str(args.controller)!r} is not a file")
    return rig, load_controller(args.controller)


def _excitation(args: argparse.Namespace, pid: AnyController):  # noqa: ANN202
    return schroeder_multisine(f0=args.f0, f_max=args.f_max, fs=pid.fs, rms=args.rms, lines=args.lines, seed=args.seed)


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
        _needs("xarray", "xarray", "--save .nc")
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
        from .plots import plot_estimate

        _save_figure(plot_estimate(estimate), args.figure, estimate.meta)
        print(f"wrote {args.figure}")


def _sweep_csv(result, out: Path) -> None:  # noqa: ANN001
    """One row per point and line; the metadata (version, rig, controller, seed) in trailing ``#`` lines."""
    from .io._results import trailer

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
        _needs("xarray", "xarray", "--out .nc")
        _needs("h5netcdf", "xarray", "--out .nc")
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
    estimate = identify(rec.force, rec.displacement, fs=rec.fs, f0=args.f0, mass=args.mass, f_max=args.f_max,
                        settle_periods=args.settle_periods, median_window=args.median_window,
                        clearance=args.clearance)  # fmt: skip
    print(f"{args.file}: {rec.force.size} samples at {rec.fs:g} Hz, {estimate.periods} periods, "
          f"{estimate.freq.size} lines from {estimate.freq[0]:g} to {estimate.freq[-1]:g} Hz")  # fmt: skip
    if estimate.weak is not None and estimate.weak.any():
        print(f"{int(estimate.weak.sum())} weak lines (force or displacement under 10x the unexcited level)")
    print(f"natural frequency {natural_frequency(estimate.freq, estimate.H):.3f} Hz (where Re F/Y = 0)")
    args.out.mkdir(exist_ok=True)
    estimate.save(args.out / "estimate.csv")
    from .plots import plot_estimate

    title = f"Identified from {Path(args.file).name}"
    _save_figure(
        plot_estimate(estimate, title=title), args.out / "estimate.png", {**estimate.meta, "file": str(args.file)}
    )
    print(f"wrote {args.out / 'estimate.csv'} and {args.out / 'estimate.png'}")


def cmd_paper(args: argparse.Namespace) -> None:
    from .paper import output_names, write_paper

    check_output_dir(args.out, "--out", output_names(), args.overwrite)
    _needs("matplotlib", "plot", "paper (it draws the figures)")
    _started(args)
    write_paper(args.out, seed=args.seed, progress=not args.no_progress)


def build_parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument("--overwrite", action="store_true", help="replace existing output files")
    common.add_argument("--debug", action="store_true", help="show the traceback of an error")
    parser = _Parser(
        prog="amb-fast",
        allow_abbrev=False,
        description="Simulate and identify a digitally controlled active magnetic bearing (paper rig by default). "
        "SI units: N, m, A, s, kg; frequencies in Hz; gains kp A/m, ki A/(m s), kd A s/m.",
    )
    parser.add_argument("--version", action="version", version=f"amb-fast {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="{paper,run,sweep,identify,fit,design}",
                                parser_class=_Parser)  # fmt: skip

    paper = sub.add_parser(
        "paper",
        allow_abbrev=False,
        parents=[common],
        help="reproduce the paper: figures, curves (CSV, NetCDF) and claims report",
    )
    paper.add_argument("--out", type=Path, default=Path("paper-output"), help="output folder (default paper-output)")
    paper.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")
    paper.add_argument("--no-progress", action="store_true", help="no progress lines")
    paper.set_defaults(func=cmd_paper)

    run = sub.add_parser("run", allow_abbrev=False, parents=[common], help="one SPHS experiment; prints a summary")
    _add_model_options(run)
    run.add_argument("--at", type=_values, default=np.array([10.0, 40.0, 100.0, 200.0]),
                     help="lines to tabulate (Hz, 'a,b,c'; default 10,40,100,200)")  # fmt: skip
    run.add_argument("--save", type=Path, help="write the estimate (.csv or .nc; load with amb_fast.load_estimate; "
                     "with --two-axis .csv or .npz)")  # fmt: skip
    run.add_argument("--figure", type=Path, help="write a figure (.png, .pdf or .svg)")
    add_two_axis_options(run)
    run.set_defaults(func=cmd_run)

    sw = sub.add_parser("sweep", allow_abbrev=False, parents=[common], help="a gain grid to NetCDF (.nc), .npz or CSV")
    _add_model_options(sw, gains=False)
    for name, (_, unit, text) in list(PID_OPTIONS.items())[:3]:
        sw.add_argument(f"--{name}", type=_values, help=f"{text} values ({unit}): 'a,b,c' or 'start:stop:count'")
    sw.add_argument("--grid", choices=["product", "zip"], default="product", help="cross the values or pair them")
    sw.add_argument("--workers", type=int, help="threads (default: all cores)")
    sw.add_argument(
        "--out", default="sweep.nc", help="output file: .nc (needs amb_fast[xarray]), .npz or .csv (default sweep.nc)"
    )
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.set_defaults(func=cmd_sweep)

    ident = sub.add_parser(
        "identify",
        allow_abbrev=False,
        parents=[common],
        help="k and c from a recording (.csv/.tsv/.txt with named columns, .mat incl. v7.3, .tdms)",
    )
    ident.add_argument("file", type=Path, help="recording: .csv/.tsv/.txt (a header names the columns), .mat, .tdms")
    ident.add_argument(
        "--force",
        default="force",
        help="force channel: name or 0-based column index (N, or a unit in its name; default 'force')",
    )
    ident.add_argument(
        "--displacement",
        default="displacement",
        help="displacement channel: name or 0-based column index (m, or a unit in its name)",
    )
    ident.add_argument("--recording", help="which recording of a file that holds several (dSPACE export, TDMS group)")
    ident.add_argument(
        "--fs", type=float, help="sampling frequency (Hz; default: from 'fs' or the time column, which it must match)"
    )
    ident.add_argument("--clearance", type=float, help="mechanical clearance (m): warn if the displacement exceeds it")
    ident.add_argument("--f0", type=float, default=1.0, help="fundamental (Hz; default 1)")
    ident.add_argument("--mass", type=float, default=0.92, help="known moving mass (kg; default 0.92)")
    ident.add_argument("--f-max", type=float, help="highest excited line (Hz; default: detected from the force)")
    ident.add_argument(
        "--settle-periods",
        type=int,
        default=0,
        help="periods to skip at the start (a warning says when a transient is left in)",
    )
    ident.add_argument("--median-window", type=int, default=5, help="median filter width (lines, odd)")
    ident.add_argument("--out", type=Path, default=Path("identify-output"), help="output folder")
    ident.set_defaults(func=cmd_identify)

    from .calibration._cli import add_design_parser, add_fit_parser

    add_fit_parser(sub, parents=[common])
    add_design_parser(sub, parents=[common])
    return parser


def _version() -> str:
    from . import __version__

    return __version__


def _one_line(
    message: Warning | str, category: type[Warning], filename: str, lineno: int, file=None, line=None
) -> None:  # noqa: ANN001
    print(f"amb-fast: warning: {message}", file=sys.stderr)


EXPECTED = (UsageError, ValueError, OSError, ImportError, TouchdownError, OverflowError, MemoryError)


#: A negative number in any notation argparse would mistake for an option ("-1e4", "-.5", "-inf").
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf$", re.IGNORECASE)


def _join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--kyx -1e4`` -> ``--kyx=-1e4``: argparse reads only plain negatives ("-5", "-0.5") as values."""
    out: list[str] = []
    for token in argv:
        if _NEGATIVE_NUMBER.match(token) and out and out[-1].startswith("--") and "=" not in out[-1]:
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(_join_negative_values(sys.argv[1:] if argv is None else argv))
    args.phase = "check"
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():  # a warning is one line on stderr, whatever the interpreter's filters
            warnings.simplefilter("default", UserWarning)
            warnings.showwarning = _one_line
            args.func(args)
    except KeyboardInterrupt:
        print("amb-fast: interrupted", file=sys.stderr)
        return 130
    except Exception as error:
        if args.debug:
            traceback.print_exc()
        status = 2 if args.phase == "check" else 1
        if isinstance(error, EXPECTED):
            text = " ".join(str(error).split()) or type(error).__name__
            print(f"amb-fast: error: {text}", file=sys.stderr)
        else:
            print(f"amb-fast: error: internal error {type(error).__name__}: {error} (please report it; --debug shows "
                  "the traceback)", file=sys.stderr)  # fmt: skip
            status = 1
        return status
    print(f"done in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
