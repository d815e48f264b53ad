"""The paper experiment as users run it, against a vectorised scipy script doing the same, in one run.

The experiment: ``run_experiment(Rig.paper(), PID.paper(), schroeder_multisine(f0=1, f_max=200),
periods=10)`` with the rig's noise on (20 nm sensor, 1 mN force) and default settings: the steady start,
10 recorded periods of 4000 samples, k(f), c(f) and their standard errors at 200 lines. On this linear
rig without a current limit or clearance, amb_fast draws each period's line spectra (exact in
distribution) instead of running the loop sample by sample; the same rig with a current limit (never
reached) runs the loop, and is timed too.

Peers, measured in the same process:

- scipy peer: what a competent numpy user writes from the same discretised model (amb_fast's exact
  zero-order-hold plant and digital PID): the closed loop as two transfer functions (force and sensor
  noise to the measured displacement), ``scipy.signal.lfilter`` superposition of the excitation and
  the noise (numpy's RNG), the transducer's AC coupling as a first-order lfilter, per-period rfft,
  averaging, F/Y, k and c, their standard errors and the median filter. The script checks that it
  gives amb_fast's k and c: to 1e-5 without noise, within the standard errors with noise.
- plain lfilter: the force-to-displacement transfer function alone over the same record (no noise,
  no estimate): the compiled floor of a linear recursion of that order.

Then where amb_fast's time goes (core call, Python layer; for the loop run sample by sample: loop,
noise, transform) and the transform's cost model. Medians of
repeated runs, in CPU time of this process (all single-threaded; the machine is shared and noisy).
Prints ratios and writes JSON. The headline ratio is the median over interleaved pairs of calls (one
amb_fast, one peer), taken last, when the peer runs fastest.

    python bench/bench_experiment.py [--quick] [--out bench/results/bench_experiment.json]
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy import ndimage, signal

import amb_fast as af
from _common import arguments, report
from _common import median_seconds as _median_seconds
from amb_fast import _core
from amb_fast._experiment import _plan
from amb_fast._linear import controller_matrices, discrete_plant, settle_periods_for, settling_radius


def median_seconds(run, repeats: int) -> float:  # noqa: ANN001
    """CPU time: everything timed here is single-threaded, and on the shared machine wall time is
    mostly waiting for a core (load averages of 5-10 on 2 cores quantise it in 4 ms time slices)."""
    return _median_seconds(run, repeats, clock=time.process_time)


@dataclass(frozen=True)
class Peer:
    """The scipy peer's model: transfer functions and everything fixed before the run."""

    b_force: np.ndarray  # force (N) -> measured displacement (m)
    b_noise: np.ndarray  # sensor noise (m) -> measured displacement (m), through the loop
    a: np.ndarray
    coupling: float  # AC-coupling pole exp(-T / tau)
    settle: int
    period: int
    harmonics: np.ndarray
    mass: float
    fs: float


def scipy_peer_model(rig: af.Rig, pid: af.PID, sphs: af.Multisine) -> Peer:
    """The closed loop of amb_fast's model (af.closed_loop), with the sensor noise as a second input:
    it enters where the sensor reading enters the controller."""
    A, B, C, _ = af.closed_loop(rig, pid)
    _, Gamma, states = discrete_plant(rig, pid.fs)
    _, Bc, _, Dc = controller_matrices(pid)
    gu = Gamma[:, 1:2]
    B_noise = np.vstack([gu * float(np.squeeze(Dc)), np.reshape(Bc, (-1, 1))])
    b_force, a = signal.ss2tf(A, B, C[:1], np.zeros((1, 1)))
    b_noise, _ = signal.ss2tf(A, B_noise, C[:1], np.ones((1, 1)))  # e = ys + noise
    radius = float(np.max(np.abs(np.linalg.eigvals(A))))
    settle = int(settle_periods_for(settling_radius(rig, pid, radius), sphs.period_samples))
    coupling = np.exp(-1.0 / (pid.fs * rig.force_coupling_tau)) if rig.force_coupling_tau else 0.0
    return Peer(b_force[0], b_noise[0], a, coupling, settle, sphs.period_samples, sphs.harmonics, rig.mass, pid.fs)


