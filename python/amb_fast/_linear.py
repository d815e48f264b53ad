"""The linearised sampled-data loop in closed form: prediction, poles, margins, effective coefficients.

Matrix-level numpy (no per-sample loops). The plant is discretised exactly (zero-order hold), so the
frequency response here is what a noise-free, settled, period-averaged experiment must reproduce.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Union

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from . import _core
from ._dispatch import two_axis_aware
from ._errors import UnstableLoopError
from ._params import PID, Rig
from ._validate import require, rig_and_controller

if TYPE_CHECKING:
    from .controllers import Controller

AnyController = Union[PID, "Controller"]
DesignController = Union[PID, "Controller", tuple, Callable[[np.ndarray], np.ndarray]]


def is_controller(value: Any) -> bool:
    """A :class:`PID` or a :class:`~amb_fast.Controller` (anything with ``to_ss``, ``fs``, ``delay``)."""
    return isinstance(value, PID) or (hasattr(value, "to_ss") and hasattr(value, "fs") and hasattr(value, "delay"))


def state_space(controller: AnyController) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The controller's delay-free ``(A, B, C, D)`` from e[k] (m) to u[k] (A)."""
    if isinstance(controller, PID):
        return controller.state_space()
    if is_controller(controller):
        A, B, C, D = controller.to_ss()
        return (np.asarray(A, float), np.asarray(B, float).reshape(-1, 1), np.asarray(C, float).reshape(1, -1),
                np.asarray(D, float).reshape(1, 1))  # fmt: skip
    raise TypeError(f"controller must be a PID or an amb_fast.Controller, got {type(controller).__name__}")


