"""The identification pipeline against the numpy reference pipeline, measured in one run.

1. One paper experiment end to end (settle + 10 periods at 4 kHz, 200 lines, all lags):
   amb_fast.run_experiment against reference.simulate + reference.pipeline (reshape-mean, rfft,
   median filter).
2. identify on 10^7 recorded samples per channel against numpy's reshape-mean + rfft of both channels
   (and against numpy computing what identify also gives: per-period spectra for the variance).

Medians of repeated runs (the machine is noisy). Prints ratios and writes JSON.

    python bench/bench_identify.py [--quick] [--out bench/results/bench_identify.json]
"""

from __future__ import annotations

import numpy as np

import amb_fast as af
from _common import arguments, median_seconds, report
from amb_fast import reference


def main() -> None:
    args = arguments(__doc__, "bench_identify")
    repeats, ref_repeats, record = (3, 1, 400_000) if args.quick else (21, 3, 10_000_000)

    rig = af.Rig(amp_bandwidth=1500.0, eddy_bandwidth=800.0, sensor_bandwidth=5000.0)
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0)
    sphs = af.schroeder_multisine()
    period, periods = sphs.period_samples, 10
    settle = int(af._linear.settle_periods_for(af._linear.spectral_radius(rig, pid), period)[0])
    lines = sphs.harmonics

    def numpy_experiment() -> None:
        force = np.tile(sphs.samples, settle + periods)
        displacement, _ = reference.simulate(rig, pid, force)
        keep = slice(settle * period, None)
        reference.pipeline(force[keep], displacement[keep], period, lines, rig.mass, pid.fs, 5)

    t = {
        "run_experiment": median_seconds(lambda: af.run_experiment(rig, pid, sphs, periods=periods), repeats),
        "numpy reference experiment": median_seconds(numpy_experiment, ref_repeats),
    }

    rng = np.random.default_rng(0)
    n = record // period * period
    force = np.tile(sphs.samples, n // period) + 1e-3 * rng.standard_normal(n)
    displacement = 1e-6 * rng.standard_normal(n)

    def numpy_mean_rfft() -> None:
        for x in (force, displacement):
            np.fft.rfft(x.reshape(-1, period).mean(axis=0))

    def numpy_with_variance() -> None:
        for x in (force, displacement):
            spectra = np.fft.rfft(x.reshape(-1, period), axis=1)[:, lines]
            spectra.mean(axis=0), spectra.var(axis=0, ddof=1)

    t["identify 1e7"] = median_seconds(
        lambda: af.identify(force, displacement, fs=pid.fs, f0=sphs.f0, mass=rig.mass, f_max=200.0), repeats
    )
    t["numpy reshape-mean + rfft 1e7"] = median_seconds(numpy_mean_rfft, repeats)
    t["numpy per-period rfft + variance 1e7"] = median_seconds(numpy_with_variance, max(1, repeats // 5))

    ratios = {
        "numpy experiment / run_experiment (target >= 300)": t["numpy reference experiment"] / t["run_experiment"],
        "identify / numpy reshape-mean + rfft (target <= 1)": t["identify 1e7"] / t["numpy reshape-mean + rfft 1e7"],
        "identify / numpy with variance": t["identify 1e7"] / t["numpy per-period rfft + variance 1e7"],
    }
    print(
        f"experiment: settle {settle} + {periods} periods of {period} samples, {lines.size} lines; record {n} samples"
    )
    report(args.out, t, ratios, "ms", 1e3)


if __name__ == "__main__":
    main()
