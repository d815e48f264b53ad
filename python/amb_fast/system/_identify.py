"""The N x N estimate from recordings of a real structure's N experiments (a rotor's four): :func:`identify`.

The recordings' per-period line spectra go to the estimator :func:`run_experiment` uses
(``_experiment.estimate``): noise-free simulated recordings give its estimate to rounding.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import _checks
from .._errors import IdentificationWarning
from .._excitation import period_samples
from .._experiment import check_channels, drive_spectra, excited_lines, median_window_value
from .._mechanics import Mechanics
from .._params import Rig
from .._validate import integer, real, require
from ..io import CHANNEL_UNITS as UNITS
from ..io import Recording, split_unit
from ._exciter import amb_force, corrected_process
from ._experiment import EstimateN, estimate, line_spectra
from ._model import known_dynamics

#: Largest condition number of the experiments' force matrix at a line: beyond it the N experiments do not
#: tell the N axes apart there (Hadamard signs give 1).
MAX_CONDITION = 1e6


def _mechanics(rig: Any) -> Mechanics:  # noqa: ANN401 - any structure with mechanics()
    mech: Any = rig if isinstance(rig, Mechanics) else getattr(rig, "mechanics", lambda: None)()
    require(isinstance(mech, Mechanics), "rig", type(rig).__name__,
            "a RotorRig, a RigidRotor, a TwoAxisRig or their Mechanics (the structure whose readout, mass and "
            "gyroscopic matrices the estimate uses)")  # fmt: skip
    return mech


def _from_recordings(recordings: Any, names: tuple[str, ...], fs: float | None, what: str) -> tuple[list, list, float]:  # noqa: ANN401, E501
    """Per experiment (samples, N) forces (or currents: ``what``) and displacements from N experiments of N
    Recordings each, and fs."""
    N, axes = len(names), ", ".join(names)
    count = len(recordings) if isinstance(recordings, (list, tuple)) else None
    require(count == N, "recordings", f"{count} experiments" if count is not None else type(recordings).__name__,
            f"{N} experiments (one per axis), each a list of {N} Recordings (axes {axes}); or {what} and "
            "displacement arrays")  # fmt: skip
    for e, experiment in enumerate(recordings):
        listed = isinstance(experiment, (list, tuple))
        ok = listed and len(experiment) == N and all(isinstance(r, Recording) for r in experiment)
        got = [type(r).__name__ for r in experiment] if listed else type(experiment).__name__
        require(ok, f"recordings[{e}]", got, f"a list of {N} amb_fast.Recording (axes {axes})")
    first = recordings[0][0]
    for e, experiment in enumerate(recordings):
        for j, rec in enumerate(experiment):
            require(abs(rec.fs - first.fs) <= 1e-9 * first.fs, f"recordings[{e}][{j}].fs", rec.fs,
                    f"{first.fs} Hz like recordings[0][0] (one clock for every channel)")  # fmt: skip
            size = experiment[0].force.size
            require(rec.force.size == size, f"recordings[{e}][{j}] length", rec.force.size,
                    f"{size} samples like recordings[{e}][0] (one acquisition per experiment)")  # fmt: skip
            if what == "current":  # a Recording's "force" channel holds the current: refuse one loaded in N
                require(not _force_channel(rec.source), f"recordings[{e}][{j}]",
                        rec.source, "a coil current (A) in its force channel, not a force: give the recordings of "
                        "shakers as force=")  # fmt: skip
    forces = [np.column_stack([r.force for r in experiment]) for experiment in recordings]
    displacements = [np.column_stack([r.displacement for r in experiment]) for experiment in recordings]
    if fs is not None:
        fs = real("fs", fs, "Hz", positive=True)
        require(abs(fs - first.fs) <= 1e-3 * first.fs, "fs", fs, f"the recordings' {first.fs_note()} within 0.1 %")
    return forces, displacements, first.fs if fs is None else fs


def _force_channel(source: str) -> bool:
    """Whether a loaded Recording's force channel (its ``source``: ``"rig.csv: force 'F [kN]' (kN -> N), ..."``)
    is named a force or has a force's unit."""
    match = re.search(r": force '(.*?)'(?: \(|, displacement)", source)
    if match is None:
        return False
    name, unit = split_unit(match.group(1))
    return "force" in name.lower() or UNITS.get((unit or "").lower(), ("",))[0] == "force"


