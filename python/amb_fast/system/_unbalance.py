"""Unbalance response of the sampled loop: the synchronous orbit of a rotor spinning through its speeds.

An unbalance ``m_e`` (kg m) at axial position ``z`` with phase ``phase`` (rad) is a force rotating with the
rotor, ``m_e W^2 (cos(W t + phase), sin(W t + phase))`` at ``z``: continuous in time, not held between
samples. Over one sample the plant integrates it exactly, ``x[k+1] = Phi x[k] + Gamma u[k] + G_W f e^{jWkT}``
with ``G_W = int_0^T e^{A(T - s)} B e^{jWs} ds`` (the top-right block of ``expm([[A, B], [0, jW]] T)``), and the
closed loop's steady response at ``z = e^{jWT}`` is exact at the sample instants: the probes' readings, the
coil currents and the bearings' forces ``-kyy d - kiy i_f`` as the loop samples them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from .._equality import ArrayRecord
from .._linear import checked_poles
from .._validate import real, require
from ._campbell import speed_grid, speed_loops, speed_plant
from ._control import ControllerSpec
from ._model import loop_model, plant, require_stable
from ._rotor import RotorRig


@dataclass(frozen=True, eq=False)
class UnbalanceResponse(ArrayRecord):
    """Synchronous response at each speed; complex amplitudes (speeds, 4) per axis ``A.x, A.y, B.x, B.y``
    (a signal is ``Re(amplitude e^{jWt})``).

    Attributes
    ----------
    speed : ndarray
        (speeds,) rad/s.
    probes : ndarray
        Probe readings, m.
    forces : ndarray
        The magnets' forces on the rotor at the bearing planes, ``-kyy d - kiy i_f``, N.
    currents : ndarray
        Coil control currents, A.
    peaks : list of (axis, speed, amplitude)
        Per axis, the local maxima of the probe amplitude over the speeds (the critical speeds passed), rad/s
        and m.
    states : list of ndarray
        Per speed, the loop's state amplitude at the sample instants (:attr:`LoopModel.states`).
    """

    speed: np.ndarray
    probes: np.ndarray
    forces: np.ndarray
    currents: np.ndarray
    peaks: list[tuple[str, float, float]]
    states: list[np.ndarray]

    def plot(self, ax: Any = None) -> Any:
        """Probe amplitudes (um) and phases against speed (rev/min). Returns the two Axes (matplotlib)."""
        from ..plots import pyplot_module

        plt = pyplot_module()
        if ax is None:
            _, ax = plt.subplots(2, 1, sharex=True, figsize=(7.0, 5.5))
        rpm = self.speed * 60.0 / (2 * np.pi)
        for j, name in enumerate(("A.x", "A.y", "B.x", "B.y")):
            ax[0].plot(rpm, 1e6 * np.abs(self.probes[:, j]), label=name)
            ax[1].plot(rpm, np.degrees(np.angle(self.probes[:, j])), label=name)
        ax[0].set_ylabel("probe amplitude (um)")
        ax[1].set_ylabel("phase (deg)")
        ax[1].set_xlabel("speed (rev/min)")
        ax[0].legend(fontsize="small")
        ax[0].set_title("Unbalance response of the sampled loop")
        return ax


def _unbalance_forces(rig: RotorRig, unbalance: Any) -> list[tuple[np.ndarray, complex]]:
    """Per unbalance: the (n,) generalized-force direction of a unit rotating force at its plane, complex,
    and ``m_e e^{j phase}``."""
    require(isinstance(unbalance, (list, tuple)) and len(unbalance) > 0, "unbalance", unbalance,
            "a list of (m_e kg m, z m, phase rad)")  # fmt: skip
    out = []
    for j, entry in enumerate(unbalance):
        ok = isinstance(entry, (list, tuple)) and len(entry) == 3
        require(ok, f"unbalance[{j}]", entry, "(m_e kg m, z m, phase rad)")
        me, _, phase = (real(f"unbalance[{j}][{k}]", v, u) for k, (v, u) in enumerate(zip(entry, ("kg m", "m", "rad"))))
        plane = rig.rotor.plane(entry[1], f"unbalance[{j}] plane")
        direction = plane.T @ np.array([1.0, -1j])  # F = Re([1, -j] e^{jWt}): (cos, sin)
        out.append((direction, me * np.exp(1j * phase)))
    return out


def _drive(rig: RotorRig, sources: list[tuple[np.ndarray, complex]]) -> np.ndarray:
    """``b`` (plant states,) complex: the rotating force ``Re(W^2 b e^{jWt})`` on the plant's state (the
    accelerations of the unbalances' forces per (rad/s)^2)."""
    A, _, lay = plant(rig)  # its size and layout (the speed's gyroscopic rows do not matter here)
    mech = rig.mechanics()
    Mt = mech.mass + mech.actuators.T @ np.diag([a.mass_loading for a in rig.axes]) @ mech.actuators
    b = np.zeros(A.shape[0], dtype=complex)
    b[list(lay.velocity)] = np.linalg.solve(Mt, sum(me * direction for direction, me in sources))
    return b


