"""Refuse or warn, never guess: checks of an identification against what the recording itself shows (no
excitation: an error; weak lines: flagged; a kept start transient, implausible magnitudes, a non-periodic force
or a too-short period, most lines weak: warnings that name the likely mistake)."""

from __future__ import annotations

import warnings

import numpy as np

from ._errors import IdentificationWarning, NoExcitationError, ShortPeriodWarning, WeakLinesWarning

WEAK = 10.0  # a line is weak under this many times the unexcited level
EXCITED = 3.0  # the excited lines as a whole must be this far above the unexcited level
TRANSIENT = 4.0  # first-vs-last difference over the consecutive-period scatter that warns
STIFFNESS = (1e2, 1e9)  # N/m
TOO_LIGHT = 0.05  # median |F/Y| / (m w^2) below which the force cannot have moved the given mass
DISPLACEMENT = 10e-3  # m
# Share of the force power that does not repeat at the lines above which the excitation is called non-periodic.
# Measured (tests/test_identify_trust.py): 1e-6 for the paper experiment (force noise 1e-3 N on 1 N rms),
# 0.08 with a force noise of 0.3 N rms, 0.14 for a 200 ppm clock drift; 0.21 for a period off by one sample in
# 4000, 0.5-1 for fs off by 25 % or more.
NON_PERIODIC = 0.15
MOSTLY_WEAK = 0.5  # warn when more than this share of the lines is weak


def floor(levels: np.ndarray) -> float | None:
    """The noise floor from the unexcited lines' levels (their median); ``None`` without any."""
    levels = np.asarray(levels, dtype=float)
    levels = levels[np.isfinite(levels)]
    return float(np.median(levels)) if levels.size else None


def require_excitation(force_lines: np.ndarray, unexcited_force: np.ndarray, offset: float = 0.0) -> None:
    """Raise :class:`NoExcitationError` unless the excited lines' force is clearly above the unexcited level.

    ``offset`` (N) is a sample of the force: lines under 1e-9 of it are rounding, not excitation (a
    constant force)."""
    level = float(np.median(np.abs(force_lines))) if force_lines.size else 0.0
    noise = floor(unexcited_force)
    if level <= 1e-9 * abs(offset) or not np.isfinite(level):
        raise NoExcitationError(f"force has no excitation at the chosen lines: it is zero or constant there "
                                f"({offset:g} N)")  # fmt: skip
    if noise is not None and level <= EXCITED * noise:
        raise NoExcitationError(
            f"force has no excitation at the chosen lines: their median level {level:.3g} N is not clearly "
            f"above the noise floor {noise:.3g} N (unexcited lines, or the period-to-period scatter; needs > "
            f"{EXCITED:g}x); pure noise, or the wrong lines (pass lines= or f_max=)"
        )


SAMPLE_PERIODS = 16  # periods the checks read (the averaged estimate reads all of them)


