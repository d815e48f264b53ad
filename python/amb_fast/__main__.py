"""``python -m amb_fast``: a first run on the paper's rig, to check an installation."""

from __future__ import annotations

import time

import numpy as np

import amb_fast as af


def main() -> None:
    rig = af.Rig(amp_bandwidth=1500.0, eddy_bandwidth=800.0, sensor_bandwidth=5000.0)
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0)
    force = np.full(int(2 * pid.fs), 1.0)  # a 1 N step for 2 s
    start = time.perf_counter()
    trace = af.simulate(rig, pid, force)
    elapsed = time.perf_counter() - start
    peak = np.max(np.abs(trace.displacement))
    print(f"amb_fast {af.__version__}: 1 N force step on the paper rig, PID kp={pid.kp} A/m ki={pid.ki} A/(m s)")
    print(f"  kd={pid.kd} A s/m, fs={pid.fs} Hz, lags: amplifier 1500 Hz, eddy current 800 Hz, sensor 5000 Hz")
    print(f"  peak displacement {peak * 1e6:.3f} um, after 2 s {trace.displacement[-1] * 1e9:.3f} nm (integral action)")
    print(f"  steady coil current {trace.current[-1] * 1e3:.3f} mA (1 N / Kiy = {1e3 / rig.kiy:.3f} mA)")
    print(f"  simulated {force.size} samples in {elapsed * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
