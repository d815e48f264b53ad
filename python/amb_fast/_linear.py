"""The linearised sampled-data loop in closed form: prediction, poles, margins, effective coefficients.

Matrix-level numpy (no per-sample loops). The plant is discretised exactly (zero-order hold), so the
frequency response here is what a noise-free, settled, period-averaged experiment must reproduce.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Union

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from ._errors import UnstableLoopError
from ._params import PID, Rig
from ._validate import require

Controller = Union[PID, tuple, Callable[[np.ndarray], np.ndarray]]


def plant_matrices(rig: Rig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` (inputs: force N, current command A) over the active states.

    States, in order, are ``y, v`` and then whichever of ``i`` (amplifier), ``i_f`` (eddy current) and
    ``ys`` (sensor) are switched on. The force law is linearised (``kyy``, ``kiy``).
    """
    stages = (("i", rig.amp_bandwidth), ("i_f", rig.eddy_bandwidth), ("ys", rig.sensor_bandwidth))
    states = ["y", "v"] + [name for name, bandwidth in stages if bandwidth is not None]
    A = np.zeros((len(states), len(states)))
    B = np.zeros((len(states), 2))

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


def discrete_plant(rig: Rig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact zero-order-hold ``Phi``, ``Gamma`` over ``1/fs`` via the augmented matrix exponential."""
    A, B, states = plant_matrices(rig)
    n = len(states)
    M = np.zeros((n + 2, n + 2))
    M[:n, :n] = A / fs
    M[:n, n:] = B / fs
    E = expm(M)
    return E[:n, :n], E[:n, n:], states


def controller_matrices(pid: PID) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The digital PID with its delay as a state space from e[k] (m) to i_cmd[k] (A).

    Only the states that carry something are kept: the integral without ``ki``, the derivative
    memory without ``kd`` and the filter state without a cutoff are left out.
    """
    T = 1.0 / pid.fs
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
    kd_gain = pid.kd * (1 - a) / T
    # Rows: state updates s[k+1] = Ac s + Bc e; u[k] = Cc s + Dc e.
    names = [n for n, on in (("I", pid.ki != 0), ("D", pid.kd != 0 and a != 0), ("E", pid.kd != 0)) if on]
    m = len(names)
    Ac, Bc, Cc = np.zeros((m, m)), np.zeros(m), np.zeros(m)
    Dc = pid.kp + pid.ki * T + kd_gain
    idx = {name: j for j, name in enumerate(names)}
    if "I" in idx:
        Ac[idx["I"], idx["I"]] = 1.0
        Bc[idx["I"]] = pid.ki * T
        Cc[idx["I"]] = 1.0
    if "D" in idx:
        Ac[idx["D"], idx["D"]] = a
        Ac[idx["D"], idx["E"]] = -kd_gain
        Bc[idx["D"]] = kd_gain
        Cc[idx["D"]] = a
    if "E" in idx:
        Bc[idx["E"]] = 1.0
        Cc[idx["E"]] = -kd_gain
    # Delay line q[k+1] = (u[k], q1[k], ...), i_cmd[k] = q_d[k].
    d = pid.delay
    if d == 0:
        return Ac, Bc[:, None], Cc[None, :], np.array([[Dc]])
    size = m + d
    A2 = np.zeros((size, size))
    A2[:m, :m] = Ac
    A2[m, :m] = Cc
    for j in range(1, d):
        A2[m + j, m + j - 1] = 1.0
    B2 = np.zeros((size, 1))
    B2[:m, 0] = Bc
    B2[m, 0] = Dc
    C2 = np.zeros((1, size))
    C2[0, -1] = 1.0
    return A2, B2, C2, np.zeros((1, 1))


def closed_loop(rig: Rig, pid: PID) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The linear loop as one discrete state space ``(A, B, C, D)`` with sample period ``1/fs``.

    Input: force f[k] (N). Outputs: sensor displacement ys(kT) (m) and coil current (A). State: the
    plant's, then the controller's (see :func:`controller_matrices`).
    """
    Phi, Gamma, states = discrete_plant(rig, pid.fs)
    Ac, Bc, Cc, Dc = controller_matrices(pid)
    n, m = len(states), Ac.shape[0]
    sensor = np.zeros((1, n))
    sensor[0, states.index("ys") if "ys" in states else 0] = 1.0
    gu, gf = Gamma[:, 1:2], Gamma[:, 0:1]
    A = np.block([[Phi + gu @ Dc @ sensor, gu @ Cc], [Bc @ sensor, Ac]])
    B = np.vstack([gf, np.zeros((m, 1))])
    command = np.hstack([Dc @ sensor, Cc])
    current = np.eye(n + m)[states.index("i")][None, :] if "i" in states else command
    C = np.vstack([np.hstack([sensor, np.zeros((1, m))]), current])
    return A, B, C, np.zeros((2, 1))


def closed_loop_poles(rig: Rig, pid: PID) -> np.ndarray:
    """Poles of the linearised sampled-data loop in the z-plane (stable: all ``|z| < 1``).

    The equivalent continuous-time poles are ``log(z) * pid.fs`` (rad/s).
    """
    return np.linalg.eigvals(closed_loop(rig, pid)[0])


def require_stable(rig: Rig, pid: PID) -> np.ndarray:
    """The closed-loop poles, or :class:`UnstableLoopError` naming the unstable ones and the gains."""
    poles = closed_loop_poles(rig, pid)
    bad = poles[np.abs(poles) >= 1.0]
    if bad.size:
        shown = ", ".join(f"{p:.6g} (|z|={abs(p):.6g})" for p in bad[:4])
        raise UnstableLoopError(
            f"the closed loop is unstable with kp={pid.kp} A/m, ki={pid.ki} A/(m s), kd={pid.kd} A s/m, "
            f"delay={pid.delay}: pole(s) on or outside the unit circle: {shown}",
            bad,
        )
    return poles


def settle_periods_for(poles: np.ndarray, period_samples: int, decay: float = 1e-9) -> int:
    """Periods of ``period_samples`` for the slowest of the (stable) ``poles`` to decay below ``decay``, plus one."""
    radius = float(np.max(np.abs(poles)))
    samples = 0.0 if radius == 0.0 else np.log(decay) / np.log(radius)
    return int(np.ceil(samples / period_samples)) + 1


def _frequencies(freq: ArrayLike, fs: float | None = None) -> np.ndarray:
    f = np.asarray(freq, dtype=float)
    require(f.ndim <= 1 and bool(np.all(np.isfinite(f))) and bool(np.all(f > 0)), "freq", freq, "finite and > 0 (Hz)")
    if fs is not None:
        require(bool(np.all(f < fs / 2)), "freq", freq, f"below the Nyquist frequency {fs / 2} Hz")
    return f


def _response(A: np.ndarray, B: np.ndarray, C: np.ndarray, z: np.ndarray) -> np.ndarray:
    """C (zI - A)^-1 B for each z; shapes (outputs, inputs, len(z))."""
    n = A.shape[0]
    M = z[:, None, None] * np.eye(n) - A
    X = np.linalg.solve(M, np.broadcast_to(B, (z.size, *B.shape)))
    return np.einsum("on,fni->oif", C, X)


def predict(rig: Rig, pid: PID, freq: ArrayLike) -> np.ndarray:
    """Exact receptance Y/F (m/N) of the linearised sampled-data loop at ``freq`` (Hz).

    Y is the sensor output and F the force, both sampled at ``pid.fs``, as an experiment records them;
    a settled, noise-free, period-averaged experiment reproduces it at every excited line to rounding.
    """
    f = _frequencies(freq, pid.fs)
    A, B, C, _ = closed_loop(rig, pid)
    z = np.exp(2j * np.pi * f.ravel() / pid.fs)
    return _response(A, B, C[:1], z)[0, 0].reshape(f.shape)


@dataclass(frozen=True)
class StabilityMargin:
    """Peak of the sensitivity function and its ISO 14839-3 zone.

    Attributes
    ----------
    peak : float
        max |S(e^{jwT})| over 0 < f < fs/2 (``inf`` for an unstable loop).
    peak_db : float
        The same in dB.
    frequency : float
        Where the peak is, Hz.
    zone : str
        "A" (peak < 3, 9.5 dB), "B" (< 4, 12 dB), "C" (< 5, 14 dB) or "D".
    stable : bool
        Whether the linearised closed loop is stable.
    """

    peak: float
    peak_db: float
    frequency: float
    zone: str
    stable: bool


def iso_zone(peak: float) -> str:
    """ISO 14839-3 zone of a sensitivity peak."""
    return "A" if peak < 3 else "B" if peak < 4 else "C" if peak < 5 else "D"


def sensitivity(rig: Rig, pid: PID, freq: ArrayLike) -> np.ndarray:
    """Sensitivity S = 1/(1 + L) with the loop broken at the controller output, at ``freq`` (Hz)."""
    f = _frequencies(freq, pid.fs)
    Phi, Gamma, states = discrete_plant(rig, pid.fs)
    sensor = np.zeros((1, len(states)))
    sensor[0, states.index("ys") if "ys" in states else 0] = 1.0
    Ac, Bc, Cc, Dc = controller_matrices(pid)
    z = np.exp(2j * np.pi * f.ravel() / pid.fs)
    plant = _response(Phi, Gamma[:, 1:2], sensor, z)[0, 0]  # i_cmd -> ys (negative gain: -Kiy)
    control = Dc[0, 0] + (_response(Ac, Bc, Cc, z)[0, 0] if Ac.size else 0.0)
    return (1.0 / (1.0 - plant * control)).reshape(f.shape)


def stability_margin(rig: Rig, pid: PID, points: int = 20_000) -> StabilityMargin:
    """Peak of |S| over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    stable = bool(np.all(np.abs(closed_loop_poles(rig, pid)) < 1.0))
    if not stable:
        return StabilityMargin(np.inf, np.inf, np.nan, "D", False)
    f = np.geomspace(0.01, pid.fs / 2 * (1 - 1e-9), points)
    S = np.abs(sensitivity(rig, pid, f))
    j = int(np.argmax(S))
    return StabilityMargin(float(S[j]), float(20 * np.log10(S[j])), float(f[j]), iso_zone(float(S[j])), True)


def controller_response(controller: Controller, freq: np.ndarray, *, discrete: bool = False) -> np.ndarray:
    """G(jw) (A/m) of a PID, a (num, den) polynomial pair in s, or a callable of s = jw."""
    s = 2j * np.pi * freq
    if isinstance(controller, PID):
        pid = controller
        if discrete:
            T = 1.0 / pid.fs
            zi = np.exp(-s * T)  # z^-1
            a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
            G = pid.kp + pid.ki * T / (1 - zi) + pid.kd * (1 - a) * (1 - zi) / (T * (1 - a * zi))
            return G * zi**pid.delay
        derivative = s if pid.derivative_cutoff is None else s / (1 + s / (2 * np.pi * pid.derivative_cutoff))
        return pid.kp + pid.ki / s + pid.kd * derivative
    require(not discrete, "discrete", discrete, "False unless the controller is a PID")
    if isinstance(controller, tuple):
        require(len(controller) == 2, "controller", controller, "a (num, den) pair of polynomial coefficients in s")
        num, den = (np.atleast_1d(np.asarray(p, dtype=float)) for p in controller)
        return np.polyval(num, s) / np.polyval(den, s)
    require(callable(controller), "controller", controller, "a PID, a (num, den) pair, or a callable of s")
    return np.asarray(controller(s), dtype=complex) * np.ones_like(s)


def effective_coefficients(
    rig: Rig, controller: Controller, freq: ArrayLike, *, discrete: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Effective stiffness (N/m) and damping (N s/m) of paper eq. 5 at ``freq`` (Hz).

    ``k_eff = Kyy + Kiy Re G(jw)``, ``c_eff = Kiy Im G(jw) / w``, with ``controller`` a :class:`PID`
    (its theoretical G(s); ``discrete=True`` uses the digital G(z), delay included), a ``(num, den)``
    pair of polynomial coefficients in s (highest power first), or a callable of s = jw.
    """
    f = _frequencies(freq)
    G = controller_response(controller, f, discrete=discrete)
    bad = ~np.isfinite(G)
    if np.any(bad):
        raise ValueError(f"controller response is not finite at {f[bad].ravel()[:5]} Hz")
    return rig.kyy + rig.kiy * G.real, rig.kiy * G.imag / (2 * np.pi * f)