def scipy_peer(peer: Peer, rig: af.Rig, sphs: af.Multisine, periods: int, rng: np.random.Generator) -> dict:
    """Simulate settle + periods from rest, then estimate as amb_fast does (no bias, no shortcuts)."""
    L, total = peer.period, peer.settle + periods
    force = np.tile(sphs.samples, total)
    y = signal.lfilter(peer.b_force, peer.a, force)
    if rig.sensor_noise > 0:
        y += signal.lfilter(peer.b_noise, peer.a, rig.sensor_noise * rng.standard_normal(force.size))
    recorded = signal.lfilter([1.0, -1.0], [1.0, -peer.coupling], force) if peer.coupling else force.copy()
    if rig.force_noise > 0:
        recorded += rig.force_noise * rng.standard_normal(force.size)
    keep = slice(peer.settle * L, None)
    F = np.fft.rfft(recorded[keep].reshape(periods, L), axis=1)[:, peer.harmonics]
    Y = np.fft.rfft(y[keep].reshape(periods, L), axis=1)[:, peer.harmonics]
    Fm, Ym = F.mean(axis=0), Y.mean(axis=0)
    H = Fm / Ym
    w = 2 * np.pi * peer.harmonics * peer.fs / L
    # First-order standard errors of Re H and Im H from the period-to-period spread of dH = (dF - H dY) / Y.
    dH = ((F - Fm) - H * (Y - Ym)) / Ym
    var_re = (dH.real**2).sum(axis=0) / (periods - 1) / periods
    var_im = (dH.imag**2).sum(axis=0) / (periods - 1) / periods
    k, c = peer.mass * w**2 + H.real, H.imag / w
    return {
        "k": k,
        "c": c,
        "k_std": np.sqrt(var_re),
        "c_std": np.sqrt(var_im) / w,
        "k_smooth": ndimage.median_filter(k, 5, mode="nearest"),
        "c_smooth": ndimage.median_filter(c, 5, mode="nearest"),
    }


def check_peer(peer: Peer, rig: af.Rig, pid: af.PID, sphs: af.Multisine, periods: int) -> str:
    """The peer computes amb_fast's numbers: equal to 1e-5 without noise (the conversion of the order-8
    loop to a transfer function costs lfilter about 7 digits: 1e-7 in the time series, 2e-6 in k),
    within the standard errors with noise."""
    quiet = replace(rig, sensor_noise=0.0, force_noise=0.0)
    ours = af.run_experiment(quiet, pid, sphs, periods=periods)
    theirs = scipy_peer(peer, quiet, sphs, periods, np.random.default_rng(0))
    worst = max(
        float(np.max(np.abs(theirs[name] - getattr(ours, name)) / np.max(np.abs(getattr(ours, name)))))
        for name in ("k", "c")
    )
    assert worst < 1e-5, f"the scipy peer does not compute amb_fast's model: {worst:.3g}"
    ours = af.run_experiment(rig, pid, sphs, periods=periods, seed=1)
    theirs = scipy_peer(peer, rig, sphs, periods, np.random.default_rng(1))
    z = max(
        float(np.max(np.abs(theirs[n] - getattr(ours, n)) / np.hypot(theirs[n + "_std"], getattr(ours, n + "_std"))))
        for n in ("k", "c")
    )
    assert z < 8, f"with noise the peer and amb_fast differ by {z:.3g} standard errors"
    ratio = float(np.median(theirs["k_std"] / ours.k_std))
    assert 0.5 < ratio < 2, f"the peer's standard errors differ from amb_fast's: median ratio {ratio:.3g}"
    return f"noise-free max relative difference {worst:.2g}; with noise max {z:.2g} standard errors"