def plant_matrices(rig: Rig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` (inputs: force N, current command A) over the active states.

    States, in order, are ``y, v`` and then whichever of ``i`` (amplifier), ``i_f`` (eddy current) and
    ``ys`` (sensor) are switched on. The force law is linearised (``kyy``, ``kiy``); the moving mass is
    ``mass + mass_loading``.
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
    m = rig.mass + rig.mass_loading
    term("v", "y", -rig.kyy / m)
    term("v", driving, -rig.kiy / m)
    B[states.index("v"), 0] = 1.0 / m
    # Each first-order stage relaxes to its input at w = 2 pi * bandwidth.
    inputs = {"i": "cmd", "i_f": coil, "ys": "y"}
    for name, bandwidth in stages:
        if bandwidth is not None:
            term(name, name, -2 * np.pi * bandwidth)
            term(name, inputs[name], 2 * np.pi * bandwidth)
    return A, B, states


def split_dead_time(dead_time: float, fs: float) -> tuple[int, float]:
    """The dead time (s) as whole samples and the fraction of a sample left over (s), as the core splits it."""
    T = 1.0 / fs
    samples = int(np.floor(dead_time / T))
    return samples, max(0.0, dead_time - samples * T)


def _zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold ``Phi``, ``Gamma`` over ``h`` via the augmented matrix exponential."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * h
    M[:n, n:] = B * h
    E = expm(M)
    return E[:n, :n], E[:n, n:]


def discrete_plant(rig: Rig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact zero-order-hold ``Phi``, ``Gamma`` over ``1/fs`` (inputs: force N, current command A).

    With a dead time ``tau = m T + delta`` the plant carries it inside as a line of commands
    ``dead1 .. dead(m)`` (and one more, ``dead(m+1)``, when ``delta > 0``): over ``[kT, kT + delta)``
    the amplifier still receives the previous command, so ``x[k+1] = Phi x + Gf f + G0 u[k-m] +
    G1 u[k-m-1]`` with ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)`` (the modified
    z-transform of the zero-order hold).
    """
    A, B, states = plant_matrices(rig)
    T = 1.0 / fs
    Phi, Gamma = _zoh(A, B, T)
    samples, fraction = split_dead_time(rig.dead_time, fs)
    line = samples + (fraction > 0)
    if line == 0:
        return Phi, Gamma, states
    n = len(states)
    G0, G1 = Gamma[:, 1], np.zeros(n)
    if fraction > 0:
        late_Phi, late_Gamma = _zoh(A, B, T - fraction)
        G0, G1 = late_Gamma[:, 1], late_Phi @ _zoh(A, B, fraction)[1][:, 1]
    Phi2 = np.zeros((n + line, n + line))
    Gamma2 = np.zeros((n + line, 2))
    Phi2[:n, :n] = Phi
    Gamma2[:n, 0] = Gamma[:, 0]
    if samples == 0:
        Gamma2[:n, 1] = G0
    else:
        Phi2[:n, n + samples - 1] = G0
    if fraction > 0:
        Phi2[:n, n + line - 1] = G1
    Gamma2[n, 1] = 1.0  # dead1' = u
    for j in range(1, line):
        Phi2[n + j, n + j - 1] = 1.0
    return Phi2, Gamma2, states + [f"dead{j + 1}" for j in range(line)]


def core_controller(controller: AnyController) -> Any:
    """The core's copy of a controller (``_core.Controller``), made once per distinct value."""
    if isinstance(controller, PID):
        return controller._to_core()
    from ._params import _core_controller

    return _core_controller(*state_space(controller), float(controller.fs), int(controller.delay))


def controller_matrices(controller: AnyController) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The digital controller with its delay as a state space from e[k] (m) to i_cmd[k] (A).

    The controller's own states (for a PID only those that carry something: see
    :meth:`PID.state_space`), then ``delay`` states of a delay line.
    """
    Ac, Bc, Cc, Dc = state_space(controller)
    # Delay line q[k+1] = (u[k], q1[k], ...), i_cmd[k] = q_d[k].
    d = controller.delay
    if d == 0:
        return Ac, Bc, Cc, Dc
    m = Ac.shape[0]
    size = m + d
    A2 = np.zeros((size, size))
    A2[:m, :m] = Ac
    A2[m, :m] = Cc[0]
    for j in range(1, d):
        A2[m + j, m + j - 1] = 1.0
    B2 = np.zeros((size, 1))
    B2[:m] = Bc
    B2[m, 0] = Dc[0, 0]
    C2 = np.zeros((1, size))
    C2[0, -1] = 1.0
    return A2, B2, C2, np.zeros((1, 1))


@two_axis_aware
def closed_loop(rig: Rig, controller: AnyController) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The linear loop as one discrete state space ``(A, B, C, D)`` with sample period ``1/fs``.

    Input: force f[k] (N). Outputs: sensor displacement ys(kT) (m) and coil current (A). State: the
    plant's, then the controller's (see :func:`controller_matrices`). ``controller``: a :class:`PID`
    or any :class:`~amb_fast.Controller`.
    """
    rig_and_controller(rig, controller, "closed_loop")
    Phi, Gamma, states = discrete_plant(rig, controller.fs)
    Ac, Bc, Cc, Dc = controller_matrices(controller)
    n, m = len(states), Ac.shape[0]
    sensor = np.zeros((1, n))
    sensor[0, states.index("ys") if "ys" in states else 0] = 1.0
    gu, gf = Gamma[:, 1:2], Gamma[:, 0:1]
    A = np.block([[Phi + gu @ Dc @ sensor, gu @ Cc], [Bc @ sensor, Ac]])
    B = np.vstack([gf, np.zeros((m, 1))])
    command = np.hstack([Dc @ sensor, Cc])
    if "i" in states:
        current = np.eye(n + m)[states.index("i")][None, :]
    elif "dead1" in states and split_dead_time(rig.dead_time, controller.fs)[0] > 0:  # the delayed command
        current = np.eye(n + m)[states.index(f"dead{split_dead_time(rig.dead_time, controller.fs)[0]}")][None, :]
    else:
        current = command
    C = np.vstack([np.hstack([sensor, np.zeros((1, m))]), current])
    return A, B, C, np.zeros((2, 1))


@two_axis_aware
def closed_loop_poles(rig: Rig, controller: AnyController) -> np.ndarray:
    """Poles of the linearised sampled-data loop in the z-plane (stable: all ``|z| < 1``).

    The equivalent continuous-time poles are ``log(z) * fs`` (rad/s).
    """
    rig_and_controller(rig, controller, "closed_loop_poles")
    return np.linalg.eigvals(closed_loop(rig, controller)[0])


def loop_poles(rig: Rig, controller: AnyController) -> np.ndarray:
    """The closed-loop poles as every run and sweep computes them (so they choose the same settling and
    flag the same points unstable): the core's eigenvalues (:func:`_eigenvalues`) of, for a PID, the
    affine stack of :func:`spectral_radius`, else :func:`closed_loop`'s matrix."""
    if isinstance(controller, PID):
        ((_, stack),) = _closed_loop_stacks(rig, controller, _gain_arrays(controller, None, None, None))
        return _eigenvalues(stack)[0]
    return _eigenvalues(closed_loop(rig, controller)[0][None])[0]


def _eigenvalues(stack: np.ndarray, workers: int = 1) -> np.ndarray:
    """Eigenvalues of a stack of square matrices (count, m, m), in the core on up to ``workers`` threads
    (one per 128 matrices: starting a thread costs about fifty 7x7 solves): one function for single runs
    and sweeps, so both see the same digits."""
    return _core.eigenvalues(np.ascontiguousarray(stack, dtype=float), max(1, min(workers, len(stack) // 128)))


@functools.lru_cache(maxsize=256)
def require_stable(rig: Rig, controller: AnyController) -> np.ndarray:
    """The closed-loop poles (as :func:`loop_poles` computes them, read-only), or
    :class:`UnstableLoopError` naming the unstable ones and the controller."""
    poles = loop_poles(rig, controller)
    poles.flags.writeable = False
    bad = poles[np.abs(poles) >= 1.0]
    if bad.size:
        shown = ", ".join(f"{p:.6g} (|z|={abs(p):.6g})" for p in bad[:4])
        if isinstance(controller, PID):
            what = (f"kp={controller.kp} A/m, ki={controller.ki} A/(m s), kd={controller.kd} A s/m, "
                    f"delay={controller.delay}")  # fmt: skip
        else:
            what = repr(controller)
        raise UnstableLoopError(
            f"the closed loop is unstable with {what}: pole(s) on or outside the unit circle: {shown}", bad
        )
    return poles


def _gain_arrays(pid: PID, kp: ArrayLike | None, ki: ArrayLike | None, kd: ArrayLike | None) -> np.ndarray:
    """Gain sets as an (N, 3) array: given arrays broadcast together, the rest from ``pid``."""
    given = {"kp": kp, "ki": ki, "kd": kd}
    arrays = [np.asarray(pid.__dict__[n] if v is None else v, dtype=float) for n, v in given.items()]
    for name, array in zip(given, arrays):
        require(bool(np.all(np.isfinite(array))), name, array, "finite")
    return np.stack(np.broadcast_arrays(*arrays), axis=-1).reshape(-1, 3)


@functools.lru_cache(maxsize=64)
def _affine_closed_loop(
    rig: Rig, pid: PID, with_integral: bool, with_derivative: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The closed-loop matrix is affine in (kp, ki, kd) for a given set of controller states:
    ``A = base + kp S0 + (ki - ki0) S1 + (kd - kd0) S2`` with ki0, kd0 = 1 where the state exists.
    ``pid``'s own gains do not matter here (callers pass them as zero, for the cache)."""
    ki0, kd0 = float(with_integral), float(with_derivative)

    def at(p: float, i: float, d: float) -> np.ndarray:
        return closed_loop(rig, replace(pid, kp=p, ki=i, kd=d))[0]

    base = at(0.0, ki0, kd0)
    slopes = [at(1.0, ki0, kd0) - base]
    slopes.append(at(0.0, 2.0, kd0) - base if with_integral else np.zeros_like(base))
    slopes.append(at(0.0, ki0, 2.0) - base if with_derivative else np.zeros_like(base))
    return base, np.array(slopes)


def _closed_loop_stacks(rig: Rig, pid: PID, gains: np.ndarray):  # noqa: ANN202
    """(rows, stack of closed-loop matrices) per pattern of controller states among the gain sets."""
    structure = replace(pid, kp=0.0, ki=0.0, kd=0.0)
    pattern = (gains[:, 1] != 0) * 1 + (gains[:, 2] != 0) * 2
    for code in np.unique(pattern):
        rows = np.flatnonzero(pattern == code)
        base, slopes = _affine_closed_loop(rig, structure, bool(code & 1), bool(code >> 1))
        offsets = gains[rows] - np.array([0.0, float(code & 1), float(code >> 1)])
        yield rows, base + np.einsum("nk,kij->nij", offsets, slopes)


def spectral_radius(
    rig: Rig,
    pid: PID,
    *,
    kp: ArrayLike | None = None,
    ki: ArrayLike | None = None,
    kd: ArrayLike | None = None,
    workers: int = 1,
) -> np.ndarray:
    """Largest |z| of the closed-loop poles for many gain sets at once (the rest of ``pid`` fixed).

    The closed-loop matrix is affine in the gains, so each gain set's matrix is a combination of four
    cached ones, and the eigenvalues of the whole stack come in one call (on ``workers`` threads).
    Returns one radius per gain set (stable: < 1), in the broadcast shape of the gains, flattened. A
    single run and a sweep use this same computation, so they choose the same settling time.
    """
    gains = _gain_arrays(pid, kp, ki, kd)
    radius = np.empty(len(gains))
    for rows, stack in _closed_loop_stacks(rig, pid, gains):
        radius[rows] = np.max(np.abs(_eigenvalues(stack, workers)), axis=-1)
    return radius


def settling_radius(rig: Rig, pid: AnyController, radius: ArrayLike) -> np.ndarray:
    """The slowest decay per sample of a run: the loop's spectral ``radius``, or the force transducer's
    AC-coupling pole ``exp(-1/(fs tau))`` when that is slower (it settles on the applied force)."""
    if rig.force_coupling_tau is None:
        return np.asarray(radius, dtype=float)
    return np.maximum(radius, np.exp(-1.0 / (pid.fs * rig.force_coupling_tau)))


def settle_periods_for(radius: np.ndarray, period_samples: int, decay: float = 1e-9) -> np.ndarray:
    """Periods of ``period_samples`` for poles of the given spectral ``radius`` (< 1) to decay below
    ``decay``: ``ceil(ln(decay) / ln(radius) / period_samples) + 1``."""
    radius = np.asarray(radius, dtype=float)
    with np.errstate(divide="ignore"):
        samples = np.where(radius > 0, np.log(decay) / np.log(np.where(radius > 0, radius, 0.5)), 0.0)
    return np.ceil(samples / period_samples).astype(np.int64) + 1


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


@two_axis_aware
def predict(
    rig: Rig,
    pid: AnyController,
    freq: ArrayLike,
    *,
    kp: ArrayLike | None = None,
    ki: ArrayLike | None = None,
    kd: ArrayLike | None = None,
) -> np.ndarray:
    """Exact receptance Y/F (m/N) of the linearised sampled-data loop at ``freq`` (Hz).

    ``pid``: a :class:`PID` or any :class:`~amb_fast.Controller`. Y is the sensor output and F the
    recorded force (through the transducer's AC coupling, if any), both sampled at ``fs``, as an
    experiment records them; a settled, noise-free, period-averaged experiment reproduces it at every
    excited line to rounding.

    With a PID, given ``kp``, ``ki`` or ``kd`` (arrays, broadcast together; the others from ``pid``), returns an
    array of shape (gain sets, len(freq)) for all of them at once: the plant's two responses are
    computed once and the controller, linear in its gains, is combined with them per gain set.
    """
    rig_and_controller(rig, pid, "predict")
    f = _frequencies(freq, pid.fs)
    z = np.exp(2j * np.pi * f.ravel() / pid.fs)
    if kp is None and ki is None and kd is None:
        A, B, C, _ = closed_loop(rig, pid)
        return (_response(A, B, C[:1], z)[0, 0] / transducer_response(rig, pid.fs, z)).reshape(f.shape)
    if not isinstance(pid, PID):
        raise ValueError(f"kp, ki, kd arrays need a PID controller, got {type(pid).__name__}")
    gains = _gain_arrays(pid, kp, ki, kd)
    Pf, Pi = _plant_responses(rig, pid.fs, f.ravel())
    K = _controller_terms(pid, f.ravel())  # (3, freq): d G / d(kp, ki, kd), delay included
    return Pf / (1.0 - Pi * (gains @ K)) / transducer_response(rig, pid.fs, z)


def transducer_response(rig: Rig, fs: float, z: np.ndarray) -> np.ndarray:
    """Recorded over applied force: (1 - z^-1) / (1 - a z^-1), a = exp(-1/(fs tau)), for an AC-coupled
    transducer (exact for the zero-order-held force); 1 when DC coupled."""
    if rig.force_coupling_tau is None:
        return np.ones_like(z)
    a = np.exp(-1.0 / (fs * rig.force_coupling_tau))
    return (1 - 1 / z) / (1 - a / z)


def _plant_responses(rig: Rig, fs: float, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sampled plant responses from force and from current command to the sensor, at ``f`` (Hz)."""
    Phi, Gamma, states = discrete_plant(rig, fs)
    sensor = np.zeros((1, len(states)))
    sensor[0, states.index("ys") if "ys" in states else 0] = 1.0
    response = _response(Phi, Gamma, sensor, np.exp(2j * np.pi * f / fs))[0]
    return response[0], response[1]


def _controller_terms(pid: PID, f: np.ndarray) -> np.ndarray:
    """The digital G(z) z^-d is kp A(z) + ki B(z) + kd C(z): rows A, B, C at ``f`` (Hz)."""
    T = 1.0 / pid.fs
    zi = np.exp(-2j * np.pi * f * T)
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
    delay = zi**pid.delay
    return np.array([np.ones_like(zi), T / (1 - zi), (1 - a) * (1 - zi) / (T * (1 - a * zi))]) * delay


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


@two_axis_aware
def sensitivity(rig: Rig, pid: AnyController, freq: ArrayLike) -> np.ndarray:
    """Sensitivity S = 1/(1 + L) with the loop broken at the controller output, at ``freq`` (Hz)."""
    rig_and_controller(rig, pid, "sensitivity")
    f = _frequencies(freq, pid.fs)
    Phi, Gamma, states = discrete_plant(rig, pid.fs)
    sensor = np.zeros((1, len(states)))
    sensor[0, states.index("ys") if "ys" in states else 0] = 1.0
    Ac, Bc, Cc, Dc = controller_matrices(pid)
    z = np.exp(2j * np.pi * f.ravel() / pid.fs)
    plant = _response(Phi, Gamma[:, 1:2], sensor, z)[0, 0]  # i_cmd -> ys (negative gain: -Kiy)
    control = Dc[0, 0] + (_response(Ac, Bc, Cc, z)[0, 0] if Ac.size else 0.0)
    return (1.0 / (1.0 - plant * control)).reshape(f.shape)


@two_axis_aware
def stability_margin(rig: Rig, pid: AnyController, points: int = 20_000) -> StabilityMargin:
    """Peak of |S| over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    rig_and_controller(rig, pid, "stability_margin")
    require(isinstance(points, int) and points >= 2, "points", points, "a whole number >= 2")
    stable = bool(np.all(np.abs(closed_loop_poles(rig, pid)) < 1.0))
    if not stable:
        return StabilityMargin(np.inf, np.inf, np.nan, "D", False)
    f = np.geomspace(0.01, pid.fs / 2 * (1 - 1e-9), points)
    S = np.abs(sensitivity(rig, pid, f))
    j = int(np.argmax(S))
    return StabilityMargin(float(S[j]), float(20 * np.log10(S[j])), float(f[j]), iso_zone(float(S[j])), True)


def controller_response(controller: DesignController, freq: np.ndarray, *, discrete: bool = False) -> np.ndarray:
    """G(jw) (A/m) of a PID, a Controller, a (num, den) polynomial pair in s, or a callable of s = jw.

    A :class:`~amb_fast.Controller` gives its continuous design's G(jw) when it has one, else (and
    with ``discrete=True``) its digital G(e^{jwT}) with the computation delay.
    """
    s = 2j * np.pi * freq
    if not isinstance(controller, PID) and is_controller(controller):
        general: Any = controller
        if discrete or getattr(general, "continuous", None) is None:
            return np.asarray(general.response(freq), dtype=complex)
        return np.asarray(general.continuous_response(freq), dtype=complex)
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
    require(not discrete, "discrete", discrete, "False unless the controller is a PID or a Controller")
    if isinstance(controller, tuple):
        require(len(controller) == 2, "controller", controller, "a (num, den) pair of polynomial coefficients in s")
        num, den = (np.atleast_1d(np.asarray(p, dtype=float)) for p in controller)
        return np.polyval(num, s) / np.polyval(den, s)
    require(
        callable(controller), "controller", controller, "a PID, a Controller, a (num, den) pair, or a callable of s"
    )
    function: Any = controller
    return np.asarray(function(s), dtype=complex) * np.ones_like(s)


@two_axis_aware
def effective_coefficients(
    rig: Rig,
    controller: DesignController,
    freq: ArrayLike,
    *,
    discrete: bool = False,
    kp: ArrayLike | None = None,
    ki: ArrayLike | None = None,
    kd: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Effective stiffness (N/m) and damping (N s/m) of paper eq. 5 at ``freq`` (Hz).

    ``k_eff = Kyy + Kiy Re G(jw)``, ``c_eff = Kiy Im G(jw) / w``, with ``controller`` a :class:`PID`
    (its theoretical G(s); ``discrete=True`` uses the digital G(z), delay included), a
    :class:`~amb_fast.Controller` (its continuous design when it has one, else or with
    ``discrete=True`` its digital G(z) with the delay), a ``(num, den)`` pair of polynomial
    coefficients in s (highest power first), or a callable of s = jw.

    With a PID, ``kp``, ``ki``, ``kd`` arrays (broadcast together) give arrays of shape
    (gain sets, len(freq)): G is linear in the gains, so each gain set costs one product.
    """
    f = _frequencies(freq)
    if kp is not None or ki is not None or kd is not None:
        if not isinstance(controller, PID):
            raise ValueError(f"controller must be a PID when kp, ki or kd arrays are given, got {controller!r}")
        gains = _gain_arrays(controller, kp, ki, kd)
        unit = [replace(controller, kp=float(j == 0), ki=float(j == 1), kd=float(j == 2)) for j in range(3)]
        terms = np.array([controller_response(u, f.ravel(), discrete=discrete) for u in unit])
        G = gains @ terms  # (gain sets, freq)
        return rig.kyy + rig.kiy * G.real, rig.kiy * G.imag / (2 * np.pi * f.ravel())
    G = controller_response(controller, f, discrete=discrete)
    bad = ~np.isfinite(G)
    if np.any(bad):
        raise ValueError(f"controller response is not finite at {f[bad].ravel()[:5]} Hz")
    return rig.kyy + rig.kiy * G.real, rig.kiy * G.imag / (2 * np.pi * f)
