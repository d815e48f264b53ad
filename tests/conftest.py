from __future__ import annotations

import os

# Small matrix calls (expm, solve) run many times over: one BLAS thread is faster than two on a loaded
# two-core machine, where OpenBLAS's threads made them up to 100x slower. Set before numpy loads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest

import amb_fast as af

# A stable baseline used across the tests: every lag configuration, delay 0-2, with or without the
# derivative filter and the integral, stays stable with these gains (checked in test_loop.py).
GAINS = dict(kp=2000.0, ki=20000.0, kd=5.0)
ALL_LAGS = dict(amp_bandwidth=1500.0, eddy_bandwidth=800.0, sensor_bandwidth=5000.0)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture
def lagged_rig() -> af.Rig:
    return af.Rig(**ALL_LAGS)


@pytest.fixture
def pid() -> af.PID:
    return af.PID(**GAINS, derivative_cutoff=1000.0)


@pytest.fixture(params=["pandas", "numpy"])
def text_parser(request, monkeypatch) -> str:
    """Text is parsed by pandas when it is installed, else by numpy: the text tests run with both."""
    if request.param == "numpy":
        monkeypatch.setitem(__import__("sys").modules, "pandas", None)
    else:
        pytest.importorskip("pandas")
    return request.param
