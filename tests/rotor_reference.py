"""Pure-numpy reference of the rigid rotor on two magnetic bearings (issue 26), for comparison tests.

Written from the equations of ``docs/model.md`` / issue 26 ("The rigid rotor") independently of the
package's N-axis code: it uses only numpy/scipy and the one-axis parameter objects (``af.Rig`` for each
axis' chain, ``af.PID`` / ``af.Controller`` for the controller entries: their delay-free state space,
``fs`` and ``delay``). Slow on purpose.

Conventions (SI throughout; frequencies in Hz at the interface):

- Rotor coordinates at the centre of mass ``q = (x, y, tx, ty)`` (m, m, rad, rad); the displacement at
  axial position z (m) is ``(x + z ty, y - z tx)``; ``m x'' = Qx``, ``m y'' = Qy``,
  ``It tx'' + Ip W ty' = Qtx``, ``It ty'' - Ip W tx' = Qty``; a force (Fx, Fy) at z gives
  ``Qx = Fx, Qy = Fy, Qtx = -z Fy, Qty = z Fx``.
- Controlled axes in the order ``A.x, A.y, B.x, B.y`` (index 0..3). Axis j: actuator force
  ``-kyy d - kiy i_f`` at its bearing plane in its direction (d the rotor's displacement there), probe at
  its sensor plane in its direction (then its first-order lag), shaker force at its bearing plane,
  mass loading a point mass at the bearing plane moving with the rotor in that direction, recorded force
  through the transducer's AC coupling ``(1 - z^-1)/(1 - a z^-1)``, ``a = exp(-T/tau)``.
- Controller: ``u_i[k] = sum_j G_ij e_j[k]``, every entry its own difference equation and its own delay
  queue of ``delay`` samples; then axis i's dead time: whole samples as a queue, the fraction ``delta``
  as "the previous command over the first delta of the sample" (the sample integrated in pieces).
- At sample k the recorded channels are the probe readings ``e[k]`` (sensor state at kT) and the
  recorded force ``f[k] - qf[k]`` with ``qf[k+1] = a qf[k] + (1 - a) f[k]`` (as the one-axis reference).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import cont2discrete

import amb_fast as af

AXES = ("A.x", "A.y", "B.x", "B.y")
HADAMARD = np.array([[1, 1, 1, 1], [1, -1, 1, -1], [1, 1, -1, -1], [1, -1, -1, 1]], dtype=float)


@dataclass
class RotorParams:
    """The rigid rotor: mass (kg), It, Ip (kg m^2), bearings and sensors (m from the centre of mass),
    speed (rad/s, positive from x towards y), process: (z m, kxy N/m, kyx N/m, cxy N s/m, cyx N s/m)
    cross-coupled springs/dampers at plane z (``Fx = -kxy y_z - cxy y_z'``, ``Fy = -kyx x_z - cyx x_z'``)."""

    mass: float
    It: float
    Ip: float
    bearings: tuple[float, float]
    sensors: tuple[float, float]
    speed: float = 0.0
    process: list[tuple[float, float, float, float, float]] = field(default_factory=list)


def row(z: float, direction: str) -> np.ndarray:
    """The row mapping q = (x, y, tx, ty) to the displacement at z (m) in ``direction`` ('x' or 'y')."""
    return np.array([1.0, 0.0, 0.0, z]) if direction == "x" else np.array([0.0, 1.0, -z, 0.0])


def _planes(params: RotorParams, which: str) -> np.ndarray:
    """(4, 4) rows for the axes A.x, A.y, B.x, B.y at the bearing ('bearings') or sensor ('sensors') planes."""
    zA, zB = params.bearings if which == "bearings" else params.sensors
    return np.array([row(zA, "x"), row(zA, "y"), row(zB, "x"), row(zB, "y")])


def rigid_body_map(params: RotorParams) -> np.ndarray:
    """(4, 4) R: bearing-plane displacements = R @ probe readings (solve the probes' geometry for q)."""
    S = _planes(params, "sensors")
    if abs(params.sensors[0] - params.sensors[1]) == 0.0:
        raise ValueError(f"sensors={params.sensors}: both probes in one plane, the rigid-body map is singular")
    return _planes(params, "bearings") @ np.linalg.inv(S)


def rotor_matrices(params: RotorParams) -> tuple[np.ndarray, np.ndarray]:
    """The rotor's own (4, 4) mass and gyroscopic matrices in q: ``M q'' + W G q' = Q``."""
    M = np.diag([params.mass, params.mass, params.It, params.It])
    G = np.zeros((4, 4))
    G[2, 3], G[3, 2] = params.Ip, -params.Ip
    return M, G


def continuous_plant(params: RotorParams, axes: Sequence[af.Rig]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``x' = A x + B (f_A.x, f_A.y, f_B.x, f_B.y, i_A.x, i_A.y, i_B.x, i_B.y)`` (N, A).

    States: ``x, y, tx, ty, vx, vy, wx, wy`` (m, rad, m/s, rad/s), then per axis its switched-on lags
    ``<axis>.i``, ``<axis>.i_f`` (A) and ``<axis>.ys`` (m).
    """
    if len(axes) != 4:
        raise ValueError(f"axes: expected 4 Rig (A.x, A.y, B.x, B.y), got {len(axes)}")
    for name, axis in zip(AXES, axes):  # the reference is the linear, noise-free loop only
        if axis.force_law != "linear":
            raise ValueError(f"axes[{name}].force_law={axis.force_law!r}: the reference is linear only")
    names = ["x", "y", "tx", "ty", "vx", "vy", "wx", "wy"]
    for name, axis in zip(AXES, axes):
        names += [f"{name}.{s}" for s, on in (("i", axis.amp_bandwidth), ("i_f", axis.eddy_bandwidth),
                                              ("ys", axis.sensor_bandwidth)) if on is not None]  # fmt: skip
    ix = {name: j for j, name in enumerate(names)}
    n = len(names)
    bear, sens = _planes(params, "bearings"), _planes(params, "sensors")
    M, G = rotor_matrices(params)
    K = np.zeros((4, 4))
    C = params.speed * G
    for j, axis in enumerate(axes):
        M = M + axis.mass_loading * np.outer(bear[j], bear[j])
        K = K + axis.kyy * np.outer(bear[j], bear[j])
    for z, kxy, kyx, cxy, cyx in params.process:
        bx, by = row(z, "x"), row(z, "y")
        K = K + kxy * np.outer(bx, by) + kyx * np.outer(by, bx)
        C = C + cxy * np.outer(bx, by) + cyx * np.outer(by, bx)
    Minv = np.linalg.inv(M)
    A, B = np.zeros((n, n)), np.zeros((n, 8))
    A[0:4, 4:8] = np.eye(4)
    A[4:8, 0:4] = -Minv @ K
    A[4:8, 4:8] = -Minv @ C
    for j, (name, axis) in enumerate(zip(AXES, axes)):
        push = Minv @ bear[j]  # acceleration of q per newton at this axis' bearing plane and direction
        B[4:8, j] = push
        coil = ix.get(f"{name}.i")
        force_current = ix.get(f"{name}.i_f", coil)
        if force_current is None:
            B[4:8, 4 + j] = -axis.kiy * push
        else:
            A[4:8, force_current] += -axis.kiy * push
        if coil is not None and axis.amp_bandwidth is not None:
            w = 2 * np.pi * axis.amp_bandwidth
            A[coil, coil] = -w
            B[coil, 4 + j] = w
        if f"{name}.i_f" in ix and axis.eddy_bandwidth is not None:
            w = 2 * np.pi * axis.eddy_bandwidth
            k = ix[f"{name}.i_f"]
            A[k, k] = -w
            if coil is None:
                B[k, 4 + j] = w
            else:
                A[k, coil] = w
        if f"{name}.ys" in ix and axis.sensor_bandwidth is not None:
            w = 2 * np.pi * axis.sensor_bandwidth
            k = ix[f"{name}.ys"]
            A[k, k] = -w
            A[k, 0:4] += w * sens[j]
    return A, B, names


def _probe_rows(params: RotorParams, names: list[str]) -> np.ndarray:
    """(4, n): the probe readings from the plant state (the lag's state, or the displacement itself)."""
    sens = _planes(params, "sensors")
    P = np.zeros((4, len(names)))
    for j, name in enumerate(AXES):
        if f"{name}.ys" in names:
            P[j, names.index(f"{name}.ys")] = 1.0
        else:
            P[j, 0:4] = sens[j]
    return P


def _ss(controller: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A controller entry's delay-free (A, B, C, D) from the public API."""
    A, B, C, D = controller.state_space() if isinstance(controller, af.PID) else controller.to_ss()
    return (np.asarray(A, float), np.asarray(B, float).reshape(-1), np.asarray(C, float).reshape(-1),
            float(np.asarray(D).reshape(-1)[0]))  # fmt: skip


def _entries(controller: Sequence[Sequence[Any]]) -> tuple[float, list[tuple[int, int, Any]]]:
    """fs (Hz) and the non-None entries (row i, column j, controller) of a 4x4 nested list."""
    if len(controller) != 4 or any(len(r) != 4 for r in controller):
        raise ValueError("controller: expected a 4x4 nested list of controllers or None")
    entries = [(i, j, c) for i, r in enumerate(controller) for j, c in enumerate(r) if c is not None]
    if not entries:
        raise ValueError("controller: every entry is None")
    fs = {c.fs for _, _, c in entries}
    if len(fs) != 1:
        raise ValueError(f"controller: entries at different fs {sorted(fs)} Hz")
    return fs.pop(), entries


def diagonal(ctrl: Any) -> list[list[Any]]:
    """The 4x4 controller matrix with ``ctrl`` on every axis and no cross paths."""
    return [[ctrl if i == j else None for j in range(4)] for i in range(4)]


def _dead_times(axes: Sequence[af.Rig], T: float) -> tuple[list[int], list[float]]:
    whole, fraction = [], []
    for axis in axes:
        w = int(np.floor(axis.dead_time / T))
        whole.append(w)
        fraction.append(max(0.0, axis.dead_time - w * T))
    return whole, fraction


def _pieces(
    A: np.ndarray, B: np.ndarray, T: float, fraction: list[float]
) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """The sample [0, T) cut where an axis' dead-time fraction switches its command; ZOH per piece."""
    n = A.shape[0]
    cuts = sorted({0.0, T, *[f for f in fraction if 0 < f < T]})
    out = []
    for t0, t1 in zip(cuts[:-1], cuts[1:]):
        Phi, Gamma, *_ = cont2discrete((A, B, np.eye(n), np.zeros((n, B.shape[1]))), t1 - t0, method="zoh")
        out.append((t0, Phi, Gamma))
    return out


def simulate(
    params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]], force: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The loop from rest, noise-free, sample by sample, on held shaker forces ``force`` (n, 4) N.

    Returns (recorded force (n, 4) N, through each axis' transducer; probe readings (n, 4) m), columns
    in the axis order A.x, A.y, B.x, B.y.
    """
    force = np.asarray(force, dtype=float)
    if force.ndim != 2 or force.shape[1] != 4:
        raise ValueError(f"force: expected shape (n, 4), got {force.shape}")
    fs, spec = _entries(controller)
    T = 1.0 / fs
    A, B, names = continuous_plant(params, axes)
    P = _probe_rows(params, names)
    whole, fraction = _dead_times(axes, T)
    pieces = _pieces(A, B, T, fraction)
    entries: list[list[Any]] = []  # [row, column, A, B, C, D, state, delay queue]
    for i, j, ctrl in spec:
        Ac, Bc, Cc, Dc = _ss(ctrl)
        entries.append([i, j, Ac, Bc, Cc, Dc, np.zeros(Ac.shape[0]), deque([0.0] * ctrl.delay)])
    dead = [deque([0.0] * w) for w in whole]
    poles = [None if a.force_coupling_tau is None else np.exp(-T / a.force_coupling_tau) for a in axes]
    qf = np.zeros(4)
    previous = np.zeros(4)
    x = np.zeros(len(names))
    recorded, measured = np.empty_like(force), np.empty_like(force)
    for k in range(force.shape[0]):
        e = P @ x
        u = np.zeros(4)
        for entry in entries:
            i, j, Ac, Bc, Cc, Dc, state, queue = entry
            queue.append(Cc @ state + Dc * e[j])
            entry[6] = Ac @ state + Bc * e[j]
            u[i] += queue.popleft()
        applied = np.empty(4)
        for a in range(4):
            dead[a].append(u[a])
            applied[a] = dead[a].popleft()
        measured[k] = e
        for a in range(4):
            pole = poles[a]
            if pole is None:
                recorded[k, a] = force[k, a]
            else:
                recorded[k, a] = force[k, a] - qf[a]
                qf[a] = pole * qf[a] + (1 - pole) * force[k, a]
        for t0, Phi, Gamma in pieces:
            held = np.array([applied[a] if t0 >= fraction[a] else previous[a] for a in range(4)])
            x = Phi @ x + Gamma @ np.concatenate([force[k], held])
        previous = applied
    return recorded, measured


def closed_loop(
    params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]], transducer: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The discrete closed loop ``X[k+1] = Ad X + Bd f[k]``, ``(e[k], r[k]) = Cd X + Dd f[k]``.

    Outputs: the 4 probe readings (m), then (``transducer=True``) the 4 recorded forces (N). State:
    plant, each entry's controller states and delay registers, each axis' dead-time registers and (for
    a fractional dead time) its previous command, then (``transducer=True``) the 4 transducer states.
    Returns (Ad, Bd, Cd, Dd, fs).
    """
    fs, spec = _entries(controller)
    T = 1.0 / fs
    A, B, names = continuous_plant(params, axes)
    n_p = len(names)
    whole, fraction = _dead_times(axes, T)
    # Compose the pieces: x[k+1] = Phi x + Gf f + G1 applied[k] + G0 applied[k-1].
    Phi, Gf = np.eye(n_p), np.zeros((n_p, 4))
    G1, G0 = np.zeros((n_p, 4)), np.zeros((n_p, 4))
    for t0, Ph, Ga in _pieces(A, B, T, fraction):
        Phi, Gf, G1, G0 = Ph @ Phi, Ph @ Gf + Ga[:, :4], Ph @ G1, Ph @ G0
        for a in range(4):
            (G1 if t0 >= fraction[a] else G0)[:, a] += Ga[:, 4 + a]
    # Index the loop's state.
    size = n_p
    layout = []
    for i, j, ctrl in spec:
        Ac, Bc, Cc, Dc = _ss(ctrl)
        layout.append((i, j, Ac, Bc, Cc, Dc, size, ctrl.delay))
        size += Ac.shape[0] + ctrl.delay
    dead_at = []
    for a in range(4):
        dead_at.append(size)
        size += whole[a]
    prev_at: list[int | None] = []
    for a in range(4):
        prev_at.append(size if fraction[a] > 0 else None)
        size += fraction[a] > 0
    trans_at = size
    if transducer:
        size += 4
    Ad, Bd = np.zeros((size, size)), np.zeros((size, 4))
    probe = np.zeros((4, size))
    probe[:, :n_p] = _probe_rows(params, names)
    u = np.zeros((4, size))  # u_i[k] as rows over X (no feedthrough from f)
    for i, j, Ac, Bc, Cc, Dc, at, delay in layout:
        m = Ac.shape[0]
        out = Dc * probe[j]
        out[at : at + m] += Cc
        Ad[at : at + m] += np.outer(Bc, probe[j])
        Ad[at : at + m, at : at + m] += Ac
        regs = at + m
        if delay == 0:
            u[i] += out
        else:
            Ad[regs] = out
            for r in range(1, delay):
                Ad[regs + r, regs + r - 1] = 1.0
            u[i, regs + delay - 1] += 1.0
    applied = np.zeros((4, size))
    for a in range(4):
        if whole[a] == 0:
            applied[a] = u[a]
        else:
            Ad[dead_at[a]] = u[a]
            for r in range(1, whole[a]):
                Ad[dead_at[a] + r, dead_at[a] + r - 1] = 1.0
            applied[a, dead_at[a] + whole[a] - 1] = 1.0
    Ad[:n_p, :n_p] += Phi
    Bd[:n_p] = Gf
    Ad[:n_p] += G1 @ applied
    for a in range(4):
        p = prev_at[a]
        if p is not None:
            Ad[p] = applied[a]
            Ad[:n_p, p] += G0[:, a]
    outputs = [probe]
    Dd = np.zeros((4, 4))
    if transducer:
        rec = np.zeros((4, size))
        Drec = np.eye(4)
        for a, axis in enumerate(axes):
            if axis.force_coupling_tau is not None:
                pole = np.exp(-T / axis.force_coupling_tau)
                Ad[trans_at + a, trans_at + a] = pole
                Bd[trans_at + a, a] = 1 - pole
                rec[a, trans_at + a] = -1.0
        outputs.append(rec)
        Dd = np.vstack([Dd, Drec])
    return Ad, Bd, np.vstack(outputs), Dd, fs


def receptance(
    params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]], freq_hz: ArrayLike
) -> np.ndarray:
    """Exact sampled-data ``Y F^-1`` (lines, 4, 4), m/N, at ``z = exp(j 2 pi f / fs)``.

    Y: the bearing-plane displacements from the 4 probe readings by the rigid-body map; F: the 4 recorded
    forces (transducers included). Rows and columns in the order A.x, A.y, B.x, B.y.
    """
    Ad, Bd, Cd, Dd, fs = closed_loop(params, axes, controller)
    R = rigid_body_map(params)
    z = np.exp(2j * np.pi * np.atleast_1d(np.asarray(freq_hz, dtype=float)) / fs)
    eye = np.eye(Ad.shape[0])
    out = np.empty((z.size, 4, 4), dtype=complex)
    for k, zk in enumerate(z):
        Gz = Cd @ np.linalg.solve(zk * eye - Ad, Bd) + Dd
        out[k] = R @ Gz[:4] @ np.linalg.inv(Gz[4:])
    return out


def loop_eigenvalues(params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]]) -> np.ndarray:
    """Eigenvalues z of the discrete closed-loop matrix (transducers excluded: outside the loop).

    Includes the exact zeros of the delay registers; ``s = fs log z`` for a Campbell diagram.
    """
    Ad = closed_loop(params, axes, controller, transducer=False)[0]
    return np.linalg.eigvals(Ad)


