"""Realisations of a controller as a discrete state space: checked coefficient arrays, sections,
series and parallel connections, delays, zeros-poles-gain, and the discretisation of a continuous design
(Tustin with optional prewarping, zero-order hold, matched poles and zeros). Plain functions on
``(A, B, C, D)`` tuples; :class:`~amb_fast.Controller` builds on them."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validate import real, require

MAX_ORDER = 24
"""Largest number of controller states (the whole-sample delay not counted)."""

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _real_array(name: str, values: Any, what: str) -> np.ndarray:
    """``values`` as a float array; complex values only with zero imaginary parts."""
    try:
        array = np.asarray(values)
        if np.iscomplexobj(array):
            require(bool(np.all(array.imag == 0)), name, values, f"{what} (not complex)")
            array = array.real
        return np.asarray(array, dtype=float)
    except (TypeError, ValueError) as error:
        if str(error).startswith(name + " must"):
            raise
        raise ValueError(f"{name} must be {what}, got {values!r}") from None


def _floats(name: str, values: ArrayLike) -> np.ndarray:
    """A 1-D array of finite real coefficients."""
    array = np.atleast_1d(_real_array(name, values, "a sequence of real numbers"))
    require(array.ndim == 1 and array.size > 0, name, values, "a non-empty 1-D sequence of coefficients")
    require(bool(np.all(np.isfinite(array))), name, values, "finite (no NaN or inf)")
    return array


def _strip_leading(poly: np.ndarray) -> np.ndarray:
    nonzero = np.flatnonzero(poly)
    return poly[nonzero[0] :] if nonzero.size else np.zeros(1)


def _proper_pair(num: ArrayLike, den: ArrayLike, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Validated (num, den) with leading zeros removed; ``num`` no longer than ``den`` (causal/proper)."""
    n, d = _strip_leading(_floats("num", num)), _strip_leading(_floats("den", den))
    require(bool(d[0] != 0), "den", den, "not all zero")
    require(
        n.size <= d.size,
        "num",
        num,
        f"of degree <= that of den (degree {d.size - 1}): a {what} of higher numerator degree is improper (non-causal)",
    )
    if d.size - 1 > MAX_ORDER:
        raise ValueError(
            f"den must be of degree <= {MAX_ORDER} (the largest controller order), got degree {d.size - 1}"
        )
    return n, d


# ---------------------------------------------------------------------------------------------- state spaces
def _static(d: float) -> Matrices:
    """A static gain ``d``: no states."""
    return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[d]], dtype=float)


def _below_nyquist(name: str, value: float, fs: float) -> None:
    require(value < fs / 2, name, value, f"below the Nyquist frequency {fs / 2} Hz")


def _section_ss(b: np.ndarray, a: np.ndarray) -> Matrices:
    """Controllable canonical form of one section b(z)/a(z) (positive powers, len(b) <= len(a) <= 3).

    Leading zeros (padding) and common trailing zeros (factors z / z) are removed first, so a first-order
    section has one state and a gain none.
    """
    a = _strip_leading(np.asarray(a, dtype=float))
    b = np.asarray(b, dtype=float)
    b = b[b.size - a.size :] if b.size > a.size else np.concatenate([np.zeros(a.size - b.size), b])
    while a.size > 1 and a[-1] == 0 and b[-1] == 0:
        a, b = a[:-1], b[:-1]
    b, a = b / a[0], a / a[0]
    n = a.size - 1
    A, B, C, D = _static(b[0])
    if n:
        A = np.zeros((n, n))
        A[0, :] = -a[1:]
        A[1:, :-1] += np.eye(n - 1)
        B = np.zeros((n, 1))
        B[0, 0] = 1.0
        C = (b[1:] - b[0] * a[1:])[None, :]
    return A, B, C, D


