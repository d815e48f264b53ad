"""Reliability: touchdown, saturation, threads, determinism, bounded memory."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af


@pytest.fixture(scope="module")
def sphs() -> af.Multisine:
    return af.schroeder_multisine(f0=2.0, f_max=100.0)


def test_touchdown_stops_an_experiment_with_time_and_position(sphs) -> None:
    pid = af.PID(kp=2000.0, ki=0.0, kd=5.0)
    loud = replace(sphs, samples=sphs.samples * 40)  # 40 N rms into a soft loop
    with pytest.raises(af.TouchdownError) as info:
        af.run_experiment(af.Rig(force_law="nonlinear"), pid, loud, settle_periods=1, periods=2)
    assert abs(info.value.position) >= af.Rig().gap and info.value.time > 0
    # A linear rig has no gap, but a clearance makes touchdown an event there too.
    rig = af.Rig(clearance=20e-6)
    with pytest.raises(af.TouchdownError, match="clearance") as info:
        af.run_experiment(rig, pid, loud, settle_periods=1, periods=2)
    assert abs(info.value.position) >= 20e-6
    trace_until = int(round(info.value.time * pid.fs))
    free = af.simulate(af.Rig(), pid, np.tile(loud.samples, 3)[:trace_until])
    assert np.max(np.abs(free.displacement)) < 20e-6 + 1e-6  # nothing was reached before that sample


def test_saturation_is_counted_flagged_and_warned(sphs) -> None:
    rig = af.Rig(current_limit=0.02)  # 20 mA: the loop needs more to hold 1 N rms
    pid = af.PID(kp=2000.0, ki=2000.0, kd=5.0)
    with pytest.warns(UserWarning, match="amplifier saturated in"):
        est = af.run_experiment(rig, pid, sphs, settle_periods=2, periods=3)
    assert est.saturated and est.saturated_samples > 0
    # The count is what the current trace shows at the limit in the recorded periods.
    with (
        pytest.warns(UserWarning, match="past the air gap"),  # 20 mA cannot hold it: it drifts off, and is flagged
        pytest.warns(UserWarning, match="amplifier saturated: the current reached its limit 0.02 A"),
    ):
        trace = af.simulate(rig, pid, np.tile(sphs.samples, 5))
    recorded = trace.current[2 * sphs.period_samples :]
    assert est.saturated_samples == int(np.sum(np.abs(recorded) == 0.02))
    quiet = af.run_experiment(af.Rig(), pid, sphs, settle_periods=2, periods=3)
    assert quiet.saturated_samples == 0 and not quiet.saturated

    result = af.sweep(rig, pid, sphs, kp=[2000.0, 2400.0], periods=3, settle_periods=2)
    assert list(result.status) == ["saturated", "saturated"]
    assert np.all(np.isnan(result.k))
    with (  # it drifted off: both implausibility checks say so
        pytest.warns(UserWarning, match="displacement amplitude .* is above 10 mm"),
        pytest.warns(UserWarning, match="median [|]F/Y[|] is"),
    ):
        est = af.identify(trace.force, trace.displacement, fs=4000.0, f0=2.0, mass=0.92)
    assert est.saturated_samples is None


def test_eight_threads_give_the_serial_results(sphs) -> None:
    rig = af.Rig(amp_bandwidth=2000.0, sensor_bandwidth=8000.0, sensor_noise=1e-8, force_noise=1e-3)
    pid = af.PID(kp=2400.0, ki=10000.0, kd=3.0, derivative_cutoff=1000.0)
    force = np.tile(sphs.samples, 6)
    calls = {
        "simulate": lambda: af.simulate(rig, pid, force, seed=4).displacement,
        "run_experiment": lambda: af.run_experiment(rig, pid, sphs, seed=4, periods=4).H,
        "identify": lambda: af.identify(force, 1e-5 * np.roll(force, 3), fs=4000.0, f0=2.0, mass=0.92).H,
        "sweep": lambda: af.sweep(rig, pid, sphs, kp=[2200.0, 2600.0], seed=4, periods=3, workers=1).H,
        "predict": lambda: af.predict(rig, pid, sphs.freq, kp=np.linspace(2000, 3000, 50)),
    }
    for name, call in calls.items():
        serial = call()
        with ThreadPoolExecutor(8) as pool:
            results = list(pool.map(lambda _: call(), range(8)))  # noqa: B023
        for result in results:
            np.testing.assert_array_equal(result, serial, err_msg=name)


def test_same_seed_same_noise_and_different_seeds_differ(sphs) -> None:
    rig = af.Rig(sensor_noise=1e-8)
    pid = af.PID(kp=2400.0, ki=10000.0, kd=3.0)
    a = af.run_experiment(rig, pid, sphs, seed=7, periods=3)
    b = af.run_experiment(rig, pid, sphs, seed=7, periods=3)
    c = af.run_experiment(rig, pid, sphs, seed=8, periods=3)
    np.testing.assert_array_equal(a.H, b.H)
    assert not np.array_equal(a.H, c.H)


MEMORY_SCRIPT = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    import numpy as np
    import amb_fast as af

    def rss(field):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    def reset_peak():
        Path("/proc/self/clear_refs").write_text("5")

    rig = af.Rig(amp_bandwidth=2000.0, sensor_bandwidth=8000.0, sensor_noise=1e-8)
    pid = af.PID(kp=2400.0, ki=10000.0, kd=3.0)
    sphs = af.schroeder_multisine()
    force = np.tile(sphs.samples, 2500)                     # 10^7 samples
    displacement = 1e-6 * np.random.default_rng(0).standard_normal(force.size)
    af.run_experiment(rig, pid, sphs, periods=3)            # warm-up: code, FFT plans
    af.identify(force[:40000], displacement[:40000], fs=4000.0, f0=1.0, mass=0.92)
    for name, call in [
        ("control", lambda: np.ones(12_500_000).sum()),      # 100 MB, freed: the measure must see it
        ("experiment", lambda: af.run_experiment(rig, pid, sphs, periods=1000, settle_periods=2)),
        ("identify", lambda: af.identify(force, displacement, fs=4000.0, f0=1.0, mass=0.92, f_max=200.0)),
    ]:
        reset_peak()
        base = rss("VmRSS")
        call()
        print(name, (rss("VmHWM") - base) / 1e6)
    """
)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self")
def test_long_experiments_and_records_keep_memory_bounded() -> None:
    """A 1000-period experiment (4e6 samples, 96 MB as time series) and identify on 10^7 samples
    (160 MB given) each raise the peak resident memory by less than 50 MB."""
    done = subprocess.run([sys.executable, "-c", MEMORY_SCRIPT], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = [line.split() for line in done.stdout.splitlines()]  # an editable install may print build lines
    growth = {f[0]: float(f[1]) for f in lines if len(f) == 2 and f[0] in ("control", "experiment", "identify")}
    assert growth.pop("control") > 90  # the measurement sees a temporary 100 MB array
    assert set(growth) == {"experiment", "identify"}
    for name, megabytes in growth.items():
        assert megabytes < 50, (name, megabytes)
