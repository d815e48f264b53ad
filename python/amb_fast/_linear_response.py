"""The loop's frequency responses at chosen lines: the receptance an experiment measures
(:func:`predict`), the sensitivity and its peak with the ISO 14839-3 zone (:func:`stability_margin`), and
the effective stiffness and damping of a controller's G (paper eq. 5, :func:`effective_coefficients`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._dispatch import axes_aware
from ._linear_loop import (
    AnyController,
    ControllerSpec,
    DesignController,
    closed_loop,
    controller_matrix,
    controller_state_space,
    is_controller,
    sampled_plant,
    sampled_sensor_rows,
)
from ._linear_poles import _gain_arrays, closed_loop_poles
from ._params import PID, Rig
from ._validate import require, rig_and_controller


def _frequencies(freq: ArrayLike, fs: float | None = None) -> np.ndarray:
    f = np.asarray(freq, dtype=float)
    require(f.ndim <= 1 and bool(np.all(np.isfinite(f))) and bool(np.all(f > 0)), "freq", freq, "finite and > 0 (Hz)")
    if fs is not None:
        require(bool(np.all(f < fs / 2)), "freq", freq, f"below the Nyquist frequency {fs / 2} Hz")
    return f


def state_response(
    A: np.ndarray, B: np.ndarray, C: np.ndarray, z: np.ndarray, *, frequency_first: bool = False
) -> np.ndarray:
    """C (zI - A)^-1 B for each z; shape (outputs, inputs, len(z)), or with ``frequency_first`` (len(z),
    outputs, inputs) (as two axes want it: a stack of matrices)."""
    n = A.shape[0]
    M = z[:, None, None] * np.eye(n) - A
    X = np.linalg.solve(M, np.broadcast_to(B, (z.size, *B.shape)))
    return np.einsum("on,fni->foi" if frequency_first else "on,fni->oif", C, X)


@axes_aware
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
        return (state_response(A, B, C[:1], z)[0, 0] / transducer_response(rig, pid.fs, z)).reshape(f.shape)
    if not isinstance(pid, PID):
        raise ValueError(f"kp, ki, kd arrays need a PID controller, got {type(pid).__name__}")
    gains = _gain_arrays(pid, kp, ki, kd)
    Pf, Pi = plant_responses(rig, pid.fs, f.ravel())
    K = _controller_terms(pid, f.ravel())  # (3, freq): d G / d(kp, ki, kd), delay included
    return Pf / (1.0 - Pi * (gains @ K)) / transducer_response(rig, pid.fs, z)


def transducer_response(rig: Rig, fs: float, z: np.ndarray) -> np.ndarray:
    """Recorded over applied force: (1 - z^-1) / (1 - a z^-1), a = exp(-1/(fs tau)), for an AC-coupled
    transducer (exact for the zero-order-held force); 1 when DC coupled."""
    if rig.force_coupling_tau is None:
        return np.ones_like(z)
    a = np.exp(-1.0 / (fs * rig.force_coupling_tau))
    return (1 - 1 / z) / (1 - a / z)


def plant_responses(rig: Rig, fs: float, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sampled plant responses from force and from current command to the sensor, at ``f`` (Hz); read-only."""
    return _plant_responses(rig, float(fs), np.ascontiguousarray(f, dtype=float).tobytes())


@functools.lru_cache(maxsize=16)
def _plant_responses(rig: Rig, fs: float, lines: bytes) -> tuple[np.ndarray, np.ndarray]:
    # Cached per rig and lines: a design's search asks for one plant's sensitivity under many controllers.
    Phi, Gamma, _ = sampled_plant(rig, fs)
    z = np.exp(2j * np.pi * np.frombuffer(lines) / fs)
    response = state_response(Phi, Gamma, sampled_sensor_rows(rig, len(Phi)), z)[0]
    response.flags.writeable = False
    return response[0], response[1]


def controller_frequency_response(controller: ControllerSpec, n: int, z: np.ndarray) -> np.ndarray:
    """The controller matrix's digital response ``K(z)`` (delays included), shape (len(z), N, N)."""
    Ac, Bc, Cc, Dc = controller_state_space(controller_matrix(controller, n))
    return Dc + (state_response(Ac, Bc, Cc, z, frequency_first=True) if Ac.size else 0.0)


def _controller_terms(pid: PID, f: np.ndarray) -> np.ndarray:
    """The digital G(z) z^-d is kp A(z) + ki B(z) + kd C(z): rows A, B, C at ``f`` (Hz)."""
    zi = np.exp(-2j * np.pi * f * (1.0 / pid.fs))
    return np.array([_digital_pid(pid, zi, *unit) for unit in np.eye(3)])


def _digital_pid(pid: PID, zi: np.ndarray, kp: float, ki: float, kd: float) -> np.ndarray:
    """The digital PID's G(z) z^-d at ``zi`` = z^-1 with gains ``kp``, ``ki``, ``kd`` (the rest from ``pid``)."""
    T = 1.0 / pid.fs
    a = np.exp(-2 * np.pi * pid.derivative_cutoff * T) if pid.derivative_cutoff is not None else 0.0
    G = kp + ki * T / (1 - zi) + kd * (1 - a) * (1 - zi) / (T * (1 - a * zi))
    return G * zi**pid.delay


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


@axes_aware
def sensitivity(rig: Rig, pid: AnyController, freq: ArrayLike, *, at: str = "controller") -> np.ndarray:
    """Sensitivity S = 1/(1 + L) with the loop broken at the controller output, at ``freq`` (Hz).

    ``at``: ``"controller"`` or ``"sensors"`` (the summing point of ISO 14839-3's test signal); on one axis
    both are the same, on N axes ``(I - K P)^-1`` and ``(I - P K)^-1``."""
    require(at in ("controller", "sensors"), "at", at, "'controller' or 'sensors'")
    rig_and_controller(rig, pid, "sensitivity")
    f = _frequencies(freq, pid.fs)
    plant = plant_responses(rig, pid.fs, f.ravel())[1]  # i_cmd -> ys (negative gain: -Kiy)
    control = controller_frequency_response(pid, 1, np.exp(2j * np.pi * f.ravel() / pid.fs))[:, 0, 0]
    return (1.0 / (1.0 - plant * control)).reshape(f.shape)


@axes_aware
def stability_margin(rig: Rig, pid: AnyController, points: int = 20_000) -> StabilityMargin:
    """Peak of |S| over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    rig_and_controller(rig, pid, "stability_margin")
    require(isinstance(points, int) and points >= 2, "points", points, "a whole number >= 2")
    stable = bool(np.all(np.abs(closed_loop_poles(rig, pid)) < 1.0))
    if not stable:
        return StabilityMargin(np.inf, np.inf, np.nan, "D", False)
    f = np.geomspace(0.01, pid.fs / 2 * (1 - 1e-9), points)
    return peak_margin(f, np.abs(sensitivity(rig, pid, f)))


def peak_margin(f: np.ndarray, values: np.ndarray) -> StabilityMargin:
    """A stable loop's margin: the peak of ``values`` (a sensitivity's magnitude at ``f``, Hz), one axis or N."""
    j = int(np.argmax(values))
    peak = float(values[j])
    return StabilityMargin(peak, float(20 * np.log10(peak)), float(f[j]), iso_zone(peak), True)


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
            return _digital_pid(pid, np.exp(-s * (1.0 / pid.fs)), pid.kp, pid.ki, pid.kd)
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


@axes_aware
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
