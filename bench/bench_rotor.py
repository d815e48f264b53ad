"""The rigid rotor (four axes): its experiment against the one-axis paper experiment, its Campbell diagram
against a numpy loop of the same linear algebra.

Experiment: ``RotorRig.example()`` (every axis ``Rig.paper()``'s chain, noise on) under its example PID,
four experiments of 10 periods of the 1-200 Hz multisine from the steady state, against the one-axis
paper experiment (``Rig.paper()``, ``PID.paper()``, 10 periods), in interleaved pairs (CPU time of this
process; the median ratio is the headline). Target (issue 26): <= 10x. Every call runs the same loop, so
the core draws from the per-line solves it kept from the call before (as repeated experiments on one
rig do); a first call on a new loop (another speed) also pays for them and for building the loop.

ISO sensitivity (issue 27): ``measure_sensitivity`` on the rotor's four axes (four experiments of 10
periods of a 1-200 Hz multisine, 1 um rms, added to each sensor's signal in turn, probe noise on) against
the one-axis paper experiment, in interleaved pairs (CPU time). Target: <= 10x.

Unbalance run-up (issue 27): ``unbalance_response`` at 500 speeds against a numpy loop solving the same
linear systems: per speed the plant, the force's drive and the held commands discretised in one complex
``scipy.linalg.expm`` of the augmented matrix, the loop closed, ``numpy.linalg.solve`` at ``z = e^{jWT}``.
Target: <= 0.2x. ``unbalance_response`` does each speed in one task of the core: one real exponential (the
force as a two-state oscillator), the poles (the stability check) and the solve through the loop's
Hessenberg form. The peer is timed twice, as the process leaves BLAS (wall) and on one BLAS thread (CPU,
like ``unbalance_response``, which runs on one: small matrices gain nothing from a second thread).

Campbell: 500 speeds, against the peer a user would write: for each speed the closed-loop matrix built
in numpy (the continuous plant and controller from amb_fast's model, ``scipy.linalg.expm`` of the
augmented matrix, the loop closed) and ``numpy.linalg.eigvals``. Target (issue 26): <= 0.2x of the peer
on one BLAS thread (``threadpoolctl.threadpool_limits(1)``: on a loaded machine its OpenBLAS threads only
slow it down), the headline; the peer as the process leaves BLAS is reported too. Wall time, the three
interleaved, medians of the repeats and of the ratios. The Campbell diagram does each speed in one task of
the core, on its threads: the hold's exponential, the loop closed, every pole (Francis QR on the Hessenberg
form) and, for the whirl, the displacement at the bearings of each pole off the real axis (inverse
iteration); it does more than the peer (the shapes).

Flexible rotor: ``FlexibleRotor.example()`` (ROSS's 30-element shaft, 8 bending modes kept in each plane:
20 coordinates) on ``Rig.paper()``'s chains under the same PID, the same experiment at standstill, against
``RotorRig.example()`` at standstill, in interleaved pairs. Target (issue 27): <= 4x. Skipped without ROSS.

The process first does what users do (a 300x300 matrix product, an eigenvalue problem) and rests half a
second, so OpenBLAS's threads are in the state a user's process leaves them.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable

import numpy as np
import scipy.linalg
from threadpoolctl import threadpool_limits

import amb_fast as af
from _common import arguments, report
from amb_fast.system import _control, _model


def peer_campbell(rig: af.RotorRig, pid: af.PID, speeds: np.ndarray) -> list[np.ndarray]:
    """The numpy loop: expm of the augmented plant, the loop closed with the controller, eigvals."""
    Ac, Bc, Cc, Dc = _control.controller_state_space(_control.controller_matrix(pid, 4))
    out = []
    for speed in speeds:
        system = rig.at_speed(float(speed))
        A, B, _ = _model.plant(system)
        S = _model.sensor_rows(system)
        n, m = B.shape
        augmented = np.zeros((n + m, n + m))
        augmented[:n, :n], augmented[:n, n:] = A / pid.fs, B / pid.fs
        E = scipy.linalg.expm(augmented)
        Phi, Gu = E[:n, :n], E[:n, n + 4 :]
        loop = np.block([[Phi + Gu @ Dc @ S, Gu @ Cc], [Bc @ S, Ac]])
        out.append(np.linalg.eigvals(loop))
    return out


def interleaved(first: Callable[[], object], second: Callable[[], object], count: int) -> tuple[float, float, float]:
    """Median CPU seconds of ``first`` and ``second`` run in turn ``count`` times, and the median of the pairs'
    ratios ``second / first``."""
    first(), second()
    pairs = []
    for _ in range(count):
        start = time.process_time()
        first()
        t1 = time.process_time() - start
        start = time.process_time()
        second()
        pairs.append((t1, time.process_time() - start))
    t1, t2 = (float(np.median([p[i] for p in pairs])) for i in (0, 1))
    return t1, t2, float(np.median([p[1] / p[0] for p in pairs]))


def flexible_ratio(sphs: af.Multisine, pid: af.PID, count: int) -> tuple[float, float, float] | None:
    """The flexible rotor's experiment against the rigid rotor's (both at standstill, noise on, 10 periods),
    interleaved: (rigid s, flexible s, median ratio), or None without ROSS."""
    try:
        flexible = af.RotorRig(af.FlexibleRotor.example(modes=8), af.Rig.paper())
    except ImportError:
        return None
    rigid = af.RotorRig.example()
    seeds = iter(range(10**6))
    return interleaved(lambda: af.run_experiment(rigid, pid, sphs, periods=10, seed=next(seeds)),
                       lambda: af.run_experiment(flexible, pid, sphs, periods=10, seed=next(seeds)), count)  # fmt: skip


def main() -> None:
    args = arguments(__doc__, "rotor")
    repeats = 3 if args.quick else 21
    a = np.random.default_rng(0).standard_normal((300, 300))
    _ = a @ a, np.linalg.eigvals(a[:100, :100])
    time.sleep(0.5)
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    one_rig, one_pid = af.Rig.paper(), af.PID.paper()
    rotor, pid = af.RotorRig.example(speed=1000.0), af.RotorRig.example_controller()
    seeds = iter(range(10**6))

    def one() -> object:
        return af.run_experiment(one_rig, one_pid, sphs, periods=10, seed=next(seeds))

    def four() -> object:
        return af.run_experiment(rotor, pid, sphs, periods=10, seed=next(seeds))

    t1, t4, ratio = interleaved(one, four, 3 * repeats)
    flexible = flexible_ratio(sphs, pid, 3 * repeats)

    campbell = campbell_ratio(rotor, pid, 100 if args.quick else 500, max(5, repeats // 4))
    iso, runup = iso_sensitivity(repeats), run_up(100 if args.quick else 500, max(2, repeats // 4))
    measured = {
        "one-axis paper experiment, 10 periods (cpu)": t1,
        "rotor experiment, 4 x 10 periods (cpu)": t4,
        **campbell[0],
        **iso[0],
        **runup[0],
    }
    ratios = {
        "rotor / one-axis experiment, interleaved pairs (target <= 10)": ratio,
        **campbell[1],
        **iso[1],
        **runup[1],
    }
    if flexible is not None:
        measured["rigid rotor experiment at standstill, 4 x 10 periods (cpu)"] = flexible[0]
        measured["flexible rotor experiment (8 modes), 4 x 10 periods (cpu)"] = flexible[1]
        ratios["flexible / rigid rotor experiment, interleaved pairs (target <= 4)"] = flexible[2]
    report(args.out, measured, ratios, "ms", 1e3)


def campbell_ratio(
    rotor: af.RotorRig, pid: af.PID, count: int, repeats: int
) -> tuple[dict[str, float], dict[str, float]]:
    """``campbell`` at ``count`` speeds against :func:`peer_campbell` on one BLAS thread and as the process
    leaves BLAS, the three in turn ``repeats`` times (after one untimed round): wall times, medians."""
    speeds = np.linspace(0.0, 6000.0, count)
    fresh = iter(np.arange(1, 10**6) * 1e-6)  # a new grid each repeat: no cached loops
    ours = lambda: af.campbell(rotor, pid, speeds + next(fresh))  # noqa: E731
    peer = lambda: peer_campbell(rotor, pid, speeds + next(fresh))  # noqa: E731
    rows: list[list[float]] = []
    for _ in range(repeats + 1):
        row = []
        for run, one in ((ours, False), (peer, True), (peer, False)):
            with threadpool_limits(1) if one else contextlib.nullcontext():
                start = time.perf_counter()
                run()
                row.append(time.perf_counter() - start)
        rows.append(row)
    rows = rows[1:]  # the first round warms up
    wall, peer_one, peer_wall = (float(np.median([r[i] for r in rows])) for i in range(3))
    measured = {f"Campbell diagram, {count} speeds (wall)": wall,
                f"numpy expm + eigvals loop, one BLAS thread, {count} speeds (wall)": peer_one,
                f"numpy expm + eigvals loop, {count} speeds (wall)": peer_wall}  # fmt: skip
    ratios = {"Campbell / numpy loop on one BLAS thread (target <= 0.2)":
              float(np.median([r[0] / r[1] for r in rows])),
              "Campbell / numpy loop as the process leaves BLAS":
              float(np.median([r[0] / r[2] for r in rows]))}  # fmt: skip
    return measured, ratios


def peer_unbalance(rig: af.RotorRig, pid: af.PID, speeds: np.ndarray, unbalance: list) -> np.ndarray:
    """The numpy loop of a run-up: per speed one complex expm (plant, commands, rotating force), the loop
    closed, one solve; the probes' complex amplitudes (speeds, 4)."""
    Ac, Bc, Cc, Dc = _control.controller_state_space(_control.controller_matrix(pid, 4))
    mech = rig.mechanics()
    Mt = mech.mass + mech.actuators.T @ np.diag([a.mass_loading for a in rig.axes]) @ mech.actuators
    force = sum(me * np.exp(1j * phase) * np.array([[1, 0, 0, z], [0, 1, -z, 0]]).T @ np.array([1, -1j])
                for me, z, phase in unbalance)  # fmt: skip
    out = []
    for speed in speeds:
        system = rig.at_speed(float(speed))
        A, B, layout = _model.plant(system)
        S = _model.sensor_rows(system)
        n, m = B.shape
        augmented = np.zeros((n + m + 1, n + m + 1), dtype=complex)
        augmented[:n, :n], augmented[:n, n : n + m], augmented[n + m, n + m] = A, B, 1j * speed
        augmented[list(layout.velocity), n + m] = np.linalg.solve(Mt, speed**2 * force)
        E = scipy.linalg.expm(augmented / pid.fs)
        Phi, Gu, G = E[:n, :n], E[:n, n + 4 : n + m], E[:n, n + m]
        loop = np.block([[Phi + Gu @ Dc @ S, Gu @ Cc], [Bc @ S, Ac]])
        z = np.exp(1j * speed / pid.fs)
        X = np.linalg.solve(z * np.eye(loop.shape[0]) - loop, np.r_[G, np.zeros(Ac.shape[0])])
        out.append(S @ X[:n])
    return np.array(out)


