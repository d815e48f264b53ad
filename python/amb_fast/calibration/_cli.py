"""The ``amb-fast fit`` and ``amb-fast design`` sub-commands (hooked into ``amb_fast.cli``).

``add_fit_parser(subparsers)`` / ``add_design_parser(subparsers)`` add them to the command's
sub-parsers; each sets ``func`` to :func:`cmd_fit` / :func:`cmd_design`, which print the reports.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._experiment import Estimate, UnexcitedLines
from .._params import PID, Rig
from ..io import load_estimate
from ._problem import FITTABLE

_COLUMNS = ("freq_Hz", "H_real_N_per_m", "H_imag_N_per_m", "k_std_N_per_m", "c_std_Ns_per_m")
_RIG_FIELDS = {f.name for f in fields(Rig)} - {"force_law"}


def read_estimate(path: str | Path, *, blocks: int, mass: float) -> Estimate:
    """An estimate from a file that ``amb-fast run --save`` (or ``identify``) writes.

    A file written by :meth:`Estimate.save` (``.nc``, or ``.csv`` with its checksum line) is read whole
    by :func:`amb_fast.load_estimate`. A plain CSV table with the columns of that file holds neither the
    periods nor the known mass: ``blocks`` (the periods averaged, up to 63) and ``mass`` (kg) are given,
    and force and displacement amplitudes are NaN.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"estimate file {str(path)!r} does not exist")
    with path.open("rb") as head:
        if path.suffix.lower() == ".nc" or head.read(10) == b"# sha256: ":
            return load_estimate(path)
    try:
        table = np.genfromtxt(path, delimiter=",", names=True)
    except ValueError as error:
        raise ValueError(f"{path}: not a CSV estimate ({error})") from None
    names = table.dtype.names or ()
    missing = [c for c in _COLUMNS if c not in names]
    if missing:
        raise ValueError(f"{path}: columns {missing} missing; expected the CSV of `amb-fast run --save`")
    table = np.atleast_1d(table)
    freq = np.asarray(table["freq_Hz"], dtype=float)
    H = table["H_real_N_per_m"] + 1j * table["H_imag_N_per_m"]
    w = 2 * np.pi * freq
    k = mass * w**2 + H.real
    nan = np.full(freq.shape, np.nan + 0j)
    return Estimate(
        freq=freq, H=H, receptance=1.0 / H, k=k, c=H.imag / w, k_smooth=k, c_smooth=H.imag / w,
        k_std=np.asarray(table["k_std_N_per_m"], dtype=float), c_std=np.asarray(table["c_std_Ns_per_m"], dtype=float),
        force=nan, displacement=nan, unexcited=UnexcitedLines(np.empty(0), np.empty(0), np.empty(0)),
        periods=blocks, blocks=blocks,
    )  # fmt: skip


