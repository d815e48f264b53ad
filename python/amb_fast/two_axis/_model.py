"""The linearised two-axis sampled-data loop in closed form (matrix-level numpy, no per-sample loops).

The continuous plant stacks the two axes' states (each as :func:`amb_fast._linear.plant_matrices` has
them), couples the rotor rows through the process and feeds each sensor lag the rotated displacement;
it is discretised exactly (matrix exponential of the augmented ``[[A, B], [0, 0]] T``), with each
axis' dead time as in one axis (whole samples into that axis' command line, the fraction by the
modified z-transform of the hold, per command column).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Union, cast

import numpy as np
from numpy.typing import ArrayLike

from .._equality import ArrayRecord
from .._linear import (
    AnyController,
    StabilityMargin,
    _checked_poles,
    _dead_time_columns,
    _eigenvalues,
    _response,
    _zoh,
    controller_matrices,
    controller_response,
    is_controller,
    iso_zone,
    loop_matrix,
    plant_matrices,
    split_dead_time,
    transducer_response,
)
from .._params import Rig
from .._validate import require
from ._rig import TwoAxisRig

#: One controller for both axes, one per axis ``(cx, cy)``, or a 2x2 matrix ``[[cxx, cxy], [cyx, cyy]]``
#: of SISO controllers (``None`` or 0 for an absent entry): ``u_i = sum_j G_ij e_j``.
ControllerSpec = Union[AnyController, "ControllerMatrix", Sequence[Any]]


@dataclass(frozen=True)
class ControllerMatrix:
    """A 2x2 matrix of SISO digital controllers (``None`` where there is none), at one ``fs``."""

    entries: tuple[tuple[Any, Any], tuple[Any, Any]]
    fs: float

    def __iter__(self):  # noqa: ANN204
        for i in range(2):
            for j in range(2):
                if self.entries[i][j] is not None:
                    yield i, j, self.entries[i][j]


def controller_matrix(controller: ControllerSpec) -> ControllerMatrix:
    """Reads a controller spec (see :data:`ControllerSpec`) into a :class:`ControllerMatrix`."""
    if isinstance(controller, ControllerMatrix):
        return controller
    if is_controller(controller):
        entries: list[list[Any]] = [[controller, None], [None, controller]]
    else:
        ok = isinstance(controller, Sequence) and len(controller) == 2
        require(ok, "controller", controller, "a controller, a pair (x, y) of them, or a 2x2 matrix of them")
        pair = cast(Sequence[Any], controller)
        if all(_absent(c) or is_controller(c) for c in pair):
            entries = [[pair[0], None], [None, pair[1]]]
        else:
            rows = [list(row) if isinstance(row, Sequence) else [] for row in pair]
            require(all(len(row) == 2 for row in rows), "controller", controller, "a 2x2 matrix of controllers")
            entries = rows
    entries = [[None if _absent(c) else c for c in row] for row in entries]
    present = [c for row in entries for c in row if c is not None]
    for c in present:
        require(is_controller(c), "controller entry", c, "a PID or an amb_fast.Controller (or None)")
    require(bool(present), "controller", controller, "at least one controller")
    fs = float(present[0].fs)
    require(all(float(c.fs) == fs for c in present), "controller fs", [c.fs for c in present], "equal for all entries")
    return ControllerMatrix((tuple(entries[0]), tuple(entries[1])), fs)  # type: ignore[arg-type]


def _absent(c: Any) -> bool:
    return c is None or (isinstance(c, (int, float)) and c == 0)


def _block_diag(*blocks: np.ndarray) -> np.ndarray:
    """scipy.linalg.block_diag of square matrices, without its array-API overhead (~50 us a call): a
    sweep builds one loop per point."""
    sizes = [b.shape[0] for b in blocks]
    out = np.zeros((sum(sizes), sum(sizes)))
    at = 0
    for b, size in zip(blocks, sizes):
        out[at : at + size, at : at + size] = b
        at += size
    return out


def mimo_controller(controller: ControllerSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The controller matrix as one discrete state space from e[k] (2 probes, m) to the two current
    commands (A), each entry's own states and delay line stacked block-diagonally."""
    return _mimo_controller(controller_matrix(controller))


