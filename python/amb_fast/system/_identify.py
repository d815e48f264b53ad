"""The N x N estimate from recordings of a real structure's N experiments (a rotor's four): :func:`identify`.

The recordings' per-period line spectra go to the estimator :func:`run_experiment` uses
(``_experiment.estimate``): noise-free simulated recordings give its estimate to rounding.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._errors import IdentificationWarning
from .._excitation import period_samples
from .._experiment import _lines
from .._mechanics import Mechanics
from .._validate import integer, real, require
from ..io._recording import Recording
from ._experiment import EstimateN, estimate

#: Largest condition number of the experiments' force matrix at a line: beyond it the N experiments do not
#: tell the N axes apart there (Hadamard signs give 1).
MAX_CONDITION = 1e6


def _mechanics(rig: Any) -> Mechanics:  # noqa: ANN401 - any structure with mechanics()
    mech: Any = rig if isinstance(rig, Mechanics) else getattr(rig, "mechanics", lambda: None)()
    require(isinstance(mech, Mechanics), "rig", type(rig).__name__,
            "a RotorRig, a RigidRotor, a TwoAxisRig or their Mechanics (the structure whose readout, mass and "
            "gyroscopic matrices the estimate uses)")  # fmt: skip
    return mech


def _from_recordings(recordings: Any, names: tuple[str, ...], fs: float | None) -> tuple[list, list, float]:  # noqa: ANN401
    """Per experiment (samples, N) forces and displacements from N experiments of N Recordings each, and fs."""
    N, axes = len(names), ", ".join(names)
    count = len(recordings) if isinstance(recordings, (list, tuple)) else None
    require(count == N, "recordings", f"{count} experiments" if count is not None else type(recordings).__name__,
            f"{N} experiments (one per axis), each a list of {N} Recordings (axes {axes}); or force and "
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
    forces = [np.column_stack([r.force for r in experiment]) for experiment in recordings]
    displacements = [np.column_stack([r.displacement for r in experiment]) for experiment in recordings]
    if fs is not None:
        fs = real("fs", fs, "Hz", positive=True)
        require(abs(fs - first.fs) <= 1e-3 * first.fs, "fs", fs, f"the recordings' {first.fs_note()} within 0.1 %")
    return forces, displacements, first.fs if fs is None else fs


def _spectra(x: np.ndarray, harmonics: np.ndarray, period: int) -> np.ndarray:
    """(experiments, periods * period, channels) to per-period line spectra (periods, lines, channel,
    experiment), unscaled DFT bins as the core's."""
    E, n, N = x.shape
    bins = np.fft.rfft(x.reshape(E, n // period, period, N), axis=2)[:, :, harmonics]
    return np.ascontiguousarray(bins.transpose(1, 2, 3, 0))


def identify(
    force: ArrayLike | Any,  # noqa: ANN401 - arrays or nested Recordings
    displacement: ArrayLike | None = None,
    *,
    f0: float,
    rig: Any,  # noqa: ANN401 - anything with mechanics()
    fs: float | None = None,
    f_max: float | None = None,
    lines: ArrayLike | None = None,
    settle_periods: int = 0,
    median_window: int = 5,
) -> EstimateN:
    """The N x N estimate from the recordings of a real structure's N experiments (a rotor's four).

    Experiment ``e`` drives axis ``j``'s shaker with ``signs[e, j]`` times one periodic multisine
    (``signs = hadamard_signs(N)``, as :func:`run_experiment` does; any signs or shakers whose force matrices
    are invertible at every line will do). The estimate is :func:`run_experiment`'s: ``H = F Y^-1`` per line,
    the displacements moved to the bearing planes by the structure's ``readout``, its mass and gyroscopic
    matrices removed from ``k``, ``c``.

    Parameters
    ----------
    force, displacement : array_like
        Forces (N, at the bearing planes) and the probes' readings (m, as the probes read them), shape
        (N experiments, samples, N axes), axes in the structure's order (``A.x, A.y, B.x, B.y``). Or
        ``force`` alone: the recordings, a list of N experiments each a list of N :class:`~amb_fast.Recording`
        (one per axis, its force and displacement channels; :func:`~amb_fast.load_recording`), ``fs``
        then from them; experiments of different lengths are cut to the shortest.
    f0 : float
        The multisine's line spacing, Hz (``fs / f0`` samples a period).
    rig : RotorRig, RigidRotor, TwoAxisRig or Mechanics
        The structure: the ``readout`` from the probes to the bearing planes, the mass and gyroscopic matrices
        removed (a rotor at its ``speed``: ``rig.at_speed(speed)`` for recordings at speed).
    fs : float, optional
        Sampling frequency, Hz: needed with arrays; with recordings it must agree with theirs within 0.1 %.
    f_max, lines : optional
        The lines, as in :func:`amb_fast.identify`; by default the harmonics the first experiment's first
        axis' force excites.
    settle_periods : int
        Periods skipped at the start of every experiment.
    median_window : int
        Odd window of ``k_smooth``, ``c_smooth`` (lines).

    Returns
    -------
    EstimateN
        As :func:`run_experiment` returns it. Trailing samples short of a whole period are dropped with an
        :class:`~amb_fast.IdentificationWarning`. A ``ValueError`` names the parameter for a wrong shape,
        number of experiments, non-finite sample, or force matrices that do not tell the axes apart (a
        condition number above 1e6 at a line: the same signs twice, an axis not driven).
    """
    mech = _mechanics(rig)
    names, N = mech.names, mech.axes
    if displacement is None:
        forces, displacements, fs = _from_recordings(force, names, fs)
    else:
        F, Y = np.asarray(force, dtype=np.float64), np.asarray(displacement, dtype=np.float64)
        require(F.ndim == 3 and F.shape[0] == N and F.shape[2] == N, "force shape", F.shape,
                f"({N} experiments, samples, {N} axes: {', '.join(names)})")  # fmt: skip
        require(Y.shape == F.shape, "displacement shape", Y.shape, f"{F.shape} like force")
        require(fs is not None, "fs", fs, "the sampling frequency (Hz) of force and displacement arrays")
        forces, displacements = list(F), list(Y)
    fs = real("fs", fs, "Hz", positive=True)
    f0 = real("f0", f0, "Hz", positive=True)
    window = integer("median_window", median_window, 1)
    require(window % 2 == 1, "median_window", median_window, "odd")
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
    for name, x in (("force", F), ("displacement", Y)):
        bad = np.argwhere(~np.isfinite(x))
        if bad.size:
            e, s, j = bad[0]
            raise ValueError(f"{name} must be finite, got {float(x[e, s, j])!r} in experiment {e}, axis {names[j]}, "
                             f"sample {s + start}")  # fmt: skip
    harmonics = _lines(F[0, :, 0], period, f0, fs, f_max, lines, offset=start)
    Fp, Yp = _spectra(F, harmonics, period), _spectra(Y, harmonics, period)
    condition = np.linalg.cond(Fp.mean(axis=0))
    bad = ~(condition <= MAX_CONDITION)
    if bad.any():
        first = int(np.argmax(bad))
        raise ValueError(f"force must tell the {N} axes apart at every line: the experiments' force matrix has "
                         f"condition number {condition[first]:.3g} at {harmonics[first] * f0:g} Hz ({int(bad.sum())} "
                         f"of {bad.size} lines above {MAX_CONDITION:g}); drive experiment e's axis j with "
                         f"hadamard_signs({N})[e, j] times the multisine")  # fmt: skip
    return estimate(Fp, Yp, harmonics * f0, mech, period, window)