def _assignments(text: str) -> dict[str, Any]:
    """'name=value,name=value' (value a number or 'none')."""
    out: dict[str, Any] = {}
    for item in filter(None, (t.strip() for t in text.split(","))):
        name, sep, value = item.partition("=")
        if not sep:
            raise argparse.ArgumentTypeError(f"expected name=value, got {item!r}")
        try:
            out[name.strip()] = None if value.strip().lower() == "none" else float(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number or 'none' for {name!r}, got {value!r}") from None
    return out


def _list(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers 'a,b,...', got {text!r}") from None


def _names(text: str) -> list[str]:
    return [n.strip() for n in text.split(",") if n.strip()]


def _band(text: str) -> tuple[float, float]:
    try:
        low, high = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'low:high' in Hz, got {text!r}") from None
    return low, high


def _rig(args: argparse.Namespace) -> Rig:
    changes = dict(args.set or {})
    unknown = set(changes) - _RIG_FIELDS
    if unknown:
        raise ValueError(f"--set: {sorted(unknown)} are not Rig fields ({', '.join(sorted(_RIG_FIELDS))})")
    if "substeps" in changes:
        changes["substeps"] = int(changes["substeps"])
    return replace(Rig.paper(), **changes)


def _add_controller_options(parser: argparse.ArgumentParser, several: bool) -> None:
    group = parser.add_argument_group("controller (defaults: PID.paper())")
    each = " (one per estimate file, 'a,b')" if several else ""
    for name, unit in (("kp", "A/m"), ("ki", "A/(m s)"), ("kd", "A s/m")):
        group.add_argument(f"--{name}", type=_list, help=f"{name} ({unit}){each}")
    group.add_argument("--derivative-cutoff", type=float, help="derivative filter corner (Hz)")
    group.add_argument("--fs", type=float, help="sampling frequency (Hz)")
    group.add_argument("--delay", type=int, help="computation delay (whole samples)")
    parser.add_argument(
        "--set",
        type=_assignments,
        metavar="NAME=X,...",
        help="rig values (SI units, 'none' switches a stage off) replacing Rig.paper()'s: the fixed values and "
        "the start values of the free ones, e.g. --set amp_bandwidth=2000,dead_time=1e-4",
    )


def _controllers(args: argparse.Namespace, count: int) -> list[PID]:
    base = PID.paper()
    common: dict[str, Any] = {}
    for name in ("derivative_cutoff", "fs", "delay"):
        if getattr(args, name) is not None:
            common[name] = getattr(args, name)
    out = []
    for i in range(count):
        gains = {}
        for name in ("kp", "ki", "kd"):
            values = getattr(args, name)
            if values:
                if len(values) not in (1, count):
                    raise ValueError(f"--{name} must give one value or one per estimate ({count}), got {len(values)}")
                gains[name] = values[i if len(values) > 1 else 0]
        out.append(replace(base, **common, **gains))
    return out


def add_fit_parser(subparsers: Any, parents: Sequence[argparse.ArgumentParser] = ()) -> argparse.ArgumentParser:
    """Add ``fit``: calibrate the rig to one or more estimate CSVs and print the report."""
    fit = subparsers.add_parser(
        "fit",
        allow_abbrev=False,
        parents=list(parents),
        help="calibrate the rig model to estimates (CSV of `run --save`); prints the fit",
    )
    fit.add_argument("estimates", nargs="+", type=Path, help="estimate CSV file(s), one per controller")
    fit.add_argument("--free", type=_names, default=["kyy", "kiy", "amp_bandwidth", "mass_loading"],
                     help=f"rig fields to fit, 'a,b' (default kyy,kiy,amp_bandwidth,mass_loading; any of "
                     f"{', '.join(FITTABLE)})")  # fmt: skip
    fit.add_argument("--periods", type=int, default=10,
                     help="periods averaged in each estimate (its blocks; default 10 as `run`)")  # fmt: skip
    _add_controller_options(fit, several=True)
    fit.set_defaults(func=cmd_fit)
    return fit


def cmd_fit(args: argparse.Namespace) -> None:
    rig = _rig(args)
    estimates = [read_estimate(p, blocks=args.periods, mass=rig.mass) for p in args.estimates]
    controllers = _controllers(args, len(estimates))
    from ._fit import fit_rig  # scipy.optimize and scipy.stats: only for this command

    result = fit_rig(estimates, rig, controllers, free=args.free)
    print(result.report())


def add_design_parser(subparsers: Any, parents: Sequence[argparse.ArgumentParser] = ()) -> argparse.ArgumentParser:
    """Add ``design``: controller parameters for target actual stiffness and damping; prints the design."""
    design = subparsers.add_parser(
        "design",
        allow_abbrev=False,
        parents=list(parents),
        help="choose PID gains for a target actual stiffness and damping",
    )
    design.add_argument("--stiffness", type=float, help="target actual stiffness (N/m)")
    design.add_argument("--damping", type=float, help="target actual damping (N s/m)")
    design.add_argument("--band", type=_band, default=(20.0, 150.0), help="design band 'low:high' (Hz; default 20:150)")
    design.add_argument("--step", type=float, default=1.0, help="frequency step in the band (Hz; default 1)")
    design.add_argument("--free", type=_names, default=["kp", "kd"], help="parameters to choose (default kp,kd)")
    design.add_argument("--max-sensitivity", type=float, help="limit of the sensitivity peak |S| (e.g. 3: zone A)")
    _add_controller_options(design, several=False)
    design.set_defaults(func=cmd_design)
    return design


def cmd_design(args: argparse.Namespace) -> None:
    if args.stiffness is None and args.damping is None:
        raise ValueError("give --stiffness and/or --damping")
    low, high = args.band
    if not (0 < low < high) or args.step <= 0:
        raise ValueError(f"--band must be 0 < low < high and --step > 0, got {low}:{high}, step {args.step}")
    freq = np.arange(low, high + 0.5 * args.step, args.step)
    rig = _rig(args)
    (controller,) = _controllers(args, 1)
    kwargs: dict[str, Any] = dict(freq=freq, stiffness=args.stiffness, damping=args.damping, free=args.free,
                                  max_sensitivity=args.max_sensitivity)  # fmt: skip
    from ._design import design_controller  # scipy.optimize: only for this command

    actual = design_controller(rig, controller, **kwargs)
    naive = design_controller(rig, controller, **kwargs, basis="effective")
    print(actual.report())
    print("")
    gains = ", ".join(f"{n} = {v:.6g}" for n, v in naive.params.items())
    print(f"for comparison, the naive design (effective coefficients on target): {gains}; its actual stiffness "
          f"misses by {naive.k_miss:.4g} N/m rms and its damping by {naive.c_miss:.4g} N s/m rms")  # fmt: skip