def _join(first: Matrices, second: Matrices, series: bool) -> Matrices:
    """``first`` then ``second`` in series (u -> first -> second -> y), or the two in parallel."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.zeros((n1 + n2, n1 + n2))
    A[:n1, :n1] = A1
    A[n1:, n1:] = A2
    if not series:
        return A, np.vstack([B1, B2]), np.hstack([C1, C2]), D1 + D2
    A[n1:, :n1] = B2 @ C1
    return A, np.vstack([B1, B2 @ D1]), np.hstack([D2 @ C1, C2]), D2 @ D1


def _delay_ss(samples: int) -> Matrices:
    """z^-samples as a shift register of ``samples`` states."""
    if samples == 0:
        return _static(1.0)
    B = np.zeros((samples, 1))
    B[0, 0] = 1.0
    C = np.zeros((1, samples))
    C[0, -1] = 1.0
    return np.eye(samples, k=-1), B, C, np.zeros((1, 1))


def _sections_ss(sections: Sequence[tuple[np.ndarray, np.ndarray]]) -> Matrices:
    """Sections b(z)/a(z) (positive powers, degree <= 2) connected in series."""
    ss = _static(1.0)
    for b, a in sections:
        ss = _join(ss, _section_ss(b, a), series=True)
    return ss


def _factors(roots: np.ndarray) -> list[list[complex]]:
    """Roots grouped into quadratic factors (a conjugate pair, or two neighbouring real roots in sorted
    order) and at most one linear factor (the last)."""
    tol = 1e-10 * np.maximum(1.0, np.abs(roots))
    real_roots = sorted(float(r.real) for r, t in zip(roots, tol) if abs(r.imag) <= t)
    upper = [complex(r) for r, t in zip(roots, tol) if r.imag > t]  # the upper member of each conjugate pair
    groups: list[list[complex]] = [[r, r.conjugate()] for r in upper]
    groups += [[real_roots[j], real_roots[j + 1]] for j in range(0, len(real_roots) - 1, 2)]
    if len(real_roots) % 2:
        groups.append([real_roots[-1]])
    return groups


def _zpk_ss(zeros: np.ndarray, poles: np.ndarray, k: float) -> Matrices:
    """Series of first- and second-order sections: poles grouped in conjugate pairs (or pairs of real
    poles), each quadratic factor of zeros given to the nearest free pole pair, most resonant first.
    The relative degree is kept: no zeros are added at the origin (unlike ``scipy.signal.tf2sos``)."""
    if poles.size == 0:
        return _static(k)
    dens = _factors(poles)
    nums: list[list[complex]] = [[] for _ in dens]
    free = set(range(len(dens)))

    def nearest(group: list[complex], candidates: list[int]) -> int:
        return min(candidates, key=lambda j: min(abs(z - p) for z in group for p in dens[j]))

    zero_groups = _factors(zeros) if k != 0 else []
    linear = [g for g in zero_groups if len(g) == 1]
    quadratic = sorted((g for g in zero_groups if len(g) == 2), key=lambda g: abs(1 - abs(g[0])))
    for group in linear + quadratic:
        fits = [j for j in free if len(dens[j]) >= len(group)]
        if len(group) == 1 and any(len(dens[j]) == 1 for j in fits):
            fits = [j for j in fits if len(dens[j]) == 1]
        j = nearest(group, fits)
        nums[j] = group
        free.discard(j)
    sections = []
    for j, (num_roots, den_roots) in enumerate(zip(nums, dens)):
        b = np.atleast_1d(np.real(np.poly(num_roots))) * (k if j == 0 else 1.0)
        sections.append((b, np.atleast_1d(np.real(np.poly(den_roots)))))
    return _sections_ss(sections)


def _conjugate_pairs(name: str, roots: np.ndarray, given: Any) -> None:
    ok = roots.size == 0 or np.allclose(np.sort_complex(roots), np.sort_complex(roots.conj()), rtol=1e-9, atol=1e-12)
    require(bool(ok), name, given, "real or in complex-conjugate pairs (a real controller)")


# ------------------------------------------------------------------------------------------- discretisation
def _discretise(num: np.ndarray, den: np.ndarray, fs: float, method: str, prewarp: float | None) -> Matrices:
    """A proper continuous (num, den) in s as a discrete state space (series of sections)."""
    require(method in ("tustin", "zoh", "matched"), "method", method, "'tustin', 'zoh' or 'matched'")
    if prewarp is not None:
        real("prewarp", prewarp, "Hz", positive=True)
        require(method == "tustin", "prewarp", prewarp, "None unless method='tustin'")
        _below_nyquist("prewarp", prewarp, fs)
    from scipy import signal  # on first use: importing it takes half a second

    zeros, poles = np.roots(num), np.roots(den)
    k = num[0] / den[0]
    T = 1.0 / fs
    if method == "tustin":
        # s = 2 fw (z - 1)/(z + 1), with fw = pi f0 / tan(pi f0 / fs) so that s = j 2 pi f0 maps exactly.
        fw = fs if prewarp is None else math.pi * prewarp / math.tan(math.pi * prewarp / fs)
        zd, pd, kd = signal.bilinear_zpk(zeros, poles, k, fw)
        return _zpk_ss(np.asarray(zd), np.asarray(pd), float(np.real(kd)))
    if method == "zoh":
        numd, dend, _ = signal.cont2discrete((num, den), T, method="zoh")
        nd, dd = _strip_leading(np.atleast_2d(numd)[0]), _strip_leading(np.asarray(dend))
        return _zpk_ss(np.roots(nd), np.roots(dd), float(nd[0] / dd[0]))
    # Matched pole-zero (python-control's convention): z = exp(sT) for every finite root, no zeros added
    # at z = -1, DC gain matched. Roots at s = 0 map to z = 1 and are matched as s <-> (z - 1)/T.
    origin = lambda r: np.abs(r) * T < 1e-12  # noqa: E731
    zd, pd = np.exp(zeros * T), np.exp(poles * T)
    zc, pc = zeros[~origin(zeros)], poles[~origin(poles)]
    excess = int(np.sum(origin(zeros))) - int(np.sum(origin(poles)))
    continuous = k * np.prod(-zc) / np.prod(-pc)
    discrete = np.prod(1 - np.exp(zc * T)) / np.prod(1 - np.exp(pc * T)) * T**excess
    return _zpk_ss(zd, pd, float(np.real(continuous / discrete)))
