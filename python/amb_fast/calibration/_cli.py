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
from .._linear import AnyController
from .._params import PID, Rig
from .._toml import load_rig
from ..controllers import load_controller, recorded_controller
from ..io import load_estimate
from ._problem import FITTABLE, same_controller

_PLAIN_PERIODS = 10  # periods of a plain CSV table (which does not record them): `run`'s default

_COLUMNS = ("freq_Hz", "H_real_N_per_m", "H_imag_N_per_m", "k_std_N_per_m", "c_std_Ns_per_m")
_RIG_FIELDS = {f.name for f in fields(Rig)} - {"force_law"}


def read_estimate(path: str | Path, *, blocks: int | None, mass: float) -> Estimate:
    """An estimate from a file that ``amb-fast run --save`` (or ``identify``) writes.

    A file written by :meth:`Estimate.save` (``.nc``, or ``.csv`` with its checksum line) is read whole
    by :func:`amb_fast.load_estimate`: it records its periods (and its controller), and ``blocks``, when
    given, must agree (``--periods``). A plain CSV table with the columns of that file holds neither the
    periods nor the known mass: ``blocks`` (the periods averaged, up to 63; default 10 as ``run``) and
    ``mass`` (kg) are given, and force and displacement amplitudes are NaN.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"estimate file {str(path)!r} does not exist")
    if _records(path):
        estimate = load_estimate(path)
        if not isinstance(estimate, Estimate):  # an EstimateN's file: fitting takes one axis
            raise ValueError(
                f"{str(path)!r} holds an estimate of {len(estimate.axes)} axes; the fit takes a one-axis estimate"
            )
        if blocks is not None and blocks != estimate.blocks:
            raise ValueError(f"--periods {blocks} contradicts {str(path)!r}, which records {estimate.blocks} periods "
                             "averaged; leave --periods out for a file that records them")  # fmt: skip
        return estimate
    blocks = _PLAIN_PERIODS if blocks is None else blocks
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


def _records(path: Path) -> bool:
    """Whether an estimate file is one :meth:`Estimate.save` wrote (it records its periods and controller)."""
    with path.open("rb") as head:
        return path.suffix.lower() == ".nc" or head.read(10) == b"# sha256: "


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
    base = load_rig(args.rig) if args.rig is not None else Rig.paper()
    return replace(base, **changes)


def _add_controller_options(parser: argparse.ArgumentParser, several: bool) -> None:
    default = "the one each file records, else PID.paper()" if several else "PID.paper()"
    group = parser.add_argument_group(f"controller (default: {default})")
    each = " (one per estimate file, 'a,b')" if several else ""
    for name, unit in (("kp", "A/m"), ("ki", "A/(m s)"), ("kd", "A s/m")):
        group.add_argument(f"--{name}", type=_list, help=f"{name} ({unit}){each}")
    group.add_argument("--derivative-cutoff", type=float, help="derivative filter corner (Hz)")
    group.add_argument("--fs", type=float, help="sampling frequency (Hz)")
    group.add_argument("--delay", type=int, help="computation delay (whole samples)")
    group.add_argument("--controller", type=Path, action="append", metavar="FILE",
                       help="any controller from a TOML or JSON file (docs/controllers.md) instead of the PID"
                       + (" (once, or once per estimate file)" if several else ""))  # fmt: skip
    parser.add_argument("--rig", type=Path, metavar="FILE",
                        help="rig file (TOML or JSON, as `fit --out` writes) replacing Rig.paper(): the fixed values "
                        "and the start values of the free ones")  # fmt: skip
    parser.add_argument(
        "--set",
        type=_assignments,
        metavar="NAME=X,...",
        help="rig values (SI units, 'none' switches a stage off) replacing those of Rig.paper() (or --rig): the fixed "
        "values and the start values of the free ones, e.g. --set amp_bandwidth=2000,dead_time=1e-4",
    )


_PID_FIELDS = ("kp", "ki", "kd", "derivative_cutoff", "fs", "delay")


def _pid_options(args: argparse.Namespace, count: int) -> list[dict[str, Any]]:
    """The PID options given, per estimate: ``[{field: value}, ...]`` (``--kp a,b`` one value per file)."""
    out: list[dict[str, Any]] = [{} for _ in range(count)]
    for name in _PID_FIELDS:
        values = getattr(args, name)
        if values is None:
            continue
        if not isinstance(values, list):
            values = [values]
        if len(values) not in (1, count):
            raise ValueError(f"--{name} must give one value or one per estimate ({count}), got {len(values)}")
        for i in range(count):
            out[i][name] = values[i if len(values) > 1 else 0]
    return out


def _controller_files(args: argparse.Namespace, count: int, options: list[dict[str, Any]]) -> list[Any]:
    files = args.controller or []
    if not files:
        return [None] * count
    if any(options):
        given = ", ".join(sorted({"--" + n.replace("_", "-") for o in options for n in o}))
        raise ValueError(f"{given} cannot go with --controller (the file sets the controller, its fs and delay)")
    if len(files) not in (1, count):
        raise ValueError(f"--controller must be given once or once per estimate file ({count}), got {len(files)}")
    loaded = {str(f): load_controller(f) for f in files}
    return [(f, loaded[str(f)]) for f in (files if len(files) == count else files * count)]


def _controllers(args: argparse.Namespace, count: int) -> list[AnyController]:
    """The controller of the ``design`` command: ``--controller FILE``, or PID.paper() with the options."""
    options = _pid_options(args, count)
    files = _controller_files(args, count, options)
    return [file[1] if file is not None else replace(PID.paper(), **opts) for file, opts in zip(files, options)]


def _same_value(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is b
    return bool(np.isclose(float(a), float(b), rtol=1e-12, atol=0.0))


def _fit_controllers(
    args: argparse.Namespace, estimates: list[Estimate], paths: list[Path]
) -> tuple[list[Any], list[str]]:
    """The controller of each estimate file and where it comes from: the one the file records (an option
    or --controller that contradicts it is an error), else --controller or PID.paper() with the options."""
    options = _pid_options(args, len(estimates))
    files = _controller_files(args, len(estimates), options)
    out, notes = [], []
    for est, path, opts, file in zip(estimates, paths, options, files):
        record = recorded_controller(est.meta.get("controller"))
        if record is None:
            if file is not None:
                out.append(file[1])
                notes.append(f"controller of --controller {str(file[0])!r} (the file records none)")
            else:
                out.append(replace(PID.paper(), **opts))
                notes.append("PID.paper()" + (" with the options given" if opts else "")
                             + " (the file records no controller)")  # fmt: skip
            continue
        if file is not None and not same_controller(file[1], record, np.asarray(est.freq, dtype=float)):
            raise ValueError(f"--controller {str(file[0])!r} ({file[1]!r}) contradicts {str(path)!r}, which records "
                             f"{record!r}; leave --controller out for a file that records its controller")  # fmt: skip
        for name, value in opts.items():
            option = "--" + name.replace("_", "-")
            if not isinstance(record, PID):
                raise ValueError(f"{option} {value:g} contradicts {str(path)!r}, which records a controller that is "
                                 f"not a PID ({record!r}); leave {option} out")  # fmt: skip
            if not _same_value(value, getattr(record, name)):
                raise ValueError(f"{option} {value:g} contradicts {str(path)!r}, which records {name} = "
                                 f"{getattr(record, name)}; leave {option} out for a file that records its "
                                 "controller")  # fmt: skip
        out.append(record)
        notes.append("controller recorded in the file")
    return out, notes


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
    fit.add_argument("--periods", type=int,
                     help="periods averaged in each estimate (its blocks) of a plain CSV table; a file saved by "
                     f"`run --save` records them (default: the file's, {_PLAIN_PERIODS} for a plain "
                     "table)")  # fmt: skip
    fit.add_argument("--out", type=Path, help="write the fitted rig to a rig file (.toml; `design --rig`, "
                     "`run --rig`, amb_fast.load_rig read it)")  # fmt: skip
    _add_controller_options(fit, several=True)
    fit.set_defaults(func=cmd_fit)
    return fit


def cmd_fit(args: argparse.Namespace) -> None:
    if args.out is not None:
        _check_output(args.out, args.overwrite)
    if args.periods is not None and args.periods < 4:
        raise ValueError(f"--periods must be >= 4 (standard errors need several periods), got {args.periods}")
    rig = _rig(args)
    paths = list(args.estimates)
    estimates = [read_estimate(p, blocks=args.periods, mass=rig.mass) for p in paths]
    controllers, notes = _fit_controllers(args, estimates, paths)
    from ._fit import fit_rig  # scipy.optimize and scipy.stats: only for this command

    args.phase = "run"  # the options and files are checked: a failure from here is not a usage error
    result = fit_rig(estimates, rig, controllers, free=args.free)
    for i, (path, est, note) in enumerate(zip(paths, estimates, notes)):
        periods = "recorded in the file" if _records(path) else "--periods" if args.periods else "the default"
        print(f"estimates[{i}] = {str(path)!r}: {note}; {est.blocks} periods averaged ({periods})")
    print("")
    print(result.report())
    if args.out is not None:
        result.save(args.out)
        print(f"\nwrote the fitted rig to {str(args.out)!r}")


def _check_output(path: Path, overwrite: bool) -> None:
    if path.suffix.lower() != ".toml":
        raise ValueError(f"--out must end in .toml, got {str(path)!r}")
    if not (path.parent if str(path.parent) else Path(".")).is_dir():
        raise ValueError(f"--out: the directory {str(path.parent)!r} does not exist")
    if path.exists() and not overwrite:
        raise ValueError(f"--out: {str(path)!r} exists; pass --overwrite to replace it")


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
    design.add_argument("--out", type=Path, help="write the designed controller to a controller file (.toml; "
                        "`run --controller`, amb_fast.load_controller read it)")  # fmt: skip
    _add_controller_options(design, several=False)
    design.set_defaults(func=cmd_design)
    return design


def cmd_design(args: argparse.Namespace) -> None:
    if args.out is not None:
        _check_output(args.out, args.overwrite)
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

    args.phase = "run"
    actual = design_controller(rig, controller, **kwargs)
    naive = design_controller(rig, controller, **kwargs, basis="effective")
    print(actual.report())
    print("")
    gains = ", ".join(f"{n} = {v:.6g}" for n, v in naive.params.items())
    print(
        f"for comparison, the naive design (effective coefficients on target): {gains}; its actual "
        + naive.misses_text()
    )
    if args.out is not None:
        actual.save(args.out)
        print(f"\nwrote the designed controller to {str(args.out)!r}")
