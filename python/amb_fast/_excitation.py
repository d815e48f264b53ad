"""Periodic multisine excitations (MODEL.md section 3)."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Union

import numpy as np

from ._equality import ArrayRecord
from ._validate import integer, real, require

Lines = Union[Literal["all", "odd", "random-odd"], Sequence[float], np.ndarray]


@dataclass(frozen=True, eq=False)
class Multisine(ArrayRecord):
    """One period of a multisine ``x(t) = sum_n A_n cos(2 pi f_n t + phi_n)``, sampled at ``fs``.

    Attributes
    ----------
    samples : ndarray
        One period, N (repeat it with ``np.tile`` for a longer record).
    freq : ndarray
        Excited lines, Hz (multiples of ``f0``).
    amplitudes : ndarray
        Amplitude of each line, N.
    phases : ndarray
        Phase of each line, rad.
    fs, f0 : float
        Sampling frequency and fundamental (frequency resolution), Hz.
    """

    samples: np.ndarray
    freq: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray
    fs: float
    f0: float

    @property
    def crest_factor(self) -> float:
        """Peak over rms of one period."""
        return float(np.max(np.abs(self.samples)) / np.sqrt(np.mean(self.samples**2)))

    @property
    def period_samples(self) -> int:
        return int(self.samples.size)

    @functools.cached_property
    def harmonics(self) -> np.ndarray:
        """Harmonic numbers of the excited lines (freq / f0)."""
        return np.rint(self.freq / self.f0).astype(np.int64)


def period_samples(fs: float, f0: float) -> int:
    """Samples per period ``fs/f0``, which must be a whole number."""
    ratio = fs / f0
    require(abs(ratio - round(ratio)) < 1e-9 * ratio, "fs/f0", ratio, "a whole number of samples per period")
    return int(round(ratio))


def schroeder_phases(count: int) -> np.ndarray:
    """Schroeder's phases ``-pi k (k-1) / K`` for ``K`` equal-amplitude lines, k = 1..K."""
    k = np.arange(1, count + 1)
    return -np.pi * k * (k - 1) / count


def _select_lines(lines: Lines, top: int, f0: float, rng: np.random.Generator) -> np.ndarray:
    """Harmonic numbers to excite, up to ``top``."""
    if isinstance(lines, str):
        require(lines in ("all", "odd", "random-odd"), "lines", lines, "'all', 'odd', 'random-odd' or frequencies")
        if lines == "all":
            return np.arange(1, top + 1)
        odd = np.arange(1, top + 1, 2)
        if lines == "odd":
            return odd
        # Random odd: in each group of 3 consecutive odd lines one, chosen at random, is left out; the
        # gaps reveal odd-order distortion, the even lines even-order distortion.
        keep = np.ones(odd.size, dtype=bool)
        for start in range(0, odd.size - odd.size % 3, 3):
            keep[start + rng.integers(3)] = False
        return odd[keep]
    freq = np.asarray(lines, dtype=float)
    harmonics = np.rint(freq / f0)
    require(
        freq.ndim == 1 and freq.size > 0 and bool(np.all(np.abs(harmonics * f0 - freq) < 1e-9 * f0)),
        "lines", lines, "'all', 'odd', 'random-odd' or a 1-D array of multiples of f0 (Hz)",
    )  # fmt: skip
    require(
        bool(np.all((harmonics >= 1) & (harmonics <= top))), "lines", lines, f"between f0 and f_max ({top * f0} Hz)"
    )
    require(np.unique(harmonics).size == harmonics.size, "lines", lines, "without repeats")
    return np.sort(harmonics).astype(np.int64)


def _synthesise(harmonics: np.ndarray, amplitude: float, phases: np.ndarray, n: int) -> np.ndarray:
    spectrum = np.zeros(n // 2 + 1, dtype=complex)
    spectrum[harmonics] = amplitude * n / 2 * np.exp(1j * phases)
    return np.fft.irfft(spectrum, n)


def _lower_crest(harmonics: np.ndarray, amplitude: float, phases: np.ndarray, n: int, iterations: int) -> np.ndarray:
    """Clip-and-restore iterations from the given phases; keeps the phases of the lowest peak seen.

    Each pass clips the signal below its peak, takes the phases of the clipped signal's spectrum at
    the excited lines, and rebuilds the signal with the prescribed amplitudes (nothing elsewhere).
    """
    best, best_peak = phases, np.max(np.abs(_synthesise(harmonics, amplitude, phases, n)))
    x = _synthesise(harmonics, amplitude, phases, n)
    for it in range(iterations):
        level = (0.97 - 0.1 * (1 - it / iterations)) * np.max(np.abs(x))
        phases = np.angle(np.fft.rfft(np.clip(x, -level, level))[harmonics])
        x = _synthesise(harmonics, amplitude, phases, n)
        peak = np.max(np.abs(x))
        if peak < best_peak:
            best, best_peak = phases, peak
    return best


def schroeder_multisine(
    f0: float = 1.0,
    f_max: float = 200.0,
    fs: float = 4000.0,
    rms: float = 1.0,
    lines: Lines = "all",
    optimize_crest: bool = False,
    seed: int | None = None,
) -> Multisine:
    """A Schroeder-phased harmonic sequence (SPHS): equal amplitudes on lines n f0 up to ``f_max``.

    Parameters
    ----------
    f0 : float
        Fundamental, Hz; ``fs/f0`` must be a whole number of samples.
    f_max : float
        Highest line, Hz (below the Nyquist frequency fs/2).
    fs : float
        Sampling frequency, Hz.
    rms : float
        Rms of the signal, N.
    lines : {"all", "odd", "random-odd"} or array of Hz
        Every harmonic, the odd ones, odd ones with one in each group of three left out at random
        (for detecting non-linear distortion), or the given frequencies.
    optimize_crest : bool
        Lower the crest factor by clip-and-restore iterations from Schroeder's phases: the excited
        amplitudes stay as they are, nothing appears on other lines.
    seed : int or None
        Seed for ``"random-odd"``.
    """
    real("f0", f0, "Hz", positive=True)
    real("fs", fs, "Hz", positive=True)
    require(real("rms", rms, "N", positive=True) <= 1e12, "rms", rms, "at most 1e12 N (larger overflows the samples)")
    real("f_max", f_max, "Hz", positive=True)
    require(f0 <= f_max < fs / 2, "f_max", f_max, f"at least f0 ({f0} Hz) and below fs/2 ({fs / 2} Hz)")
    if seed is not None:
        integer("seed", seed, 0)
    n = period_samples(fs, f0)
    harmonics = _select_lines(lines, int(np.floor(f_max / f0 + 1e-9)), f0, np.random.default_rng(seed))
    amplitude = rms * np.sqrt(2.0 / harmonics.size)
    phases = schroeder_phases(harmonics.size)
    if optimize_crest:
        phases = _lower_crest(harmonics, amplitude, phases, n, iterations=300)
    samples = _synthesise(harmonics, amplitude, phases, n)
    return Multisine(
        samples=samples,
        freq=harmonics * f0,
        amplitudes=np.full(harmonics.size, amplitude),
        phases=np.asarray(phases, dtype=float),
        fs=float(fs),
        f0=float(f0),
    )
