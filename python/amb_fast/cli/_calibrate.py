"""The sub-commands ``fit`` and ``design`` (:mod:`amb_fast.calibration` on the command line)."""

from __future__ import annotations

import argparse
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._experiment import Estimate
from .._params import PID, Rig
from .._sweep import controller_params
from .._toml import load_rig
from .._validate import real
from ..calibration import FITTABLE, PLAIN_PERIODS, read_estimate, records, same_controller
from ..controllers import load_controller, recorded_controller
from ._options import UsageError, _option_names, _started, check_output

_RIG_FIELDS = {f.name for f in fields(Rig)} - {"force_law"}
_PID_FIELDS = ("kp", "ki", "kd", "derivative_cutoff", "fs", "delay")
_CONTROLLER_OPTIONS = [name.replace("_", "-") for name in _PID_FIELDS]
MAX_DESIGN_LINES = 1_000_000  # design frequencies: beyond this --step is a typo, and the arrays fill the memory


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
    parser.add_argument("--set", type=_assignments, metavar="NAME=X,...",
                        help="rig values (SI units, 'none' switches a stage off) replacing those of Rig.paper() (or "
                        "--rig): the fixed values and the start values of the free ones, e.g. --set "
                        "amp_bandwidth=2000,dead_time=1e-4")  # fmt: skip


def _rig(args: argparse.Namespace) -> Rig:
    changes = dict(args.set or {})
    unknown = set(changes) - _RIG_FIELDS
    if unknown:
        raise ValueError(f"--set: {sorted(unknown)} are not Rig fields ({', '.join(sorted(_RIG_FIELDS))})")
    if "substeps" in changes:  # a whole number: 2.5 is a typo, not 2
        substeps = changes["substeps"]
        if substeps is None or not float(substeps).is_integer():
            raise UsageError(f"--set substeps must be a whole number >= 1, got {substeps}")
        changes["substeps"] = int(substeps)
    base = load_rig(args.rig) if args.rig is not None else Rig.paper()
    try:
        return replace(base, **changes)
    except ValueError as error:  # "mass must be ...": the value came from --set
        raise UsageError(f"--set: {error}") from None


def _controller_options(args: argparse.Namespace, count: int) -> list[tuple[dict[str, Any], Any]]:
    """Per estimate: the PID options given (``--kp a,b`` one value per file) and the ``(path, controller)`` of
    ``--controller`` (or None)."""
    options: list[dict[str, Any]] = [{} for _ in range(count)]
    for name in _PID_FIELDS:
        values = getattr(args, name)
        if values is None:
            continue
        values = values if isinstance(values, list) else [values]
        if len(values) not in (1, count):
            raise ValueError(f"--{name} must give one value or one per estimate ({count}), got {len(values)}")
        for i in range(count):
            options[i][name] = values[i if len(values) > 1 else 0]
    files = args.controller or []
    if not files:
        return [(opts, None) for opts in options]
    if any(options):
        given = ", ".join(sorted({"--" + n.replace("_", "-") for o in options for n in o}))
        raise ValueError(f"{given} cannot go with --controller (the file sets the controller, its fs and delay)")
    if len(files) not in (1, count):
        raise ValueError(f"--controller must be given once or once per estimate file ({count}), got {len(files)}")
    loaded = {str(f): load_controller(f) for f in files}
    return [({}, (f, loaded[str(f)])) for f in (files if len(files) == count else files * count)]


