"""The measurement-noise stream (cpp/include/amb_fast/random.hpp): xoshiro256++ against an independent
pure-Python implementation, a pinned stream (the same bits on every platform), the normal distribution
(moments, Kolmogorov-Smirnov, tails), independence, and the same numbers however a run is cut."""

from __future__ import annotations

import hashlib
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

import amb_fast as af
from amb_fast import _core

MASK = (1 << 64) - 1
FORCE_STREAM = 0x9E3779B97F4A7C15  # the force noise of seed s is the stream of s ^ this (loop.cpp)


def xoshiro256pp(seed: int, n: int) -> list[int]:
    """Blackman and Vigna's reference code (prng.di.unimi.it), state from splitmix64, in Python ints."""
    state = []
    for _ in range(4):
        seed = (seed + 0x9E3779B97F4A7C15) & MASK
        z = seed
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        state.append(z ^ (z >> 31))
    s0, s1, s2, s3 = state

    def rotl(x: int, k: int) -> int:
        return ((x << k) | (x >> (64 - k))) & MASK

    out = []
    for _ in range(n):
        out.append((rotl((s0 + s3) & MASK, 23) + s0) & MASK)
        t = (s1 << 17) & MASK
        s2 ^= s0
        s3 ^= s1
        s1 ^= s2
        s0 ^= s3
        s2 ^= t
        s3 = rotl(s3, 45)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2026, MASK])
def test_generator_is_xoshiro256pp(seed: int) -> None:
    assert _core.xoshiro256pp(seed, 1000).tolist() == xoshiro256pp(seed, 1000)


def test_stream_is_pinned() -> None:
    """The stream of a seed is part of the results: this fails if any bit of it changes (another
    compiler, platform or library), the ziggurat's wedge and tail paths included."""
    head = _core.normal_noise(2026, [8])
    expected = [-0.7239510484068481, -1.1143897443671393, 1.5564137174349624, -0.3241484870616147,
                -0.0501374951397197, 1.5916839429533076, 1.1115082893164416, 1.7109259089697988]  # fmt: skip
    assert head.tolist() == expected
    many = _core.normal_noise(2026, [200_000])
    assert (np.abs(many) > 3.6541528853610088).sum() > 20  # the tail method ran
    digest = hashlib.sha256(many.astype("<f8").tobytes()).hexdigest()
    assert digest == STREAM_2026_SHA256


STREAM_2026_SHA256 = "ecddb9ba6e7b6efb89315ab656f002a5a84fc3498ca768a4a0d00d03f1bac852"


@pytest.fixture(scope="module")
def deviates() -> np.ndarray:
    return _core.normal_noise(20261122, [4_000_000])


def test_moments(deviates: np.ndarray) -> None:
    """Mean, variance, skewness and excess kurtosis within 5 standard errors of N(0, 1)'s."""
    n = deviates.size
    assert abs(deviates.mean()) < 5 / np.sqrt(n)
    assert abs(deviates.var() - 1) < 5 * np.sqrt(2 / n)
    assert abs(stats.skew(deviates)) < 5 * np.sqrt(6 / n)
    assert abs(stats.kurtosis(deviates)) < 5 * np.sqrt(24 / n)


def test_kolmogorov_smirnov(deviates: np.ndarray) -> None:
    """The KS distance to N(0, 1) is below its 0.1 % critical value 1.95 / sqrt(n) (0.001 here), while
    a 1 % error in the scale or a 0.003 shift of the mean, far too small for the moments' tolerance
    to matter, is rejected: the tolerance does not pass by accident."""
    n = deviates.size
    critical = 1.949 / np.sqrt(n)
    assert stats.kstest(deviates, "norm").statistic < critical
    assert stats.kstest(1.01 * deviates, "norm").statistic > critical
    assert stats.kstest(deviates + 0.003, "norm").statistic > critical
    # The body percentile by percentile, within 5 standard errors of each quantile.
    p = np.linspace(0.01, 0.99, 99)
    x = stats.norm.ppf(p)
    se = np.sqrt(p * (1 - p) / n) / stats.norm.pdf(x)
    assert np.all(np.abs(np.quantile(deviates, p) - x) < 5 * se)


