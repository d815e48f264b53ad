"""The options every sub-command shares (the rig, the controller, outputs), their checks, and the
model they build."""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Iterable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from .._excitation import schroeder_multisine
from .._linear import AnyController
from .._params import PID, Rig
from .._toml import load_rig
from ..controllers import load_controller
from ..io import atomic_path

RIG_OPTIONS = {  # option (the Rig field with "_" for "-") -> (unit, help)
    "mass": ("kg", "known moving mass m of eq. 9"),
    "kyy": ("N/m", "position stiffness of the magnet pair (negative)"),
    "kiy": ("N/A", "current stiffness"),
    "bias-current": ("A", "bias current of the magnet pair"),
    "amp-bandwidth": ("Hz", "amplifier current-loop bandwidth, or 'none'"),
    "eddy-bandwidth": ("Hz", "eddy-current force lag corner, or 'none'"),
    "sensor-bandwidth": ("Hz", "displacement sensor bandwidth, or 'none'"),
    "sensor-noise": ("m rms", "displacement sensor noise"),
    "force-noise": ("N rms", "force transducer noise"),
    "mass-loading": ("kg", "extra mass moving with the platform"),
    "force-coupling-tau": ("s", "AC-coupling time constant of the force transducer, or 'none'"),
    "dead-time": ("s", "transport delay from the current command to the amplifier (DSP latency)"),
}
PID_OPTIONS = {  # option (the PID field with "_" for "-") -> (unit, help)
    "kp": ("A/m", "proportional gain"),
    "ki": ("A/(m s)", "integral gain"),
    "kd": ("A s/m", "derivative gain"),
    "derivative-cutoff": ("Hz", "derivative filter corner, or 'none'"),
    "fs": ("Hz", "sampling frequency"),
}
GAINS = ("kp", "ki", "kd")


class UsageError(Exception):
    """A mistake in the command line or its files: reported in one line, without a traceback."""


