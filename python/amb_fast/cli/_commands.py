"""The sub-commands ``run``, ``sweep``, ``identify`` and ``paper``."""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._experiment import Estimate, identify, run_experiment
from .._linear import AnyController, closed_loop_poles, require_stable, stability_margin
from .._params import Rig
from .._sweep import RIG_FIELDS, controller_params, point_model, sweep
from .._sweep_result import SWEPT
from .._validate import integer, real
from ..claims import natural_frequency
from ..io import load_recording
from ..two_axis import run_two_axis, two_axis_model
from ._options import (
    ESTIMATE_SUFFIXES,
    FIGURE_SUFFIXES,
    PID_OPTIONS,
    RIG_OPTIONS,
    SWEEP_SUFFIXES,
    TWO_AXIS_SUFFIXES,
    UsageError,
    _excitation,
    _model,
    _needs,
    _save_figure,
    _started,
    _values,
    at_lines,
    check_output,
    check_output_dir,
    check_save_and_figure,
)


def natural_frequency_line(estimate: Estimate) -> str:
    """The natural frequency where Re F/Y crosses zero; where it does not within the band, why not (never NaN)."""
    fn = natural_frequency(estimate.freq, estimate.H)
    if np.isfinite(fn):
        return f"natural frequency   {fn:.3f} Hz (where Re F/Y = 0)"
    real = np.real(estimate.H)
    band = f"{estimate.freq[0]:g}-{estimate.freq[-1]:g} Hz"
    if np.all(real > 0):
        why = f"Re F/Y > 0 throughout: the resonance lies above {estimate.freq[-1]:g} Hz; raise --f-max"
    elif np.all(real <= 0):
        why = f"Re F/Y <= 0 throughout: the resonance lies below {estimate.freq[0]:g} Hz"
    else:
        why = "Re F/Y only rises through zero: no resonance"
    return f"natural frequency   none in {band} ({why})"


def _report(estimate: Estimate, at: Sequence[float], *notes: str) -> str:
    """The natural frequency, the peak of |Y/F|, ``notes``, then k and c (with their standard errors) and |Y/F| at
    the excited lines nearest to ``at`` (Hz); weak lines (force or displacement under 10x the unexcited level) are
    marked."""
    peak = int(np.argmax(np.abs(estimate.receptance)))
    weak = np.zeros(estimate.freq.size, bool) if estimate.weak is None else np.asarray(estimate.weak, bool)
    lines = [natural_frequency_line(estimate),
             f"peak |Y/F|          {abs(estimate.receptance[peak]):.4g} m/N at {estimate.freq[peak]:g} Hz", *notes, "",
             f"{'f (Hz)':>8} {'k (N/m)':>12} {'+-k (N/m)':>10} {'c (N s/m)':>12} {'+-c (N s/m)':>11} "
             f"{'|Y/F| (m/N)':>12}"]  # fmt: skip
    for f in at:
        i = int(np.argmin(np.abs(estimate.freq - f)))
        lines.append(f"{estimate.freq[i]:8g} {estimate.k[i]:12.6g} {estimate.k_std[i]:10.3g} {estimate.c[i]:12.6g} "
                     f"{estimate.c_std[i]:11.3g} {abs(estimate.receptance[i]):12.4g}"
                     + ("  weak" if weak[i] else ""))  # fmt: skip
    return "\n".join(lines)


