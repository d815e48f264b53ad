"""The ``amb-fast`` command (also ``python -m amb_fast``).

SI units on every option: forces in N, displacements in m, gains in A/m (kp), A/(m s) (ki) and
A s/m (kd), bandwidths and frequencies in Hz, masses in kg, time constants in s.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from ._excitation import schroeder_multisine
from ._experiment import Estimate, identify, run_experiment
from ._linear import closed_loop_poles, stability_margin
from ._params import PID, Rig
from ._recording import load_recording
from ._sweep import sweep
from .claims import natural_frequency

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
    ex = parser.add_argument_group("excitation and experiment")
    ex.add_argument("--f0", type=float, default=1.0, help="fundamental of the SPHS (Hz; default 1)")
    ex.add_argument("--f-max", type=float, default=200.0, help="highest line (Hz; default 200)")
    ex.add_argument("--rms", type=float, default=1.0, help="excitation rms (N; default 1)")
    ex.add_argument("--lines", choices=["all", "odd", "random-odd"], default="all", help="which harmonics to excite")
    ex.add_argument("--periods", type=int, default=10, help="periods averaged (default 10)")
    ex.add_argument("--settle-periods", type=int, help="periods before recording (default: from the slowest pole)")
    ex.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")


def _model(args: argparse.Namespace, *, gains: bool = True) -> tuple[Rig, PID]:
    """The paper's rig and controller with the options that were given (the others are absent)."""
    rig_changes = {field: getattr(args, o.replace("-", "_")) for o, (field, _, _) in RIG_OPTIONS.items()
                   if hasattr(args, o.replace("-", "_"))}  # fmt: skip
    if hasattr(args, "force_law"):
        rig_changes["force_law"] = args.force_law
    pid_changes = {field: getattr(args, o.replace("-", "_")) for o, (field, _, _) in PID_OPTIONS.items()
                   if hasattr(args, o.replace("-", "_")) and (gains or field not in ("kp", "ki", "kd"))}  # fmt: skip
    if hasattr(args, "delay"):
        pid_changes["delay"] = args.delay
    return replace(Rig.paper(), **rig_changes), replace(PID.paper(), **pid_changes)


def _excitation(args: argparse.Namespace, pid: PID):  # noqa: ANN202
    return schroeder_multisine(f0=args.f0, f_max=args.f_max, fs=pid.fs, rms=args.rms, lines=args.lines, seed=args.seed)


def _summary(estimate: Estimate, rig: Rig, pid: PID, at: Sequence[float]) -> str:
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


def save_estimate(estimate: Estimate, path: Path) -> None:
    """An estimate as CSV (one row per line, units in the header) or .npz."""
    columns = {
        "freq_Hz": estimate.freq, "k_N_per_m": estimate.k, "c_Ns_per_m": estimate.c,
        "k_smooth_N_per_m": estimate.k_smooth, "c_smooth_Ns_per_m": estimate.c_smooth,
        "k_std_N_per_m": estimate.k_std, "c_std_Ns_per_m": estimate.c_std,
        "H_real_N_per_m": estimate.H.real, "H_imag_N_per_m": estimate.H.imag,
        "receptance_abs_m_per_N": np.abs(estimate.receptance),
    }  # fmt: skip
    if path.suffix == ".csv":
        np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns),
                   comments="", fmt="%.10g")  # fmt: skip
    elif path.suffix == ".npz":
        np.savez(path, **columns)
    else:
        raise UsageError(f"--save must end in .csv or .npz, got {str(path)!r}")


def cmd_run(args: argparse.Namespace) -> None:
    rig, pid = _model(args)
    excitation = _excitation(args, pid)
    estimate = run_experiment(
        rig, pid, excitation, periods=args.periods, settle_periods=args.settle_periods, seed=args.seed
    )
    print(_summary(estimate, rig, pid, args.at))
    if args.save:
        save_estimate(estimate, args.save)
        print(f"wrote {args.save}")
    if args.figure:
        from .plots import plot_estimate

        plot_estimate(estimate).savefig(args.figure, dpi=120)
        print(f"wrote {args.figure}")


def cmd_sweep(args: argparse.Namespace) -> None:
    rig, pid = _model(args, gains=False)
    if args.kp is None and args.ki is None and args.kd is None:
        raise UsageError("give at least one of --kp, --ki, --kd (e.g. --kp 2000:3000:11)")
    excitation = _excitation(args, pid)
    gains = {name: getattr(args, name) for name in ("kp", "ki", "kd") if getattr(args, name) is not None}
    result = sweep(rig, pid, excitation, **gains, grid=args.grid, periods=args.periods,
                   settle_periods=args.settle_periods, workers=args.workers, seed=args.seed,
                   progress=None if not args.no_progress else False)  # fmt: skip
    counts = {s: int(np.sum(result.status == s)) for s in np.unique(result.status)}
    print(f"{result.status.size} points: " + ", ".join(f"{n} {s}" for s, n in counts.items()))
    out = Path(args.out)
    if out.suffix == ".csv":
        names = list(result.points)
        rows = [[*[result.points[n][i] for n in names], result.status[i], f, result.k[i, j], result.c[i, j],
                 result.k_std[i, j], result.c_std[i, j], abs(1 / result.H[i, j])]
                for i in range(result.status.size) for j, f in enumerate(result.freq)]  # fmt: skip
        header = ",".join([*names, "status", "freq_Hz", "k_N_per_m", "c_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m",
                           "receptance_abs_m_per_N"])  # fmt: skip
        with out.open("w") as handle:
            handle.write(header + "\n")
            for row in rows:
                handle.write(",".join(str(v) for v in row) + "\n")
    else:
        result.save(out)
    print(f"wrote {out}")


