"""``amb-fast rotor``: the identification of the bearings at speed (shakers or the bearings as exciters), the
Campbell diagram, the ISO 14839-3 sensitivity table and the unbalance run-up of a rotor on two magnetic
bearings, described by a rotor file (TOML) or ``RotorRig.example()``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from .._excitation import schroeder_multisine
from .._validate import integer
from ..system import (
    RotorRig,
    campbell,
    load_rotor,
    measure_sensitivity,
    require_stable,
    run_experiment,
    unbalance_response,
)
from ._options import (
    UsageError,
    _option_names,
    _save_figure,
    _started,
    _values,
    check_save_and_figure,
    default_at,
    default_f_max,
)


def add_rotor_parser(subparsers: Any, parents: list[argparse.ArgumentParser]) -> None:
    rotor = subparsers.add_parser(
        "rotor",
        parents=parents,
        help="a rotor on two bearings: experiment | campbell | sensitivity | unbalance",
    )
    rotor.add_argument("step", choices=["experiment", "campbell", "sensitivity", "unbalance"],
                       help="experiment: the bearings' 4x4 coefficients at speed; campbell: poles against speed; "
                       "sensitivity: the ISO 14839-3 table per axis; unbalance: the run-up's synchronous "
                       "response")  # fmt: skip
    rotor.add_argument("--rotor", type=Path, help="rotor file (.toml; default RotorRig.example() under its PID)")
    rotor.add_argument("--speeds", type=_values, help="rad/s, 'a,b,c' or 'start:stop:count' (default 0:6000:61 for "
                       "campbell; 10:600:120 for unbalance, up to 90 %% of the Nyquist rate pi fs of a controller "
                       "too slow for 600; experiment and sensitivity: the rotor's speed, or the first value "
                       "given)")  # fmt: skip
    rotor.add_argument("--exciter", choices=["shaker", "amb"], default="shaker",
                       help="experiment: shakers at the bearing planes, or the bearings themselves (the multisine "
                       "on the current commands; the force from coil current and probes)")  # fmt: skip
    rotor.add_argument("--rms", type=float, help="experiment: the multisine's rms per axis (default 10 N with "
                       "shakers, 1 A with --exciter amb)")  # fmt: skip
    rotor.add_argument("--save", type=Path, help="experiment: write the estimate (.nc, .npz or .csv; load with "
                       "amb_fast.load_estimate)")  # fmt: skip
    rotor.add_argument("--unbalance", default="1e-4,0.1,0",
                       help="m_e (kg m), z (m), phase (rad) of the unbalance (default 1e-4,0.1,0)")  # fmt: skip
    rotor.add_argument("--periods", type=int, default=10, help="periods averaged (experiment, sensitivity; default 10)")
    rotor.add_argument("--seed", type=int, default=1, help="seed of the noise (experiment, sensitivity)")
    rotor.add_argument("--figure", type=Path, help="write a figure (.png, .pdf or .svg): experiment, campbell and "
                       "unbalance")  # fmt: skip
    rotor.set_defaults(func=cmd_rotor, option_names=_option_names("speeds", "periods", "seed", "rms", "unbalance"))


def _unbalance(text: str) -> list[tuple[float, float, float]]:
    try:
        me, z, phase = (float(v) for v in text.split(","))
    except ValueError:
        raise UsageError(f"--unbalance must be 'm_e,z,phase' (kg m, m, rad), got {text!r}") from None
    if not np.all(np.isfinite([me, z, phase])):  # an input mistake (exit status 2), not a failed run
        raise UsageError(f"--unbalance must be finite numbers 'm_e,z,phase' (kg m, m, rad), got {text!r}")
    return [(me, z, phase)]


def cmd_rotor(args: argparse.Namespace) -> None:
    rig, pid = load_rotor(args.rotor) if args.rotor is not None else (RotorRig.example(), RotorRig.example_controller())
    if args.figure is not None and args.step == "sensitivity":
        raise UsageError("--figure goes with experiment, campbell and unbalance (sensitivity prints a table)")
    for option, value in (("--exciter", args.exciter != "shaker"), ("--rms", args.rms is not None),
                          ("--save", args.save is not None)):  # fmt: skip
        if value and args.step != "experiment":
            raise UsageError(f"{option} goes with experiment, not {args.step}")
    check_save_and_figure(args, (".nc", ".npz", ".csv"))
    if args.rms is not None and not (np.isfinite(args.rms) and args.rms > 0):
        raise UsageError(f"--rms must be a finite amplitude > 0 ({'A' if args.exciter == 'amb' else 'N'} rms), "
                         f"got {args.rms:g}")  # fmt: skip
    unbalance = _unbalance(args.unbalance) if args.step == "unbalance" else None
    # The run-up stays below the Nyquist rate pi fs of a slow controller (fs < 191 Hz).
    top = 600.0 if 600.0 < np.pi * pid.fs else 0.9 * np.pi * pid.fs
    defaults = {"campbell": np.linspace(0.0, 6000.0, 61), "unbalance": np.linspace(min(10.0, top / 2), top, 120)}
    speeds: np.ndarray = args.speeds if args.speeds is not None else defaults.get(args.step, np.zeros(1))
    if speeds.size == 0 or not np.all(np.isfinite(speeds)):
        raise UsageError(f"--speeds must be finite speeds in rad/s, got {args.speeds}")
    if args.step in ("sensitivity", "experiment"):  # options are mistakes before the run (exit 2), not failed runs
        integer("--periods", args.periods, 2)
        integer("--seed", args.seed, 0)
        if args.speeds is not None:  # at the first speed given
            rig = rig.at_speed(float(args.speeds[0]))
        require_stable(rig, pid, f"the closed loop at speed {rig.rotor.speed:g} rad/s")  # as `run` checks its loop
    if args.step == "unbalance" and not np.all(np.abs(speeds) < np.pi * pid.fs):
        raise UsageError(f"--speeds must be below the Nyquist rate pi fs = {np.pi * pid.fs:g} rad/s for unbalance (the "
                         f"controller samples at {pid.fs:g} Hz), got up to {np.abs(speeds).max():g}")  # fmt: skip
    _started(args)
    meta = {"command": f"rotor {args.step}", "rotor": str(args.rotor or "RotorRig.example()")}
    if args.step == "experiment":
        _experiment(rig, pid, args, meta)
    elif args.step == "campbell":
        _campbell(rig, pid, speeds, args, meta)
    elif args.step == "sensitivity":
        _sensitivity(rig, pid, args)
    else:
        _unbalance_run(rig, pid, speeds, unbalance, args, meta)


def _experiment(rig: RotorRig, pid: Any, args: argparse.Namespace, meta: dict) -> None:
    amb = args.exciter == "amb"
    unit = "A" if amb else "N"
    rms = args.rms if args.rms is not None else (1.0 if amb else 10.0)  # 10 N: a 10 kg rotor moves ~ 1 um
    sphs = schroeder_multisine(f0=1.0, f_max=default_f_max(1.0, pid.fs, 200.0), rms=rms, fs=pid.fs)
    est = run_experiment(rig, pid, sphs, exciter=args.exciter, periods=args.periods, seed=args.seed)
    by = "the bearings (current commands)" if amb else "shakers at the bearing planes"
    print(f"Bearing coefficients at {rig.rotor.speed:g} rad/s, excited by {by}: {rms:g} {unit} rms per axis, "
          f"1-{sphs.freq[-1]:g} Hz, {args.periods} periods x {len(est.axes)} experiments")  # fmt: skip
    if amb:
        print("k, c: from H = F Y^-1 with F from the coil currents (the hold and the lags included); "
              "process: the hold and the model's lags removed")  # fmt: skip
    values = est.process if amb and est.process is not None else est.k + 2j * np.pi * est.freq[:, None, None] * est.c
    label = "process" if amb else "actual"
    print(f"{'f (Hz)':>7}  {'entry':<10} {label + ' k (N/m)':>16} {'+- (N/m)':>10} {label + ' c (N s/m)':>18}")
    for f in default_at(est.freq):  # 10, 40, 100, 200 Hz, or lines spread over a lower band (--rotor's fs)
        j = int(np.argmin(np.abs(est.freq - f)))
        w = 2 * np.pi * est.freq[j]
        for a, b in ((0, 0), (0, 1), (2, 2), (2, 3), (0, 2)):
            print(f"{est.freq[j]:7.1f}  {est.axes[a] + '<' + est.axes[b]:<10} {values[j, a, b].real:16.6g} "
                  f"{est.k_std[j, a, b]:10.3g} {values[j, a, b].imag / w:18.6g}")  # fmt: skip
    if args.save is not None:
        print(f"wrote {est.save(args.save)}")
    if args.figure is not None:
        from ..system import effective_coefficients

        effective = effective_coefficients(rig, pid, est.freq) if not amb else None
        _save_figure(est.plot(terms="direct", effective=effective), args.figure, meta)


def _campbell(rig: RotorRig, pid: Any, speeds: np.ndarray, args: argparse.Namespace, meta: dict) -> None:
    result = campbell(rig, pid, speeds)
    onset = "stable at every speed given" if result.onset_speed is None else (
        f"UNSTABLE from {result.onset_speed:g} rad/s")  # fmt: skip
    print(f"Campbell diagram, {speeds.size} speeds {speeds[0]:g}-{speeds[-1]:g} rad/s: {onset}")
    top = min(200.0, pid.fs / 2)  # Hz: a slow controller's loop has no modes above its fs/2
    print(f"{'speed (rad/s)':>14}  whirling modes below {top:g} Hz: frequency (Hz), damping ratio, whirl")
    for i in np.unique(np.linspace(0, speeds.size - 1, min(5, speeds.size)).astype(int)):
        shown = (result.whirl[i] != 0) & (result.damping[i] < 0.9) & (result.frequency[i] < top)
        rows = zip(result.frequency[i][shown], result.damping[i][shown], result.whirl[i][shown])
        modes = sorted({(round(float(f), 1), round(float(d), 3), "F" if w > 0 else "B") for f, d, w in rows})
        print(f"{speeds[i]:>14g}  " + ", ".join(f"{f} Hz {d} {w}" for f, d, w in modes))
    if args.figure is not None:
        _save_figure(result.plot(max_frequency=top).figure, args.figure, meta)


def _sensitivity(rig: RotorRig, pid: Any, args: argparse.Namespace) -> None:
    # 2-1000 Hz, or up to the highest line below the controller's fs/2 when that is lower (a default follows fs)
    sphs = schroeder_multisine(f0=2.0, f_max=default_f_max(2.0, pid.fs, 1000.0), rms=1e-6, fs=pid.fs)
    measured = measure_sensitivity(rig, pid, sphs, periods=args.periods, seed=args.seed)
    print(f"ISO 14839-3 sensitivity at {rig.rotor.speed:g} rad/s (test signal 1 um rms, 2-{sphs.freq[-1]:g} Hz, "
          f"{args.periods} periods): zones A/B, B/C, C/D at 3, 4, 5 (9.5, 12, 14 dB)")  # fmt: skip
    print(measured.table())


def _unbalance_run(rig: RotorRig, pid: Any, speeds: np.ndarray, unbalance: Any, args: argparse.Namespace,
                   meta: dict) -> None:  # fmt: skip
    result = unbalance_response(rig, pid, speeds, unbalance)
    print(f"Unbalance {unbalance[0][0]:g} kg m at z = {unbalance[0][1]:g} m, {speeds.size} speeds "
          f"{speeds[0]:g}-{speeds[-1]:g} rad/s; peaks of the probe amplitude:")  # fmt: skip
    for name, speed, amplitude in result.peaks:
        print(f"  {name}: {1e6 * amplitude:.2f} um at {speed:g} rad/s ({speed * 60 / (2 * np.pi):.0f} rev/min)")
    if not result.peaks:
        print("  none within the speeds given (no critical speed passed)")
    if args.figure is not None:
        _save_figure(result.plot()[0].figure, args.figure, meta)