def _sampled_periods(signal: np.ndarray, period: int) -> tuple[np.ndarray, int]:
    """At most SAMPLE_PERIODS of the record's whole periods, spread over it (rows), and how many it has."""
    periods = signal[: signal.size // period * period].reshape(-1, period)
    total = periods.shape[0]
    return periods[np.unique(np.linspace(0, total - 1, min(total, SAMPLE_PERIODS)).astype(int))], total


def noise_levels(
    signal: np.ndarray,
    period: int,
    harmonics: np.ndarray,
    unexcited: np.ndarray,
    skip: np.ndarray | None = None,
) -> np.ndarray:
    """Levels of one channel that show its noise in the average of all its periods.

    The unexcited lines; with none, the harmonics above the band that the force does not excite (``skip``:
    harmonics excited beyond the chosen lines); with none of those, the period-to-period scatter at the
    lines. The last two are measured on at most SAMPLE_PERIODS periods (spread over the record) and scaled
    by sqrt(used / all), as noise averages down, so the check costs a few periods, not a pass over the record.
    """
    if unexcited.size:
        return unexcited
    pick, total = _sampled_periods(signal, period)
    scale = np.sqrt(pick.shape[0] / total)
    top = int(harmonics.max())
    above = np.arange(top + 1, period // 2)
    if skip is not None and skip.size:
        above = np.setdiff1d(above, skip)
    if above.size:
        return np.abs(np.fft.rfft(pick.mean(axis=0)))[above] * (2.0 / period) * scale
    spectra = np.fft.rfft(pick, axis=1)[:, harmonics] * (2.0 / period)
    return np.std(spectra, axis=0, ddof=1) / np.sqrt(total)


def weak_lines(force: np.ndarray, displacement: np.ndarray, unexcited_force: np.ndarray,
               unexcited_displacement: np.ndarray) -> np.ndarray:  # fmt: skip
    """Per excited line: force or displacement under WEAK times the unexcited level (False without unexcited lines)."""
    weak = np.zeros(np.shape(force), dtype=bool)
    for values, levels in ((force, unexcited_force), (displacement, unexcited_displacement)):
        noise = floor(levels)
        if noise is not None and noise > 0:
            weak |= np.abs(values) < WEAK * noise
    return weak


def _lines_above(level: np.ndarray, noise: np.ndarray | float) -> np.ndarray:
    """Harmonic numbers (1-based, column h - 1 is h) whose level is above 1e-3 of the largest and WEAK x noise."""
    if level.size == 0 or not level.max() > 0:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero((level > 1e-3 * level.max()) & (level > WEAK * noise)) + 1


def detect_lines(level: np.ndarray) -> np.ndarray:
    """The lines above WEAK times the median of all harmonics (the noise floor while fewer than half are excited)."""
    return _lines_above(level, float(np.median(level)) if level.size else 0.0)


def top_harmonic(period: int) -> int:
    """The highest harmonic of the period strictly below the Nyquist frequency."""
    return period // 2 - 1 if period % 2 == 0 else period // 2


def period_spectra(signal: np.ndarray, period: int) -> np.ndarray:
    """Spectra (amplitudes, complex) of at most SAMPLE_PERIODS periods spread over the record, at harmonics
    1..top_harmonic(period): column h - 1 is harmonic h. A few periods suffice for the checks."""
    return np.fft.rfft(_sampled_periods(signal, period)[0], axis=1)[:, 1 : top_harmonic(period) + 1] * (2.0 / period)


def excited_harmonics(spectra: np.ndarray) -> np.ndarray:
    """Harmonic numbers the sampled periods' spectra (:func:`period_spectra`) show excited: their average
    above 1e-3 of the largest and WEAK times its own period-to-period scatter (the standard error of the
    average). Unlike :func:`detect_lines`, it holds when most harmonics are excited."""
    if spectra.shape[0] < 2 or spectra.size == 0:
        return np.zeros(0, dtype=np.int64)
    return _lines_above(np.abs(spectra.mean(axis=0)), np.std(spectra, axis=0, ddof=1) / np.sqrt(spectra.shape[0]))


def non_periodic_fraction(spectra: np.ndarray, excited: np.ndarray) -> float:
    """Share (0-1) of the force power, over the sampled periods and harmonics 1..top, that does not repeat
    at the excited harmonics: all of it between them, plus the period-to-period deviation on them (unbiased).

    A force periodic with the period scores its noise share (1e-6 in the paper experiment); a period that is
    wrong by one sample in 4000 scores 0.2, by 25 % 0.5-1: the force then leaks between the lines or its
    line phases turn from period to period."""
    power = np.abs(spectra) ** 2
    total = float(power.sum())
    if spectra.shape[0] < 2 or not total > 0 or not np.isfinite(total):
        return 0.0
    on = np.zeros(spectra.shape[1], dtype=bool)
    on[np.asarray(excited, dtype=np.int64) - 1] = True
    n = spectra.shape[0]
    lines = spectra[:, on]
    deviation = float((np.abs(lines - lines.mean(axis=0)) ** 2).sum()) * n / (n - 1)
    return (float(power[:, ~on].sum()) + deviation) / total


def non_periodic_message(fraction: float, fs: float, f0: float, period: int, periods: int, what: str = "force") -> str:
    """What a non-periodic force (``what``: or the current driving it) means, naming fs, f0 and the measured share."""
    return (
        f"the {what} does not repeat with the period fs/f0 = {period} samples (fs = {fs:g} Hz, f0 = {f0:g} Hz): "
        f"{fraction:.0%} of its power (in {periods} periods sampled) changes from period to period or falls "
        f"between the excited lines (a periodic excitation: under {NON_PERIODIC:.0%}). The estimate is then "
        "biased by leakage and its frequencies are wrong if fs or f0 is: check fs (the recording's sample rate) "
        "and f0 (the excitation's line spacing, 1/period), and that the excitation repeats every period"
    )


def warn_short_period(
    excited: np.ndarray, fs: float, f0: float, period: int, stacklevel: int = 4, what: str = "force"
) -> None:
    """Warn (:class:`ShortPeriodWarning`) when the force (``what``) excites 3 or more harmonics, all multiples of one
    g >= 2 (a single sine, a stepped sine's line, is left alone)."""
    if excited.size < 3:
        return
    factor = int(np.gcd.reduce(np.asarray(excited, dtype=np.int64)))
    if factor < 2:
        return
    warnings.warn(
        ShortPeriodWarning(
            f"every harmonic the {what} excites ({excited.size} of them) is a multiple of {factor}: it repeats every "
            f"{period // factor} samples, 1/{factor} of fs/f0 = {period} samples (fs = {fs:g} Hz, f0 = {f0:g} Hz). "
            f"If fs is right, the excitation's f0 is {factor * f0:g} Hz and the estimate is right; if f0 is right, "
            f"fs is {fs / factor:g} Hz and the estimate's frequencies are {factor}x too high: check fs",
            factor,
        ),
        stacklevel=stacklevel,
    )


def warn_mostly_weak(
    weak: np.ndarray,
    force_noise: float | None,
    displacement_noise: float | None,
    stacklevel: int = 4,
    what: tuple[str, str] = ("force", "N"),
) -> None:
    """Warn (:class:`WeakLinesWarning`) when more than MOSTLY_WEAK of the lines are weak (``what``: the
    driving channel's name and unit, the force in N or the coil current in A)."""
    count, lines = int(np.count_nonzero(weak)), int(np.size(weak))
    if lines == 0 or count <= MOSTLY_WEAK * lines:
        return
    levels = ", ".join(
        f"{name} {level:.3g} {unit}"
        for name, level, unit in ((what[0], force_noise, what[1]), ("displacement", displacement_noise, "m"))
        if level is not None
    )
    warnings.warn(
        WeakLinesWarning(
            f"{count} of {lines} excited lines are weak: their {what[0]} or displacement is under {WEAK:g}x the noise "
            f"level ({levels}), so the estimate there is mostly noise (Estimate.weak flags them). Raise the "
            "excitation, average more periods, or check that the displacement is the response to this force",
            count,
            lines,
        ),
        stacklevel=stacklevel,
    )


def warn_transient(displacement: np.ndarray, period: int, stacklevel: int = 4) -> None:
    """Warn when the first recorded period differs from the last beyond the consecutive-period scatter."""
    periods = displacement.size // period
    if periods < 4:
        return
    p = displacement[: periods * period].reshape(periods, period)
    last = p[-1]
    with np.errstate(over="ignore", invalid="ignore"):  # a diverged record: the other checks say so
        difference = float(np.sqrt(np.mean((p[0] - last) ** 2)))
        later = np.unique(np.linspace(periods // 2, periods - 2, 8).astype(int))  # a few pairs in the second half
        scatter = float(np.median([np.sqrt(np.mean((p[i] - p[i + 1]) ** 2)) for i in later]))
        size = float(np.sqrt(np.mean((last - last.mean()) ** 2)))
    if difference > TRANSIENT * scatter and difference > 1e-4 * size:
        warnings.warn(
            f"the first period differs from the last by {difference:.3g} m rms, {difference / max(scatter, 1e-300):.3g}"
            " times the period-to-period scatter: a start transient (or a drift) is in the estimate; skip it with "
            "settle_periods=",
            IdentificationWarning,
            stacklevel=stacklevel,
        )


def warn_implausible(
    k: np.ndarray,
    H: np.ndarray,
    displacement: np.ndarray,
    clearance: float | None,
    stacklevel: int = 4,
    inertia: np.ndarray | None = None,
) -> None:
    """Warnings for magnitudes that point to a unit mistake or swapped channels.

    ``inertia``: m w^2 at each line (N/m). Whatever the bearing does, |F/Y| = |K_b(w) - m w^2| stays near or
    above m w^2 except in a narrow band around a resonance; a force far below that at most lines is
    not the force that moved this mass (kN read as N, or the mass in g).
    """
    stiffness = float(np.median(np.abs(k)))
    dynamic = float(np.median(np.abs(H)))
    ratio = float(np.median(np.abs(H) / inertia)) if inertia is not None and inertia.size else np.inf
    messages = []
    if dynamic < 1.0:
        messages.append(f"the median |F/Y| is {dynamic:.3g} N/m: force and displacement look swapped (or not in N "
                        "and m)")  # fmt: skip
    elif ratio < TOO_LIGHT:
        messages.append(f"the force is {ratio:.2g} of what accelerating the given mass takes (median |F/Y| / (m w^2) "
                        "over the lines): is the force in kN instead of N, or the mass not in kg?")  # fmt: skip
    elif not STIFFNESS[0] <= stiffness <= STIFFNESS[1]:
        messages.append(f"the median stiffness {stiffness:.3g} N/m is outside {STIFFNESS[0]:g}-{STIFFNESS[1]:g} N/m: "
                        "check the units of force (N) and displacement (m)")  # fmt: skip
    amplitude = 0.5 * float(np.ptp(displacement)) if displacement.size else 0.0  # a few periods suffice
    if amplitude > (DISPLACEMENT if clearance is None else clearance):
        what = f"the clearance {clearance:g} m" if clearance is not None else f"{DISPLACEMENT * 1e3:g} mm"
        messages.append(f"the displacement amplitude {amplitude:.3g} m is above {what}: is the displacement in mm or "
                        "um instead of m? (load_recording scales a unit in the column name)")  # fmt: skip
    for message in messages:
        warnings.warn(message, IdentificationWarning, stacklevel=stacklevel)
