"""Pure-numpy reference of the two-axis loop, written from ``docs/model.md`` independently of the package's
N-axis code (for comparison tests, as ``rotor_reference.py``).

A plain Python loop, slow on purpose: the tests compare the compiled MIMO loop and the closed-form
prediction with it. The plant is written out from the equations (not from :mod:`amb_fast.system`), each sample
is integrated in pieces between the instants at which an axis' dead-time fraction switches its
command (:func:`scipy.signal.cont2discrete` per piece), and every SISO controller entry runs as its own
difference equation with its own delay queue.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.signal import cont2discrete

from amb_fast import TwoAxisRig
from amb_fast._linear import state_space
from amb_fast.system import ControllerSpec, controller_matrix


def continuous_plant(rig: TwoAxisRig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``x' = A x + B (fx, fy, ux, uy)`` written from the equations; states ``x.y, x.v, ...`` per axis."""
    names: list[str] = []
    for a, axis in zip("xy", rig.axes):
        names += [f"{a}.y", f"{a}.v"]
        names += [f"{a}.{s}" for s, on in (("i", axis.amp_bandwidth), ("i_f", axis.eddy_bandwidth),
                                           ("ys", axis.sensor_bandwidth)) if on is not None]  # fmt: skip
    ix = {name: j for j, name in enumerate(names)}
    A, B = np.zeros((len(names), len(names))), np.zeros((len(names), 4))
    c, s = np.cos(rig.sensor_angle), np.sin(rig.sensor_angle)
    rotated = {"x": {"x.y": c, "y.y": s}, "y": {"x.y": -s, "y.y": c}}  # R^T q
    cross_k = {"x": ("y", rig.kxy), "y": ("x", rig.kyx)}
    cross_c = {"x": ("y", rig.cxy), "y": ("x", rig.cyx)}
    for col, (a, axis) in enumerate(zip("xy", rig.axes)):
        m = axis.mass + axis.mass_loading
        # current into the amplifier stage, the force-producing current
        coil = f"{a}.i" if axis.amp_bandwidth is not None else None
        force_current = f"{a}.i_f" if axis.eddy_bandwidth is not None else coil
        A[ix[f"{a}.y"], ix[f"{a}.v"]] = 1.0
        A[ix[f"{a}.v"], ix[f"{a}.y"]] += -axis.kyy / m
        other, k = cross_k[a]
        A[ix[f"{a}.v"], ix[f"{other}.y"]] += -k / m
        other, d = cross_c[a]
        A[ix[f"{a}.v"], ix[f"{other}.v"]] += -d / m
        B[ix[f"{a}.v"], col] = 1.0 / m
        if force_current is None:
            B[ix[f"{a}.v"], 2 + col] = -axis.kiy / m
        else:
            A[ix[f"{a}.v"], ix[force_current]] = -axis.kiy / m
        if axis.amp_bandwidth is not None:
            w = 2 * np.pi * axis.amp_bandwidth
            A[ix[f"{a}.i"], ix[f"{a}.i"]] = -w
            B[ix[f"{a}.i"], 2 + col] = w
        if axis.eddy_bandwidth is not None:
            w = 2 * np.pi * axis.eddy_bandwidth
            A[ix[f"{a}.i_f"], ix[f"{a}.i_f"]] = -w
            if coil is None:
                B[ix[f"{a}.i_f"], 2 + col] = w
            else:
                A[ix[f"{a}.i_f"], ix[coil]] = w
        if axis.sensor_bandwidth is not None:
            w = 2 * np.pi * axis.sensor_bandwidth
            A[ix[f"{a}.ys"], ix[f"{a}.ys"]] = -w
            for source, gain in rotated[a].items():
                A[ix[f"{a}.ys"], ix[source]] += w * gain
    return A, B, names