class _Parser(argparse.ArgumentParser):
    """argparse with its errors in the command's one-line form (exit status 2), and no abbreviated options."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **{"allow_abbrev": False, **kwargs})

    def error(self, message: str) -> NoReturn:
        print(f"amb-fast: error: {message} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)


ESTIMATE_SUFFIXES = (".csv", ".nc")
TWO_AXIS_SUFFIXES = (".csv", ".nc", ".npz")  # amb-fast run --two-axis --save: EstimateN.save's
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
SWEEP_SUFFIXES = (".nc", ".npz", ".csv")


def _existing_parent(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def _writable_directory(directory: Path, option: str) -> None:
    """The directory a file goes into: it exists, is a directory and may be written (an atomic write puts a
    temporary file beside the target)."""
    if not directory.exists():
        raise UsageError(f"{option}: the directory {str(directory)!r} does not exist")
    if not directory.is_dir():
        raise UsageError(f"{option}: {str(directory)!r} is not a directory")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise UsageError(f"{option}: the directory {str(directory)!r} is not writable")


def check_output(path: Path, option: str, suffixes: Sequence[str], overwrite: bool) -> Path:
    """Refuse an output path before any work: its suffix, its directory, an existing file (without --overwrite)."""
    if path.suffix.lower() not in suffixes:
        raise UsageError(f"{option} must end in {', '.join(suffixes)}, got {str(path)!r}")
    _writable_directory(_existing_parent(path), option)
    if path.is_dir():
        raise UsageError(f"{option}: {str(path)!r} is a directory")
    if path.exists() and not overwrite:
        raise UsageError(f"{option}: {str(path)!r} exists; pass --overwrite to replace it")
    return path


def check_output_dir(directory: Path, option: str, names: Sequence[str], overwrite: bool) -> Path:
    """An output folder: it may not exist yet (its parent must); files in it are not overwritten without --overwrite."""
    if directory.exists() and not directory.is_dir():
        raise UsageError(f"{option}: {str(directory)!r} exists and is not a directory")
    _writable_directory(directory if directory.exists() else _existing_parent(directory), option)
    folders = [name for name in names if (directory / name).is_dir()]
    if folders:  # not even --overwrite replaces a directory by a file
        raise UsageError(f"{option}: {str(directory / folders[0])!r} is a directory, where a file goes")
    existing = [name for name in names if (directory / name).exists()]
    if existing and not overwrite:
        shown = ", ".join(existing[:4]) + (" ..." if len(existing) > 4 else "")
        raise UsageError(f"{option}: {str(directory)!r} already holds {shown}; pass --overwrite to replace them")
    return directory


def check_save_and_figure(args: argparse.Namespace, save_suffixes: Sequence[str]) -> None:
    """``--save`` and ``--figure`` (when given): their paths, and the extras that write them."""
    if args.save is not None:
        check_output(args.save, "--save", save_suffixes, args.overwrite)
        if args.save.suffix.lower() == ".nc":
            _needs("h5netcdf", "xarray", "--save .nc")
    if args.figure is not None:
        check_output(args.figure, "--figure", FIGURE_SUFFIXES, args.overwrite)
        _needs("matplotlib", "plot", "--figure")


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

    from ..io import figure_metadata

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
    """'1,2,3' or 'start:stop:count' (inclusive, evenly spaced); an empty item ('2000,,3000') is refused,
    not skipped: it is a typo, and the grid would silently lose a point."""
    try:
        if ":" in text:
            start, stop, count = text.split(":")
            if int(count) < 1:
                raise argparse.ArgumentTypeError(f"'start:stop:count' needs a count >= 1, got {text!r}")
            return np.linspace(float(start), float(stop), int(count))
        items = text.split(",")
        if any(not item.strip() for item in items):
            raise argparse.ArgumentTypeError(f"an empty value in {text!r}: expected 'a,b,c' or 'start:stop:count'")
        return np.array([float(v) for v in items])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'a,b,c' or 'start:stop:count', got {text!r}") from None


def _add_model_options(parser: argparse.ArgumentParser, gains: bool = True) -> None:
    rig = parser.add_argument_group("rig (defaults: Rig.paper())")
    rig.add_argument("--rig", type=Path, metavar="FILE", help="rig file (TOML or JSON, as `fit --out` writes) "
                     "replacing Rig.paper(); the rig options below change its values")  # fmt: skip
    for option, (unit, text) in RIG_OPTIONS.items():
        rig.add_argument(f"--{option}", type=_number_or_none, default=argparse.SUPPRESS, metavar="X",
                         help=f"{text} ({unit})")  # fmt: skip
    rig.add_argument("--force-law", choices=["linear", "nonlinear"], default=argparse.SUPPRESS, help="magnet force law")
    pid = parser.add_argument_group("controller (defaults: PID.paper())")
    for option, (unit, text) in PID_OPTIONS.items():
        if gains or option not in GAINS:
            pid.add_argument(f"--{option}", type=_number_or_none, default=argparse.SUPPRESS, metavar="X",
                             help=f"{text} ({unit})")  # fmt: skip
    pid.add_argument("--delay", type=int, default=argparse.SUPPRESS, help="computation delay (whole samples)")
    text = ("any digital controller from a TOML or JSON file (PID, notch, low-pass, lead-lag, second-order, "
            "transfer-function blocks in series; docs/controllers.md) instead of the PID")  # fmt: skip
    pid.add_argument("--controller", type=Path, metavar="FILE", help=text)
    ex = parser.add_argument_group("excitation and experiment")
    ex.add_argument("--f0", type=float, default=1.0, help="fundamental of the SPHS (Hz; default 1)")
    ex.add_argument("--f-max", type=float, help=f"highest line (Hz; default {DEFAULT_F_MAX:g}, or the highest "
                    "harmonic of --f0 below --fs/2 when that is lower)")  # fmt: skip
    ex.add_argument("--rms", type=float, default=1.0, help="excitation rms (N; default 1)")
    ex.add_argument("--lines", choices=["all", "odd", "random-odd"], default="all", help="which harmonics to excite")
    ex.add_argument("--periods", type=int, default=10, help="periods averaged (default 10)")
    ex.add_argument("--settle-periods", type=int, help="periods before recording (default: from the slowest pole)")
    ex.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")


def _model(args: argparse.Namespace, *, gains: bool = True) -> tuple[Rig, AnyController]:
    """The paper's rig and controller with the options that were given (the others are absent); the
    controller of ``--controller FILE`` instead of the PID when given."""

    def present(names: list[str]) -> dict[str, Any]:
        return {name: getattr(args, name) for name in names if hasattr(args, name)}

    rig_changes = present([*_attributes(RIG_OPTIONS), "force_law"])
    pid_changes = present([n for n in [*_attributes(PID_OPTIONS), "delay"] if gains or n not in GAINS])
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


def _attributes(options: Iterable[str]) -> list[str]:
    """The attribute (and Rig or PID field) names of options: ``bias-current`` -> ``bias_current``."""
    return [option.replace("-", "_") for option in options]


DEFAULT_F_MAX = 200.0  # Hz: the paper's band
DEFAULT_AT = (10.0, 40.0, 100.0, 200.0)  # Hz: the paper's table


def default_f_max(f0: float, fs: float, ceiling: float = DEFAULT_F_MAX) -> float:
    """The default highest line (Hz): ``ceiling`` (200 Hz), or the highest harmonic of ``f0`` below ``fs/2`` when
    that is lower (``--fs 300``), and at least ``f0`` (``--f0 250``): a default follows the options given."""
    if not (np.isfinite(f0) and f0 > 0 and np.isfinite(fs) and fs > 0):
        return ceiling  # the library names the bad value
    top = np.ceil(fs / 2 / f0) - 1  # harmonics strictly below Nyquist
    return float(f0 * max(1.0, min(np.floor(ceiling / f0 + 1e-9), top)))


def default_at(freq: np.ndarray) -> np.ndarray:
    """The lines (Hz) a table shows by default: 10, 40, 100 and 200 Hz when the band holds them all, else four
    excited lines spread evenly (logarithmically) over the band, so a default never falls outside it."""
    if freq[0] <= min(DEFAULT_AT) and max(DEFAULT_AT) <= freq[-1]:
        return np.array(DEFAULT_AT)
    wanted = np.geomspace(freq[0], freq[-1], 4)
    return np.unique(freq[[int(np.argmin(np.abs(freq - f))) for f in wanted]])


def at_lines(at: np.ndarray | None, freq: np.ndarray) -> np.ndarray:
    """The lines of the table: ``--at`` refused outside the excited band ``freq`` (Hz), or by default
    :func:`default_at`, which follows the band of the options given (--f-max 20, --lines odd, --fs 300)."""
    if at is None:
        return default_at(freq)
    outside = [float(f) for f in at if not freq[0] <= f <= freq[-1]]
    if outside:
        raise UsageError(f"--at must be within the excited band {freq[0]:g}-{freq[-1]:g} Hz, got {outside}")
    return at


def _excitation(args: argparse.Namespace, pid: AnyController):  # noqa: ANN202
    f_max = default_f_max(args.f0, pid.fs) if args.f_max is None else args.f_max
    return schroeder_multisine(f0=args.f0, f_max=f_max, fs=pid.fs, rms=args.rms, lines=args.lines, seed=args.seed)


# -- the library's messages in the command's words -------------------------------------------------------------


def _option_names(*options: str) -> dict[str, str]:
    return dict(zip(_attributes(options), (f"--{option}" for option in options)))


#: Python keyword argument -> the option that sets it, per command: the one place where the library's
#: parameter names (``settle_periods``, ``fs``) become options (``--settle-periods``, ``--fs``) in messages.
MODEL_OPTION_NAMES = _option_names(*RIG_OPTIONS, *PID_OPTIONS, "f0", "f-max", "rms", "periods", "settle-periods",
                                   "seed", "delay", "force-law", "workers", "grid")  # fmt: skip
IDENTIFY_OPTION_NAMES = _option_names("fs", "f0", "f-max", "mass", "settle-periods", "median-window", "clearance",
                                      "recording", "time", "lines") | {"path": "FILE"}  # fmt: skip
#: Names that also stand for the data ("force must be finite" is about the samples, "time must be increasing"
#: about the column): only ``name=`` is taken for an option.
_DATA = frozenset({"time", "force", "displacement", "path"})


def cli_text(text: str, names: dict[str, str]) -> str:
    """``text`` with the library's parameter names replaced by the options in ``names``: ``name=`` anywhere
    (``pass fs=`` -> ``pass --fs``, ``time=None`` -> ``--time none``); a name with an underscore anywhere as a
    word; other names where they stand in an ``a/b`` pair (``fs/f0 must be``) or precede ``must`` or a
    number in parentheses. A hint in both spellings, ``(A; on the command line B)``, keeps the command's half."""

    def one_spelling(match: re.Match) -> str:  # "(force=1; on the command line --force 1)" -> "(--force 1)"
        python, command = match.group(1), match.group(2)
        return f"({command})" if "=" in python else f"({python})"  # "pass fs= (Hz; ...)": fs= becomes --fs

    def swap(match: re.Match) -> str:
        name, equals = match.group("name"), match.group("equals")
        if name not in names:
            return match.group(0)
        if equals is not None:  # "recording=NAME" -> "--recording NAME", "time=None" -> "--time none"
            value = equals[1:]
            return names[name] + (" " + ("none" if value == "None" else value) if value else "")
        if name in _DATA:
            return match.group(0)
        start, end = match.start(), match.end()
        leads = (
            (start > 0 and text[start - 1] == "/")
            or text.startswith(("/", " must"), end)
            or re.match(r" \(-?\d", text[end:]) is not None
        )  # "at least f0 (1.0 Hz)", not "the wrong lines (pass"
        return names[name] if "_" in name or leads else match.group(0)

    text = re.sub(r"\(([^();]*); on the command line ([^()]*)\)", one_spelling, text)
    return re.sub(r"(?<![\w\-'\".])(?P<name>[A-Za-z_][A-Za-z0-9_]*)(?P<equals>=(?:None|[A-Z]+)?)?(?![\w'\"])", swap,
                  text)  # fmt: skip