def iso_sensitivity(repeats: int) -> tuple[dict[str, float], dict[str, float]]:
    """The ISO 14839-3 measurement of the rotor's four axes against the one-axis paper experiment."""
    sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
    test_signal = af.schroeder_multisine(f0=1.0, f_max=200.0, rms=1e-6)
    one_rig, one_pid = af.Rig.paper(), af.PID.paper()
    rotor, pid = af.RotorRig.example(speed=1000.0), af.RotorRig.example_controller()
    seeds = iter(range(10**6))
    runs = (lambda: af.run_experiment(one_rig, one_pid, sphs, periods=10, seed=next(seeds)),
            lambda: af.measure_sensitivity(rotor, pid, test_signal, periods=10, seed=next(seeds)))  # fmt: skip
    pairs = []
    for _ in range(3 * repeats + 1):
        times = []
        for run in runs:
            start = time.process_time()
            run()
            times.append(time.process_time() - start)
        pairs.append(times)
    pairs = pairs[1:]  # the first pair warms up
    t1, t4 = (float(np.median([p[i] for p in pairs])) for i in (0, 1))
    measured = {"one-axis paper experiment, beside the ISO runs (cpu)": t1,
                "ISO sensitivity of the rotor, 4 x 10 periods (cpu)": t4}  # fmt: skip
    ratios = {"ISO sensitivity / one-axis experiment, interleaved (target <= 10)":
              float(np.median([p[1] / p[0] for p in pairs]))}  # fmt: skip
    return measured, ratios


