"""Pure-numpy reference of the loop, written from MODEL.md independently of the C++ core.

It is a plain Python loop, slow on purpose: tests and benchmarks compare the compiled core with it.
Discretisation uses :func:`scipy.signal.cont2discrete` (zero-order hold), not the core's own code.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.signal import cont2discrete

from ._params import PID, Rig


def plant_matrices(rig: Rig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` (inputs: force N, current command A) over the active states.

    States, in order, are ``y, v`` and then whichever of ``i`` (amplifier), ``i_f`` (eddy current) and
    ``ys`` (sensor) are switched on.
    """
    states = ["y", "v"] + [
        name
        for name, bandwidth in (("i", rig.amp_bandwidth), ("i_f", rig.eddy_bandwidth), ("ys", rig.sensor_bandwidth))
        if bandwidth is not None
    ]
    n = len(states)
    A = np.zeros((n, n))
    B = np.zeros((n, 2))

    def term(row: str, source: str, gain: float) -> None:
        if source == "cmd":
            B[states.index(row), 1] += gain
        else:
            A[states.index(row), states.index(source)] += gain

    coil = "i" if "i" in states else "cmd"
    driving = "i_f" if "i_f" in states else coil
    term("y", "v", 1.0)
    term("v", "y", -rig.kyy / rig.mass)
    term("v", driving, -rig.kiy / rig.mass)
    B[states.index("v"), 0] = 1.0 / rig.mass
    if "i" in states:
        wa = 2 * np.pi * rig.amp_bandwidth
        term("i", "i", -wa)
        term("i", "cmd", wa)
    if "i_f" in states:
        we = 2 * np.pi * rig.eddy_bandwidth
        term("i_f", "i_f", -we)
        term("i_f", coil, we)
    if "ys" in states:
        ws = 2 * np.pi * rig.sensor_bandwidth
        term("ys", "ys", -ws)
        term("ys", "y", ws)
    return A, B, states


def magnet_force(rig: Rig, y: float, i: float) -> float:
    """Differential magnet-pair force on the platform (N), MODEL.md section 4."""
    i0 = rig.bias_current
    g = i0 * rig.kiy / -rig.kyy
    km = rig.kiy * g**2 / (4 * i0)
    return km * ((i0 - i) ** 2 / (g - y) ** 2 - (i0 + i) ** 2 / (g + y) ** 2)


def simulate(rig: Rig, pid: PID, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed loop from rest; returns (sensor displacement m, coil current A) at every sample."""
    force = np.asarray(force, dtype=float)
    T = 1.0 / pid.fs
    A, B, states = plant_matrices(rig)
    n = len(states)
    Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, 2))), T, method="zoh")
    sensed = states.index("ys") if "ys" in states else 0
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0

    x = np.zeros(n)
    integral = derivative = e_prev = 0.0
    pending = deque([0.0] * pid.delay)
    displacement = np.empty(force.size)
    current = np.empty(force.size)
    for k, f in enumerate(force):
        e = x[sensed]
        integral += pid.ki * T * e
        derivative = a * derivative + pid.kd * (1 - a) * (e - e_prev) / T
        e_prev = e
        pending.append(pid.kp * e + integral + derivative)
        i_cmd = pending.popleft()
        displacement[k] = e
        current[k] = x[states.index("i")] if "i" in states else i_cmd
        if rig.force_law == "linear":
            x = Phi @ x + Gamma @ np.array([f, i_cmd])
        else:
            x = _rk4_sample(rig, states, x, f, i_cmd, T)
    return displacement, current


def _rk4_sample(rig: Rig, states: list[str], x: np.ndarray, f: float, i_cmd: float, T: float) -> np.ndarray:
    A, B, _ = plant_matrices(rig)

    def rhs(x: np.ndarray) -> np.ndarray:
        # The linear matrices carry the lags; the magnet force replaces the linear force on v.
        dx = A @ x + B @ np.array([f, i_cmd])
        coil = x[states.index("i")] if "i" in states else i_cmd
        driving = x[states.index("i_f")] if "i_f" in states else coil
        dx[1] = (f + magnet_force(rig, x[0], driving)) / rig.mass
        return dx

    h = T / rig.substeps
    for _ in range(rig.substeps):
        k1 = rhs(x)
        k2 = rhs(x + h / 2 * k1)
        k3 = rhs(x + h / 2 * k2)
        k4 = rhs(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def closed_loop(rig: Rig, pid: PID) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The linear loop as one discrete state space ``(A, B, C, D)`` with sample period ``1/fs``.

    Input: force f[k] (N). Outputs: sensor displacement ys(kT) (m) and coil current (A). State: the
    plant's, then the PID's integral I[k-1], derivative D[k-1], last error e[k-1], and the delay line
    u[k-1], ..., u[k-d].
    """
    T = 1.0 / pid.fs
    A, B, states = plant_matrices(rig)
    n = len(states)
    Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, 2))), T, method="zoh")
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
    kd_gain = pid.kd * (1 - a) / T
    d = pid.delay
    size = n + 3 + d
    I_, D_, E_ = n, n + 1, n + 2  # positions of I[k-1], D[k-1], e[k-1]
    sensor = np.zeros(size)
    sensor[states.index("ys") if "ys" in states else 0] = 1.0

    # u[k] = (kp + ki T + kd_gain) e[k] + I[k-1] + a D[k-1] - kd_gain e[k-1], e[k] = sensor . z
    u = (pid.kp + pid.ki * T + kd_gain) * sensor
    u[I_] += 1.0
    u[D_] += a
    u[E_] -= kd_gain
    i_cmd = u if d == 0 else np.eye(size)[n + 3 + d - 1]

    Acl = np.zeros((size, size))
    Acl[:n, :n] = Phi
    Acl[:n] += np.outer(Gamma[:, 1], i_cmd)
    Acl[I_] = pid.ki * T * sensor
    Acl[I_, I_] += 1.0
    Acl[D_] = kd_gain * sensor
    Acl[D_, D_] += a
    Acl[D_, E_] -= kd_gain
    Acl[E_] = sensor
    if d:
        Acl[n + 3] = u
        for j in range(1, d):
            Acl[n + 3 + j, n + 3 + j - 1] = 1.0
    Bcl = np.zeros((size, 1))
    Bcl[:n, 0] = Gamma[:, 0]
    current = np.eye(size)[states.index("i")] if "i" in states else i_cmd
    Ccl = np.vstack([sensor, current])
    return Acl, Bcl, Ccl, np.zeros((2, 1))
