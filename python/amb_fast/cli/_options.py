"""The options every sub-command shares (the rig, the controller, outputs), their checks, and the
model they build."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import NoReturn

import numpy as np

from .._excitation import schroeder_multisine
from .._linear import AnyController
from .._params import PID, Rig
from .._toml import load_rig
from ..controllers import load_controller
from ..io import atomic_path

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

    from ..io._results import figure_metadata

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
    rig.add_argument("--rig", type=Path, metavar="FILE", help="rig file (TOML or JSON, as `fit --out` writes) "
                     "replacing Rig.paper(); the rig options below change its values")  # fmt: skip
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
    base = Rig.paper() if getattr(args, "rig", None) is None else load_rig(args.rig)
    rig = replace(base, **rig_changes)
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