def experiment(
    params: RotorParams,
    axes: Sequence[af.Rig],
    controller: Sequence[Sequence[Any]],
    period_force: np.ndarray,
    periods: int,
    settle: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Four experiments from rest with Hadamard signs on the shakers (experiment e applies
    ``HADAMARD[e, j] * s[k]`` at axis j), ``settle`` periods dropped, ``periods`` averaged, FFT, and
    ``H = F Y^-1`` per line with Y at the bearing planes from the probes by the rigid-body map.

    Returns (freq Hz of DFT bins 1..L//2-1, H (bins, 4, 4) N/m).
    """
    s = np.asarray(period_force, dtype=float)
    L = s.size
    fs, _ = _entries(controller)
    R = rigid_body_map(params)
    bins = np.arange(1, L // 2)
    F = np.empty((bins.size, 4, 4), dtype=complex)
    Y = np.empty_like(F)
    for e in range(4):
        drive = np.tile(np.outer(s, HADAMARD[e]), (settle + periods, 1))
        recorded, measured = simulate(params, axes, controller, drive)
        start = settle * L
        Fe = np.fft.fft(recorded[start:].reshape(periods, L, 4).mean(axis=0), axis=0)[bins]
        Pe = np.fft.fft(measured[start:].reshape(periods, L, 4).mean(axis=0), axis=0)[bins]
        F[:, :, e] = Fe
        Y[:, :, e] = Pe @ R.T
    return bins * fs / L, F @ np.linalg.inv(Y)


def bearing_matrices(params: RotorParams) -> tuple[np.ndarray, np.ndarray]:
    """The rotor's mass ``Mb`` (kg) and gyroscopic ``Gb`` (kg, per rad/s of speed) matrices (4, 4) in
    bearing-plane coordinates ``yb = Bm q`` (axes A.x, A.y, B.x, B.y): with forces Fb at the bearing
    planes, ``Mb yb'' + W Gb yb' = Fb`` where ``Mb = Bm^-T M Bm^-1``, ``Gb = Bm^-T G Bm^-1``. Mass loading
    not included (the known rotor only, as paper eq. 9)."""
    Bm_inv = np.linalg.inv(_planes(params, "bearings"))
    M, G = rotor_matrices(params)
    return Bm_inv.T @ M @ Bm_inv, Bm_inv.T @ G @ Bm_inv


def actual_coefficients(params: RotorParams, freq_hz: ArrayLike, H: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``K + j w C = H + w^2 Mb - j w W Gb`` per line: K (lines, 4, 4) N/m and C (lines, 4, 4) N s/m
    from ``H = F Y^-1`` (lines, 4, 4) N/m in bearing-plane coordinates at ``freq_hz`` (Hz)."""
    Mb, Gb = bearing_matrices(params)
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)[:, None, None]
    KC = H + w**2 * Mb - 1j * w * params.speed * Gb
    return KC.real, KC.imag / w


def loop_modes(
    params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues z of the closed loop (as :func:`loop_eigenvalues`), their mode shapes at the bearing
    planes (n, 4) complex (A.x, A.y, B.x, B.y, from the eigenvector's rotor coordinates), and the whirl
    direction of each: +1 forward (same sense as the spin, x towards y), -1 backward, 0 for a real or
    zero eigenvalue (no whirl; ``|sin arg z| <= 1e-8`` counts as real).

    For the mode ``v z^k`` with ``arg z > 0`` the displacement at a bearing, ``X + j Y`` as a point in the
    plane, is ``(X + jY)/2 z^k + (X - jY)*/2 z*^k``: forward when ``|X + jY| > |X - jY|`` summed (squared)
    over both bearings; for ``arg z < 0`` (the conjugate mode) the other way round.
    """
    Ad = closed_loop(params, axes, controller, transducer=False)[0]
    z, vectors = np.linalg.eig(Ad)
    shapes, direction = whirl_direction(params, vectors[:4], np.angle(z), np.abs(z) > 1e-9)
    return z, shapes, direction


def whirl_direction(
    params: RotorParams, q: np.ndarray, angle: np.ndarray, whirling: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Bearing-plane shapes (n, 4) and whirl directions (n,) (+1 forward, -1 backward, 0 none) of modes
    with rotor coordinates ``q`` (4, n) (columns: eigenvectors' x, y, tx, ty) and ``angle`` (n,): the
    eigenvalue's angle (``arg z`` for a discrete mode, ``Im s`` for a continuous one; only its sign and
    whether it is within 1e-8 rad of 0 or pi, reported as no whirl). ``whirling``: (n,) bool, False
    forces 0 (e.g. a zero eigenvalue)."""
    shapes = (_planes(params, "bearings") @ q).T
    X, Y = shapes[:, [0, 2]], shapes[:, [1, 3]]
    spin = (np.abs(X + 1j * Y) ** 2 - np.abs(X - 1j * Y) ** 2).sum(axis=1)
    angle = np.asarray(angle, dtype=float)
    moving = np.abs(np.sin(angle)) > 1e-8  # within 1e-8 rad of 0 or pi: a real eigenvalue to rounding
    if whirling is not None:
        moving &= whirling
    return shapes, np.where(moving, np.sign(spin * np.sign(angle)), 0).astype(int)


def amb_exciter(
    params: RotorParams, axes: Sequence[af.Rig], controller: Sequence[Sequence[Any]], freq_hz: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bearings as exciters, exact and noise-free: a current ``w`` added to each axis' command after the
    controller (before its dead time), no shaker; the force estimated as ``F = -kyy d - kiy i`` from the
    bearing-plane displacements ``d`` (the probes by the rigid-body map) and the coil currents ``i`` at the
    sample instants (the amplifier's state, or with no amplifier lag the command after the dead time's whole
    samples); ``H = F Y^-1``.

    Built from this module's own sampled plant (the sample integrated in pieces, as :func:`closed_loop`) and
    the controller's entries: ``u = K e + w``, so ``u = (I - K Pe)^-1 w``. Returns (H (lines, 4, 4) N/m,
    the bearing-plane displacements per injected current (lines, 4, 4) m/A, the currents per injected
    current (lines, 4, 4)).
    """
    fs, spec = _entries(controller)
    T = 1.0 / fs
    A, B, names = continuous_plant(params, axes)
    n_p = len(names)
    whole, fraction = _dead_times(axes, T)
    Phi, G1, G0 = np.eye(n_p), np.zeros((n_p, 4)), np.zeros((n_p, 4))  # x' = Phi x + G1 a[k] + G0 a[k-1]
    for t0, Ph, Ga in _pieces(A, B, T, fraction):
        Phi, G1, G0 = Ph @ Phi, Ph @ G1, Ph @ G0
        for a in range(4):
            (G1 if t0 >= fraction[a] else G0)[:, a] += Ga[:, 4 + a]
    probe = _probe_rows(params, names)
    R = rigid_body_map(params)
    kyy = np.array([a.kyy for a in axes])
    kiy = np.array([a.kiy for a in axes])
    z = np.exp(2j * np.pi * np.atleast_1d(np.asarray(freq_hz, dtype=float)) / fs)
    H, Yw, Iw = (np.empty((z.size, 4, 4), dtype=complex) for _ in range(3))
    for k, zk in enumerate(z):
        applied = np.diag(zk ** -np.array(whole, dtype=float))  # a = z^-whole u
        X = np.linalg.solve(zk * np.eye(n_p) - Phi, (G1 + G0 / zk) @ applied)  # plant state per command
        Pe = probe @ X
        Pi = np.array([X[names.index(f"{name}.i")] if f"{name}.i" in names else applied[j]
                       for j, name in enumerate(AXES)])  # fmt: skip
        K = np.zeros((4, 4), dtype=complex)
        for i, j, ctrl in spec:
            Ac, Bc, Cc, Dc = _ss(ctrl)
            entry = Dc + (Cc @ np.linalg.solve(zk * np.eye(Ac.shape[0]) - Ac, Bc) if Ac.size else 0.0)
            K[i, j] += entry * zk**-ctrl.delay
        U = np.linalg.inv(np.eye(4) - K @ Pe)
        Yw[k], Iw[k] = R @ Pe @ U, Pi @ U
        H[k] = (-kyy[:, None] * Yw[k] - kiy[:, None] * Iw[k]) @ np.linalg.inv(Yw[k])
    return H, Yw, Iw


def bearing_process(params: RotorParams, freq_hz: ArrayLike) -> np.ndarray:
    """The process's ``K + j w C`` (lines, 4, 4) N/m at the bearing planes (A.x, A.y, B.x, B.y): its
    stiffness and damping over q, ``Bm^-T (K + j w C) Bm^-1``."""
    Bm_inv = np.linalg.inv(_planes(params, "bearings"))
    w = 2 * np.pi * np.atleast_1d(np.asarray(freq_hz, dtype=float))
    out = np.zeros((w.size, 4, 4), dtype=complex)
    for z, kxy, kyx, cxy, cyx in params.process:
        bx, by = row(z, "x"), row(z, "y")
        for wk, o in zip(w, out):
            o += (
                Bm_inv.T
                @ ((kxy + 1j * wk * cxy) * np.outer(bx, by) + (kyx + 1j * wk * cyx) * np.outer(by, bx))
                @ Bm_inv
            )
    return out
