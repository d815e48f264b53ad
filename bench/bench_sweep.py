"""Gain sweeps: throughput, thread scaling, vectorised prediction and memory, measured in one run.

1. A 1,000-point kp sweep of the paper experiment as users run it (``Rig.paper()``, ``PID.paper()``,
   noise on, the default steady start, 10 periods at 4 kHz, 200 lines): experiments per second and
   the cost per simulated sample per gain set, against one run_experiment and scipy.signal.lfilter on
   the loop's closed-loop transfer function.
2. The same sweep on 1 and 2 worker threads, and a 40-point sweep on 1 and 2 (the issue's scaling
   case: too few points to hide an uneven split): medians of each in blocks, and the median ratio of
   interleaved pairs (the goal's measure: robust to the machine's drift between blocks). In the same
   rounds as the 40-point pairs, pairs of the core's call alone and of pure arithmetic (eigenvalues of a
   large stack of small matrices): what the shared machine gives two threads at those moments; and pairs
   of the 40-point sweep each run right after a user's 300x300 ``a @ a`` (a process that has done what
   users do: OpenBLAS's idle workers spinning).
3. predict over 10^5 gain sets x 200 lines against a plain loop over gain sets calling predict; and
   sweeps whose points each need their own loop (200 points of the amplifier's bandwidth, of a notch's
   frequency) against the loop of run_experiment a user would write.
4. Peak memory of a 10^5-point sweep (10 Hz fundamental, 20 lines) against the size of its estimates.

Medians of repeated runs (noisy 2-core machine). Prints ratios, writes JSON.

    python bench/bench_sweep.py [--quick] [--out bench/results/bench_sweep.json]
"""

from __future__ import annotations

import resource
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import signal

import amb_fast as af
from _common import arguments, median_seconds, report
from amb_fast import _core
from amb_fast._experiment import _plan