def cmd_run(args: argparse.Namespace) -> None:
    check_save_and_figure(args, TWO_AXIS_SUFFIXES if args.two_axis else ESTIMATE_SUFFIXES)
    rig, pid = _model(args)
    excitation = _excitation(args, pid)
    args.at = at_lines(args.at, excitation.freq)
    integer("--periods", args.periods, 2)
    if args.settle_periods is not None:
        integer("--settle-periods", args.settle_periods, 0)
    cross = {"kxy": "N/m", "kyx": "N/m", "cxy": "N s/m", "cyx": "N s/m", "sensor_angle": "rad", "cross_kp": "A/m"}
    for name, unit in cross.items():  # here, not in the run: a NaN is an input mistake, named by its option
        real("--" + name.replace("_", "-"), getattr(args, name), unit)
    if args.two_axis:
        if rig.force_law != "linear":  # the library names x.force_law; this is the rig of the options
            raise UsageError(f"--two-axis models the linear force law only; the rig's is {rig.force_law!r} "
                             "(--force-law or --rig)")  # fmt: skip
        two_axis_model(args, rig, pid)  # an unstable loop is a mistake in the options, as with one axis
        _started(args)
        run_two_axis(args, rig, pid, excitation)
        return
    if any(getattr(args, name) for name in cross):
        raise UsageError("--kxy, --kyx, --cxy, --cyx, --sensor-angle and --cross-kp need --two-axis")
    require_stable(rig, pid)
    _started(args)
    estimate = run_experiment(
        rig, pid, excitation, periods=args.periods, settle_periods=args.settle_periods, seed=args.seed
    )
    margin = stability_margin(rig, pid)
    print(_report(
        estimate, args.at,
        f"stability margin    peak |S| = {margin.peak:.3f} ({margin.peak_db:.1f} dB) at {margin.frequency:.1f} Hz, "
        f"ISO 14839-3 zone {margin.zone}",
        f"slowest pole        |z| = {np.abs(closed_loop_poles(rig, pid)).max():.6f}",
        f"periods averaged    {estimate.periods}",
    ))  # fmt: skip
    if args.save:
        estimate.save(args.save)
        print(f"wrote {args.save}")
    if args.figure:
        from ..plots import plot_estimate

        _save_figure(plot_estimate(estimate), args.figure, estimate.meta)
        print(f"wrote {args.figure}")


def _swept(args: argparse.Namespace, controller: AnyController) -> dict[str, Any]:
    """The sweep's axes, as :func:`amb_fast.sweep` takes them: ``--kp/--ki/--kd`` and every ``--vary NAME=VALUES``
    (a Rig field or a controller parameter), in the order given; refused before any work when a name is unknown,
    given twice, or also set to one value by its own option."""
    axes: dict[str, Any] = {n: getattr(args, n) for n in ("kp", "ki", "kd") if getattr(args, n) is not None}
    known = [*RIG_FIELDS, *controller_params(controller)]
    for item in args.vary:
        name, equals, text = item.partition("=")
        name = name.strip().replace("-", "_")
        if not equals or not name:
            raise UsageError(f"--vary takes NAME=VALUES (e.g. --vary amp_bandwidth=1000:3000:5), got {item!r}")
        if name not in known:
            raise UsageError(f"--vary: {name!r} is neither a numeric rig field nor a parameter of the controller; "
                             f"one of {', '.join(known)}")  # fmt: skip
        if name in axes:
            raise UsageError(f"--vary {name}: {name} is already swept ({'--' + name if name in SWEPT else '--vary'})")
        option = name.replace("_", "-")
        if name not in SWEPT and hasattr(args, name) and option in RIG_OPTIONS | PID_OPTIONS:  # given (SUPPRESS)
            raise UsageError(f"--{option} sets {name} to one value and --vary sweeps it: give one of them")
        try:
            axes[name] = _values(text)
        except argparse.ArgumentTypeError as error:
            raise UsageError(f"--vary {name}: {error}") from None
    return axes


def _check_swept_values(args: argparse.Namespace, rig: Rig, controller: AnyController, axes: dict[str, Any]) -> None:
    """The swept values as the run builds its points: a value the rig or the controller refuses (``--vary
    mass=-1``, ``--kp nan``, a notch above fs/2) is a mistake in the options, refused before the work. Every
    value is checked finite; the smallest and largest on the rig or controller (their limits are bounds)."""
    for name, values in axes.items():
        option = f"--{name}" if name in SWEPT and getattr(args, name, None) is not None else f"--vary {name}"
        values = np.asarray(values, dtype=float)
        if not np.all(np.isfinite(values)):
            raise UsageError(f"{option} must be finite values, got {values[~np.isfinite(values)].tolist()}")
        for value in {float(values.min()), float(values.max())}:
            try:
                point_model(rig, controller, {name: value})
            except ValueError as error:
                raise UsageError(f"{option} {value:g}: {error}") from None


