"""The Campbell diagram of the sampled loop: its closed-loop poles against the rotor's speed.

At each speed the loop is assembled and discretised exactly (the gyroscopic matrix grows with the speed);
its poles ``z`` give ``s = fs log z``, a frequency ``|Im s| / 2 pi`` (Hz) and a damping ratio
``-Re s / |s|``. A pole's whirl comes from its mode shape at the bearing planes: forward when the orbit
turns with the spin (x towards y), backward against it.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._blas import blas_parked
from .._equality import ArrayRecord
from .._linear import split_dead_time
from .._validate import require
from ._control import ControllerMatrix, ControllerSpec, controller_matrix, controller_state_space
from ._model import Layout, System, plant, sensor_rows
from ._rotor import RotorRig


@dataclass(frozen=True, eq=False)
class Campbell(ArrayRecord):
    """Closed-loop poles of the sampled loop at each speed; arrays (speeds, poles), poles sorted by
    frequency at each speed (equal frequencies: the pole above the real axis first, then by modulus).

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
        ``+1`` forward, ``-1`` backward, ``0`` for a pole without rotor motion at the bearings or on the
        real axis of ``z``: real ``s``, or a pole at the Nyquist frequency ``fs / 2`` (``z < 0``: its samples
        alternate along a line, forward and backward whirl sample alike).
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
        from ..plots import pyplot_module

        plt = pyplot_module()
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


def _bearing_form(system: System, states: int) -> tuple[np.ndarray, np.ndarray]:
    """The rows ``R`` (N, states) of each axis' displacement at its bearing plane, and the Hermitian form
    ``F`` (N, N) over them: ``p^H F p`` (``p = R v``) is the forward minus backward whirl of the bearing
    planes' orbits (``|a + j b|^2 - |a - j b|^2 = -4 Im(conj(a) b)`` per bearing, a = x, b = y)."""
    mech = system.mechanics()
    _, _, lay = plant(system)
    R = np.zeros((mech.axes, states))
    R[:, list(lay.position)] = mech.actuators
    F = np.zeros((mech.axes, mech.axes), dtype=complex)
    for j, name in enumerate(mech.names):
        if name.endswith("x") and name[:-1] + "y" in mech.names:
            k = mech.names.index(name[:-1] + "y")
            F[j, k], F[k, j] = 2j, -2j
    return R, F