@pytest.fixture(scope="module")
def tails() -> tuple[int, np.ndarray]:
    """The deviates beyond 2 of a long stream (16e6 draws, about 4100 beyond the ziggurat's r)."""
    z = _core.normal_noise(7, [16_000_000])
    return z.size, z[np.abs(z) > 2.0]


@pytest.mark.parametrize("x", [2.0, 3.0, 3.6541528853610088, 4.0, 4.5, 5.0])
def test_tail_probabilities(tails: tuple[int, np.ndarray], x: float) -> None:
    """P(|z| > x) within 5 binomial standard errors, at and beyond the ziggurat's tail start r = 3.654."""
    n, beyond = tails
    p = 2 * stats.norm.sf(x)
    count = np.count_nonzero(np.abs(beyond) > x)
    assert abs(count - n * p) < 5 * np.sqrt(n * p * (1 - p))


def test_tail_shape(tails: tuple[int, np.ndarray]) -> None:
    """Beyond r (where Marsaglia's tail method takes over) the deviates follow the normal tail: KS
    against the truncated normal (its p-values over 300 seeds of 4e6 draws were uniform), both signs."""
    r = 3.6541528853610088
    _, beyond = tails
    tail = beyond[np.abs(beyond) > r]
    truncated = stats.truncnorm(r, np.inf)
    assert stats.kstest(np.abs(tail), truncated.cdf).pvalue > 1e-3
    assert abs(np.mean(tail > 0) - 0.5) < 5 * 0.5 / np.sqrt(tail.size)


def _correlations(a: np.ndarray, b: np.ndarray) -> list[float]:
    return [float(np.corrcoef(a, b)[0, 1]), float(np.corrcoef(a**2, b**2)[0, 1])]


def test_streams_and_seeds_are_independent() -> None:
    """The two noise sources of a seed, neighbouring seeds and neighbouring samples of one stream are
    uncorrelated, also in their squares: |r| < 5 / sqrt(n)."""
    n = 1_000_000
    bound = 5 / np.sqrt(n)
    for seed in (0, 1, 2026):
        sensor = _core.normal_noise(seed, [n])
        force = _core.normal_noise(seed ^ FORCE_STREAM, [n])
        neighbour = _core.normal_noise(seed + 1, [n])
        pairs = [(sensor, force), (sensor, neighbour), (sensor[1:], sensor[:-1]), (sensor[2:], sensor[:-2])]
        for a, b in pairs:
            assert max(abs(r) for r in _correlations(a, b)) < bound


@settings(max_examples=40, deadline=None)
@given(st.integers(0, MASK), st.lists(st.integers(0, 3000), min_size=1, max_size=8))
def test_chunking_does_not_change_the_stream(seed: int, chunks: list[int]) -> None:
    np.testing.assert_array_equal(_core.normal_noise(seed, chunks), _core.normal_noise(seed, [sum(chunks)]))


def test_sigma_scales_the_stream() -> None:
    np.testing.assert_array_equal(_core.normal_noise(5, [1000], 2e-8), 2e-8 * _core.normal_noise(5, [1000]))


def test_loop_records_the_force_stream() -> None:
    """The recorded force of a DC-coupled transducer under zero force is the force stream itself,
    however the loop cuts its run into chunks (1024 samples) and the record into calls."""
    rig = replace(af.Rig.paper(), force_coupling_tau=None, force_noise=1e-3, sensor_noise=2e-8)
    n = 5000
    trace = af.simulate(rig, af.PID.paper(), np.zeros(n), seed=11)
    np.testing.assert_array_equal(trace.force, _core.normal_noise(11 ^ FORCE_STREAM, [n], 1e-3))


def test_noise_levels_in_the_loop() -> None:
    """The sensor noise reaches the recorded displacement at its rms, without a force (the loop's own
    response to the noise is far below it at 20 nm)."""
    rig = replace(af.Rig.paper(), force_coupling_tau=None)
    trace = af.simulate(rig, af.PID.paper(), np.zeros(40_000), seed=3)
    assert trace.force.std() == pytest.approx(rig.force_noise, rel=0.02)
    assert np.abs(trace.displacement).max() < 10 * rig.sensor_noise