def _drives(rig: RotorRig, sources: list[tuple[np.ndarray, complex]], speed: float, T: float) -> np.ndarray:
    """``G_W f``: what one sample of the rotating force ``Re(f e^{jWt})`` adds to the plant's state from
    ``t = 0`` at the speed ``W``, (plant states,) complex, integrated exactly in one exponential."""
    A0, A1, _, _ = speed_plant(rig)
    n = A0.shape[0]
    augmented = np.zeros((n + 1, n + 1), dtype=complex)
    augmented[:n, :n], augmented[:n, n], augmented[n, n] = A0 + speed * A1, speed**2 * _drive(rig, sources), 1j * speed
    return scipy.linalg.expm(augmented * T)[:n, n]


def unbalance_response(
    rig: RotorRig, controller: ControllerSpec, speeds: ArrayLike, unbalance: Any
) -> UnbalanceResponse:
    """The exact synchronous response of the sampled loop to rotating unbalances at each of ``speeds``
    (rad/s): ``unbalance=[(m_e, z, phase), ...]`` (kg m, m from the centre of mass, rad; on a
    :class:`FlexibleRotor` ``z`` is a node's axial position, :attr:`FlexibleRotor.positions`).

    A speed at which the loop is unstable is refused (:class:`UnstableLoopError`, naming it): there is no
    steady response there; :func:`campbell` finds such speeds. Every speed's loop, force, poles and steady
    state come from one exponential, eigenvalue problem and solve in the core, on its threads."""
    W, spec = speed_grid(rig, controller, speeds)
    fs = spec.fs
    require(
        bool(np.all(np.abs(W) < np.pi * fs)), "speeds", speeds, f"below the Nyquist rate pi fs = {np.pi * fs:g} rad/s"
    )
    sources = _unbalance_forces(rig, unbalance)
    poles, _, X, _ = speed_loops(rig, spec, W, drive=_drive(rig, sources))  # X: the state, X z^k at sample k
    unstable = np.flatnonzero(np.any(np.abs(poles) >= 1.0, axis=1))
    if unstable.size:
        first = float(W[unstable[0]])
        checked_poles(poles[unstable[0]], lambda: f"the closed loop at speed {first:g} rad/s is unstable")
    _, _, lay = plant(rig)
    model = loop_model(rig, spec)  # its output rows C do not depend on the speed
    probes, currents = X @ model.C[:4].T, X @ model.C[4:].T
    d = X[:, list(lay.position)] @ rig.mechanics().actuators.T
    i_f = np.stack([X[:, lay.eddy[j]] if lay.eddy[j] >= 0 else X[:, lay.coil[j]] if lay.coil[j] >= 0
                    else currents[:, j] for j in range(4)], axis=1)  # fmt: skip
    forces = -np.array([a.kyy for a in rig.axes]) * d - np.array([a.kiy for a in rig.axes]) * i_f
    amplitude = np.abs(probes)
    peaks = []
    for j, name in enumerate(("A.x", "A.y", "B.x", "B.y")):
        a = amplitude[:, j]
        for k in np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])) + 1:
            peaks.append((name, float(W[k]), float(a[k])))
    return UnbalanceResponse(W, probes, forces, currents, peaks, list(X))


def with_unbalance(
    system: Any, controller: ControllerSpec, args: dict[str, np.ndarray], force: np.ndarray, unbalance: Any
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The core's loop and forces for :func:`simulate` with rotating unbalances at the rotor's constant speed.

    The loop gains a harmonic oscillator at the speed ``W``, states ``(cos W t, sin W t)`` at the samples,
    whose output is the unbalance force ``Re(f e^{jWt})``, continuous in time (``x[k+1] += G_W f e^{jWkT}``,
    :func:`_drives`, as real columns). The core starts from rest: a unit kick on one extra force channel at
    sample 0 (not recorded, no noise) sets the state at sample 1 to the loop's step from rest with the
    oscillator at ``t = 0``. An unstable loop is refused (:class:`UnstableLoopError`, naming the speed):
    the unbalance would only show as the core's overflow."""
    require(isinstance(system, RotorRig), "rig", type(system).__name__, "a RotorRig (an unbalance needs a rotor)")
    speed = system.rotor.speed
    require(speed != 0.0, "the rotor's speed", speed,
            "non-zero with an unbalance (at standstill it exerts no force): rig.at_speed(W), rad/s")  # fmt: skip
    require_stable(system, controller, f"the closed loop at speed {speed:g} rad/s")
    model = loop_model(system, controller)
    T = 1.0 / model.fs
    G = _drives(system, _unbalance_forces(system, unbalance), speed, T)
    s, n, N = model.M.shape[0], G.size, model.Bf.shape[1]
    M = np.zeros((s + 2, s + 2))
    M[:s, :s] = model.M
    M[:n, s], M[:n, s + 1] = G.real, -G.imag  # Re(G e^{jWt}) = Re G cos - Im G sin
    c, si = np.cos(speed * T), np.sin(speed * T)
    M[s:, s:] = [[c, -si], [si, c]]
    Bf = np.zeros((s + 2, N + 1))
    Bf[:s, :N], Bf[:, N] = model.Bf, M[:, s]  # the kick: M applied to the oscillator at (1, 0)
    kick = np.zeros((force.shape[0], 1))
    kick[:1] = 1.0
    return dict(args, M=M, Bf=Bf, Bn=np.vstack([args["Bn"], np.zeros((2, args["Bn"].shape[1]))]),
                C=np.hstack([args["C"], np.zeros((args["C"].shape[0], 2))]),
                transducer_pole=np.append(args["transducer_pole"], 0.0),
                force_noise=np.append(args["force_noise"], 0.0)), np.hstack([force, kick])  # fmt: skip
