"""The identification experiment: simulated (run_experiment) or recorded (identify)."""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _checks, _core
from ._dispatch import axes_aware, recordings_aware
from ._equality import ArrayRecord
from ._errors import IdentificationWarning, NonPeriodicExcitationWarning
from ._excitation import Multisine, period_samples
from ._linear import AnyController, core_controller, require_stable, settle_periods_for, settling_radius
from ._params import Rig
from ._ross import to_ross
from ._validate import integer, optional_positive, real, require, rig_and_controller, seed_value, series
from .io import ONE_AXIS, estimate_fields_from_csv, estimate_fields_from_dataset, register_estimate_kind, save_estimate


@dataclass(frozen=True, eq=False)
class UnexcitedLines(ArrayRecord):
    """Levels at the harmonics of f0 below the highest excited line that carry no excitation.

    What shows there is noise plus non-linear distortion.

    Attributes
    ----------
    freq : ndarray
        Hz.
    force : ndarray
        Amplitude of the period-averaged force, N.
    displacement : ndarray
        Amplitude of the period-averaged displacement, m.
    """

    freq: np.ndarray
    force: np.ndarray
    displacement: np.ndarray


@dataclass(frozen=True, eq=False)
class EstimateBase(ArrayRecord):
    """What every estimate holds at its excited lines ``freq`` (Hz): per line a number for one axis
    (:class:`Estimate`), an N x N matrix for N axes (:class:`~amb_fast.system.EstimateN`); their docstrings
    give the units."""

    freq: np.ndarray
    H: np.ndarray
    receptance: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    force: np.ndarray
    displacement: np.ndarray


@dataclass(frozen=True, eq=False)
class Estimate(EstimateBase):
    """Frequency-domain estimate at the excited lines (MODEL.md section 3).

    Two estimates are ``==`` when every field but ``meta`` is equal (arrays value by value, NaN equal to
    NaN): a rerun with the same seed gives an equal one.

    Attributes
    ----------
    freq : ndarray
        Excited lines, Hz.
    H : ndarray
        Dynamic stiffness F/Y, complex, N/m.
    receptance : ndarray
        Y/F = 1/H, complex, m/N.
    k, c : ndarray
        Actual stiffness (N/m) and damping (N s/m), paper eq. 9: ``k = m w^2 + Re H``, ``c = Im H / w``.
    k_smooth, c_smooth : ndarray
        ``k`` and ``c`` median filtered across the lines (window ``median_window``; the ends repeat
        the edge value).
    k_std, c_std : ndarray
        Standard errors of ``k`` and ``c`` (N/m, N s/m), from the period-to-period variance of the
        spectra (first-order propagation through F/Y). They have ``blocks - 1`` degrees of freedom:
        use Student's t, not 1.96, for an interval from few periods.
    force, displacement : ndarray
        Period-averaged complex amplitudes at the lines, N and m.
    unexcited : UnexcitedLines
        Levels at the unexcited harmonics.
    periods : int
        Periods averaged.
    saturated_samples : int or None
        Recorded samples at which the amplifier clipped the current command (simulations; ``None`` for
        recordings, where it cannot be seen). A saturated estimate is not a linear one: check it.
    blocks : int
        Independent groups behind the standard errors: every period up to 63 periods, else batch
        means of ``periods // 32`` consecutive periods (32 to 63 of them).
    weak : ndarray of bool or None
        Per line: its force or displacement is under 10x the noise level, so noise weighs on it. The
        noise level is the median at the unexcited lines; :func:`identify` with every line excited uses
        the harmonics above the band that the force does not excite, or the period-to-period scatter.
        (``run_experiment`` with no unexcited line: all False.) :func:`identify` warns
        (:class:`WeakLinesWarning`) when more than half the lines are weak.
    meta : dict
        What produced it: ``source`` ("run_experiment" or "identify"), the rig, the controller, the seed,
        fs, f0, mass, settle_periods. Saved with the estimate (:meth:`save`).
    """

    unexcited: UnexcitedLines
    periods: int
    blocks: int
    saturated_samples: int | None = None
    weak: np.ndarray | None = None
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def saturated(self) -> bool:
        """Whether the amplifier clipped during the recorded periods."""
        return bool(self.saturated_samples)

    def save(self, path: str | Path) -> Path:
        """Write atomically to ``.csv`` (a metadata header and a SHA-256) or ``.nc`` (NetCDF, checksummed);
        :func:`amb_fast.load_estimate` reads it back, unexcited lines and metadata included."""
        return save_estimate(self, path)

    def to_xarray(self):  # noqa: ANN201 - xarray is optional
        """An ``xarray.Dataset`` over ``freq`` (and ``unexcited_freq``) with units; metadata in ``attrs``."""
        from .io._results import estimate_to_xarray

        return estimate_to_xarray(self)

    def to_dataframe(self):  # noqa: ANN201 - pandas is optional
        """A ``pandas.DataFrame``, one row per line (excited and unexcited), units in the column names."""
        from .io._results import estimate_to_dataframe

        return estimate_to_dataframe(self)

    def to_ross(self, n: int, *, smoothed: bool = False, **kwargs: Any) -> Any:
        """This estimate as a symmetric ``ross.BearingElement`` at node ``n``: k, c on both axes, no cross
        terms, over the lines in rad/s (see :func:`amb_fast.two_axis.to_ross`; needs the ``ross`` extra)."""
        return to_ross(self, n, smoothed=smoothed, **kwargs)