@functools.lru_cache(maxsize=64)
def _mimo_controller(controller: ControllerMatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`mimo_controller`, once per distinct controller (a sweep of the rig keeps it); read-only."""
    blocks = [(i, j, controller_matrices(c)) for i, j, c in controller]
    A = _block_diag(*[b[2][0] for b in blocks])
    n = A.shape[0]
    B, C, D = np.zeros((n, 2)), np.zeros((2, n)), np.zeros((2, 2))
    at = 0
    for i, j, (_, Bc, Cc, Dc) in blocks:
        m = Bc.shape[0]
        B[at : at + m, j] = Bc[:, 0]
        C[i, at : at + m] = Cc[0]
        D[i, j] += Dc[0, 0]
        at += m
    for matrix in (A, B, C, D):
        matrix.flags.writeable = False
    return A, B, C, D


@functools.lru_cache(maxsize=64)
def _axis_plant(axis: Rig) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """:func:`plant_matrices` of one axis, once per distinct axis (a sweep of the coupling keeps both);
    read-only."""
    A, B, states = plant_matrices(axis)
    A.flags.writeable = B.flags.writeable = False
    return A, B, tuple(states)


def plant_matrices2(rig: TwoAxisRig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` of the coupled plant; inputs ``(fx, fy, ux, uy)`` (N, N, A, A).

    States: axis x's (``x.y, x.v, ...``), then axis y's, named ``"x.<state>"``, ``"y.<state>"``.
    """
    parts = [_axis_plant(axis) for axis in rig.axes]
    states = [f"{name}.{s}" for name, (_, _, st) in zip("xy", parts) for s in st]
    A = _block_diag(parts[0][0], parts[1][0])
    n0 = parts[0][0].shape[0]
    B = np.zeros((A.shape[0], 4))
    B[:n0, [0, 2]] = parts[0][1]
    B[n0:, [1, 3]] = parts[1][1]
    pos = [states.index("x.y"), states.index("y.y")]
    vel = [states.index("x.v"), states.index("y.v")]
    Kp, Cp = rig.process_stiffness, rig.process_damping
    for a, axis in enumerate(rig.axes):
        m = axis.moving_mass
        for b in range(2):
            A[vel[a], pos[b]] -= Kp[a, b] / m
            A[vel[a], vel[b]] -= Cp[a, b] / m
    # Each probe reads R^T q through its own axis' lag.
    Rt = rig.rotation.T
    for a, (name, axis) in enumerate(zip("xy", rig.axes)):
        if axis.sensor_bandwidth is not None:
            row = states.index(f"{name}.ys")
            w = 2 * np.pi * axis.sensor_bandwidth
            A[row, pos[a]] = 0.0
            A[row, pos] += w * Rt[a]
    return A, B, states


def sensor_rows(rig: TwoAxisRig, states: list[str]) -> np.ndarray:
    """(2, states): what the two probes read (before noise)."""
    S = np.zeros((2, len(states)))
    pos = [states.index("x.y"), states.index("y.y")]
    for a, name in enumerate("xy"):
        if f"{name}.ys" in states:
            S[a, states.index(f"{name}.ys")] = 1.0
        else:
            S[a, pos] = rig.rotation.T[a]
    return S


def discrete_plant2(rig: TwoAxisRig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs ``fx, fy, ux, uy``) with each axis' dead time.

    An axis with dead time ``m T + delta`` gets a command line ``<axis>.dead1 ..`` (one more when
    ``delta > 0``): ``x[k+1] = Phi x + Gf f + G0 u[k-m] + G1 u[k-m-1]`` per command column, with
    ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)``.
    """
    A, B, states = plant_matrices2(rig)
    T = 1.0 / fs
    Phi, Gamma = _zoh(A, B, T)
    n = len(states)
    splits = [split_dead_time(axis.dead_time, fs) for axis in rig.axes]
    lines = [s + (f > 0) for s, f in splits]
    size = n + sum(lines)
    Phi2, Gamma2 = np.zeros((size, size)), np.zeros((size, 4))
    Phi2[:n, :n] = Phi
    Gamma2[:n, :2] = Gamma[:, :2]
    names = list(states)
    at = n
    for a, (split, line) in enumerate(zip(splits, lines)):
        col = 2 + a
        Gamma2[:n, col], Phi2[:n, at : at + line] = _dead_time_columns(A, B, Gamma, col, T, split)
        if line:
            Gamma2[at, col] = 1.0  # <axis>.dead1' = u
            Phi2[at : at + line, at : at + line] = np.eye(line, k=-1)  # <axis>.dead(j+1)' = <axis>.dead(j)
        names += [f"{'xy'[a]}.dead{j + 1}" for j in range(line)]
        at += line
    return Phi2, Gamma2, names


@dataclass(frozen=True, eq=False)
class LoopModel(ArrayRecord):
    """The closed two-axis loop as one discrete state space (sample period ``1/fs``).

    ``z[k+1] = M z + Bf f + Bn n``; outputs ``o = C z + Dn n``: the two probe readings (m), then the
    two coil currents (A). ``f``: applied forces (N); ``n``: probe noise (m). ``poles``: the recorded
    forces' AC-coupling poles per axis (0: DC coupled).
    """

    M: np.ndarray
    Bf: np.ndarray
    Bn: np.ndarray
    C: np.ndarray
    Dn: np.ndarray
    states: list[str]
    fs: float
    poles: np.ndarray


@functools.lru_cache(maxsize=64)
def _loop_model(rig: TwoAxisRig, controller: ControllerMatrix) -> LoopModel:
    fs = controller.fs
    Phi, Gamma, states = discrete_plant2(rig, fs)
    Ac, Bc, Cc, Dc = mimo_controller(controller)
    n, m = Phi.shape[0], Ac.shape[0]
    S = sensor_rows(rig, states)
    Gf, Gu = Gamma[:, :2], Gamma[:, 2:]
    M = loop_matrix(Phi, Gu, S, Ac, Bc, Cc, Dc)
    Bf = np.vstack([Gf, np.zeros((m, 2))])
    Bn = np.vstack([Gu @ Dc, Bc])
    command, command_noise = np.hstack([Dc @ S, Cc]), Dc
    C, Dn = np.zeros((4, n + m)), np.zeros((4, 2))
    C[:2, :n] = S
    Dn[:2] = np.eye(2)
    for a, (name, axis) in enumerate(zip("xy", rig.axes)):
        whole = split_dead_time(axis.dead_time, fs)[0]
        if f"{name}.i" in states:
            C[2 + a, states.index(f"{name}.i")] = 1.0
        elif whole > 0:
            C[2 + a, states.index(f"{name}.dead{whole}")] = 1.0
        else:
            C[2 + a], Dn[2 + a] = command[a], command_noise[a]
    poles = np.array([0.0 if r.force_coupling_tau is None else np.exp(-1.0 / (fs * r.force_coupling_tau))
                      for r in rig.axes])  # fmt: skip
    names = states + [f"controller{j}" for j in range(m)]
    return LoopModel(M, Bf, Bn, C, Dn, names, fs, poles)


def loop_model(rig: TwoAxisRig, controller: ControllerSpec) -> LoopModel:
    """The closed loop of ``rig`` under ``controller`` (cached per distinct value)."""
    require(isinstance(rig, TwoAxisRig), "rig", type(rig).__name__, "a TwoAxisRig")
    return _loop_model(rig, controller_matrix(controller))


def closed_loop(rig: TwoAxisRig, controller: ControllerSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two-axis loop as one discrete state space ``(A, B, C, D)`` (sample period ``1/fs``), as
    :func:`amb_fast.closed_loop` for one axis: inputs the applied forces ``fx, fy`` (N); outputs the probe
    readings (m) and the coil currents (A) of x and y. States: :attr:`LoopModel.states`."""
    model = loop_model(rig, controller)
    return model.M, model.Bf, model.C, np.zeros((4, 2))