def _same_value(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is b
    return bool(np.isclose(float(a), float(b), rtol=1e-12, atol=0.0))


def _fit_controllers(
    args: argparse.Namespace, estimates: list[Estimate], paths: list[Path]
) -> tuple[list[Any], list[str]]:
    """The controller of each estimate file and where it comes from: the one the file records (an option
    or --controller that contradicts it is an error), else --controller or PID.paper() with the options."""
    out, notes = [], []
    for est, path, (opts, file) in zip(estimates, paths, _controller_options(args, len(estimates))):
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


def add_fit_parser(subparsers: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add ``fit``: calibrate the rig to one or more estimate CSVs and print the report."""
    help = "calibrate the rig model to estimates (CSV of `run --save`); prints the fit"
    fit = subparsers.add_parser("fit", parents=parents, help=help)
    fit.add_argument("estimates", nargs="+", type=Path, help="estimate CSV file(s), one per controller")
    fit.add_argument("--free", type=_names, default=["kyy", "kiy", "amp_bandwidth", "mass_loading"],
                     help=f"rig fields to fit, 'a,b' (default kyy,kiy,amp_bandwidth,mass_loading; any of "
                     f"{', '.join(FITTABLE)})")  # fmt: skip
    fit.add_argument("--periods", type=int,
                     help="periods averaged in each estimate (its blocks) of a plain CSV table; a file saved by "
                     f"`run --save` records them (default: the file's, {PLAIN_PERIODS} for a plain "
                     "table)")  # fmt: skip
    fit.add_argument("--out", type=Path, help="write the fitted rig to a rig file (.toml; `design --rig`, "
                     "`run --rig`, amb_fast.load_rig read it)")  # fmt: skip
    _add_controller_options(fit, several=True)
    fit.set_defaults(func=cmd_fit, option_names=_option_names("free", "periods", *_CONTROLLER_OPTIONS))


def cmd_fit(args: argparse.Namespace) -> None:
    if args.out is not None:
        check_output(args.out, "--out", (".toml",), args.overwrite)
    if args.periods is not None and args.periods < 4:
        raise ValueError(f"--periods must be >= 4 (standard errors need several periods), got {args.periods}")
    rig = _rig(args)
    paths = list(args.estimates)
    estimates = [read_estimate(p, blocks=args.periods, mass=rig.mass) for p in paths]
    controllers, notes = _fit_controllers(args, estimates, paths)
    _check_fit(args, rig, estimates, paths, controllers)
    from ..calibration import fit_rig  # scipy.optimize and scipy.stats: only for this command

    _started(args)
    result = fit_rig(estimates, rig, controllers, free=args.free)
    for i, (path, est, note) in enumerate(zip(paths, estimates, notes)):
        periods = "recorded in the file" if records(path) else "--periods" if args.periods else "the default"
        print(f"estimates[{i}] = {str(path)!r}: {note}; {est.blocks} periods averaged ({periods})")
    print("")
    print(result.report())
    if args.out is not None:
        result.save(args.out)
        print(f"\nwrote the fitted rig to {str(args.out)!r}")


def _check_fit(
    args: argparse.Namespace, rig: Rig, estimates: list[Estimate], paths: list[Path], controllers: list[Any]
) -> None:
    """What :func:`fit_rig` would refuse only once the command has started: --free, and estimate files it
    cannot weigh or combine (mistakes in the command line or its files, exit status 2)."""
    _check_free(args.free, list(FITTABLE), "a rig field the fit can choose")
    for name in args.free:
        if getattr(rig, name) is None:
            raise UsageError(f"--free {name}: the rig's {name} is 'none' (its stage is off), so the fit has no start "
                             f"value; give one with --set {name}=X")  # fmt: skip
    for est, path in zip(estimates, paths):
        if est.blocks < 4:
            raise UsageError(
                f"{str(path)!r} averages {est.blocks} periods; a fit needs >= 4 (standard errors from "
                "fewer cannot weight it)" + ("" if records(path) else "; give them with --periods")
            )
        weights = np.concatenate([np.asarray(est.k_std, float), np.asarray(est.c_std, float)])
        if not np.all(np.isfinite(weights) & (weights > 0)):
            raise UsageError(f"{str(path)!r} has standard errors k_std, c_std that are not all finite and > 0 (a "
                             "noise-free estimate has no weights to fit with)")  # fmt: skip
    rates = sorted({float(c.fs) for c in controllers})
    if len(rates) > 1:
        raise UsageError(f"the estimates' controllers run at different fs {rates} Hz: fit estimates of one rig at "
                         "one fs")  # fmt: skip


def _check_free(free: list[str], known: list[str], what: str) -> None:
    """``--free``: one or more distinct names, each one of ``known``."""
    if not free or len(set(free)) != len(free):
        raise UsageError(f"--free must name one or more distinct parameters, got {','.join(free)!r}")
    for name in free:
        if name not in known:
            raise UsageError(f"--free: {name!r} is not {what}; one of {', '.join(known)}")


def add_design_parser(subparsers: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add ``design``: controller parameters for target actual stiffness and damping; prints the design."""
    design = subparsers.add_parser("design", parents=parents,
                                   help="choose PID gains for a target actual stiffness and damping")  # fmt: skip
    design.add_argument("--stiffness", type=float, help="target actual stiffness (N/m)")
    design.add_argument("--damping", type=float, help="target actual damping (N s/m)")
    design.add_argument("--band", type=_band, help="design band 'low:high' (Hz; default 20:150, or up to the "
                        "controller's fs/2 when that is lower)")  # fmt: skip
    design.add_argument("--step", type=float, help="frequency step in the band (Hz; default 1, or a 20th of a band "
                        "narrower than 20 Hz)")  # fmt: skip
    design.add_argument("--free", type=_names, default=["kp", "kd"], help="parameters to choose (default kp,kd)")
    design.add_argument("--max-sensitivity", type=float, help="limit of the sensitivity peak |S| (e.g. 3: zone A)")
    design.add_argument("--out", type=Path, help="write the designed controller to a controller file (.toml; "
                        "`run --controller`, amb_fast.load_controller read it)")  # fmt: skip
    _add_controller_options(design, several=False)
    design.set_defaults(func=cmd_design, option_names=_option_names("stiffness", "damping", "max-sensitivity", "free",
                                                                    "step", *_CONTROLLER_OPTIONS))  # fmt: skip


def cmd_design(args: argparse.Namespace) -> None:
    if args.out is not None:
        check_output(args.out, "--out", (".toml",), args.overwrite)
    if args.stiffness is None and args.damping is None:
        raise ValueError("give --stiffness and/or --damping")
    for option, value, unit in (("--stiffness", args.stiffness, "N/m"), ("--damping", args.damping, "N s/m")):
        if value is not None:  # here, not in the design: a NaN target is an input mistake (exit status 2)
            real(option, value, unit)
    if args.max_sensitivity is not None and not (np.isfinite(args.max_sensitivity) and args.max_sensitivity > 1):
        raise UsageError(f"--max-sensitivity must be a finite |S| peak > 1 (3: ISO 14839-3 zone A), got "
                         f"{args.max_sensitivity:g}")  # fmt: skip
    low, high = (20.0, 150.0) if args.band is None else args.band
    if not (np.isfinite(high) and 0 < low < high):
        raise UsageError(f"--band must be finite frequencies 0 < low < high (Hz), got {low:g}:{high:g}")
    step = min(1.0, (high - low) / 20) if args.step is None else args.step  # a narrow band keeps 21 frequencies
    real("--step", step, "Hz", positive=True)
    if (high - low) / step > MAX_DESIGN_LINES:
        raise UsageError(f"--step {step:g} gives {(high - low) / step:.3g} frequencies in {low:g}:{high:g} Hz; at "
                         f"most {MAX_DESIGN_LINES} (a larger --step)")  # fmt: skip
    rig = _rig(args)
    ((options, file),) = _controller_options(args, 1)
    controller = file[1] if file is not None else replace(PID.paper(), **options)
    params = controller_params(controller)
    on_rig = [name for name in args.free if name in _RIG_FIELDS]
    if on_rig:
        raise UsageError(f"--free: {on_rig[0]!r} is a rig field; design chooses controller parameters (fit fits the "
                         "rig)")  # fmt: skip
    _check_free(args.free, list(params), "a parameter of the controller")
    for name in args.free:
        if params[name] is None:
            where = "the controller file" if file is not None else f"--{name.replace('_', '-')} X"
            raise UsageError(f"--free {name}: the controller's {name} is 'none', so the design has no start value; "
                             f"give one ({where})")  # fmt: skip
    freq = np.arange(low, high + 0.5 * step, step)
    nyquist = controller.fs / 2
    if args.band is None:  # the default follows the controller's fs (--fs 200: 20-99 Hz)
        freq = freq[freq < nyquist]
        if freq.size == 0:  # no --band was given: say so, and what to give
            raise UsageError(f"the default band {low:g}:{high:g} Hz lies above fs/2 = {nyquist:g} Hz (the controller "
                             f"samples at {controller.fs:g} Hz): give a --band below it")  # fmt: skip
    if freq.size == 0 or freq[-1] >= nyquist:
        raise UsageError(f"--band must lie below fs/2 = {nyquist:g} Hz (the controller samples at {controller.fs:g} "
                         f"Hz), got {low:g}:{high:g}")  # fmt: skip
    kwargs: dict[str, Any] = dict(freq=freq, stiffness=args.stiffness, damping=args.damping, free=args.free,
                                  max_sensitivity=args.max_sensitivity)  # fmt: skip
    from ..calibration import design_controller  # scipy.optimize: only for this command

    _started(args)
    actual = design_controller(rig, controller, **kwargs)
    naive = design_controller(rig, controller, **kwargs, basis="effective")
    print(actual.report())
    print("")
    gains = ", ".join(f"{n} = {v:.6g}" for n, v in naive.params.items())
    print(f"for comparison, the naive design (effective coefficients on target): {gains}; its actual "
          + naive.misses_text())  # fmt: skip
    if args.out is not None:
        actual.save(args.out)
        print(f"\nwrote the designed controller to {str(args.out)!r}")