def cmd_sweep(args: argparse.Namespace) -> None:
    if args.out is None:  # NetCDF only where its extra is installed: no option asked for it
        netcdf = all(importlib.util.find_spec(m) is not None for m in ("h5netcdf", "xarray"))
        args.out = "sweep.nc" if netcdf else "sweep.npz"
    out = check_output(Path(args.out), "--out", SWEEP_SUFFIXES, args.overwrite)
    if out.suffix.lower() == ".nc":
        _needs("h5netcdf", "xarray", "--out .nc")
        if args.grid == "zip":  # written through xarray (product grids are written directly)
            _needs("xarray", "xarray", "--out .nc with --grid zip")
    rig, pid = _model(args, gains=False)
    axes = _swept(args, pid)
    if not axes:
        raise UsageError("give at least one of --kp, --ki, --kd, --vary (e.g. --kp 2000:3000:11 or "
                         "--vary amp_bandwidth=1000:3000:5)")  # fmt: skip
    given = {name: len(values) for name, values in axes.items()}
    if args.grid == "zip" and len(set(given.values())) > 1:
        raise UsageError(f"--grid zip needs as many values of each swept parameter, got {given}")
    if any(n == 0 for n in given.values()):
        raise UsageError("every swept parameter needs at least one value")
    if args.workers is not None:
        integer("--workers", args.workers, 1)
    integer("--periods", args.periods, 2)
    if args.settle_periods is not None:
        integer("--settle-periods", args.settle_periods, 0)
    _check_swept_values(args, rig, pid, axes)
    excitation = _excitation(args, pid)
    _started(args)
    result = sweep(rig, pid, excitation, **axes, grid=args.grid, periods=args.periods,
                   settle_periods=args.settle_periods, workers=args.workers, seed=args.seed,
                   progress=None if not args.no_progress else False)  # fmt: skip
    counts = {s: int(np.sum(result.status == s)) for s in np.unique(result.status)}
    print(f"{result.status.size} points: " + ", ".join(f"{n} {s}" for s, n in counts.items()))
    result.save(out)
    other_tools = (
        " (a table for other tools: amb_fast.load_sweep reads .nc and .npz)" if out.suffix.lower() == ".csv" else ""
    )
    print(f"wrote {out}{other_tools}")


def _channel(text: str) -> str | int:
    """A channel by name, or by 0-based column index when all digits."""
    return int(text) if text.isdigit() else text


def _rig_mass(meta: object) -> float | None:
    rig = meta.get("rig") if isinstance(meta, dict) else None
    mass = rig.get("mass") if isinstance(rig, dict) else None
    return float(mass) if isinstance(mass, (int, float)) and np.isfinite(mass) and mass > 0 else None


def _file_mass(path: Path) -> float | None:
    """The moving mass (kg) a recording written by amb_fast records (``simulate(...).save``, ``save_recording``
    with a rig in ``meta``: the ``# meta:`` line at the end of a text file, the ``amb_fast`` text variable of a
    ``.mat``), else None."""
    suffix = path.suffix.lower()
    if suffix == ".mat":
        from scipy.io import loadmat

        try:  # a v7.3 (HDF5) or damaged file records nothing here; the reader reports a damaged one
            stamp = loadmat(path, variable_names=["amb_fast"]).get("amb_fast")
            return None if stamp is None else _rig_mass(json.loads(str(np.asarray(stamp).ravel()[0])))
        except Exception:  # noqa: BLE001
            return None
    if suffix not in (".csv", ".tsv", ".txt"):
        return None
    with path.open("rb") as handle:  # the metadata trails the data: read the last 64 kB only
        handle.seek(max(0, path.stat().st_size - 65536))
        tail = handle.read().decode("utf-8", errors="replace")
    for line in reversed(tail.splitlines()):
        if line.startswith("# meta: "):
            try:
                return _rig_mass(json.loads(line[len("# meta: ") :]))
            except ValueError:
                return None
    return None


def _read_recording(args: argparse.Namespace):  # noqa: ANN202
    """The recording; a file that cannot be read is a mistake in the input (exit status 2), whatever the reader
    raised (scipy's MatReadError, nptdms's errors, ...)."""
    options: dict = {"force": _channel(args.force), "displacement": _channel(args.displacement), "fs": args.fs,
                     "recording": args.recording}  # fmt: skip
    if args.time is not None:  # else the reader's default time column
        options["time"] = None if args.time.lower() == "none" else _channel(args.time)
    scale = {role: value for role, value in (("force", args.force_scale), ("displacement", args.displacement_scale))
             if value is not None}  # fmt: skip
    for role, value in scale.items():
        if not (math.isfinite(value) and value != 0.0):
            raise UsageError(f"--{role}-scale must be a finite number != 0 ({'N' if role == 'force' else 'm'} per "
                             f"unit of the file), got {value:g}")  # fmt: skip
    if scale:
        options["scale"] = scale
    try:
        return load_recording(args.file, **options)
    except (ValueError, OSError, ImportError, UsageError):
        raise
    except Exception as error:
        raise UsageError(f"{args.file}: could not read it ({type(error).__name__}: {error})") from error


