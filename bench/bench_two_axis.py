"""Two axes: one two-axis experiment (two experiments in lock step) against one one-axis experiment.

Times are medians of repeated calls, in CPU time of this process (the 2-core machine is shared, so wall
time mostly measures the neighbours) and in wall time; the target is a ratio <= 2.5.

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

    one(), two()
    time.sleep(0.5)
    measured, ratios = {}, {}
    for clock, timer in (("cpu", median_cpu_seconds), ("wall", median_seconds)):
        t1, t2 = timer(one, repeats), timer(two, repeats)
        measured[f"one-axis paper experiment, 10 periods ({clock}, ms)"] = t1
        measured[f"two-axis paper experiment, 2 x 10 periods ({clock}, ms)"] = t2
        ratios[f"two-axis / one-axis ({clock}; target <= 2.5)"] = t2 / t1
    report(args.out, measured, ratios, "ms", 1e3)


if __name__ == "__main__":
    main()