def identify(
    force: ArrayLike | Any = None,  # noqa: ANN401 - arrays or nested Recordings
    displacement: ArrayLike | None = None,
    *,
    current: ArrayLike | Any = None,  # noqa: ANN401 - arrays or nested Recordings
    f0: float,
    rig: Any,  # noqa: ANN401 - anything with mechanics()
    fs: float | None = None,
    f_max: float | None = None,
    lines: ArrayLike | None = None,
    settle_periods: int = 0,
    median_window: int = 5,
) -> EstimateN:
    """The N x N estimate from the recordings of a real structure's N experiments (a rotor's four).

    Experiment ``e`` drives axis ``j``'s shaker (``force=``) or current command (``current=``, the bearings as
    exciters) with ``signs[e, j]`` times one periodic multisine (``signs = hadamard_signs(N)``, as
    :func:`run_experiment` does; any signs whose force or current matrices are invertible at every line will
    do). The estimate is :func:`run_experiment`'s: ``H = F Y^-1`` per line, the displacements moved to the
    bearing planes by the structure's ``readout``, its mass and gyroscopic matrices removed from ``k``, ``c``.
    With ``current=`` the force is estimated per line from the coil current and the probes by the rig's
    actuator model, ``F = -kyy d - kiy i``, and ``EstimateN.process`` is the process at the bearings with the
    hold and the known lags removed, as ``run_experiment(..., exciter="amb")`` gives them.

    Parameters
    ----------
    force, displacement : array_like
        Forces (N, at the bearing planes) and the probes' readings (m, as the probes read them), shape
        (N experiments, samples, N axes), axes in the structure's order (``A.x, A.y, B.x, B.y``). Or
        ``force`` alone: the recordings, a list of N experiments each a list of N :class:`~amb_fast.Recording`
        (one per axis, its force and displacement channels; :func:`~amb_fast.load_recording`), ``fs``
        then from them; experiments of different lengths are cut to the shortest.
    current : array_like, optional
        Instead of ``force``: the coil currents (A, the amplifiers' outputs as recorded, injection included),
        the same shapes; or the recordings, each :class:`~amb_fast.Recording`'s force channel holding the
        current (one named a force or in N, kN, mN is refused). Needs ``rig`` with its axes (kyy, kiy, lags).
    f0 : float
        The multisine's line spacing, Hz (``fs / f0`` samples a period).
    rig : RotorRig, RigidRotor, TwoAxisRig or Mechanics
        The structure: the ``readout`` from the probes to the bearing planes, the mass and gyroscopic matrices
        removed (a rotor at its ``speed``: ``rig.at_speed(speed)`` for recordings at speed). With ``current``
        a RotorRig or TwoAxisRig: its axes' actuator model estimates the force and corrects the process.
    fs : float, optional
        Sampling frequency, Hz: needed with arrays; with recordings it must agree with theirs within 0.1 %.
    f_max, lines : optional
        The lines, as in :func:`amb_fast.identify`; by default the harmonics the first experiment's first
        axis' force (or current) excites.
    settle_periods : int
        Periods skipped at the start of every experiment.
    median_window : int
        Odd window of ``k_smooth``, ``c_smooth`` (lines).

    Returns
    -------
    EstimateN
        As :func:`run_experiment` returns it. Trailing samples short of a whole period are dropped with an
        :class:`~amb_fast.IdentificationWarning`. A ``ValueError`` names the parameter for a wrong shape,
        number of experiments, non-finite sample, or force (current) matrices that do not tell the axes apart
        (a condition number above 1e6 at a line: the same signs twice, an axis not driven). Every experiment's
        every axis gets :func:`amb_fast.identify`'s checks, each warning naming the first experiment and axis it
        found: a force (current) that does not repeat with ``fs/f0`` (:class:`NonPeriodicExcitationWarning`) or
        repeats with a fraction of it (:class:`ShortPeriodWarning`), more than half the lines weak
        (:class:`WeakLinesWarning`), a start transient and implausible magnitudes
        (:class:`IdentificationWarning`).
    """
    require(
        (force is None) != (current is None),
        "force, current",
        "both" if force is not None else "neither",
        "one of them: force= (shakers' forces, N) or current= (the bearings as exciters: coil currents, A)",
    )
    what = "force" if current is None else "current"
    mech, axes = _mechanics(rig), getattr(rig, "axes", None)
    names, N = mech.names, mech.axes
    if what == "current":
        require(isinstance(axes, (tuple, list)) and len(axes) == N and all(isinstance(a, Rig) for a in axes), "rig",
                type(rig).__name__, "a RotorRig or TwoAxisRig with current=: its axes' kyy, kiy estimate the force "
                "and their lags correct the process")  # fmt: skip
    drive = force if current is None else current
    if displacement is None:
        forces, displacements, fs = _from_recordings(drive, names, fs, what)
    else:
        F, Y = np.asarray(drive, dtype=np.float64), np.asarray(displacement, dtype=np.float64)
        require(F.ndim == 3 and F.shape[0] == N and F.shape[2] == N, f"{what} shape", F.shape,
                f"({N} experiments, samples, {N} axes: {', '.join(names)})")  # fmt: skip
        require(Y.shape == F.shape, "displacement shape", Y.shape, f"{F.shape} like {what}")
        require(fs is not None, "fs", fs, f"the sampling frequency (Hz) of {what} and displacement arrays")
        forces, displacements = list(F), list(Y)
    fs = real("fs", fs, "Hz", positive=True)
    f0 = real("f0", f0, "Hz", positive=True)
    window = median_window_value(median_window)
    period = period_samples(fs, f0)
    start = integer("settle_periods", settle_periods, 0) * period
    n = min(x.shape[0] for x in forces)
    whole = start + max(0, n - start) // period * period
    require((whole - start) // period >= 2, "periods after settling", (whole - start) // period,
            f">= 2 (standard errors need two; {n} samples, {period} a period, {start} settling)")  # fmt: skip
    dropped = sum(x.shape[0] - whole for x in forces)
    if dropped:
        warnings.warn(f"recordings are not a whole number of periods of {period} samples: dropped {dropped} "
                      f"samples (over the {N} experiments) after the last whole period", IdentificationWarning,
                      stacklevel=2)  # fmt: skip
    F, Y = (np.stack([x[start:whole] for x in xs]) for xs in (forces, displacements))
    for name, x in ((what, F), ("displacement", Y)):
        bad = np.argwhere(~np.isfinite(x))
        if bad.size:
            e, s, j = bad[0]
            raise ValueError(f"{name} must be finite, got {float(x[e, s, j])!r} in experiment {e}, axis {names[j]}, "
                             f"sample {s + start}")  # fmt: skip
    harmonics = excited_lines(F[0, :, 0], period, f0, fs, f_max, lines, offset=start)
    Fp, Yp = line_spectra(F, period, harmonics), line_spectra(Y, period, harmonics)
    condition = np.linalg.cond(Fp.mean(axis=0))
    bad = ~(condition <= MAX_CONDITION)
    if bad.any():
        first = int(np.argmax(bad))
        raise ValueError(f"{what} must tell the {N} axes apart at every line: the experiments' {what} matrix has "
                         f"condition number {condition[first]:.3g} at {harmonics[first] * f0:g} Hz ({int(bad.sum())} "
                         f"of {bad.size} lines above {MAX_CONDITION:g}); drive experiment e's axis j with "
                         f"hadamard_signs({N})[e, j] times the multisine")  # fmt: skip
    if what == "force":
        est = estimate(Fp, Yp, harmonics * f0, mech, period, window)
    else:
        est = estimate(amb_force(rig, Yp, Fp), Yp, harmonics * f0, mech, period, window)
        est = replace(est, process=corrected_process(rig, fs, est.freq, est.H))
    chosen = lines is not None or f_max is not None
    clearance = [a.clearance for a in axes] if isinstance(axes, (tuple, list)) else [None] * N
    _check(F, Y, harmonics, chosen, est, mech, clearance, fs, f0, what)
    return est