def closed_loop_poles(rig: TwoAxisRig, controller: ControllerSpec) -> np.ndarray:
    """Poles of the linearised two-axis sampled-data loop in the z-plane (stable: all ``|z| < 1``), from
    the core's eigenvalue solver, as for one axis (a sweep checks its points with the same numbers)."""
    return _eigenvalues(loop_model(rig, controller).M[None])[0]


def require_stable(rig: TwoAxisRig, controller: ControllerSpec) -> np.ndarray:
    """The closed-loop poles (read-only), or :class:`UnstableLoopError` naming the unstable ones."""
    return _require_stable(rig, controller_matrix(controller))


@functools.lru_cache(maxsize=64)
def _require_stable(rig: TwoAxisRig, controller: ControllerMatrix) -> np.ndarray:
    return _checked_poles(closed_loop_poles(rig, controller), lambda: "the two-axis closed loop is unstable")


def _frequencies(freq: ArrayLike, fs: float) -> np.ndarray:
    """``freq`` as a 1-D array (a scalar too), checked below Nyquist; unlike the one-axis check, one message
    for all faults and no 0-d or 2-D arrays (results are stacks of 2x2 matrices, one per frequency)."""
    f = np.atleast_1d(np.asarray(freq, dtype=float))
    ok = f.ndim == 1 and bool(np.all(np.isfinite(f))) and bool(np.all(f > 0)) and bool(np.all(f < fs / 2))
    require(ok, "freq", freq, f"a 1-D array of frequencies in (0, {fs / 2}) Hz")
    return f


