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
from .._validate import real, require
from ._control import ControllerSpec, controller_matrix
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
        from ..plots import _pyplot

        plt = _pyplot()
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


def unbalance_response(
    rig: RotorRig, controller: ControllerSpec, speeds: ArrayLike, unbalance: Any
) -> UnbalanceResponse:
    """The exact synchronous response of the sampled loop to rotating unbalances at each of ``speeds``
    (rad/s): ``unbalance=[(m_e, z, phase), ...]`` (kg m, m from the centre of mass, rad; on a
    :class:`FlexibleRotor` ``z`` is a node's axial position, :attr:`FlexibleRotor.positions`).

    A speed at which the loop is unstable is refused (:class:`UnstableLoopError`, naming it): there is no
    steady response there; :func:`campbell` finds such speeds."""
    require(isinstance(rig, RotorRig), "rig", type(rig).__name__, "a RotorRig")
    W = np.atleast_1d(np.asarray(speeds, dtype=float))
    require(W.ndim == 1 and W.size >= 1 and bool(np.all(np.isfinite(W))), "speeds", speeds,
            "a 1-D array of finite speeds, rad/s")  # fmt: skip
    spec = controller_matrix(controller, 4)
    fs, T = spec.fs, 1.0 / spec.fs
    require(
        bool(np.all(np.abs(W) < np.pi * fs)), "speeds", speeds, f"below the Nyquist rate pi fs = {np.pi * fs:g} rad/s"
    )
    sources = _unbalance_forces(rig, unbalance)
    probes, forces, currents = (np.zeros((W.size, 4), dtype=complex) for _ in range(3))
    states = []
    for i, speed in enumerate(W):
        system = rig.at_speed(float(speed))
        require_stable(system, spec, f"the closed loop at speed {speed:g} rad/s")
        A, B, lay = plant(system)
        model = loop_model(system, spec)
        n, size = A.shape[0], model.M.shape[0]
        mech = system.mechanics()
        Mt = mech.mass + mech.actuators.T @ np.diag([a.mass_loading for a in system.axes]) @ mech.actuators
        force = sum((me * speed**2) * direction for direction, me in sources)  # generalized, complex
        b = np.zeros(n, dtype=complex)
        b[list(lay.velocity)] = np.linalg.solve(Mt, force)
        augmented = np.zeros((n + 1, n + 1), dtype=complex)
        augmented[:n, :n], augmented[:n, n], augmented[n, n] = A * T, b * T, 1j * speed * T
        G = scipy.linalg.expm(augmented)[:n, n]
        z = np.exp(1j * speed * T)
        drive = np.zeros(size, dtype=complex)
        drive[:n] = G
        X = np.linalg.solve(z * np.eye(size) - model.M, drive)  # the state at the sample instants k: X z^k
        states.append(X)
        probes[i] = model.C[:4] @ X
        currents[i] = model.C[4:] @ X
        d = mech.actuators @ X[list(lay.position)]
        i_f = np.array([X[lay.eddy[j]] if lay.eddy[j] >= 0 else X[lay.coil[j]] if lay.coil[j] >= 0 else currents[i, j]
                        for j in range(4)])  # fmt: skip
        forces[i] = -np.array([a.kyy for a in system.axes]) * d - np.array([a.kiy for a in system.axes]) * i_f
    amplitude = np.abs(probes)
    peaks = []
    for j, name in enumerate(("A.x", "A.y", "B.x", "B.y")):
        a = amplitude[:, j]
        for k in range(1, W.size - 1):
            if a[k] > a[k - 1] and a[k] >= a[k + 1]:
                peaks.append((name, float(W[k]), float(a[k])))
    return UnbalanceResponse(W, probes, forces, currents, peaks, states)
