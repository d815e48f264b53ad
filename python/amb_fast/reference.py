"""Pure-numpy reference of the loop, written from MODEL.md independently of the C++ core.

It is a plain Python loop, slow on purpose: tests and benchmarks compare the compiled core with it.
Discretisation uses :func:`scipy.signal.cont2discrete` (zero-order hold), not the core's own code.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.signal import cont2discrete

from ._linear import plant_matrices
from ._params import PID, Rig


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
            x = _rk4_sample(rig, A, B, states, x, f, i_cmd, T)
    return displacement, current


def _rk4_sample(
    rig: Rig, A: np.ndarray, B: np.ndarray, states: list[str], x: np.ndarray, f: float, i_cmd: float, T: float
) -> np.ndarray:
    def rhs(x: np.ndarray) -> np.ndarray:
        # The linear matrices carry the lags; the magnet force replaces the linear force on v.
        dx = A @ x + B @ np.array([f, i_cmd])
        coil = x[states.index("i")] if "i" in states else i_cmd
        driving = x[states.index("i_f")] if "i_f" in states else coil
        dx[1] = (f + magnet_force(rig, x[0], driving)) / (rig.mass + rig.mass_loading)
        return dx

    h = T / rig.substeps
    for _ in range(rig.substeps):
        k1 = rhs(x)
        k2 = rhs(x + h / 2 * k1)
        k3 = rhs(x + h / 2 * k2)
        k4 = rhs(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def receptance(rig: Rig, pid: PID, freq: np.ndarray) -> np.ndarray:
    """Y/F at ``freq`` (Hz) by composing transfer functions, not by the closed-loop state space:
    ys/f = P_f / (1 - P_i G z^-d), with the plant's two ZOH transfer functions P_f, P_i from
    :func:`scipy.signal.cont2discrete` and the digital PID G(z) written out from MODEL.md."""
    T = 1.0 / pid.fs
    A, B, states = plant_matrices(rig)
    n = len(states)
    sensed = states.index("ys") if "ys" in states else 0
    Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, 2))), T, method="zoh")
    z = np.exp(2j * np.pi * np.asarray(freq, dtype=float) * T)
    P = np.array([np.linalg.solve(zk * np.eye(n) - Phi, Gamma)[sensed] for zk in z])  # (freq, 2)
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
    G = pid.kp + pid.ki * T / (1 - 1 / z) + pid.kd * (1 - a) * (1 - 1 / z) / (T * (1 - a / z))
    return P[:, 0] / (1 - P[:, 1] * G * z ** (-pid.delay))


def pipeline(
    force: np.ndarray, displacement: np.ndarray, period: int, lines: np.ndarray, mass: float, fs: float, window: int
) -> dict[str, np.ndarray]:
    """The estimation pipeline in plain numpy: reshape-mean, rfft, H = F/Y, eq. 9, median filter.

    ``lines`` are harmonic numbers; the record must be whole periods, already settled.
    """
    from scipy.ndimage import median_filter

    F = np.fft.rfft(force.reshape(-1, period).mean(axis=0))[lines] * 2 / period
    Y = np.fft.rfft(displacement.reshape(-1, period).mean(axis=0))[lines] * 2 / period
    H = F / Y
    w = 2 * np.pi * lines * fs / period
    k = mass * w**2 + H.real
    c = H.imag / w
    smooth = {name: median_filter(v, size=window, mode="nearest") for name, v in (("k", k), ("c", c))}
    return {"force": F, "displacement": Y, "H": H, "k": k, "c": c, "k_smooth": smooth["k"], "c_smooth": smooth["c"]}