def _whirl(values: np.ndarray, shapes: np.ndarray, F: np.ndarray) -> np.ndarray:
    """+1 forward, -1 backward, 0 none, per speed and pole: ``values`` (speeds, n), ``shapes`` (speeds, N, n)
    the bearing planes' displacements ``R v`` of each pole's unit eigenvector ``v`` (zero where not needed:
    a pole on the real axis does not whirl).

    A pole on the real axis has whirl 0, on the negative axis too: its samples alternate along a line
    (forward and backward whirl at the Nyquist frequency ``fs / 2`` sample alike), so it has no sense of turning.

    A repeated pole (x and y alike: any rotor at standstill, the parallel mode at any speed) has no
    mode shape of its own, only a plane of them (the core's two copies span it); within it the shapes of pure
    whirl are the eigenvectors of the forward form relative to the amplitude (one forward, one backward), and
    those are used: for the 2x2 pencil ``(Fg, Dg)`` their signs are those of its two eigenvalues, whose product
    is ``det Fg / det Dg`` and whose sum is ``tr(Dg^-1 Fg)``."""
    # p^H F p over F's few non-zero entries, elementwise on (speeds, n) arrays (not einsum, whose three-operand
    # complex forms are slow, nor a stack of small matrix products)
    measure = np.zeros(values.shape)
    for i, j in zip(*np.nonzero(F)):
        measure += (F[i, j] * shapes[:, i].conj() * shapes[:, j]).real
    amplitude = (shapes.real**2 + shapes.imag**2).sum(axis=1)
    angle = np.angle(values)
    # For Im s < 0 (the conjugate pole) the same orbit reads the other way round.
    turning = np.sign(angle)
    whirl = np.sign(np.round(measure / np.maximum(amplitude, 1e-300), 9)) * turning
    order = np.argsort(values.real + 1e3 * values.imag, axis=1, kind="stable")
    ordered = np.take_along_axis(values, order, axis=1)
    close = np.abs(np.diff(ordered, axis=1)) <= 1e-8 * np.maximum(1.0, np.abs(ordered[:, 1:]))
    speed, k = np.nonzero(close)  # repeated poles come in pairs (x and y)
    if speed.size:
        first, second = order[speed, k], order[speed, k + 1]
        rows = np.moveaxis(shapes, 1, 0)  # (N, speeds, n): the sums over N below add whole rows (fast)
        a, b = rows[:, speed, first], rows[:, speed, second]  # (N, pairs) each
        Fa, Fb = F @ a, F @ b
        # The Hermitian 2x2 forms Dg = V^H V and Fg = V^H F V of V = [a, b], their off-diagonal entries averaged
        d00, d11 = (a.real**2 + a.imag**2).sum(axis=0), (b.real**2 + b.imag**2).sum(axis=0)
        d01 = (a.conj() * b).sum(axis=0)
        f00, f11 = (a.conj() * Fa).sum(axis=0).real, (b.conj() * Fb).sum(axis=0).real
        f01 = ((a.conj() * Fb).sum(axis=0) + (Fa.conj() * b).sum(axis=0)) / 2
        det_d = d00 * d11 - (d01.real**2 + d01.imag**2)
        det_f = f00 * f11 - (f01.real**2 + f01.imag**2)
        det_d = np.where(det_d != 0, det_d, 1e-300)
        size_f = np.maximum(np.maximum(np.abs(f00), np.abs(f11)), np.abs(f01))
        size_d = np.maximum(np.maximum(d00, d11), np.abs(d01))
        size = size_f / np.maximum(size_d, 1e-300)  # |eigenvalues|
        mixed = det_f / det_d < -1e-9 * size**2  # one forward, one backward
        trace = (f00 * d11 + f11 * d00 - 2.0 * (f01 * d01.conj()).real) / det_d
        same = np.where(np.abs(trace) > 1e-9 * size, np.sign(trace), 0.0)
        hi = np.where(mixed, 1.0, same) * turning[speed, first]
        lo = np.where(mixed, -1.0, same) * turning[speed, first]
        whirl[speed, first], whirl[speed, second] = hi, lo
    moving = amplitude > 1e-9  # rotor motion at the bearings (of a unit eigenvector)
    # Off the real axis: neither a real pole nor one at the Nyquist frequency (angle pi)
    oscillating = (np.abs(angle) > 1e-9) & (np.pi - np.abs(angle) > 1e-9)
    return np.where(moving & oscillating, whirl, 0).astype(int)


def _workers(count: int) -> int:
    """All cores for a diagram of many speeds (a thread costs about one speed's work), one for a few."""
    return 0 if count >= 32 else 1


def speed_plant(rig: RotorRig) -> tuple[np.ndarray, np.ndarray, np.ndarray, Layout]:
    """The continuous plant as affine in the speed: ``A(W) = A0 + W A1`` (``A1``: the gyroscopic rows per
    rad/s), its ``B`` and layout."""
    A0, B, layout = plant(rig.at_speed(0.0))
    return A0, plant(rig.at_speed(1.0))[0] - A0, B, layout


_LoopParts = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _loop_parts(rig: RotorRig, controller: ControllerMatrix) -> _LoopParts:
    """:func:`loop_model`'s loop as :func:`_core.speed_loops` takes it: ``A0``, ``A1``, the commands' ``B``, the holds
    ``[T, T - delta, ...]`` (per fractional dead time ``delta``: its command enters as ``G0 = Gamma(T - delta)``
    and a sample late as ``Gamma(T) - G0``), ``P`` and ``L`` (the lines and the controller, at every speed)."""
    A0, A1, B, _ = speed_plant(rig)
    n, N = A0.shape[0], B.shape[1] // 2
    splits = [split_dead_time(axis.dead_time, controller.fs) for axis in rig.axes]
    fractions = sorted({f for _, f in splits if f > 0})
    lines = [m + (f > 0) for m, f in splits]
    size, width = n + sum(lines), n + N * (1 + len(fractions))
    # Rows [0, width): the plant's rows in terms of the columns of [Phi | Gamma ...]; then the lines' rows.
    Phi, Gu = np.zeros((width + size - n, size)), np.zeros((width + size - n, N))
    Phi[:n, :n] = np.eye(n)
    at = n
    for a, ((whole, f), line) in enumerate(zip(splits, lines)):
        G0 = np.zeros(width)
        G0[n + N * (1 + fractions.index(f)) + a if f > 0 else n + a] = 1.0
        if whole == 0:
            Gu[:width, a] = G0
        else:
            Phi[:width, at + whole - 1] = G0
        if f > 0:
            Phi[:width, at + line - 1] -= G0
            Phi[n + a, at + line - 1] += 1.0  # Gamma(T) - G0
        if line:
            Gu[width + at - n, a] = 1.0  # <axis>.dead1' = u
            Phi[width + at - n : width + at - n + line, at : at + line] = np.eye(line, k=-1)
        at += line
    Ac, Bc, Cc, Dc = controller_state_space(controller)
    S = np.zeros((N, size))
    S[:, :n] = sensor_rows(rig)
    closed = np.hstack([Phi + Gu @ (Dc @ S), Gu @ Cc])
    L = np.vstack([np.zeros((n, closed.shape[1])), closed[width:], np.hstack([Bc @ S, Ac])])
    T = 1.0 / controller.fs
    return A0, A1, B[:, N:], np.array([T] + [T - f for f in fractions]), closed[:width], L