def actual_coefficients(H: np.ndarray, freq: np.ndarray, mass: float) -> tuple[np.ndarray, np.ndarray]:
    """Actual stiffness k (N/m) and damping c (N s/m) from the dynamic stiffness ``H`` = F/Y (N/m) at ``freq``
    (Hz) of a known ``mass`` (kg), paper eq. 9: ``k = m w^2 + Re H``, ``c = Im H / w`` (the core's estimator
    computes the same)."""
    w = 2 * np.pi * np.asarray(freq, dtype=float)
    return mass * w**2 + H.real, H.imag / w


def _plan(harmonics: np.ndarray, period: int, skip: np.ndarray | None = None) -> tuple[_core.LinePlan, np.ndarray]:
    """The core's plan for these excited harmonics, and the unexcited ones below the highest (read-only;
    made once per distinct excitation). ``skip``: harmonics the force excites beyond the chosen ones, which
    are neither estimated nor taken for noise."""
    skip_bytes = b"" if skip is None else np.asarray(skip, dtype=np.int64).tobytes()
    return _cached_plan(np.asarray(harmonics, dtype=np.int64).tobytes(), int(period), skip_bytes)


@functools.lru_cache(maxsize=64)
def _cached_plan(harmonics_bytes: bytes, period: int, skip_bytes: bytes = b"") -> tuple[_core.LinePlan, np.ndarray]:
    harmonics = np.frombuffer(harmonics_bytes, dtype=np.int64)
    gaps = np.ones(int(harmonics.max()) + 1, dtype=bool)
    gaps[0] = False
    gaps[harmonics] = False
    skip = np.frombuffer(skip_bytes, dtype=np.int64)
    gaps[skip[skip < gaps.size]] = False
    unexcited = np.flatnonzero(gaps)
    unexcited.flags.writeable = False
    return _core.LinePlan(period=period, excited=harmonics, unexcited=unexcited), unexcited


_RAW = ("H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force", "displacement")  # as the core gives them


def _estimate(
    raw: _core.LineEstimate,
    harmonics: np.ndarray,
    unexcited: np.ndarray,
    f0: float,
    saturated: int | None = None,
    meta: dict[str, Any] | None = None,
    weak: np.ndarray | None = None,
) -> Estimate:
    if weak is None:
        weak = _checks.weak_lines(raw.force, raw.displacement, raw.unexcited_force, raw.unexcited_displacement)
    return Estimate(
        freq=harmonics * f0,
        receptance=1.0 / raw.H,
        **{name: getattr(raw, name) for name in _RAW},
        unexcited=UnexcitedLines(unexcited * f0, raw.unexcited_force, raw.unexcited_displacement),
        periods=int(raw.periods),
        blocks=int(raw.blocks),
        saturated_samples=saturated,
        weak=weak,
        meta=meta or {},
    )


def median_window_value(median_window: int) -> int:
    """``median_window``, checked: a positive odd number of lines."""
    window = integer("median_window", median_window, 1)
    require(window % 2 == 1, "median_window", median_window, "odd")
    return window


def run_options(periods: int, settle_periods: int | None, median_window: int, start: str) -> dict[str, Any]:
    """The run options of :func:`run_experiment` (one axis or N) and of every point of a sweep, checked:
    at least two ``periods``, ``settle_periods`` None (automatic) or >= 0, an odd ``median_window``, ``start``
    'steady' or 'rest'."""
    require(start in ("steady", "rest"), "start", start, "'steady' or 'rest'")
    settle = None if settle_periods is None else integer("settle_periods", settle_periods, 0)
    periods = integer("periods", periods, 2)
    return dict(periods=periods, settle_periods=settle, median_window=median_window_value(median_window), start=start)