def _check(
    F: np.ndarray, Y: np.ndarray, harmonics: np.ndarray, chosen: bool, est: EstimateN, mech: Mechanics,
    clearance: list[float | None], fs: float, f0: float, what: str,
) -> None:  # fmt: skip
    """:func:`amb_fast.identify`'s checks on every experiment's every axis (F: force or current, Y: probes; each
    (experiments, samples, N) after settling); each warning once, naming the first experiment and axis."""
    E, _, N = F.shape
    period = period_samples(fs, f0)
    unit = "N" if what == "force" else "A"
    weak = np.zeros(harmonics.size, dtype=bool)
    floors = np.zeros(2)
    tags: list[str] = []  # where each caught warning came from
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for e in range(E):
            for j in range(N):
                where = f"experiment {e}, axis {est.axes[j]}"
                drive = drive_spectra(F[e, :, j], period, harmonics, chosen)
                found, force_noise, displacement_noise = check_channels(F[e, :, j], Y[e, :, j], period, harmonics,
                                                                        drive, fs, f0, what=what)  # fmt: skip
                weak |= found
                floors = np.fmax(floors, [_checks.floor(force_noise) or 0.0, _checks.floor(displacement_noise) or 0.0])
                _checks.warn_transient(Y[e, :, j], period)
                tags += [where] * (len(caught) - len(tags))
        _checks.warn_mostly_weak(weak, floors[0], floors[1], what=(what, unit))
        tags += [f"{E} experiments"] * (len(caught) - len(tags))
        inertia = np.abs(known_dynamics(mech, est.freq).real)
        for i in range(N):
            # From the bearings the structure's own k is its process, perhaps nil: range-check H instead.
            k = est.k[:, i, i] if what == "force" else est.H[:, i, i].real
            _checks.warn_implausible(k, est.H[:, i, i], Y[:, -16 * period :, i], clearance[i],
                                     inertia=inertia[:, i, i])  # fmt: skip
            tags += [f"axis {est.axes[i]}"] * (len(caught) - len(tags))
    seen: set[str] = set()
    for where, w in zip(tags, caught):
        kind = f"{w.category.__name__} {str(w.message).split()[:3]}"  # the check, not its numbers
        if kind not in seen:  # once per kind: the first experiment and axis that showed it
            seen.add(kind)
            note = w.message if isinstance(w.message, Warning) else w.category(w.message)
            note.args = (f"{where}: {note.args[0]}", *note.args[1:])  # keeps its attributes (fraction, ...)
            warnings.warn(note, stacklevel=3)
