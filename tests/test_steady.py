"""The periodic steady-state start, the settling limit and Ctrl-C (issue: speed where users run it)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest
from scipy import signal as sig
from scipy import stats

import amb_fast as af


def rel(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(actual - expected) / np.abs(expected)))


@pytest.fixture(scope="module")
def sphs() -> af.Multisine:
    return af.schroeder_multisine(f0=1.0, f_max=200.0)


QUIET_PAPER = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)


@pytest.mark.parametrize(
    ("rig", "pid"),
    [
        (QUIET_PAPER, af.PID.paper()),
        # A 100 s AC coupling and an integral corner near 1e-4 Hz: poles within 1e-5 of the unit circle,
        # which from rest would need about 10^5 periods to settle.
        (replace(QUIET_PAPER, force_coupling_tau=100.0), replace(af.PID.paper(), ki=0.5)),
        (af.Rig(amp_bandwidth=1500.0, sensor_bandwidth=5000.0), af.PID(kp=2000.0, ki=20000.0, kd=5.0, delay=2)),
    ],
)
def test_steady_start_equals_the_exact_response_without_settling(rig, pid, sphs) -> None:
    radius = np.max(np.abs(af.closed_loop_poles(rig, pid)))
    est = af.run_experiment(rig, pid, sphs, periods=2)
    assert rel(est.receptance, af.predict(rig, pid, est.freq)) < 1e-9
    assert radius < 1  # and the rule for a start from rest would have asked for:
    if radius > 0.99999:
        with pytest.raises(ValueError, match=r"settling from rest would take \d+ periods .*slowest pole has \|z\|"):
            af.run_experiment(rig, pid, sphs, start="rest")


def test_steady_start_equals_a_long_settled_run_from_rest(sphs) -> None:
    """The same periods as an independent simulation from rest (scipy's dlsim of the closed loop),
    settled until its slowest pole has decayed to 1e-13."""
    rig, pid = af.Rig(amp_bandwidth=1500.0), af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0)
    A, B, C, D = af.closed_loop(rig, pid)
    radius = np.max(np.abs(af.closed_loop_poles(rig, pid)))
    periods = int(np.ceil(np.log(1e-13) / np.log(radius) / sphs.period_samples)) + 1  # settled to 1e-13
    _, y, _ = sig.dlsim((A, B, C[:1], D[:1], 1 / pid.fs), np.tile(sphs.samples, periods))
    last = y[-sphs.period_samples :, 0]
    steady = af.run_experiment(rig, pid, sphs, periods=2, start="steady")
    expected = np.fft.rfft(last)[sphs.harmonics] * 2 / sphs.period_samples
    assert rel(steady.displacement, expected) < 1e-9


def test_rest_start_keeps_automatic_settling_and_agrees(sphs) -> None:
    rig, pid = af.Rig(amp_bandwidth=1500.0), af.PID(kp=2000.0, ki=20000.0, kd=5.0)
    steady = af.run_experiment(rig, pid, sphs, periods=2)
    rest = af.run_experiment(rig, pid, sphs, periods=2, start="rest")
    assert rel(rest.receptance, steady.receptance) < 1e-8
    with pytest.raises(ValueError, match="start must be 'steady' or 'rest'"):
        af.run_experiment(rig, pid, sphs, start="settled")


def test_nonlinear_law_settles_from_the_linearised_steady_state(sphs) -> None:
    rig = replace(af.Rig(amp_bandwidth=1500.0), force_law="nonlinear")
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0)
    small = replace(sphs, samples=0.05 * sphs.samples)
    est = af.run_experiment(rig, pid, small, periods=2)
    linear = af.predict(replace(rig, force_law="linear"), pid, est.freq)
    assert rel(est.receptance, linear) < 1e-3  # the distortion of the magnet law at 0.05 N rms


def test_first_recorded_period_is_statistically_like_later_ones(sphs) -> None:
    """The noise-driven state starts in its stationary distribution: across seeds, the first period's
    displacement spread at the lines equals that of a period long after the start."""
    rig = replace(af.Rig.paper(), force_noise=0.0)
    pid = af.PID.paper()
    first, late = [], []
    for seed in range(60):
        est_first = af.run_experiment(rig, pid, sphs, periods=2, seed=seed)
        est_late = af.run_experiment(rig, pid, sphs, periods=2, settle_periods=30, seed=seed)
        first.append(est_first.displacement)
        late.append(est_late.displacement)
    spread_first = np.std(np.array(first), axis=0)
    spread_late = np.std(np.array(late), axis=0)
    # Same distribution at every line: the ratio of variances is F(59, 59)-distributed; the pooled log
    # ratio over the 200 lines is near zero (its standard error is about 0.26 / sqrt(200) per line).
    log_ratio = np.log(spread_first**2 / spread_late**2)
    assert abs(np.mean(log_ratio)) < 0.08
    # and from rest (no stationary start) the first period is not like the later ones at low frequency
    rest = [af.run_experiment(rig, pid, sphs, periods=2, seed=s, start="rest", settle_periods=0).displacement
            for s in range(20)]  # fmt: skip
    transient = np.abs(np.mean(np.array(rest), axis=0) - np.mean(np.array(late), axis=0))[:5]
    assert np.all(transient > 5 * spread_late[:5] / np.sqrt(20))


def test_standard_errors_stay_honest_from_the_steady_start(sphs) -> None:
    """95 % Student-t intervals from k_std cover the exact k at 92-98 % of the lines (200 seeds)."""
    rig, pid = af.Rig.paper(), af.PID.paper()
    exact = af.predict(rig, pid, sphs.freq)
    k_exact = rig.mass * (2 * np.pi * sphs.freq) ** 2 + (1 / exact).real
    result = af.sweep(rig, pid, sphs, kp=np.full(200, pid.kp), grid="zip", periods=10, seed=7, progress=False)
    t = stats.t.ppf(0.975, result.blocks - 1)
    covered = np.abs(result.k - k_exact) <= t * result.k_std
    assert 0.92 <= covered.mean() <= 0.98


INTERRUPTED = [
    "af.run_experiment(af.Rig.paper(), af.PID.paper(), ms, start='rest', settle_periods=100000)",
    "af.simulate(af.Rig.paper(), af.PID.paper(), np.zeros(400_000_000))",
    "af.sweep(af.Rig.paper(), af.PID.paper(), ms, kp=np.linspace(2000, 3000, 64), start='rest',"
    " settle_periods=3000, progress=False)",
    "af.two_axis.sweep(af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f0=0.25, f_max=50.0),"
    " kp=np.linspace(2000, 3000, 1000), start='rest')",
]


@pytest.mark.parametrize("call", INTERRUPTED, ids=["run_experiment", "simulate", "sweep", "two-axis sweep"])
def test_ctrl_c_stops_a_long_core_call(call: str) -> None:
    """SIGINT during a call that would run for minutes ends it with KeyboardInterrupt (the time it takes
    is measured in bench/, not asserted here beyond 'long before the call would have finished')."""
    script = "\n".join(["import amb_fast as af, numpy as np", "ms = af.schroeder_multisine(f0=1.0, f_max=200.0)",
                         "print('go', flush=True)", call, "print('finished')"])  # fmt: skip
    process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)  # fmt: skip
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "go"
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert "finished" not in out
    assert "KeyboardInterrupt" in err
