"""The paper's observations (sections 3.1, 3.2.1-3.2.3 and the conclusions) as checks on data.

Each check is a plain function of arrays (frequencies in Hz, stiffness N/m, damping N s/m, receptance
magnitude m/N; a gain family is three or more gain values in increasing order with one row of data
per value), so it can be fed any data, including data where the observation does not hold. Each
returns a :class:`Claim` with the metric, the measured values and the verdict.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Claim:
    """One observation of the paper and whether the data reproduce it."""

    id: str
    section: str
    statement: str
    metric: str
    measured: str
    reproduced: bool


def _band(freq: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return (freq >= lo) & (freq <= hi)


def _low(freq: np.ndarray, family: np.ndarray) -> np.ndarray:
    """Per member of a family: the mean over the lines at 1-10 Hz."""
    return family[:, _band(freq, 1, 10)].mean(axis=1)


def _change(family: np.ndarray) -> np.ndarray:
    """The change across a family (last - first), relative to its middle member."""
    return np.abs(family[-1] - family[0]) / np.abs(family[len(family) // 2])


def _increasing(values: np.ndarray) -> bool:
    return bool(np.all(np.diff(values) > 0))


def _decreasing(values: np.ndarray) -> bool:
    return bool(np.all(np.diff(values) < 0))


def _fmt(values: np.ndarray, unit: str = "", digits: int = 4) -> str:
    return ", ".join(f"{v:.{digits}g}" for v in np.atleast_1d(values)) + (f" {unit}" if unit else "")


def natural_frequency(freq: np.ndarray, H: np.ndarray, half_width: float = 5.0) -> float:
    """Undamped natural frequency (Hz) where Re(F/Y) = k(w) - m w^2 crosses zero (the quadrature point
    of modal testing). Near it k(w) is nearly constant, so Re(F/Y) is fitted as a - b w^2 by least
    squares over the lines within ``half_width`` Hz of the first crossing (and always the two lines that
    bracket it, however far apart), and w_n = sqrt(a / b). The fit averages the noise of a dozen lines; it
    is tied to the stiffness, as the paper's reasoning is, and far steadier than the peak of |Y/F| on a 1 Hz
    grid.

    Returns NaN when Re(F/Y) does not fall through zero over the lines: the band holds no resonance (it
    ends below it or starts above it). Callers should say so ("outside the band"), not print the NaN.
    """
    real = np.real(H)
    i = np.flatnonzero((real[:-1] > 0) & (real[1:] <= 0))
    if i.size == 0:
        return float("nan")
    first = int(i[0])
    w2 = (2 * np.pi * np.asarray(freq, dtype=float)) ** 2
    near = np.abs(freq - freq[first]) <= half_width
    near[first : first + 2] = True  # sparse lines: the bracketing pair alone still gives a line
    slope, intercept = np.polyfit(w2[near], real[near], 1)
    ratio = -intercept / slope if slope != 0 else np.nan
    if not (np.isfinite(ratio) and ratio > 0):  # a noisy fit: interpolate between the bracketing lines
        a, b = real[first], real[first + 1]
        ratio = w2[first] + (w2[first + 1] - w2[first]) * a / (a - b)
    return float(np.sqrt(ratio) / (2 * np.pi))


# --- Section 3.1 --------------------------------------------------------------------------------


def effective_frequency_dependent_and_smooth(freq: np.ndarray, k_eff: np.ndarray, c_eff: np.ndarray) -> Claim:
    span = [np.ptp(x) / np.median(np.abs(x)) for x in (k_eff, c_eff)]
    rough = [np.median(np.abs(np.diff(x, 2))) / np.median(np.abs(x)) for x in (k_eff, c_eff)]
    ok = min(span) > 0.05 and max(rough) < 1e-2
    return Claim(
        "3.1-a", "3.1", "Effective stiffness and damping are frequency dependent and smooth (Fig. 4).",
        "range / median |x| > 5 % (frequency dependent) and median |2nd difference| / median |x| < 1 % (smooth), "
        "for k_eff and c_eff",
        f"range: {_fmt(np.array(span) * 100)} %; roughness: {_fmt(np.array(rough) * 100)} %", ok,
    )  # fmt: skip


def damping_actual_matches_effective(freq: np.ndarray, c: np.ndarray, c_eff: np.ndarray) -> Claim:
    # As the paper compares Figs. 4 and 5: differences against the scale the curves are drawn on.
    ratio = np.max(np.abs(c - c_eff)) / np.ptp(c_eff)
    worst = freq[int(np.argmax(np.abs(c - c_eff)))]
    return Claim(
        "3.1-b", "3.1", "Actual damping is quite similar to the effective damping throughout the frequency range.",
        "largest |c - c_eff| over all lines < 10 % of the range of c_eff (the scale of Figs. 4 and 5)",
        f"{ratio * 100:.2f} % (largest at {worst:g} Hz)", bool(ratio < 0.1),
    )  # fmt: skip


def stiffness_agrees_low_diverges_high(freq: np.ndarray, k: np.ndarray, k_eff: np.ndarray) -> Claim:
    low, high = freq <= 107.5, freq >= 107.5
    agree = float(np.median(np.abs(k[low] - k_eff[low]) / np.abs(k_eff[low])))
    slope = np.polyfit(freq[high], k[high], 1)[0]
    slope_eff = np.polyfit(freq[high], k_eff[high], 1)[0]
    ok = agree < 0.1 and slope_eff > 0 > slope
    return Claim(
        "3.1-c", "3.1", "Actual stiffness is similar to effective at 1-107 Hz; at 108-200 Hz the effective "
        "stiffness increases while the actual decreases.",
        "median |k - k_eff| / k_eff at 1-107 Hz < 10 %; least-squares slope at 108-200 Hz: k_eff > 0 > k",
        f"median difference {agree * 100:.2f} %; slopes: effective {slope_eff:.4g}, actual {slope:.4g} N/m per Hz",
        ok,
    )  # fmt: skip


# --- Section 3.2.1: integral gain ---------------------------------------------------------------


def ki_raises_resonance_peak(freq: np.ndarray, gains: np.ndarray, receptance: np.ndarray) -> Claim:
    peaks = np.abs(receptance).max(axis=1)
    return Claim(
        "3.2.1-a", "3.2.1", "Increasing Ki increases the response amplitude at the natural frequency (Fig. 6).",
        "peak |Y/F| strictly increasing with Ki", f"{_fmt(peaks, 'm/N')}", _increasing(peaks),
    )  # fmt: skip


def ki_acts_at_low_frequency_only(freq: np.ndarray, gains: np.ndarray, receptance: np.ndarray) -> Claim:
    mag = np.abs(receptance)
    spread = np.ptp(mag, axis=0) / mag.mean(axis=0)
    low, high = spread[_band(freq, 1, 10)].mean(), spread[_band(freq, 100, np.inf)].mean()
    ok = low > 10 * high and high < 0.02
    return Claim(
        "3.2.1-b", "3.2.1", "Integral feedback dominates the low-frequency response and has negligible effect at "
        "high frequency.",
        "relative spread of |Y/F| across the Ki family: mean at 1-10 Hz > 10x mean at >= 100 Hz, and the latter < 2 %",
        f"1-10 Hz: {low * 100:.3g} %; >= 100 Hz: {high * 100:.3g} %", ok,
    )  # fmt: skip


def ki_lowers_low_frequency_damping(freq: np.ndarray, gains: np.ndarray, c: np.ndarray) -> Claim:
    low = _low(freq, c)
    change = float(_change(low))
    ok = _decreasing(low) and change > 0.2
    return Claim(
        "3.2.1-c", "3.2.1", "Damping decreases significantly with increasing Ki at low frequency.",
        "mean c at 1-10 Hz strictly decreasing with Ki, by more than 20 % of the baseline across the family",
        f"{_fmt(low, 'N s/m')} (change {change * 100:.3g} %)", ok,
    )  # fmt: skip


def ki_attenuates_low_frequency_response(freq: np.ndarray, gains: np.ndarray, receptance: np.ndarray) -> Claim:
    low = _low(freq, np.abs(receptance))
    return Claim(
        "3.2.1-d", "3.2.1", "Increasing Ki attenuates the dynamic response at low frequency.",
        "mean |Y/F| at 1-10 Hz strictly decreasing with Ki", _fmt(low, "m/N"), _decreasing(low),
    )  # fmt: skip


def ki_raises_low_frequency_stiffness(freq: np.ndarray, gains: np.ndarray, k: np.ndarray) -> Claim:
    low = _low(freq, k)
    return Claim(
        "3.2.1-e", "3.2.1", "Stiffness at low frequency increases with Ki (Fig. 6).",
        "mean k at 1-10 Hz strictly increasing with Ki", _fmt(low, "N/m", 6), _increasing(low),
    )  # fmt: skip


def ki_raises_stiffness_near_resonance_marginally(
    freq: np.ndarray, gains: np.ndarray, k: np.ndarray, H: np.ndarray
) -> Claim:
    fn = np.array([natural_frequency(freq, h) for h in H])
    around = k[:, _band(freq, fn[len(fn) // 2] - 5, fn[len(fn) // 2] + 5)].mean(axis=1)
    change = float(_change(around))
    ok = _increasing(around) and change < 0.01 and _increasing(fn)
    return Claim(
        "3.2.1-f", "3.2.1", "Around the natural frequency the actual stiffness increases marginally with Ki, so the "
        "natural frequency increases (Fig. 7).",
        "mean k within 5 Hz of the natural frequency strictly increasing with Ki and changing by < 1 %; natural "
        "frequency (where Re F/Y crosses zero) strictly increasing",
        f"k: {_fmt(around, 'N/m', 7)} (change {change * 100:.3g} %); f_n: {_fmt(fn, 'Hz', 7)}", ok,
    )  # fmt: skip


# --- Section 3.2.2: derivative gain -------------------------------------------------------------


def kd_reduces_resonance_peak(freq: np.ndarray, gains: np.ndarray, c: np.ndarray, H: np.ndarray) -> Claim:
    peaks = np.abs(1 / H).max(axis=1)
    fn = natural_frequency(freq, H[len(H) // 2])
    damping = c[:, _band(freq, fn - 5, fn + 5)].mean(axis=1)
    reduction = 1 - peaks[-1] / peaks[0]
    ok = _increasing(damping) and _decreasing(peaks) and reduction > 0.3
    return Claim(
        "3.2.2-a", "3.2.2", "Increasing Kd increases damping, so the response at resonance is reduced "
        "significantly (Figs. 8, 9).",
        "mean c within 5 Hz of the natural frequency strictly increasing with Kd; peak |Y/F| strictly decreasing, "
        "by more than 30 % across the family",
        f"c: {_fmt(damping, 'N s/m')}; peaks: {_fmt(peaks, 'm/N')} (reduction {reduction * 100:.3g} %)", ok,
    )  # fmt: skip


def kd_changes_stiffness_at_high_frequency_only(freq: np.ndarray, gains: np.ndarray, k: np.ndarray) -> Claim:
    low, high = _low(freq, k), k[:, _band(freq, 150, np.inf)].mean(axis=1)
    change_low = np.ptp(low) / abs(low[len(low) // 2])
    change_high = np.ptp(high) / abs(high[len(high) // 2])
    ok = change_low < 0.02 and change_high > 0.2
    return Claim(
        "3.2.2-b", "3.2.2", "Kd affects stiffness little at low frequency but greatly at high frequency (Fig. 8).",
        "relative change of mean k across the Kd family: < 2 % at 1-10 Hz, > 20 % at >= 150 Hz",
        f"1-10 Hz: {change_low * 100:.3g} %; >= 150 Hz: {change_high * 100:.3g} %", ok,
    )  # fmt: skip


# --- Section 3.2.3: proportional gain ------------------------------------------------------------


def kp_raises_stiffness_and_natural_frequency(
    freq: np.ndarray, gains: np.ndarray, k: np.ndarray, H: np.ndarray
) -> Claim:
    stiffness = k.mean(axis=1)
    fn = np.array([natural_frequency(freq, h) for h in H])
    ok = _increasing(stiffness) and _increasing(fn)
    return Claim(
        "3.2.3-a", "3.2.3", "Increasing Kp increases stiffness, so the resonant frequency increases (Fig. 10).",
        "mean k over the band and the natural frequency both strictly increasing with Kp",
        f"k: {_fmt(stiffness, 'N/m')}; f_n: {_fmt(fn, 'Hz')}", ok,
    )  # fmt: skip


def kp_raises_low_frequency_damping(freq: np.ndarray, gains: np.ndarray, c: np.ndarray, H: np.ndarray) -> Claim:
    low_c = _low(freq, c)
    fn = natural_frequency(freq, H[0])
    below = np.abs(1 / H)[:, freq < 0.8 * fn].mean(axis=1)
    ok = _increasing(low_c) and _decreasing(below)
    return Claim(
        "3.2.3-b", "3.2.3", "Increasing Kp also increases damping at low frequency, so the response below "
        "resonance decreases (Fig. 10).",
        "mean c at 1-10 Hz strictly increasing with Kp; mean |Y/F| below 0.8 x the lowest natural frequency strictly "
        "decreasing",
        f"c: {_fmt(low_c, 'N s/m')}; |Y/F|: {_fmt(below, 'm/N')}", ok,
    )  # fmt: skip


# --- Conclusions ---------------------------------------------------------------------------------


def every_gain_moves_stiffness_and_damping(families: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> Claim:
    """``families``: gain name -> (k, c), each (family members, lines)."""
    moves = {name: (float(np.max(_change(k))), float(np.max(_change(c)))) for name, (k, c) in families.items()}
    ok = all(min(m) > 0.01 for m in moves.values())
    shown = "; ".join(f"{n}: k {m[0] * 100:.3g} %, c {m[1] * 100:.3g} %" for n, m in moves.items())
    return Claim(
        "4", "4", "Each of Kp, Ki and Kd changes both the actual stiffness and the actual damping.",
        "for every gain family, the largest relative change across the family at any line exceeds 1 % for both k and c",
        shown, ok,
    )  # fmt: skip


FamilyData = Mapping[str, Mapping[str, np.ndarray]]


def check_all(
    freq: np.ndarray, k: np.ndarray, c: np.ndarray, k_eff: np.ndarray, c_eff: np.ndarray, families: FamilyData
) -> list[Claim]:
    """Every check. ``families[name]`` has ``gains``, ``k``, ``c`` and ``H`` (F/Y), one row per gain."""
    ki, kd, kp = families["ki"], families["kd"], families["kp"]
    return [
        effective_frequency_dependent_and_smooth(freq, k_eff, c_eff),
        damping_actual_matches_effective(freq, c, c_eff),
        stiffness_agrees_low_diverges_high(freq, k, k_eff),
        ki_raises_resonance_peak(freq, ki["gains"], 1 / ki["H"]),
        ki_acts_at_low_frequency_only(freq, ki["gains"], 1 / ki["H"]),
        ki_lowers_low_frequency_damping(freq, ki["gains"], ki["c"]),
        ki_attenuates_low_frequency_response(freq, ki["gains"], 1 / ki["H"]),
        ki_raises_low_frequency_stiffness(freq, ki["gains"], ki["k"]),
        ki_raises_stiffness_near_resonance_marginally(freq, ki["gains"], ki["k"], ki["H"]),
        kd_reduces_resonance_peak(freq, kd["gains"], kd["c"], kd["H"]),
        kd_changes_stiffness_at_high_frequency_only(freq, kd["gains"], kd["k"]),
        kp_raises_stiffness_and_natural_frequency(freq, kp["gains"], kp["k"], kp["H"]),
        kp_raises_low_frequency_damping(freq, kp["gains"], kp["c"], kp["H"]),
        every_gain_moves_stiffness_and_damping({n: (f["k"], f["c"]) for n, f in families.items()}),
    ]


def markdown(claims: list[Claim]) -> str:
    """The claims as a Markdown table."""
    rows = ["| # | Observation (paper section) | Metric | Measured | Reproduced |", "|---|---|---|---|---|"]
    for claim in claims:
        cells = [claim.id, claim.statement, claim.metric, claim.measured, "yes" if claim.reproduced else "**no**"]
        rows.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    done = sum(c.reproduced for c in claims)
    return "\n".join(rows) + f"\n\n{done} of {len(claims)} observations reproduced.\n"