def speed_loops(rig: RotorRig, controller: ControllerMatrix, speeds: np.ndarray, **options: Any) -> tuple:
    """:func:`_core.speed_loops` for ``rig`` under ``controller`` at ``speeds`` (rad/s), on the core's threads:
    the poles and, as ``options`` ask (else None), shapes, steady states and the loops (:func:`loop_model`'s)."""
    return _on_core_threads(_loop_parts(rig, controller), speeds, **options)


def _on_core_threads(parts: _LoopParts, speeds: np.ndarray, **options: Any) -> tuple:
    """:func:`_core.speed_loops` of the loop ``parts`` (:func:`_loop_parts`) at ``speeds``, with OpenBLAS's idle
    workers parked while the core's threads run: after the user's multi-threaded numpy call they busy-wait for
    about 0.1 s on the cores those threads need (a 500-speed Campbell diagram: 40 -> 57-79 ms)."""
    workers = _workers(speeds.size)
    with blas_parked() if workers != 1 else contextlib.nullcontext():
        return _core.speed_loops(*parts, speeds, workers=workers, **options)


def speed_grid(rig: RotorRig, controller: ControllerSpec, speeds: ArrayLike) -> tuple[np.ndarray, ControllerMatrix]:
    """What a diagram over the speeds of ``rig`` starts from: ``speeds`` checked as a 1-D array of finite speeds
    (rad/s) and ``controller`` as the four axes' :class:`ControllerMatrix`; ``rig`` must be a :class:`RotorRig`."""
    require(isinstance(rig, RotorRig), "rig", type(rig).__name__, "a RotorRig")
    W = np.atleast_1d(np.asarray(speeds, dtype=float))
    require(W.ndim == 1 and W.size >= 1 and bool(np.all(np.isfinite(W))), "speeds", speeds,
            "a 1-D array of finite speeds, rad/s")  # fmt: skip
    return W, controller_matrix(controller, 4)


def campbell(rig: RotorRig, controller: ControllerSpec, speeds: ArrayLike) -> Campbell:
    """The closed-loop poles of the sampled loop of ``rig`` at each of ``speeds`` (rad/s).

    Every pole (rotor, lags, controller) is kept; ``whirl`` marks those that move the rotor. Unstable
    speeds are reported (``onset_speed``), not raised: a Campbell diagram is how one finds them.
    """
    W, spec = speed_grid(rig, controller, speeds)
    fs = spec.fs
    parts = _loop_parts(rig, spec)
    R, F = _bearing_form(rig, parts[-1].shape[0])
    values, shapes, _, _ = _on_core_threads(parts, W, R=R)
    angle = np.angle(values)
    # By frequency, then the upper pole of a conjugate pair first, then by modulus: no tie left to the core's order
    order = np.lexsort((np.abs(values), -angle, np.abs(angle)), axis=-1)
    values = np.take_along_axis(values, order, axis=1)
    shapes = np.take_along_axis(shapes, order[:, None, :], axis=2)
    whirl = _whirl(values, shapes, F)
    z = values
    s = fs * np.log(z.astype(complex))
    frequency = np.abs(s.imag) / (2 * np.pi)
    damping = -s.real / np.maximum(np.abs(s), 1e-300)
    unstable = np.any(np.abs(z) >= 1.0, axis=1)
    onset = float(W[np.argmax(unstable)]) if unstable.any() else None
    return Campbell(W, z, frequency, damping, whirl, onset, fs)
