"""Time per simulated sample of the compiled loop against its peers, measured in one run.

On the rig users run: ``Rig.paper()`` under ``PID.paper()``, its measurement noise on (the headline)
and off. "amb_fast linear" is the compiled core as called by amb_fast.simulate; the row below it adds
the Python layer (input conversion and checks). A 6-state controller (the paper's PID, a 700 Hz notch
and a second-order 1500 Hz low-pass) on the same rig shows what a general controller costs against the
PID. Peers: the pure-numpy reference loop, scipy.signal.dlsim
and python-control's forced_response on the same closed loop as one discrete state space, and
scipy.signal.lfilter on its force-to-displacement transfer function (the compiled floor for a linear
recursion of that order). Prints ratios (medians of repeated runs; the machine is noisy) and writes
JSON.

    python bench/bench_core.py [--quick] [--out bench/results/bench_core.json]
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import signal

import amb_fast as af
from _common import arguments, median_seconds, report
from amb_fast import reference
from amb_fast._linear import core_controller


def per_sample(run, samples: int, repeats: int) -> float:  # noqa: ANN001
    return median_seconds(run, repeats) / samples


def main() -> None:
    args = arguments(__doc__, "bench_core")

    long_n, slow_n, repeats = (20_000, 2_000, 3) if args.quick else (1_000_000, 20_000, 15)
    cached_n = 20_000
    rig, pid = af.Rig.paper(), af.PID.paper()
    quiet = replace(rig, sensor_noise=0.0, force_noise=0.0)
    six = pid.to_controller() * af.notch(700.0) * af.low_pass(1500.0, order=2)
    assert six.order == 6, six.order
    force = np.random.default_rng(0).standard_normal(long_n)
    short = force[:slow_n]

    A, B, C, D = af.closed_loop(rig, pid)
    dt = 1.0 / pid.fs
    b, a = signal.ss2tf(A, B, C[:1], D[:1])
    core_rig, core_quiet, core_pid = rig._to_core(), quiet._to_core(), core_controller(pid)
    core_six = core_controller(six)
    timings = {
        "amb_fast linear, paper rig, noise on": per_sample(
            lambda: af._core.simulate(core_rig, core_pid, force, 1), long_n, repeats
        ),
        "amb_fast linear, paper rig, noise off": per_sample(
            lambda: af._core.simulate(core_quiet, core_pid, force, 1), long_n, repeats
        ),
        "amb_fast linear, 6-state controller, noise off": per_sample(
            lambda: af._core.simulate(core_quiet, core_six, force, 1), long_n, repeats
        ),
        "amb_fast.simulate (+ validation, copy), noise on": per_sample(
            lambda: af.simulate(rig, pid, force, seed=1), long_n, repeats
        ),
        "amb_fast nonlinear, noise on": per_sample(
            lambda: af.simulate(replace(rig, force_law="nonlinear"), pid, 0.01 * force, seed=1), long_n, repeats
        ),
        "scipy.signal.lfilter (closed-loop TF)": per_sample(lambda: signal.lfilter(b[0], a, force), long_n, repeats),
        # A record that stays in cache: the loop's own cost, without writing 24 MB of fresh output.
        "amb_fast linear, paper rig, noise on, 2e4 samples": per_sample(
            lambda: af._core.simulate(core_rig, core_pid, force[:cached_n], 1), cached_n, 20 * repeats
        ),
        "amb_fast linear, paper rig, noise off, 2e4 samples": per_sample(
            lambda: af._core.simulate(core_quiet, core_pid, force[:cached_n], 1), cached_n, 20 * repeats
        ),
        "amb_fast linear, 6-state controller, noise off, 2e4 samples": per_sample(
            lambda: af._core.simulate(core_quiet, core_six, force[:cached_n], 1), cached_n, 20 * repeats
        ),
        "scipy.signal.lfilter (closed-loop TF), 2e4 samples": per_sample(
            lambda: signal.lfilter(b[0], a, force[:cached_n]), cached_n, 20 * repeats
        ),
        "numpy reference loop": per_sample(lambda: reference.simulate(rig, pid, short), slow_n, max(1, repeats // 5)),
        "scipy.signal.dlsim": per_sample(lambda: signal.dlsim((A, B, C, D, dt), short), slow_n, max(1, repeats // 5)),
    }
    try:
        import control

        system = control.ss(A, B, C, D, dt)
        time_axis = np.arange(slow_n) * dt
        timings["control.forced_response"] = per_sample(
            lambda: control.forced_response(system, time_axis, short), slow_n, max(1, repeats // 5)
        )
    except ImportError:
        print("python-control not installed (pip install 'amb_fast[bench]'): skipping that peer")

    core = timings["amb_fast linear, paper rig, noise on"]
    quiet_core = timings["amb_fast linear, paper rig, noise off"]
    print(
        f"closed-loop order {A.shape[0]}, {long_n} samples (slow peers: {slow_n}; in cache: {cached_n}), "
        f"median of {repeats}"
    )
    ratios = {name + " / core": seconds / core for name, seconds in timings.items()}
    ratios |= {
        "numpy reference / core (target >= 300)": timings["numpy reference loop"] / core,
        "core, noise on / lfilter (no noise)": core / timings["scipy.signal.lfilter (closed-loop TF)"],
        "core, noise off / lfilter (target <= 1.5)": quiet_core / timings["scipy.signal.lfilter (closed-loop TF)"],
        "6-state controller / PID, noise off (target <= 1.5)": (
            timings["amb_fast linear, 6-state controller, noise off"] / quiet_core
        ),
        "6-state controller / PID, noise off, 2e4 samples": (
            timings["amb_fast linear, 6-state controller, noise off, 2e4 samples"]
            / timings["amb_fast linear, paper rig, noise off, 2e4 samples"]
        ),
        "core, noise off / lfilter, 2e4 samples": (
            timings["amb_fast linear, paper rig, noise off, 2e4 samples"]
            / timings["scipy.signal.lfilter (closed-loop TF), 2e4 samples"]
        ),
        "nonlinear / linear, noise on (target <= 10)": timings["amb_fast nonlinear, noise on"] / core,
    }
    report(args.out, timings, ratios, "ns/sample", 1e9)


if __name__ == "__main__":
    main()
