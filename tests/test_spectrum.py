"""The estimator's transform (LineTransform in cpp/src/line_transform.cpp) against numpy.fft.rfft: the
vendored pocketfft and the direct sum, every kind of period length, the bins at 0 and Nyquist, and the
cost model's choice."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
from amb_fast import _core

TOL = 1e-12  # relative to the largest bin of the spectrum

LENGTHS = [4000, 4096, 1000, 4001, 3 * 7 * 11 * 13, 2 * 4001, 4, 5, 6, 7, 31, 64]  # 4001 is prime (Bluestein)


def bins_of(L: int, rng: np.random.Generator) -> list[int]:
    half = L // 2
    chosen = {0, 1, half, max(half - 1, 0)} | set(rng.integers(0, half + 1, size=min(12, half + 1)).tolist())
    return sorted(chosen)


@pytest.mark.parametrize("method", ["fft", "direct", "auto"])
@pytest.mark.parametrize("L", LENGTHS)
def test_matches_numpy_rfft(L: int, method: str, rng) -> None:
    x = rng.standard_normal(L) + 3.0  # a mean too: bin 0 is the largest
    bins = bins_of(L, rng)
    expected = np.fft.rfft(x)[bins]
    lines, used = _core.line_spectrum(x, bins, method)
    assert used == method or method == "auto"
    scale = np.abs(np.fft.rfft(x)).max()
    assert np.max(np.abs(lines - expected)) <= TOL * scale


@pytest.mark.parametrize("method", ["fft", "direct"])
def test_each_excited_line_to_1e_12_of_itself(method: str) -> None:
    """The paper's period and lines: a Schroeder multisine with sensor-level noise, each excited line
    within 1e-12 of its own magnitude (not only of the largest)."""
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    x = sphs.samples + 1e-6 * np.random.default_rng(3).standard_normal(sphs.samples.size)
    bins = sphs.harmonics.tolist()
    expected = np.fft.rfft(x)[bins]
    lines, _ = _core.line_spectrum(x, bins, method)
    assert np.max(np.abs(lines - expected) / np.abs(expected)) <= TOL


def test_fft_is_numpy_bit_for_bit(rng) -> None:
    """Same algorithm as numpy.fft (pocketfft's real transform); equal bit for bit here, though only the
    1e-12 bound above is promised."""
    x = rng.standard_normal(4000)
    lines, _ = _core.line_spectrum(x, list(range(2001)), "fft")
    assert np.max(np.abs(lines - np.fft.rfft(x))) <= TOL * np.abs(lines).max()


def test_cost_model_choice() -> None:
    """A handful of lines of a 4000-sample period: the direct sum; the paper's 200 lines: the FFT; a prime
    period, whose FFT goes through Bluestein's algorithm, keeps the direct sum for more lines."""
    x = np.zeros(4000)
    assert _core.line_spectrum(x, [1, 2, 3])[1] == "direct"
    assert _core.line_spectrum(x, list(range(1, 201)))[1] == "fft"
    assert _core.line_spectrum(x, list(range(1, 11)))[1] == "fft"
    assert _core.line_spectrum(np.zeros(4001), list(range(1, 41)))[1] == "direct"


def test_bad_bins_are_refused() -> None:
    with pytest.raises(ValueError, match="bin"):
        _core.line_spectrum(np.zeros(10), [6])
    with pytest.raises(ValueError, match="method"):
        _core.line_spectrum(np.zeros(10), [1], "goertzel")


@pytest.mark.parametrize("lines", [[3], list(range(1, 201))])
def test_estimator_agrees_with_numpy_pipeline_either_way(lines: list[int], rng) -> None:
    """identify with few lines (3 bins, excited and unexcited: the direct sum) and with the paper's 200
    (the FFT) against numpy's reshape-mean + rfft."""
    period, periods = 4000, 4
    t = np.arange(period * periods) / 4000.0
    force = sum(np.cos(2 * np.pi * f * t + f) for f in lines) + 1e-3 * rng.standard_normal(t.size)
    displacement = 1e-5 * np.roll(force, 3) + 1e-8 * rng.standard_normal(t.size)
    est = af.identify(force, displacement, fs=4000.0, f0=1.0, mass=0.92, lines=lines)
    harmonics = np.array(lines)
    mean_f = np.fft.rfft(force.reshape(periods, period).mean(axis=0))[harmonics] * 2 / period
    mean_y = np.fft.rfft(displacement.reshape(periods, period).mean(axis=0))[harmonics] * 2 / period
    np.testing.assert_allclose(est.force, mean_f, rtol=1e-12, atol=0)
    np.testing.assert_allclose(est.displacement, mean_y, rtol=1e-12, atol=0)


@pytest.mark.parametrize("method", ["fft", "direct"])
def test_rows_of_periods(method: str, rng) -> None:
    x = rng.standard_normal((5, 400))
    lines, _ = _core.line_spectrum(x, [0, 3, 200], method)
    expected = np.fft.rfft(x, axis=1)[:, [0, 3, 200]]
    assert lines.shape == (5, 3)
    assert np.max(np.abs(lines - expected)) <= TOL * np.abs(np.fft.rfft(x, axis=1)).max()


def test_batch_means_of_a_long_record(rng) -> None:
    """Beyond 63 periods the estimator transforms block means (here 70 periods: 35 blocks of 2, scaled
    in place): the averaged spectra and the batch-means standard errors against numpy."""
    period, periods, G = 400, 70, 2
    lines = np.arange(1, 21)
    t = np.arange(period * periods) / 4000.0
    force = sum(np.cos(2 * np.pi * 10 * n * t + n) for n in lines) + 1e-2 * rng.standard_normal(t.size)
    displacement = 1e-5 * np.roll(force, 3) + 1e-7 * rng.standard_normal(t.size)
    est = af.identify(force, displacement, fs=4000.0, f0=10.0, mass=0.92, f_max=200.0)
    assert est.blocks == periods // G
    Fb = np.fft.rfft(force.reshape(-1, G, period).mean(axis=1), axis=1)[:, lines]
    Yb = np.fft.rfft(displacement.reshape(-1, G, period).mean(axis=1), axis=1)[:, lines]
    Fm, Ym = Fb.mean(axis=0), Yb.mean(axis=0)
    np.testing.assert_allclose(est.force, Fm * 2 / period, rtol=1e-12, atol=0)
    np.testing.assert_allclose(est.displacement, Ym * 2 / period, rtol=1e-12, atol=0)
    H = Fm / Ym
    dH = ((Fb - Fm) - H * (Yb - Ym)) / Ym
    to_mean = G / ((est.blocks - 1) * periods)
    w = 2 * np.pi * est.freq
    np.testing.assert_allclose(est.k_std, np.sqrt((dH.real**2).sum(axis=0) * to_mean), rtol=1e-9)
    np.testing.assert_allclose(est.c_std, np.sqrt((dH.imag**2).sum(axis=0) * to_mean) / w, rtol=1e-9)