def run_up(count: int, repeats: int) -> tuple[dict[str, float], dict[str, float]]:
    """``unbalance_response`` at ``count`` speeds against :func:`peer_unbalance`, interleaved: CPU time of
    both on one BLAS thread, and the peer's wall time as the process leaves BLAS against ours."""
    from amb_fast._blas import blas_on_one_thread

    rig, pid = af.RotorRig.example(), af.RotorRig.example_controller()
    unbalance = [(1e-4, 0.1, 0.0)]
    speeds = np.linspace(10.0, 3000.0, count)
    exact = af.unbalance_response(rig, pid, speeds, unbalance).probes
    worst = np.max(np.abs(peer_unbalance(rig, pid, speeds, unbalance) - exact)) / np.max(np.abs(exact))
    assert worst < 1e-9, worst  # the same linear systems
    fresh = iter(np.arange(1, 10**6) * 1e-6)  # a new grid each repeat: no cached loops
    ours = lambda: af.unbalance_response(rig, pid, speeds + next(fresh), unbalance)  # noqa: E731
    peer = lambda: peer_unbalance(rig, pid, speeds + next(fresh), unbalance)  # noqa: E731
    rows: list[list[float]] = []
    for _ in range(repeats + 1):
        row = []
        for run, clock, one in ((ours, time.process_time, False), (peer, time.process_time, True),
                                (ours, time.perf_counter, False), (peer, time.perf_counter, False)):  # fmt: skip
            with blas_on_one_thread() if one else contextlib.nullcontext():
                start = clock()
                run()
                row.append(clock() - start)
        rows.append(row)
    cpu, peer_cpu, wall, peer_wall = (float(np.median([r[i] for r in rows[1:]])) for i in range(4))
    measured = {f"unbalance run-up, {count} speeds (cpu)": cpu,
                f"numpy expm + solve loop, one BLAS thread, {count} speeds (cpu)": peer_cpu,
                f"unbalance run-up, {count} speeds (wall)": wall,
                f"numpy expm + solve loop, {count} speeds (wall)": peer_wall}  # fmt: skip
    ratios = {"run-up / numpy loop on one BLAS thread, cpu (target <= 0.2)":
              float(np.median([r[0] / r[1] for r in rows[1:]])),
              "run-up / numpy loop as the process leaves BLAS, wall":
              float(np.median([r[2] / r[3] for r in rows[1:]]))}  # fmt: skip
    return measured, ratios


if __name__ == "__main__":
    main()
