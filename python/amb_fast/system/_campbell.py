"""The Campbell diagram of the sampled loop: its closed-loop poles against the rotor's speed.

At each speed the loop is assembled and discretised exactly (the gyroscopic matrix grows with the speed);
its poles ``z`` give ``s = fs log z``, a frequency ``|Im s| / 2 pi`` (Hz) and a damping ratio
``-Re s / |s|``. A pole's whirl comes from its mode shape at the bearing planes: forward when the orbit
turns with the spin (x towards y), backward against it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._equality import ArrayRecord
from .._validate import require
from ._control import ControllerSpec, controller_matrix
from ._model import System, loop_model, plant
from ._rotor import RotorRig


@dataclass(frozen=True, eq=False)
class Campbell(ArrayRecord):
    """Closed-loop poles of the sampled loop at each speed; arrays (speeds, poles), poles sorted by
    frequency at each speed.

    Attributes
    ----------
    speed : ndarray
        (speeds,) rad/s.
    z : ndarray
        Poles in the z-plane (stable: ``|z| < 1``).
    frequency : ndarray
        ``|Im s| / 2 pi``, Hz, with ``s = fs log z``.
    damping : ndarray
        Damping ratio ``-Re s / |s|`` (negative: unstable).
    whirl : ndarray
        ``+1`` forward, ``-1`` backward, ``0`` for a pole without rotor motion at the bearings or without
        oscillation (real ``s``).
    onset_speed : float or None
        The lowest speed given at which the loop is unstable, rad/s; None if stable at every speed.
    fs : float
        Hz.
    """

    speed: np.ndarray
    z: np.ndarray
    frequency: np.ndarray
    damping: np.ndarray
    whirl: np.ndarray
    onset_speed: float | None
    fs: float

    def plot(self, *, max_frequency: float | None = None, ax: Any = None) -> Any:
        """Frequency of every whirling mode (damping ratio below 0.9) against speed (rev/min), forward and
        backward marked, with the synchronous line (1X); unstable poles circled. Returns the Axes
        (matplotlib, the extra ``plot``)."""
        from ..plots import _pyplot

        plt = _pyplot()
        if ax is None:
            _, ax = plt.subplots(figsize=(7.0, 4.5))
        rpm = self.speed * 60.0 / (2 * np.pi)
        whirling = (self.whirl != 0) & (self.damping < 0.9)
        top = max_frequency if max_frequency is not None else 2.0 * float(np.max(self.frequency[whirling], initial=1.0))
        # Whirling modes only: the near-real poles of integrators and lags (damping ratio near 1) are not.
        shown = whirling & (self.frequency <= top)
        for sign, label, style, marker in ((1, "forward whirl", "C0", "^"), (-1, "backward whirl", "C1", "v")):
            mask = shown & (self.whirl == sign)
            x = np.broadcast_to(rpm[:, None], mask.shape)[mask]
            ax.scatter(x, self.frequency[mask], s=10, color=style, marker=marker, label=label)
        bad = shown & (np.abs(self.z) >= 1.0)
        if bad.any():
            x = np.broadcast_to(rpm[:, None], bad.shape)[bad]
            ax.scatter(x, self.frequency[bad], s=40, facecolors="none", edgecolors="red", label="unstable")
        ax.plot(rpm, self.speed / (2 * np.pi), "k--", lw=1, label="1X (synchronous)")
        ax.set_xlabel("speed (rev/min)")
        ax.set_ylabel("frequency (Hz)")
        ax.set_ylim(0.0, top)
        ax.legend(loc="upper left", fontsize="small")
        ax.set_title("Campbell diagram of the sampled loop")
        return ax


def _forward_form(system: System, states: int) -> tuple[np.ndarray, np.ndarray]:
    """Hermitian forms over the loop's state: ``v^H F v`` is the forward minus backward whirl of the
    bearing planes' orbits (``|a + j b|^2 - |a - j b|^2 = -4 Im(conj(a) b)`` per bearing, a = x, b = y),
    ``v^H D v`` their squared amplitude."""
    mech = system.mechanics()
    _, _, lay = plant(system)
    d = np.zeros((mech.axes, states))
    d[:, list(lay.position)] = mech.actuators  # each axis' displacement at its bearing plane
    F = np.zeros((states, states), dtype=complex)
    for j, name in enumerate(mech.names):
        if name.endswith("x") and name[:-1] + "y" in mech.names:
            a, b = d[j], d[mech.names.index(name[:-1] + "y")]
            F += 2j * (np.outer(a, b) - np.outer(b, a))
    return F, d.T @ d


def _whirl(values: np.ndarray, vectors: np.ndarray, F: np.ndarray, D: np.ndarray) -> np.ndarray:
    """+1 forward, -1 backward, 0 none, per eigenvector (columns).

    A repeated pole (x and y alike: any rotor at standstill, the parallel mode at any speed) has no
    mode shape of its own, only a plane of them; within it the shapes of pure whirl are the eigenvectors
    of the forward form relative to the amplitude (one forward, one backward), and those are used."""
    FV, DV = F @ vectors, D @ vectors
    measure = np.einsum("ij,ij->j", vectors.conj(), FV).real
    amplitude = np.einsum("ij,ij->j", vectors.conj(), DV).real
    total = np.einsum("ij,ij->j", vectors.conj(), vectors).real
    # For Im s < 0 (the conjugate pole) the same orbit reads the other way round.
    turning = np.sign(np.angle(values))
    whirl = np.sign(np.round(measure / np.maximum(amplitude, 1e-300), 9)) * turning
    order = np.argsort(values.real + 1e3 * values.imag, kind="stable")
    close = np.abs(np.diff(values[order])) <= 1e-8 * np.maximum(1.0, np.abs(values[order][1:]))
    for k in np.flatnonzero(close):  # repeated poles come in pairs (x and y)
        group = order[k : k + 2]
        V = vectors[:, group]
        Dg, Fg = V.conj().T @ D @ V, V.conj().T @ F @ V
        root = np.linalg.cholesky((Dg + Dg.conj().T) / 2 + 1e-300 * np.eye(2))
        within = np.linalg.solve(root, np.linalg.solve(root, (Fg + Fg.conj().T) / 2).conj().T)
        pure = np.sign(np.round(np.linalg.eigvalsh((within + within.conj().T) / 2), 9)) * turning[group[0]]
        whirl[group] = np.sort(pure)[::-1]
    moving = amplitude > 1e-9 * total  # rotor motion at the bearings
    oscillating = np.abs(np.angle(values)) > 1e-9
    return np.where(moving & oscillating, whirl, 0).astype(int)


def campbell(rig: RotorRig, controller: ControllerSpec, speeds: ArrayLike) -> Campbell:
    """The closed-loop poles of the sampled loop of ``rig`` at each of ``speeds`` (rad/s).

    Every pole (rotor, lags, controller) is kept; ``whirl`` marks those that move the rotor. Unstable
    speeds are reported (``onset_speed``), not raised: a Campbell diagram is how one finds them.
    """
    require(isinstance(rig, RotorRig), "rig", type(rig).__name__, "a RotorRig")
    W = np.atleast_1d(np.asarray(speeds, dtype=float))
    require(W.ndim == 1 and W.size >= 1 and bool(np.all(np.isfinite(W))), "speeds", speeds,
            "a 1-D array of finite speeds, rad/s")  # fmt: skip
    spec = controller_matrix(controller, 4)
    fs = spec.fs
    zs, whirls = [], []
    F = D = np.zeros((0, 0))
    for speed in W:
        system = rig.at_speed(float(speed))
        M = loop_model(system, spec).M
        if F.shape[0] != M.shape[0]:
            F, D = _forward_form(system, M.shape[0])
        values, vectors = np.linalg.eig(M)
        order = np.argsort(np.abs(np.angle(values)), kind="stable")
        values, vectors = values[order], vectors[:, order]
        zs.append(values)
        whirls.append(_whirl(values, vectors, F, D))
    z = np.array(zs)
    s = fs * np.log(z.astype(complex))
    frequency = np.abs(s.imag) / (2 * np.pi)
    damping = -s.real / np.maximum(np.abs(s), 1e-300)
    unstable = np.any(np.abs(z) >= 1.0, axis=1)
    onset = float(W[np.argmax(unstable)]) if unstable.any() else None
    return Campbell(W, z, frequency, damping, np.array(whirls), onset, fs)
