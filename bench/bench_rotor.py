"""The rigid rotor (four axes): its experiment against the one-axis paper experiment, its Campbell diagram
against a numpy loop of the same linear algebra.

Experiment: ``RotorRig.example()`` (every axis ``Rig.paper()``'s chain, noise on) under its example PID,
four experiments of 10 periods of the 1-200 Hz multisine from the steady state, against the one-axis
paper experiment (``Rig.paper()``, ``PID.paper()``, 10 periods), in interleaved pairs (CPU time of this
process; the median ratio is the headline). Target (issue 26): <= 10x. Every call runs the same loop, so
the core draws from the per-line solves it kept from the call before (as repeated experiments on one
rig do); a first call on a new loop (another speed) also pays for them and for building the loop.

Campbell: 500 speeds, against the peer a user would write: for each speed the closed-loop matrix built
in numpy (the continuous plant and controller from amb_fast's model, ``scipy.linalg.expm`` of the
augmented matrix, the loop closed) and ``numpy.linalg.eigvals``. Target (issue 26): <= 0.2x; today's
Campbell assembles each speed's loop in Python and computes eigenvectors too (for the whirl), so it is
slower than that peer: the target needs the loop assembled in the core.

The process first does what users do (a 300x300 matrix product, an eigenvalue problem) and rests half a
second, so OpenBLAS's threads are in the state a user's process leaves them.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg

import amb_fast as af
from _common import arguments, median_seconds, report
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

    one(), four()
    pairs = []
    for _ in range(3 * repeats):
        start = time.process_time()
        one()
        t1 = time.process_time() - start
        start = time.process_time()
        four()
        pairs.append((t1, time.process_time() - start))
    t1, t4 = (float(np.median([p[i] for p in pairs])) for i in (0, 1))
    ratio = float(np.median([p[1] / p[0] for p in pairs]))

    speeds = np.linspace(0.0, 6000.0, 100 if args.quick else 500)
    fresh = iter(np.arange(1, 10**6) * 1e-6)  # a new grid each repeat: no cached loops

    def campbell() -> object:
        return af.campbell(rotor, pid, speeds + next(fresh))

    def peer() -> object:
        return peer_campbell(rotor, pid, speeds + next(fresh))

    c_time = median_seconds(campbell, max(1, repeats // 4))
    p_time = median_seconds(peer, max(1, repeats // 4))
    measured = {
        "one-axis paper experiment, 10 periods (cpu)": t1,
        "rotor experiment, 4 x 10 periods (cpu)": t4,
        f"Campbell diagram, {speeds.size} speeds (wall)": c_time,
        f"numpy expm + eigvals loop, {speeds.size} speeds (wall)": p_time,
    }
    ratios = {
        "rotor / one-axis experiment, interleaved pairs (target <= 10)": ratio,
        "Campbell / numpy loop (target <= 0.2)": c_time / p_time,
    }
    report(args.out, measured, ratios, "ms", 1e3)


if __name__ == "__main__":
    main()
