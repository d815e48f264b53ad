"""Two axes: one two-axis experiment (two experiments) against one one-axis experiment.

From the steady state the two-axis experiment draws its periods' line spectra directly (exact in
distribution, docs/model.md "Two axes"), where the one-axis experiment runs its loop sample by sample;
the coupling changes its cost only through the loop's size, as a coupled row (a seal-like process,
misaligned probes, cross feedback: 16 states against 14) shows beside the paper's uncoupled rig. Times
are medians of repeated calls, in CPU time of this process (the 2-core machine is shared, so wall time
mostly measures the neighbours) and in wall time; the target is a ratio <= 2.5.

Both calls are warmed up first, then the process rests for half a second: the first call of each
builds and caches its model with numpy/scipy linear algebra, after which OpenBLAS's worker threads
spin for a while, and their CPU time would be charged to whichever call is timed next.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

import amb_fast as af
from _common import arguments, median_seconds, report
from amb_fast import two_axis as ta


def median_cpu_seconds(run: Callable[[], object], repeats: int) -> float:
    run()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        run()
        times.append(time.process_time() - start)
    return float(np.median(times))


def main() -> None:
    args = arguments(__doc__, "two_axis")
    repeats = 3 if args.quick else 41
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    pid = af.PID.paper()
    one_rig, two_rig = af.Rig.paper(), ta.TwoAxisRig.paper()
    seeds = iter(range(10**6))

    def one() -> object:
        return af.run_experiment(one_rig, pid, sphs, periods=10, seed=next(seeds))

    def two() -> object:
        return ta.run_experiment(two_rig, pid, sphs, periods=10, seed=next(seeds))

    coupled_rig = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=10e3, kyx=-10e3, sensor_angle=0.05)
    cross = [[pid, af.PID(kp=200.0, ki=0.0, kd=0.2, fs=pid.fs)], [None, pid]]

    def coupled() -> object:
        return ta.run_experiment(coupled_rig, cross, sphs, periods=10, seed=next(seeds))

    one(), two(), coupled()
    time.sleep(0.5)
    measured, ratios = {}, {}
    for clock, timer in (("cpu", median_cpu_seconds), ("wall", median_seconds)):
        t1, t2 = timer(one, repeats), timer(two, repeats)
        measured[f"one-axis paper experiment, 10 periods ({clock}, ms)"] = t1
        measured[f"two-axis paper experiment, 2 x 10 periods ({clock}, ms)"] = t2
        ratios[f"two-axis / one-axis ({clock}; target <= 2.5)"] = t2 / t1
        if clock == "cpu":
            t3 = timer(coupled, repeats)
            measured["two-axis coupled experiment, 2 x 10 periods (cpu, ms)"] = t3
            ratios["two-axis coupled / one-axis (cpu)"] = t3 / t1
    report(args.out, measured, ratios, "ms", 1e3)


if __name__ == "__main__":
    main()