def reset_peak_rss() -> None:
    """Linux: make the peak resident size (VmHWM) start again from the current size."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def peak_rss_bytes() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux reports KiB


def rss_bytes() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    return 0


def main() -> None:
    args = arguments(__doc__, "bench_sweep")
    points, repeats, predict_sets, memory_points = (64, 1, 1_000, 2_000) if args.quick else (1_000, 5, 100_000, 100_000)

    rig, pid = af.Rig.paper(), af.PID.paper()
    sphs = af.schroeder_multisine()
    kp = np.linspace(2000.0, 3000.0, points)  # all stable: every point is simulated
    r = {}

    # 1-2. Sweep throughput and scaling.
    sweep = lambda workers: af.sweep(rig, pid, sphs, kp=kp, workers=workers, progress=False)  # noqa: E731
    result = sweep(1)
    samples = float(np.sum(result.settle_periods + result.periods) * sphs.period_samples)
    r["sweep 1 worker s"] = median_seconds(lambda: sweep(1), repeats)
    r["sweep 2 workers s"] = median_seconds(lambda: sweep(2), repeats)
    few = lambda workers: af.sweep(rig, pid, sphs, kp=kp[:: max(1, points // 40)][:40], workers=workers, progress=False)  # noqa: E731
    r["40-point sweep 1 worker s"] = median_seconds(lambda: few(1), 3 * repeats)
    r["40-point sweep 2 workers s"] = median_seconds(lambda: few(2), 3 * repeats)
    # The scaling again from interleaved pairs (one run on 1 worker, then one on 2, the ratio of the two,
    # the median over pairs): both sides of each pair see the same machine, where the blocks above can
    # catch the shared machine in different moods (40-point block ratios from 1.2 to 1.75 seen on one build).
    paired = {}
    for label, run, count in (("", sweep, 2 * repeats + 1), (", 40 points, pairs back to back", few, 6 * repeats + 1)):
        ratios_of_pairs = []
        for _ in range(count):
            one, two = (median_seconds(lambda r=run, w=w: r(w), 1, warm_up=False) for w in (1, 2))
            ratios_of_pairs.append(one / two)
        paired[f"scaling 1 -> 2 workers{label}, interleaved pairs"] = float(np.median(ratios_of_pairs))
    # The 40-point scaling (the goal's measure) again, beside what the machine gives two threads at the same
    # moments: each round times a pair of the sweep, a pair of the core's call alone for the same 40 points
    # (no Python in it), and a pair of pure arithmetic with nothing shared (the eigenvalues of 4,000 random
    # 7x7 matrices, claimed 64 at a time by the threads). The machine's mood changes from minute to minute
    # (the 40-point scaling from 1.2 to 1.75 in runs of one build), so the three are taken in the same
    # rounds, and the sweep's share of the ceiling per round says what amb_fast loses on its own.
    forty = kp[:: max(1, points // 40)][:40]
    plan, _ = _plan(sphs.harmonics, sphs.period_samples)
    controllers = [replace(pid, kp=k)._to_core() for k in forty]
    zeros, seeds = np.zeros(forty.size, dtype=np.int64), np.arange(1, forty.size + 1, dtype=np.uint64)
    core_args = (sphs.samples, [rig._to_core()] * forty.size, controllers, zeros, seeds, 10, plan, 5)
    stack = np.random.default_rng(0).random((4000, 7, 7))
    rounds = {
        "sweep": few,
        "core": lambda w: _core.run_sweep(*core_args, w, True),
        "ceiling": lambda w: _core.eigenvalues(stack, w),
    }
    # The process that has done what users do: each 40-point run right after a 300x300 ``a @ a`` (numpy's
    # OpenBLAS runs it on its threads, whose idle workers then spin ~0.1 s on the cores), timed from the
    # sweep's start. Issue 25 case 11: 1.2x here against 1.75x in a clean process before sweeps stopped them.
    user = np.random.default_rng(1).random((300, 300))

    def after_numpy(workers: int) -> float:
        user @ user
        start = time.perf_counter()
        few(workers)
        return time.perf_counter() - start

    scaling: dict[str, list[float]] = {name: [] for name in (*rounds, "after numpy")}
    for _ in range(6 * repeats + 1):
        for name, run in rounds.items():
            one, two = (median_seconds(lambda r=run, w=w: r(w), 1, warm_up=False) for w in (1, 2))
            scaling[name].append(one / two)
        one, two = (after_numpy(w) for w in (1, 2))
        scaling["after numpy"].append(one / two)
    sweep40, core40, ceiling40 = (np.array(scaling[name]) for name in rounds)
    numpy40 = np.array(scaling["after numpy"])
    paired["scaling 1 -> 2 workers, 40 points, interleaved pairs in rounds with the two below"] = float(
        np.median(sweep40)
    )
    paired["scaling 1 -> 2 workers, 40 points, the core's call alone, same rounds"] = float(np.median(core40))
    paired["scaling 1 -> 2 threads of pure arithmetic (the machine's ceiling), same rounds"] = float(
        np.median(ceiling40)
    )
    paired["40-point sweep's scaling / the core's call alone's, per round"] = float(np.median(sweep40 / core40))
    paired["40-point sweep's scaling / the ceiling's, per round"] = float(np.median(sweep40 / ceiling40))
    paired["scaling 1 -> 2 workers, 40 points, each right after the user's 300x300 a @ a, same rounds"] = float(
        np.median(numpy40)
    )
    paired["40-point sweep after a @ a: scaling / the ceiling's, per round"] = float(np.median(numpy40 / ceiling40))
    single = median_seconds(lambda: af.run_experiment(rig, pid, sphs), 5 * repeats)
    single_samples = (result.settle_periods[0] + result.periods) * sphs.period_samples
    A, B, C, D = af.closed_loop(rig, pid)
    b, a = signal.ss2tf(A, B, C[:1], D[:1])
    force = np.random.default_rng(0).standard_normal(1_000_000)
    lfilter = median_seconds(lambda: signal.lfilter(b[0], a, force), 5) / force.size

    # 3. Vectorised prediction.
    gains = np.linspace(2000.0, 3000.0, predict_sets)
    r["predict vectorised s"] = median_seconds(lambda: af.predict(rig, pid, sphs.freq, kp=gains), repeats)
    loop_sets = max(10, predict_sets // 1000)
    loop = median_seconds(lambda: [af.predict(rig, replace(pid, kp=g), sphs.freq) for g in gains[:loop_sets]], repeats)
    r["predict loop s (extrapolated)"] = loop * predict_sets / loop_sets

    # 3b. Sweeps whose points each need their own loop (a rig field, a controller block's parameter): 200
    # points of the amplifier's bandwidth and of a notch's frequency on 2 threads, against the loop of
    # run_experiment a user would write. Every round shifts the values a little, so no cached loop or
    # controller from an earlier round is reused (each sweep is a first sweep).
    notched = pid.to_controller() * af.notch(700.0)
    rebuilt_points = 20 if args.quick else 200
    shifts = iter(range(1, 10**6))
    cases = {
        "amp_bandwidth": (pid, lambda: np.linspace(800.0, 1500.0, rebuilt_points) + 1e-6 * next(shifts),
                          lambda v: (replace(rig, amp_bandwidth=v), pid)),
        "notch_freq": (notched, lambda: np.linspace(400.0, 900.0, rebuilt_points) + 1e-6 * next(shifts),
                       lambda v: (rig, notched.with_params(notch_freq=v))),
    }  # fmt: skip
    for name, (controller, values, model) in cases.items():
        swept, looped = [], []
        for _ in range(max(3, repeats)):
            start = time.perf_counter()
            af.sweep(rig, controller, sphs, workers=2, progress=False, **{name: values()})
            swept.append(time.perf_counter() - start)
            grid = values()
            start = time.perf_counter()
            for v in grid:
                af.run_experiment(*model(v), sphs)
            looped.append(time.perf_counter() - start)
        r[f"{rebuilt_points}-point {name} sweep, 2 workers s"] = float(np.median(swept))
        r[f"{rebuilt_points} run_experiment calls over {name} s"] = float(np.median(looped))

    # 4. Memory of a large sweep: estimates only, never time series.
    coarse = af.schroeder_multisine(f0=10.0, f_max=200.0)
    reset_peak_rss()
    before = rss_bytes()
    big = af.sweep(rig, pid, coarse, kp=np.linspace(2000.0, 3000.0, memory_points), workers=2, progress=False)
    grown = peak_rss_bytes() - before
    estimates = sum(getattr(big, n).nbytes for n in ("H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std"))

    per_set_sample_1 = r["sweep 1 worker s"] / samples
    ratios = {
        "experiments per second (2 workers)": points / r["sweep 2 workers s"],
        "ns per sample per gain set, 1 worker": per_set_sample_1 * 1e9,
        "ns per sample per gain set, 2 workers": r["sweep 2 workers s"] / samples * 1e9,
        "ns per sample, single run_experiment": single / single_samples * 1e9,
        "ns per sample, lfilter": lfilter * 1e9,
        "sweep (1 worker) per sample per set / lfilter (goal <= 1)": per_set_sample_1 / lfilter,
        "scaling 1 -> 2 workers, blocks (goal >= 1.7)": r["sweep 1 worker s"] / r["sweep 2 workers s"],
        "scaling 1 -> 2 workers, 40 points, blocks (goal >= 1.7)": r["40-point sweep 1 worker s"]
        / r["40-point sweep 2 workers s"],
        **paired,
        **{
            f"{name} sweep: points per second (2 workers)": rebuilt_points
            / r[f"{rebuilt_points}-point {name} sweep, 2 workers s"]
            for name in cases
        },
        **{
            f"{name}: loop of run_experiment / sweep": r[f"{rebuilt_points} run_experiment calls over {name} s"]
            / r[f"{rebuilt_points}-point {name} sweep, 2 workers s"]
            for name in cases
        },
        "predict: gain sets x lines per second": predict_sets * sphs.freq.size / r["predict vectorised s"],
        "predict: loop / vectorised": r["predict loop s (extrapolated)"] / r["predict vectorised s"],
        "memory sweep: points": memory_points,
        "memory sweep: peak RSS growth MB": grown / 1e6,
        "memory sweep: estimates MB": estimates / 1e6,
    }
    report(args.out, r, ratios, "s", 1.0)


if __name__ == "__main__":
    main()