def main() -> None:
    args = arguments(__doc__, "bench_experiment")
    repeats, loop_n = (3, 40_000) if args.quick else (21, 400_000)
    rig, pid = af.Rig.paper(), af.PID.paper()
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    periods, L = 10, sphs.period_samples
    peer = scipy_peer_model(rig, pid, sphs)
    print(check_peer(peer, rig, pid, sphs, periods))
    total = peer.settle + periods
    record = np.tile(sphs.samples, total)
    rng = np.random.default_rng(2)

    t = {
        "amb_fast run_experiment (paper, noise on)": median_seconds(
            lambda: af.run_experiment(rig, pid, sphs, periods=periods, seed=1), repeats
        ),
        "scipy peer: lfilter superposition + rfft estimate": median_seconds(
            lambda: scipy_peer(peer, rig, sphs, periods, rng), repeats
        ),
        "plain lfilter on the closed-loop TF (same record)": median_seconds(
            lambda: signal.lfilter(peer.b_force, peer.a, record), repeats
        ),
    }

    # Where amb_fast's time goes. The paper rig (linear, no current limit, no clearance) draws its
    # periods' spectra from the steady state: the core call (per-line solves, the draws, the estimator)
    # and the Python layer around it (checks, the Estimate). A rig with a current limit runs its loop
    # sample by sample and streams the periods into the estimator: the same rig with a limit it never
    # reaches (1 A; the paper experiment peaks at 0.15 A) shows what such rigs cost. Then the time-domain
    # parts: the estimator (two transforms per period, accumulation, co-moments) from identify on 10
    # recorded periods; per sample, the loop through _core.simulate (which also allocates and fills its
    # output arrays), noise on and off.
    t_exp = t["amb_fast run_experiment (paper, noise on)"]
    plan, _ = _plan(sphs.harmonics, L)  # the core's estimator alone (af.identify adds its input checks)
    cr, cp = rig._to_core(), pid._to_core()
    t_core = median_seconds(lambda: _core.run_experiment(cr, cp, sphs.samples, 0, periods, plan, 1, 5, True), repeats)
    limited = replace(rig, current_limit=1.0)
    t_loop = median_seconds(lambda: af.run_experiment(limited, pid, sphs, periods=periods, seed=1), repeats)
    trace = af.simulate(rig, pid, np.tile(sphs.samples, periods), seed=3)
    t_est = median_seconds(
        lambda: _core.identify(trace.force, trace.displacement, 0, plan, rig.mass, pid.fs, 5), repeats
    )
    breakdown = {
        "breakdown: core call (drawn spectra and estimate)": t_core,
        "breakdown: Python layer (checks, Estimate)": t_exp - t_core,
        "rig with a current limit (loop sample by sample), noise on": t_loop,
        "estimator over 10 recorded periods (core identify)": t_est,
    }
    quiet = replace(rig, sensor_noise=0.0, force_noise=0.0)
    cq = quiet._to_core()
    force = np.tile(sphs.samples, loop_n // L)
    n = force.size
    loop_on = median_seconds(lambda: _core.simulate(cr, cp, force, 1), repeats) / n
    loop_off = median_seconds(lambda: _core.simulate(cq, cp, force, 1), repeats) / n
    per_sample = {"loop, noise off (ns/sample)": loop_off, "loop, noise on (ns/sample)": loop_on,
                  "noise, both sources (ns/sample)": loop_on - loop_off}  # fmt: skip
    per_period = {"estimator per period: 2 transforms + sums (us)": t_est / periods}
    if hasattr(_core, "line_spectrum"):  # the transform alone, per period of 4000 samples
        rows = trace.displacement.reshape(periods, L)
        bins = sphs.harmonics.tolist()
        for method, chosen in (("fft", bins), ("direct", bins), ("fft", bins[:1]), ("direct", bins[:1])):
            per_period[f"one transform, {method}, {len(chosen)} lines (us)"] = (
                median_seconds(lambda m=method, b=chosen: _core.line_spectrum(rows, b, m), repeats) / periods
            )
    print(f"settle {peer.settle} + {periods} periods of {L} samples, {sphs.harmonics.size} lines, median of {repeats}")
    # The headline ratio, from interleaved pairs (one amb_fast call, then one peer call, the ratio of
    # the two, the median over pairs), measured last: both sides of each pair see the same machine and
    # the same state of the process. The separate medians above run first and in blocks; the peer runs
    # markedly faster later in the process (5.3 against 7.8-8.8 ms seen: its megabyte arrays come
    # cheaper once the allocator has grown), so they flatter amb_fast, and this one does not.
    pairs, ours, theirs = [], [], []
    for _ in range(2 * repeats):
        start = time.process_time()
        af.run_experiment(rig, pid, sphs, periods=periods, seed=1)
        middle = time.process_time()
        scipy_peer(peer, rig, sphs, periods, rng)
        ours.append(middle - start)
        theirs.append(time.process_time() - middle)
        pairs.append(theirs[-1] / ours[-1])
    print(f"interleaved: amb_fast {np.median(ours) * 1e3:.3f} ms, scipy peer {np.median(theirs) * 1e3:.3f} ms")
    ratios = {
        "scipy peer / amb_fast, interleaved pairs (median)": float(np.median(pairs)),
        "scipy peer / amb_fast": t["scipy peer: lfilter superposition + rfft estimate"] / t_exp,
        "scipy peer / amb_fast with a current limit (loop sample by sample)": (
            t["scipy peer: lfilter superposition + rfft estimate"] / t_loop
        ),
        "plain lfilter / amb_fast": t["plain lfilter on the closed-loop TF (same record)"] / t_exp,
    }
    for label, value in per_sample.items():
        print(f"{label:58s} {value * 1e9:12.4g} ns")
    for label, value in per_period.items():
        print(f"{label:58s} {value * 1e6:12.4g} us")
    report(args.out, t | breakdown, ratios, "ms", 1e3)
    payload = json.loads(args.out.read_text())
    payload |= {"per_sample_seconds": per_sample, "per_period_seconds": per_period}
    args.out.write_text(json.dumps(payload, indent=2))


if __name__ == "__main__":
    main()