def cmd_identify(args: argparse.Namespace) -> None:
    # The inputs first (the options, the file), then the outputs, then the work: the recording is read and
    # analysed before anything is written, and every mistake found so far is an input mistake (status 2).
    integer("--settle-periods", args.settle_periods, 0)
    integer("--median-window", args.median_window, 1)
    if args.median_window % 2 == 0:
        raise UsageError(f"--median-window must be odd, got {args.median_window}")
    for option, value in (("--f0", args.f0), ("--mass", args.mass), ("--f-max", args.f_max), ("--fs", args.fs),
                          ("--clearance", args.clearance)):  # fmt: skip
        if value is not None and not (np.isfinite(value) and value > 0):
            raise UsageError(f"{option} must be a finite number > 0, got {value}")
    if args.at is not None and not np.all(np.isfinite(args.at)):
        raise UsageError(f"--at must be finite frequencies (Hz), got {args.at.tolist()}")
    if not args.file.exists():
        raise UsageError(f"the recording {str(args.file)!r} does not exist")
    if not args.file.is_file():
        raise UsageError(f"the recording {str(args.file)!r} is not a file")
    mass, mass_from = args.mass, "--mass"
    if mass is None:
        mass, mass_from = _file_mass(args.file), f"recorded in {args.file.name}"
    if mass is None:  # no silent guess: the stiffness is k = Re F/Y + m w^2, so the mass sets every k
        raise UsageError(f"--mass is needed: {args.file.name} does not record the moving mass (kg) of paper eq. 9 "
                         "(the paper rig's is 0.92)")  # fmt: skip
    figure = args.figure if args.figure is not None else args.out / "estimate.png"
    if args.figure is not None:
        check_output(args.figure, "--figure", FIGURE_SUFFIXES, args.overwrite)
    check_output_dir(args.out, "--out", ("estimate.csv",) if args.figure else ("estimate.csv", "estimate.png"),
                     args.overwrite)  # fmt: skip
    if (args.out / "estimate.csv").resolve() == args.file.resolve():  # --overwrite would replace the input
        raise UsageError(f"--out: {str(args.out / 'estimate.csv')!r} is the recording itself; choose another --out")
    _needs("matplotlib", "plot", "identify (it draws the figure)")
    rec = _read_recording(args)
    try:
        estimate = identify(rec.force, rec.displacement, fs=rec.fs, f0=args.f0, mass=mass, f_max=args.f_max,
                            lines=args.lines, settle_periods=args.settle_periods, median_window=args.median_window,
                            clearance=args.clearance)  # fmt: skip
    except ValueError as error:  # a refused fs says where it came from (the file's clock, or --fs)
        if "fs" in str(error):
            error.args = (f"{error}; {rec.fs_note()}",)
        raise
    args.at = at_lines(args.at, estimate.freq)
    _started(args)
    print(f"{args.file}: {rec.force.size} samples at {rec.fs:g} Hz, {estimate.periods} periods, "
          f"{estimate.freq.size} lines from {estimate.freq[0]:g} to {estimate.freq[-1]:g} Hz")  # fmt: skip
    print(f"mass                {mass:g} kg ({mass_from})")
    if estimate.weak is not None and estimate.weak.any():
        print(f"{int(estimate.weak.sum())} weak lines (force or displacement under 10x the unexcited level)")
    print(_report(estimate, args.at))
    args.out.mkdir(exist_ok=True)
    estimate.save(args.out / "estimate.csv")
    from ..plots import plot_estimate

    title = f"Identified from {Path(args.file).name}"
    _save_figure(plot_estimate(estimate, title=title), figure, {**estimate.meta, "file": str(args.file)})
    print(f"wrote {args.out / 'estimate.csv'} and {figure}")


def cmd_paper(args: argparse.Namespace) -> None:
    from ..paper import output_names, write_paper

    check_output_dir(args.out, "--out", output_names(), args.overwrite)
    _needs("matplotlib", "plot", "paper (it draws the figures)")
    integer("--seed", args.seed, 0)  # here, not in the study: exit status 2, named by its option
    _started(args)
    write_paper(args.out, seed=args.seed, progress=not args.no_progress)
