"""The linearised loop as state spaces: the continuous plant over its active states and its exact
zero-order-hold discretisation (dead time included), the digital controller with its delay line, and the
closed loop they make. ``AnyController`` and ``DesignController`` name the controllers the functions take.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Union

import numpy as np
from scipy.linalg import expm

from ._dispatch import axes_aware
from ._params import PID, Rig
from ._validate import rig_and_controller

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


def zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
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

    Made once per distinct ``(rig, fs)`` (a closed loop's poles for a PID take four loops of one plant;
    sweeps over the rig make many): ``Phi`` and ``Gamma`` are read-only.
    """
    Phi, Gamma, states = _discrete_plant(rig, float(fs))
    return Phi, Gamma, list(states)


@functools.lru_cache(maxsize=256)
def _discrete_plant(rig: Rig, fs: float) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    Phi, Gamma, states = _discretised(rig, fs)
    Phi.flags.writeable = Gamma.flags.writeable = False
    return Phi, Gamma, tuple(states)


def _discretised(rig: Rig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    A, B, states = plant_matrices(rig)
    T = 1.0 / fs
    Phi, Gamma = zoh(A, B, T)
    samples, fraction = split_dead_time(rig.dead_time, fs)
    line = samples + (fraction > 0)
    if line == 0:
        return Phi, Gamma, states
    n = len(states)
    Phi2 = np.zeros((n + line, n + line))
    Gamma2 = np.zeros((n + line, 2))
    Phi2[:n, :n] = Phi
    Gamma2[:n, 0] = Gamma[:, 0]
    Gamma2[:n, 1], Phi2[:n, n:] = dead_time_columns(A, B, Gamma, 1, T, (samples, fraction))
    Gamma2[n, 1] = 1.0  # dead1' = u
    Phi2[n:, n:] = np.eye(line, k=-1)  # dead(j+1)' = dead(j)
    return Phi2, Gamma2, states + [f"dead{j + 1}" for j in range(line)]


def dead_time_columns(
    A: np.ndarray, B: np.ndarray, Gamma: np.ndarray, col: int, T: float, split: tuple[int, float]
) -> tuple[np.ndarray, np.ndarray]:
    """How the command of input ``col`` reaches the sampled plant when it arrives ``split = (m, delta)``
    (:func:`split_dead_time`) late (see :func:`discrete_plant`): ``(now, delayed)``, the plant's column of
    ``Gamma`` for this sample's command (``G0`` when ``m == 0``, else zero) and its columns for the
    command line ``dead1 .. dead<m + (delta > 0)>`` (``G0`` at ``dead<m>``, ``G1`` at the last when
    ``delta > 0``, zero elsewhere). ``A``, ``B``: the continuous plant; ``Gamma``: its hold over ``T``."""
    samples, fraction = split
    n = A.shape[0]
    G0, G1 = Gamma[:, col], np.zeros(n)
    if fraction > 0:
        late_Phi, late_Gamma = zoh(A, B, T - fraction)
        G0, G1 = late_Gamma[:, col], late_Phi @ zoh(A, B, fraction)[1][:, col]
    delayed = np.zeros((n, samples + (fraction > 0)))
    if samples > 0:
        delayed[:, samples - 1] = G0
    if fraction > 0:
        delayed[:, -1] = G1
    return (G0 if samples == 0 else np.zeros(n)), delayed


def sensor_row(states: list[str]) -> np.ndarray:
    """(1, states): the row that reads the sensor output from the plant's state (``ys``, or ``y`` when the
    sensor has no lag)."""
    row = np.zeros((1, len(states)))
    row[0, states.index("ys") if "ys" in states else 0] = 1.0
    return row


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


def loop_matrix(
    Phi: np.ndarray, Gu: np.ndarray, S: np.ndarray, Ac: np.ndarray, Bc: np.ndarray, Cc: np.ndarray, Dc: np.ndarray
) -> np.ndarray:
    """The closed loop's state matrix ``[[Phi + Gu Dc S, Gu Cc], [Bc S, Ac]]`` (``Gu``: the commands' columns
    of ``Gamma``, ``S``: the sensor rows; one axis or two), assembled in place (np.block costs more than the
    products, and sweeps build many)."""
    n, m = Phi.shape[0], Ac.shape[0]
    A = np.empty((n + m, n + m))
    A[:n, :n], A[:n, n:], A[n:, :n], A[n:, n:] = Phi + Gu @ Dc @ S, Gu @ Cc, Bc @ S, Ac
    return A


@axes_aware
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
    sensor = sensor_row(states)
    gf = Gamma[:, 0:1]
    A = loop_matrix(Phi, Gamma[:, 1:2], sensor, Ac, Bc, Cc, Dc)
    B = np.vstack([gf, np.zeros((m, 1))])
    command = np.hstack([Dc @ sensor, Cc])
    samples = split_dead_time(rig.dead_time, controller.fs)[0]
    if "i" in states:
        current = np.eye(n + m)[states.index("i")][None, :]
    elif samples > 0:  # the delayed command (dead1 .. dead<samples> are states then)
        current = np.eye(n + m)[states.index(f"dead{samples}")][None, :]
    else:
        current = command
    C = np.vstack([np.hstack([sensor, np.zeros((1, m))]), current])
    return A, B, C, np.zeros((2, 1))