def cmd_identify(args: argparse.Namespace) -> None:
    rec = load_recording(args.file, force=args.force, displacement=args.displacement, fs=args.fs)
    estimate = identify(rec.force, rec.displacement, fs=rec.fs, f0=args.f0, mass=args.mass, f_max=args.f_max,
                        settle_periods=args.settle_periods, median_window=args.median_window)  # fmt: skip
    print(f"{args.file}: {rec.force.size} samples at {rec.fs:g} Hz, {estimate.periods} periods, "
          f"{estimate.freq.size} lines from {estimate.freq[0]:g} to {estimate.freq[-1]:g} Hz")  # fmt: skip
    print(f"natural frequency {natural_frequency(estimate.freq, estimate.H):.3f} Hz (where Re F/Y = 0)")
    args.out.mkdir(parents=True, exist_ok=True)
    save_estimate(estimate, args.out / "estimate.csv")
    from .plots import plot_estimate

    plot_estimate(estimate, title=f"Identified from {Path(args.file).name}").savefig(args.out / "estimate.png", dpi=120)
    print(f"wrote {args.out / 'estimate.csv'} and {args.out / 'estimate.png'}")


def cmd_paper(args: argparse.Namespace) -> None:
    from .paper import write_paper

    write_paper(args.out, seed=args.seed, progress=not args.no_progress)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="amb-fast",
        allow_abbrev=False,
        description="Simulate and identify a digitally controlled active magnetic bearing (paper rig by default). "
        "SI units: N, m, A, s, kg; frequencies in Hz; gains kp A/m, ki A/(m s), kd A s/m.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="{paper,run,sweep,identify}")

    paper = sub.add_parser(
        "paper", allow_abbrev=False, help="reproduce the paper: figures, curves (CSV, NetCDF) and claims report"
    )
    paper.add_argument("--out", type=Path, default=Path("paper-output"), help="output folder (default paper-output)")
    paper.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")
    paper.add_argument("--no-progress", action="store_true", help="no progress lines")
    paper.set_defaults(func=cmd_paper)

    run = sub.add_parser("run", allow_abbrev=False, help="one SPHS experiment; prints a summary")
    _add_model_options(run)
    run.add_argument("--at", type=_values, default=np.array([10.0, 40.0, 100.0, 200.0]),
                     help="lines to tabulate (Hz, 'a,b,c'; default 10,40,100,200)")  # fmt: skip
    run.add_argument("--save", type=Path, help="write the estimate (.csv or .npz)")
    run.add_argument("--figure", type=Path, help="write a figure (.png)")
    run.set_defaults(func=cmd_run)

    sw = sub.add_parser("sweep", allow_abbrev=False, help="a gain grid to NetCDF (.nc), .npz or CSV")
    _add_model_options(sw, gains=False)
    for name, (_, unit, text) in list(PID_OPTIONS.items())[:3]:
        sw.add_argument(f"--{name}", type=_values, help=f"{text} values ({unit}): 'a,b,c' or 'start:stop:count'")
    sw.add_argument("--grid", choices=["product", "zip"], default="product", help="cross the values or pair them")
    sw.add_argument("--workers", type=int, help="threads (default: all cores)")
    sw.add_argument("--out", default="sweep.nc", help="output file: .nc (needs amb_fast[xarray]), .npz or .csv")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.set_defaults(func=cmd_sweep)

    ident = sub.add_parser(
        "identify", allow_abbrev=False, help="k and c from a recording (CSV with named columns, or .mat)"
    )
    ident.add_argument("file", type=Path, help="recording: .csv (header names the columns) or .mat")
    ident.add_argument("--force", default="force", help="force channel name (N; default 'force')")
    ident.add_argument("--displacement", default="displacement", help="displacement channel name (m)")
    ident.add_argument("--fs", type=float, help="sampling frequency (Hz; default: from 'fs' or 'time' in the file)")
    ident.add_argument("--f0", type=float, default=1.0, help="fundamental (Hz; default 1)")
    ident.add_argument("--mass", type=float, default=0.92, help="known moving mass (kg; default 0.92)")
    ident.add_argument("--f-max", type=float, help="highest excited line (Hz; default: detected from the force)")
    ident.add_argument("--settle-periods", type=int, default=0, help="periods to skip at the start")
    ident.add_argument("--median-window", type=int, default=5, help="median filter width (lines, odd)")
    ident.add_argument("--out", type=Path, default=Path("identify-output"), help="output folder")
    ident.set_defaults(func=cmd_identify)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        args.func(args)
    except (UsageError, ValueError, OSError, ImportError) as error:
        print(f"amb-fast {args.command}: error: {error}", file=sys.stderr)
        return 2
    print(f"done in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