MAX_AUTOMATIC_SETTLE = 10_000


def automatic_settle(rig: Rig, controller: AnyController, radius: float, period: int, start: str) -> int:
    """Settling periods chosen when none are given: none for a steady start of a linear rig, else
    enough for the slowest pole to decay below 1e-9; more than 10^4 is refused, naming the pole."""
    if start == "steady" and rig.force_law == "linear":
        return 0
    origin = "rest" if start == "rest" else "the linearised steady state"
    return settle_from(float(settling_radius(rig, controller, radius)), period, origin)


def settle_from(slowest: float, period: int, origin: str = "rest") -> int:
    """Periods of ``period`` samples for a pole of radius ``slowest`` to decay below 1e-9 (settling from
    ``origin``); more than 10^4 is refused, naming the pole."""
    periods = int(settle_periods_for(np.array(slowest), period))
    if periods > MAX_AUTOMATIC_SETTLE:
        raise ValueError(
            f"settling from {origin} would take {periods} periods (> {MAX_AUTOMATIC_SETTLE}): the slowest pole has "
            f"|z| = {slowest:.12g}, a stability margin of 1 - |z| = {1 - slowest:.3g} per sample; use "
            "start='steady' (linear rigs) or give settle_periods"
        )
    return periods


@axes_aware
def run_experiment(
    rig: Rig,
    controller: AnyController,
    excitation: Multisine,
    *,
    periods: int = 10,
    settle_periods: int | None = None,
    seed: int | None = None,
    median_window: int = 5,
    start: Literal["steady", "rest"] = "steady",
) -> Estimate:
    """Simulate the SPHS experiment and estimate k(f), c(f), in one C++ call that keeps no time series.

    ``controller``: a :class:`PID` or any :class:`~amb_fast.Controller` (transfer functions, filter
    blocks, python-control systems), at the excitation's sample rate.

    ``start="steady"`` (the default) starts the loop in the periodic steady state of the repeated
    excitation, solved exactly (``x0 = Phi^N x0 + x_N``), with the noise-driven part of the state drawn
    from its stationary distribution: no settling is needed, and without noise the recorded periods
    equal those of an infinitely settled run to rounding, however slow the slowest pole. A non-linear
    force law starts from the linearised steady state and settles from there. ``start="rest"`` starts
    from rest, as a real rig does.

    From the steady start of a linear rig with nothing to watch (no ``current_limit``, no
    ``clearance``), the loop is not run sample by sample: each recorded period's force and displacement
    spectra at the lines are drawn directly, exactly in distribution (the loop is linear, so a period's
    spectrum is its steady response plus the response to that period's noise spectrum and to the state's
    change over the period; docs "Model", "Drawing the spectra"). The estimate is the same function of
    them, several times faster; a seed then gives other numbers than :func:`simulate` with that seed.
    Everywhere else (``start="rest"``, limits, clearances, the non-linear law) the loop runs sample by
    sample and streams its periods into the estimator.

    The excitation period is repeated for ``settle_periods``, then ``periods`` more are recorded,
    averaged and transformed. ``settle_periods=None`` takes 0 for a steady start of a linear rig, else
    enough for the slowest pole ``z_max`` of the linearised closed loop (or the force transducer's AC
    coupling, if slower) to decay below 1e-9: ``ceil(ln 1e-9 / ln |z_max| / period) + 1``; more than
    10^4 periods is refused (``ValueError``).
    ``seed`` fixes the measurement noise. Raises :class:`UnstableLoopError` before simulating a loop
    with a pole on or outside the unit circle, and :class:`TouchdownError` (time, position) if the
    platform reaches its clearance. Amplifier saturation during the recorded periods is counted in
    ``Estimate.saturated_samples`` and warned about.
    """
    rig_and_controller(rig, controller, "run_experiment")
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    pid = controller
    require(excitation.fs == pid.fs, "excitation.fs", excitation.fs, f"equal to the controller's fs ({pid.fs} Hz)")
    options = run_options(periods, settle_periods, median_window, start)
    periods, settle_periods, window = options["periods"], options["settle_periods"], options["median_window"]
    period = excitation.period_samples
    poles = require_stable(rig, pid)
    if settle_periods is None:  # the same rule as amb_fast.sweep, so a sweep point reruns bit for bit
        settle_periods = automatic_settle(rig, pid, float(np.max(np.abs(poles), initial=0.0)), period, start)
    harmonics = excitation.harmonics
    plan, unexcited = _plan(harmonics, period)
    seed = seed_value(seed)
    raw = _core.run_experiment(
        rig._to_core(),
        core_controller(pid),
        excitation.samples,
        settle_periods,
        periods,
        plan,
        seed,
        window,
        start == "steady",
    )
    if raw.saturated_samples:
        total = periods * period
        warnings.warn(
            f"the amplifier saturated in {raw.saturated_samples} of {total} recorded samples: the estimate is "
            "flagged (Estimate.saturated) and is not that of the linear loop",
            stacklevel=3,
        )
    meta = {"source": "run_experiment", "rig": rig, "controller": pid, "seed": seed, "fs": excitation.fs,
            "f0": excitation.f0, "mass": rig.mass, "settle_periods": settle_periods}  # fmt: skip
    # No periodicity or weak-line warnings here: the excitation is periodic by construction, the noise is the
    # caller's choice, and Estimate.weak flags the lines as a sweep point's estimate does.
    return _estimate(raw, harmonics, unexcited, excitation.f0, saturated=int(raw.saturated_samples), meta=meta)