def predict(rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike) -> np.ndarray:
    """Exact 2x2 receptance Y/F (m/N) of the linearised two-axis loop, shape (len(freq), 2, 2).

    Y: the probe readings (rotated, lagged, as recorded); F: the recorded forces on the actuator axes
    (through each axis' AC-coupled transducer). ``R[:, i, j] = dY_i / dF_j``.
    """
    model = loop_model(rig, controller)
    f = _frequencies(freq, model.fs)
    z = np.exp(2j * np.pi * f / model.fs)
    P = _response(model.M, model.Bf, model.C[:2], z, frequency_first=True)
    T = np.stack([transducer_response(axis, model.fs, z) for axis in rig.axes], axis=-1)  # (freq, 2)
    return P / T[:, None, :]


def sensitivity(rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike) -> np.ndarray:
    """Sensitivity ``S = (I - K P)^-1`` at the controller outputs, shape (len(freq), 2, 2).

    ``P``: current commands to probe readings; ``K``: the controller matrix (delays included)."""
    model = loop_model(rig, controller)
    f = _frequencies(freq, model.fs)
    z = np.exp(2j * np.pi * f / model.fs)
    Phi, Gamma, states = discrete_plant2(rig, model.fs)
    P = _response(Phi, Gamma[:, 2:], sensor_rows(rig, states), z, frequency_first=True)
    Ac, Bc, Cc, Dc = mimo_controller(controller)
    K = Dc + (_response(Ac, Bc, Cc, z, frequency_first=True) if Ac.size else 0.0)
    return np.linalg.inv(np.eye(2) - K @ P)


@dataclass(frozen=True)
class StabilityMargin2(StabilityMargin):
    """Peak sensitivity of the two-axis loop: MIMO (largest singular value) and per axis (ISO 14839-3).

    Attributes
    ----------
    peak, peak_db, frequency, zone, stable
        As :class:`amb_fast.StabilityMargin`, for ``max sigma_max(S)``.
    x, y : StabilityMargin
        Per axis: the peak of the diagonal entry ``|S_ii|`` (the loop of that axis opened with the
        other closed).
    """

    x: StabilityMargin
    y: StabilityMargin


def stability_margin(rig: TwoAxisRig, controller: ControllerSpec, points: int = 20_000) -> StabilityMargin2:
    """Peaks of the sensitivity over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    require(isinstance(points, int) and points >= 2, "points", points, "a whole number >= 2")
    fs = controller_matrix(controller).fs
    if not np.all(np.abs(closed_loop_poles(rig, controller)) < 1.0):
        unstable = StabilityMargin(np.inf, np.inf, np.nan, "D", False)
        return StabilityMargin2(np.inf, np.inf, np.nan, "D", False, unstable, unstable)
    f = np.geomspace(0.01, fs / 2 * (1 - 1e-9), points)
    S = sensitivity(rig, controller, f)

    def margin(values: np.ndarray) -> StabilityMargin:
        j = int(np.argmax(values))
        peak = float(values[j])
        return StabilityMargin(peak, float(20 * np.log10(peak)), float(f[j]), iso_zone(peak), True)

    top = margin(np.linalg.svd(S, compute_uv=False)[:, 0])
    return StabilityMargin2(top.peak, top.peak_db, top.frequency, top.zone, True,
                            margin(np.abs(S[:, 0, 0])), margin(np.abs(S[:, 1, 1])))  # fmt: skip


def effective_coefficients(
    rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike, *, discrete: bool = False, process: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Effective 2x2 stiffness (N/m) and damping (N s/m) matrices at ``freq`` (Hz), shape (len(freq), 2, 2).

    Paper eq. 5 per axis and cross term: ``K_eff = diag(Kyy) + diag(Kiy) Re(G R^T)``,
    ``C_eff = diag(Kiy) Im(G R^T) / w``, with ``G`` the controller matrix (each entry's theoretical
    G(jw), or with ``discrete=True`` its digital G(z) with the delay) and ``R^T`` the probes' rotation.
    ``process=True`` adds the process ``K_p``, ``C_p``, which the actual coefficients contain too.
    """
    spec = controller_matrix(controller)
    f = np.atleast_1d(np.asarray(freq, dtype=float))
    require(f.ndim == 1 and bool(np.all(np.isfinite(f) & (f > 0))), "freq", freq, "finite and > 0 (Hz)")
    G = np.zeros((f.size, 2, 2), dtype=complex)
    for i, j, c in spec:
        G[:, i, j] = controller_response(c, f, discrete=discrete)
    G = G @ rig.rotation.T
    kyy = np.array([a.kyy for a in rig.axes])
    kiy = np.array([a.kiy for a in rig.axes])[:, None]
    w = 2 * np.pi * f[:, None, None]
    K = np.diag(kyy) + kiy * G.real
    C = kiy * G.imag / w
    if process:
        K, C = K + rig.process_stiffness, C + rig.process_damping
    return K, C
