"""Schroeder multisines: lines, phases, crest factors."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af


def spectrum(ms: af.Multisine) -> np.ndarray:
    """Complex amplitudes of one period, bin n = n f0."""
    return np.fft.rfft(ms.samples) * 2 / ms.samples.size


def test_paper_sphs_has_its_lines_phases_and_crest_factor() -> None:
    ms = af.schroeder_multisine()  # 1-200 Hz, 1 Hz fundamental, 4 kHz
    X = spectrum(ms)
    assert ms.samples.size == 4000
    np.testing.assert_array_equal(ms.freq, np.arange(1, 201))
    np.testing.assert_allclose(np.abs(X[1:201]), ms.amplitudes, rtol=1e-12)
    others = np.abs(np.delete(X, np.arange(1, 201)))
    assert others.max() < 1e-12 * ms.amplitudes[0]
    n = np.arange(1, 201)
    expected = -np.pi * n * (n - 1) / 200  # MODEL.md section 3
    np.testing.assert_allclose(np.angle(X[1:201] * np.exp(-1j * expected)), 0, atol=1e-9)
    assert np.sqrt(np.mean(ms.samples**2)) == pytest.approx(1.0, rel=1e-12)
    assert 1.6 < ms.crest_factor < 1.8


def test_optimised_crest_factor_keeps_the_spectrum_flat() -> None:
    ms = af.schroeder_multisine(optimize_crest=True)
    X = spectrum(ms)
    assert ms.crest_factor <= 1.45
    np.testing.assert_allclose(np.abs(X[1:201]), ms.amplitudes, rtol=1e-12)
    assert np.abs(np.delete(X, np.arange(1, 201))).max() < 1e-12 * ms.amplitudes[0]


def test_odd_and_random_odd_lines() -> None:
    odd = af.schroeder_multisine(lines="odd")
    np.testing.assert_array_equal(odd.freq, np.arange(1, 200, 2))
    random_odd = af.schroeder_multisine(lines="random-odd", seed=7)
    groups = np.arange(1, 200, 2)[:99].reshape(-1, 3)  # 33 full groups of three odd lines
    for group in groups:
        assert np.isin(group, random_odd.freq).sum() == 2
    assert np.all(random_odd.freq % 2 == 1)
    again = af.schroeder_multisine(lines="random-odd", seed=7)
    np.testing.assert_array_equal(random_odd.freq, again.freq)
    X = spectrum(random_odd)
    excited = np.rint(random_odd.freq).astype(int)
    assert np.abs(np.delete(X, excited)).max() < 1e-12 * random_odd.amplitudes[0]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(fs=4000.0, f0=3.0), "fs/f0 must be a whole number"),
        (dict(f_max=2000.0), "f_max must be at least f0"),
        (dict(f_max=0.5), "f_max must be at least f0"),
        (dict(lines=[1.0, 250.0]), "lines must be between f0 and f_max"),
        (dict(lines=[1.5]), "lines must be"),
        (dict(lines="even"), "lines must be"),
        (dict(rms=-1.0), "rms must be"),
    ],
)
def test_bad_multisines_are_refused(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        af.schroeder_multisine(**kwargs)