@recordings_aware
def identify(
    force: ArrayLike,
    displacement: ArrayLike,
    *,
    fs: float,
    f0: float,
    mass: float,
    f_max: float | None = None,
    lines: ArrayLike | None = None,
    settle_periods: int = 0,
    median_window: int = 5,
    clearance: float | None = None,
) -> Estimate:
    """Estimate k(f), c(f) from a recording of force (N) and displacement (m) sampled at ``fs`` (Hz).

    The same C++ estimator as :func:`run_experiment`. The record after ``settle_periods`` must hold at
    least two periods of ``fs/f0`` samples; trailing samples short of a whole period are dropped with
    a warning. ``mass`` (kg) is the known system mass of paper eq. 9.

    Excited lines: ``lines`` (Hz, multiples of f0), else every harmonic of ``f0`` up to ``f_max``; with
    neither given, the harmonics whose period-averaged force amplitude exceeds 1e-3 of the largest and
    10x the median of all harmonics (so pass ``lines`` or ``f_max`` when over half of them are excited).
    With ``lines`` or ``f_max``, exactly those lines are estimated; harmonics the force excites beyond them
    (above 1e-3 of the largest and 10x their own period-to-period scatter) are neither estimated nor taken
    for noise: ``Estimate.unexcited`` holds only the harmonics below the band that carry no excitation.

    Refuses (:class:`NoExcitationError`) a force with no excitation at the chosen lines: zero, constant, or
    not clearly (3x) above the noise floor at the unexcited lines. Flags lines under 10x that floor
    (``Estimate.weak``) and warns (:class:`WeakLinesWarning`) when more than half of them are. Warns
    (:class:`NonPeriodicExcitationWarning`) when more than 15 % of the force power, in up to 16 periods
    sampled, does not repeat at the excited lines (changes from period to period or falls between them): the
    force is not periodic with ``fs/f0`` samples, most often because ``fs`` or ``f0`` is wrong (the
    estimate's frequencies are then wrong too). A warning, not an error: the numbers are computed as asked,
    and ``warnings.simplefilter("error", amb_fast.IdentificationWarning)`` makes every such check refuse.
    Warns (:class:`ShortPeriodWarning`) when the 3 or more harmonics the force excites are all multiples of
    one g >= 2: it repeats every ``fs/f0/g`` samples, so either f0 is g times larger or fs g times smaller.
    Warns (:class:`IdentificationWarning`) when the first recorded period differs from the last beyond the
    period-to-period scatter (a start transient: pass ``settle_periods``), and for magnitudes that suggest a
    unit mistake: a median stiffness outside 1e2-1e9 N/m, a displacement amplitude above 10 mm (or above
    ``clearance``, m, when given), force and displacement swapped.
    """
    force, displacement = series("force", force), series("displacement", displacement)
    require(force.size == displacement.size, "displacement length", displacement.size, f"{force.size} like force")
    fs = real("fs", fs, "Hz", positive=True)
    f0 = real("f0", f0, "Hz", positive=True)
    mass = real("mass", mass, "kg", positive=True)
    window = median_window_value(median_window)
    settle_periods = integer("settle_periods", settle_periods, 0)
    period = period_samples(fs, f0)
    start = settle_periods * period
    require(force.size >= start + period, "recording length", force.size,
            f"at least settle_periods + 1 periods ({start + period} samples)")  # fmt: skip
    whole = start + (force.size - start) // period * period
    if whole < force.size:
        warnings.warn(
            f"recording is not a whole number of periods of {period} samples: dropped the last "
            f"{force.size - whole} samples",
            IdentificationWarning,
            stacklevel=3,
        )
        force, displacement = force[:whole], displacement[:whole]
    require((whole - start) // period >= 2, "periods after settling", (whole - start) // period,
            ">= 2 (standard errors need at least two)")  # fmt: skip
    clearance = optional_positive("clearance", clearance, "m")
    harmonics = excited_lines(force[start:], period, f0, fs, f_max, lines, offset=start)
    drive = drive_spectra(force[start:], period, harmonics, chosen=lines is not None or f_max is not None)
    plan, unexcited = _plan(harmonics, period, skip=drive[1])
    try:
        raw = _core.identify(force, displacement, settle_periods, plan, mass, fs, window)
    except ValueError:
        for name, values in (("force", force), ("displacement", displacement)):
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:  # the index in the whole recording, settle periods included
                raise ValueError(f"{name} must be finite, got {float(values[bad[0]])!r} at sample {bad[0]}") from None
        if np.ptp(force[start:]) == 0.0:  # no excitation explains the failure better than its consequence
            raise _checks.NoExcitationError(f"force has no excitation at the chosen lines: it is zero or constant "
                                            f"there ({force[start]:g} N)") from None  # fmt: skip
        raise
    levels = (raw.force, raw.displacement, raw.unexcited_force, raw.unexcited_displacement)
    weak, force_noise, displacement_noise = check_channels(
        force[start:], displacement[start:], period, harmonics, drive, fs, f0, levels=levels,
        excited_from=max(abs(force[start]), abs(force[-1])),
    )  # fmt: skip
    _checks.warn_mostly_weak(weak, _checks.floor(force_noise), _checks.floor(displacement_noise))
    _checks.warn_transient(displacement[start:], period)
    inertia = mass * (2 * np.pi * harmonics * fs / period) ** 2
    _checks.warn_implausible(raw.k, raw.H, displacement[max(start, whole - 16 * period) :], clearance,
                             inertia=inertia)  # fmt: skip
    meta = {"source": "identify", "rig": None, "controller": None, "seed": None, "fs": fs, "f0": f0, "mass": mass,
            "settle_periods": settle_periods}  # fmt: skip
    return _estimate(raw, harmonics, unexcited, f0, meta=meta, weak=weak)


