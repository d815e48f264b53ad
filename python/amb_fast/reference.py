"""Pure-numpy reference of the loop, written from MODEL.md independently of the C++ core.

It is a plain Python loop, slow on purpose: tests and benchmarks compare the compiled core with it.
Discretisation uses :func:`scipy.signal.cont2discrete` (zero-order hold), not the core's own code.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.signal import cont2discrete

from ._linear import AnyController, plant_matrices, state_space
from ._params import PID, Rig


def magnet_force(rig: Rig, y: float, i: float) -> float:
    """Differential magnet-pair force on the platform (N), MODEL.md section 4."""
    i0, g = rig.bias_current, rig.gap
    km = rig.kiy * g**2 / (4 * i0)
    return km * ((i0 - i) ** 2 / (g - y) ** 2 - (i0 + i) ** 2 / (g + y) ** 2)


def zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n = A.shape[0]
    Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, B.shape[1]))), h, method="zoh")
    return Phi, Gamma


def _plant(rig: Rig, T: float) -> tuple[np.ndarray, np.ndarray, list[str], int, int, float]:
    """The plant's A, B, states, the sensed state's index, and the dead time's whole samples and fraction (s)."""
    A, B, states = plant_matrices(rig)
    whole = int(np.floor(rig.dead_time / T))
    return A, B, states, states.index("ys") if "ys" in states else 0, whole, max(0.0, rig.dead_time - whole * T)


def _pid_pole(pid: PID, T: float) -> float:
    """The derivative filter's pole exp(-2 pi fd T), 0 without a filter."""
    return float(np.exp(-2 * np.pi * pid.derivative_cutoff * T)) if pid.derivative_cutoff is not None else 0.0


class _Law:
    """The controller's difference equations: the PID written out from MODEL.md, any other
    controller as its state space (s' = A s + B e, u = C s + D e)."""

    def __init__(self, controller: AnyController) -> None:
        self.pid = controller if isinstance(controller, PID) else None
        T = 1.0 / controller.fs
        if self.pid is not None:
            self.a = _pid_pole(self.pid, T)
            self.integral = self.derivative = self.e_prev = 0.0
        else:
            self.A, self.B, self.C, self.D = state_space(controller)
            self.s = np.zeros(self.A.shape[0])
        self.T = T

    def __call__(self, e: float) -> float:
        if self.pid is not None:
            pid, T = self.pid, self.T
            self.integral += pid.ki * T * e
            self.derivative = self.a * self.derivative + pid.kd * (1 - self.a) * (e - self.e_prev) / T
            self.e_prev = e
            return pid.kp * e + self.integral + self.derivative
        u = float(self.C[0] @ self.s + self.D[0, 0] * e)
        self.s = self.A @ self.s + self.B[:, 0] * e
        return u


def simulate(rig: Rig, pid: AnyController, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed loop from rest; returns (sensor displacement m, coil current A) at every sample.

    ``pid``: a :class:`PID` (its law written out from MODEL.md) or any controller (its state space).

    A dead time delays the command by its whole samples (a longer queue) and, for its fraction
    delta, feeds the amplifier the previous command over the first delta of each sample: the sample
    is integrated in two pieces.
    """
    force = np.asarray(force, dtype=float)
    T = 1.0 / pid.fs
    A, B, states, sensed, whole, fraction = _plant(rig, T)
    pieces = (fraction, T - fraction) if fraction > 0 else (T,)  # the first of two still gets the previous command
    steps = [zoh(A, B, h) for h in pieces]
    law = _Law(pid)

    x = np.zeros(len(states))
    previous = 0.0
    pending = deque([0.0] * (pid.delay + whole))
    displacement = np.empty(force.size)
    current = np.empty(force.size)
    for k, f in enumerate(force):
        e = x[sensed]
        pending.append(law(e))
        i_cmd = pending.popleft()
        displacement[k] = e
        current[k] = x[states.index("i")] if "i" in states else i_cmd
        for h, (Phi, Gamma), u in zip(pieces, steps, (previous, i_cmd)[2 - len(pieces) :]):
            if rig.force_law == "linear":
                x = Phi @ x + Gamma @ np.array([f, u])
            else:
                x = _rk4_sample(rig, A, B, states, x, f, u, h)
        previous = i_cmd
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


def receptance(rig: Rig, pid: AnyController, freq: np.ndarray) -> np.ndarray:
    """Y/F at ``freq`` (Hz) by composing transfer functions, not by the closed-loop state space:
    ys/f = P_f / (1 - P_i G z^-d), with the plant's two ZOH transfer functions P_f, P_i from
    :func:`scipy.signal.cont2discrete` (with the dead time: whole samples as z^-m, the fraction as
    the two pieces of the sample) and the digital PID G(z) written out from MODEL.md."""
    T = 1.0 / pid.fs
    A, B, states, sensed, whole, fraction = _plant(rig, T)
    n = len(states)
    Phi, Gamma = zoh(A, B, T)
    z = np.exp(2j * np.pi * np.asarray(freq, dtype=float) * T)
    if fraction > 0:  # the command reaches the plant as G0 u[k] + G1 u[k-1] (then the whole samples)
        late_Phi, late_Gamma = zoh(A, B, T - fraction)
        G0, G1 = late_Gamma[:, 1], late_Phi @ zoh(A, B, fraction)[1][:, 1]
    else:
        G0, G1 = Gamma[:, 1], np.zeros(n)
    P = np.array(
        [np.linalg.solve(zk * np.eye(n) - Phi, np.column_stack([Gamma[:, 0], (G0 + G1 / zk) * zk**-whole]))[sensed]
         for zk in z]
    )  # (freq, 2)  # fmt: skip
    if isinstance(pid, PID):
        a = _pid_pole(pid, T)
        G = pid.kp + pid.ki * T / (1 - 1 / z) + pid.kd * (1 - a) * (1 - 1 / z) / (T * (1 - a / z))
    else:  # G(z) = C (zI - A)^-1 B + D of the controller's own state space
        Ac, Bc, Cc, Dc = state_space(pid)
        m = Ac.shape[0]
        G = np.array([(Cc @ np.linalg.solve(zk * np.eye(m) - Ac, Bc))[0, 0] if m else 0.0 for zk in z]) + Dc[0, 0]
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