def simulate(
    rig: TwoAxisRig, controller: ControllerSpec, force: np.ndarray, sensor_noise: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The loop from rest on forces (n, 2); returns recorded forces, probe readings, coil currents (n, 2).

    ``sensor_noise`` (n, 2), m, is added to the probe readings (the controllers see it); no force noise.
    """
    force = np.asarray(force, dtype=float)
    spec = controller_matrix(controller, 2)
    T = 1.0 / spec.fs
    A, B, names = continuous_plant(rig)
    ix = {name: j for j, name in enumerate(names)}
    n = len(names)
    noise = np.zeros_like(force) if sensor_noise is None else np.asarray(sensor_noise, dtype=float)
    whole, fraction = [], []
    for axis in rig.axes:
        w = int(np.floor(axis.dead_time / T))
        whole.append(w)
        fraction.append(max(0.0, axis.dead_time - w * T))
    # The sample in pieces: axis a still feels its previous command before fraction[a].
    cuts = sorted({0.0, T, *[f for f in fraction if 0 < f < T]})
    pieces = []
    for t0, t1 in zip(cuts[:-1], cuts[1:]):
        Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, 4))), t1 - t0, method="zoh")
        pieces.append((t0, Phi, Gamma))
    c, s = np.cos(rig.sensor_angle), np.sin(rig.sensor_angle)
    entries = []  # (row, column, A, B, C, D, state, delay queue)
    for i, j, ctrl in spec:
        Ac, Bc, Cc, Dc = state_space(ctrl)
        entries.append([i, j, Ac, Bc[:, 0], Cc[0], float(Dc[0, 0]), np.zeros(Ac.shape[0]), deque([0.0] * ctrl.delay)])
    dead = [deque([0.0] * w) for w in whole]
    poles = [None if a.force_coupling_tau is None else np.exp(-T / a.force_coupling_tau) for a in rig.axes]
    q = [0.0, 0.0]
    previous = [0.0, 0.0]
    x = np.zeros(n)
    recorded, measured, current = (np.empty_like(force) for _ in range(3))
    for k in range(force.shape[0]):
        e = np.empty(2)
        for a, name in enumerate("xy"):
            if f"{name}.ys" in ix:
                e[a] = x[ix[f"{name}.ys"]]
            else:
                qx, qy = x[ix["x.y"]], x[ix["y.y"]]
                e[a] = c * qx + s * qy if a == 0 else -s * qx + c * qy
        e += noise[k]
        u = [0.0, 0.0]
        for entry in entries:
            i, j, Ac, Bc, Cc, Dc, state, queue = entry
            out = Cc @ state + Dc * e[j]
            entry[6] = Ac @ state + Bc * e[j]
            queue.append(out)
            u[i] += queue.popleft()
        applied = []
        for a in range(2):
            dead[a].append(u[a])
            applied.append(dead[a].popleft())
        for a, name in enumerate("xy"):
            if f"{name}.i" in ix:
                current[k, a] = x[ix[f"{name}.i"]]
            else:
                current[k, a] = applied[a]
            measured[k, a] = e[a]
            pole = poles[a]
            if pole is None:
                recorded[k, a] = force[k, a]
            else:
                recorded[k, a] = force[k, a] - q[a]
                q[a] = pole * q[a] + (1 - pole) * force[k, a]
        for t0, Phi, Gamma in pieces:
            held = [applied[a] if t0 >= fraction[a] else previous[a] for a in range(2)]
            x = Phi @ x + Gamma @ np.array([force[k, 0], force[k, 1], held[0], held[1]])
        previous = applied
    return recorded, measured, current


def run_experiment(
    rig: TwoAxisRig, controller: ControllerSpec, period_force: np.ndarray, settle_periods: int, periods: int
) -> tuple[np.ndarray, np.ndarray]:
    """Both experiments from rest (x = +s, +s; y = +s, -s), settled, then ``F Y^-1`` per DFT bin of the
    period-averaged channels. Returns (bins 1..period/2-1, H of shape (bins, 2, 2))."""
    L = period_force.size
    F = np.empty((L // 2 - 1, 2, 2), dtype=complex)
    Y = np.empty_like(F)
    for e, signs in enumerate(((1.0, 1.0), (1.0, -1.0))):
        drive = np.tile(np.outer(period_force, signs), (settle_periods + periods, 1))
        recorded, measured, _ = simulate(rig, controller, drive)
        start = settle_periods * L
        for channel in range(2):
            F[:, channel, e] = np.fft.fft(recorded[start:, channel].reshape(periods, L).mean(axis=0))[1 : L // 2]
            Y[:, channel, e] = np.fft.fft(measured[start:, channel].reshape(periods, L).mean(axis=0))[1 : L // 2]
    return np.arange(1, L // 2), F @ np.linalg.inv(Y)