def drive_spectra(
    force: np.ndarray, period: int, harmonics: np.ndarray, chosen: bool
) -> tuple[np.ndarray, np.ndarray | None, float]:
    """What :func:`check_channels` reads of the force (or the current driving the loop), after settling: a few
    periods' spectra; the harmonics it excites beyond the lines when ``lines=`` or ``f_max=`` ``chosen`` them
    (neither estimated nor taken for noise; else None); the share of its power that does not repeat at the
    excited harmonics (a wrong fs or f0)."""
    spectra = _checks.period_spectra(force, period)
    others = np.setdiff1d(_checks.excited_harmonics(spectra), harmonics) if chosen else None
    excited = harmonics if others is None else np.union1d(harmonics, others)
    return spectra, others, _checks.non_periodic_fraction(spectra, excited)


def check_channels(
    force: np.ndarray, displacement: np.ndarray, period: int, harmonics: np.ndarray,
    drive: tuple[np.ndarray, np.ndarray | None, float], fs: float, f0: float, *,
    levels: tuple[np.ndarray, ...] | None = None, excited_from: float | None = None, what: str = "force",
    stacklevel: int = 4,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`identify`'s checks of one recorded force (``what``: or current) and displacement after settling,
    which :func:`amb_fast.system.identify` runs on every experiment's every axis: refuses a force with no
    excitation (given ``excited_from``, a force sample in N), warns when it does not repeat with the period or
    repeats with a fraction of it; returns the weak lines and both channels' noise levels. ``drive``: the
    force's :func:`drive_spectra`; ``levels``: the estimator's amplitudes (force, displacement) at the lines and
    at the unexcited harmonics, else measured here."""
    spectra, others, fraction = drive
    if levels is None:
        excited = harmonics if others is None else np.union1d(harmonics, others)
        gaps = np.setdiff1d(np.arange(1, harmonics.max()), excited)  # the unexcited harmonics below the top
        averages = [np.fft.rfft(x.reshape(-1, period).mean(axis=0)) * (2.0 / period) for x in (force, displacement)]
        levels = (*(a[harmonics] for a in averages), *(np.abs(a[gaps]) for a in averages))
    force_lines, displacement_lines, unexcited_force, unexcited_displacement = levels
    force_noise = _checks.noise_levels(force, period, harmonics, unexcited_force, skip=others)
    message = _checks.non_periodic_message(fraction, fs, f0, period, spectra.shape[0], what=what)
    if excited_from is not None:
        try:
            _checks.require_excitation(force_lines, force_noise, offset=excited_from)
        except _checks.NoExcitationError as error:
            if fraction > _checks.NON_PERIODIC:  # the likelier cause: say it in the error
                raise _checks.NoExcitationError(f"{error}; also, {message}") from None
            raise
    if fraction > _checks.NON_PERIODIC:
        warnings.warn(NonPeriodicExcitationWarning(message, fraction), stacklevel=stacklevel)
    else:  # periodic, perhaps with a whole fraction of the period (fs too large by that factor)
        _checks.warn_short_period(_checks.excited_harmonics(spectra), fs, f0, period, stacklevel + 1, what=what)
    displacement_noise = _checks.noise_levels(displacement, period, harmonics, unexcited_displacement, skip=others)
    weak = _checks.weak_lines(force_lines, displacement_lines, force_noise, displacement_noise)
    return weak, force_noise, displacement_noise


def excited_lines(
    force: np.ndarray, period: int, f0: float, fs: float, f_max: float | None, lines, offset: int = 0
) -> np.ndarray:  # noqa: ANN001, E501
    top = _checks.top_harmonic(period)  # the highest harmonic below Nyquist
    if f_max is not None:
        real("f_max", f_max, "Hz", positive=True)
        require(f0 <= f_max < fs / 2, "f_max", f_max, f"at least f0 ({f0} Hz) and below fs/2 ({fs / 2} Hz)")
        top = int(np.floor(f_max / f0 + 1e-9))
    if lines is not None:
        freq = np.atleast_1d(np.asarray(lines, dtype=float))
        harmonics = np.rint(freq / f0)
        ok = (
            freq.ndim == 1
            and bool(np.all(np.isfinite(freq)))
            and bool(np.all(np.abs(harmonics * f0 - freq) < 1e-6 * f0))
        )
        require(ok, "lines", lines, "a 1-D array of multiples of f0 (Hz)")
        require(bool(np.all((harmonics >= 1) & (harmonics <= top))), "lines", lines,
                f"within the band f0..{top * f0} Hz")  # fmt: skip
        return np.unique(harmonics).astype(np.int64)
    if f_max is not None:
        return np.arange(1, top + 1)
    # Neither given: the lines the force actually excites (finite data assumed; the core checks).
    if not np.all(np.isfinite(force)):
        bad = int(np.flatnonzero(~np.isfinite(force))[0])
        raise ValueError(
            f"force must be finite, got {float(force[bad])!r} at sample {bad + offset}"
        )  # in the recording
    mean = force.reshape(-1, period).mean(axis=0)
    if np.ptp(mean) == 0.0:
        raise _checks.NoExcitationError(f"force has no excitation: it is constant ({mean[0]:g} N) after settling")
    level = np.abs(np.fft.rfft(mean))[1 : top + 1]
    found = _checks.detect_lines(level)
    if found.size == 0:
        raise _checks.NoExcitationError(
            "force has no excitation: no harmonic of f0 stands clearly (10x) above the others; zero, constant or "
            "pure-noise force, or pass lines= or f_max="
        )
    return found


def _from_fields(fields: dict[str, Any]) -> Estimate:
    return Estimate(**fields | {"unexcited": UnexcitedLines(*fields["unexcited"])})


# amb_fast.load_estimate (the io layer) reads the one-axis files through this
register_estimate_kind(
    "# amb_fast estimate",
    ONE_AXIS,
    lambda text, name: _from_fields(estimate_fields_from_csv(text)),
    lambda ds: _from_fields(estimate_fields_from_dataset(ds)),
    None,
)
