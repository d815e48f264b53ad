"""The linearised loop of N axes in closed form: one assembly for every structure.

The continuous plant joins the structure (:class:`Mechanics`) with each axis' chain of the one-axis rig
(amplifier and eddy-current lags, the probe's lag, mass loading at the bearing plane); it is discretised
exactly (matrix exponential of the augmented ``[[A, B], [0, 0]] T``), with each axis' dead time as on one
axis (whole samples into that axis' command line, the fraction by the modified z-transform of the hold).
States, in order: per coordinate ``k`` its position ``<q>`` and velocity ``<q>'``, then the chain of axis ``k``
(``i``, ``i_f``, ``ys`` as present); then each axis' command line (``dead1`` ..). For one axis that is
the one-axis plant's order; for two axes the two-axis rig's.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike

from .._equality import ArrayRecord
from .._linear import (
    StabilityMargin,
    checked_poles,
    controller_response,
    dead_time_columns,
    eigenvalues,
    iso_zone,
    loop_matrix,
    split_dead_time,
    state_response,
    transducer_response,
    zoh,
)
from .._mechanics import Mechanics
from .._params import Rig
from .._validate import require
from ._control import ControllerMatrix, ControllerSpec, controller_matrix, controller_state_space


class System(Protocol):
    """What the N-axis functions take: a structure (``mechanics()``) and one :class:`Rig` chain per axis;
    hashable (a frozen dataclass), as the models are cached per distinct system."""

    def __hash__(self) -> int: ...

    @property
    def axes(self) -> tuple[Rig, ...]: ...

    def mechanics(self) -> Mechanics: ...


@dataclass(frozen=True)
class Layout:
    """Where the plant's states are: per coordinate its position and velocity; per axis its coil current
    (``i``), force-producing current (``i_f``) and probe output (``ys``), or -1 where the stage is ideal."""

    position: tuple[int, ...]
    velocity: tuple[int, ...]
    coil: tuple[int, ...]
    eddy: tuple[int, ...]
    sensor: tuple[int, ...]
    names: tuple[str, ...]


def _layout(mechanics: Mechanics, axes: tuple[Rig, ...]) -> Layout:
    names: list[str] = []
    position, velocity = [], []
    coil, eddy, sensor = [-1] * len(axes), [-1] * len(axes), [-1] * len(axes)
    for k, coordinate in enumerate(mechanics.coordinate_names):
        position.append(len(names))
        names.append(coordinate)
        velocity.append(len(names))
        names.append(f"{coordinate}'")
        if k < len(axes):
            axis, label = axes[k], mechanics.names[k]
            for stages, stage, bandwidth in ((coil, "i", axis.amp_bandwidth), (eddy, "i_f", axis.eddy_bandwidth),
                                             (sensor, "ys", axis.sensor_bandwidth)):  # fmt: skip
                if bandwidth is not None:
                    stages[k] = len(names)
                    names.append(f"{label}.{stage}")
    return Layout(tuple(position), tuple(velocity), tuple(coil), tuple(eddy), tuple(sensor), tuple(names))


@functools.lru_cache(maxsize=64)
def plant(system: System) -> tuple[np.ndarray, np.ndarray, Layout]:
    """Continuous ``A``, ``B`` of the plant; inputs: the N shaker forces (N), then the N current commands
    (A). Read-only, made once per distinct system."""
    mech, axes = system.mechanics(), tuple(system.axes)
    N = mech.axes
    require(len(axes) == N, "axes", len(axes), f"{N} (one chain per controlled axis)")
    require(mech.coordinates >= N, "structure", f"{mech.coordinates} coordinates", f">= {N} (its axes)")
    lay = _layout(mech, axes)
    n = len(lay.names)
    A, B = np.zeros((n, n)), np.zeros((n, 2 * N))
    act = mech.actuators
    mass = mech.mass + act.T @ np.diag([a.mass_loading for a in axes]) @ act
    stiffness = mech.stiffness + act.T @ np.diag([a.kyy for a in axes]) @ act
    damping = mech.damping + mech.speed * mech.gyroscopic
    inverse = np.linalg.inv(mass)
    pos, vel = list(lay.position), list(lay.velocity)
    A[pos, vel] = 1.0
    A[np.ix_(vel, pos)] = -inverse @ stiffness
    A[np.ix_(vel, vel)] = -inverse @ damping
    forcing = inverse @ act.T  # (n, N): a unit force at each axis' bearing plane
    B[vel, :N] = forcing
    for j, axis in enumerate(axes):
        # The magnet's force -kiy i_f, from the eddy stage, the coil or the command itself.
        source = lay.eddy[j] if lay.eddy[j] >= 0 else lay.coil[j]
        if source >= 0:
            A[vel, source] += -axis.kiy * forcing[:, j]
        else:
            B[vel, N + j] += -axis.kiy * forcing[:, j]
        # Each first-order stage relaxes to its input at w = 2 pi * bandwidth.
        if lay.coil[j] >= 0:
            w = 2 * np.pi * float(axis.amp_bandwidth or 0.0)
            A[lay.coil[j], lay.coil[j]] = -w
            B[lay.coil[j], N + j] = w
        if lay.eddy[j] >= 0:
            w = 2 * np.pi * float(axis.eddy_bandwidth or 0.0)
            A[lay.eddy[j], lay.eddy[j]] = -w
            if lay.coil[j] >= 0:
                A[lay.eddy[j], lay.coil[j]] = w
            else:
                B[lay.eddy[j], N + j] = w
        if lay.sensor[j] >= 0:
            w = 2 * np.pi * float(axis.sensor_bandwidth or 0.0)
            A[lay.sensor[j], lay.sensor[j]] = -w
            A[lay.sensor[j], pos] += w * mech.probes[j]
    A.flags.writeable = B.flags.writeable = False
    return A, B, lay


def sensor_rows(system: System) -> np.ndarray:
    """(N, plant states): what the N probes read, before noise (their lag's output, or the structure)."""
    mech = system.mechanics()
    _, _, lay = plant(system)
    S = np.zeros((mech.axes, len(lay.names)))
    for j in range(mech.axes):
        if lay.sensor[j] >= 0:
            S[j, lay.sensor[j]] = 1.0
        else:
            S[j, list(lay.position)] = mech.probes[j]
    return S


@functools.lru_cache(maxsize=64)
def discrete_plant(system: System, fs: float) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs: N forces, N commands) with each axis' dead time.

    An axis with dead time ``m T + delta`` gets a command line ``<axis>.dead1 ..`` (one more when
    ``delta > 0``): ``x[k+1] = Phi x + Gf f + G0 u[k-m] + G1 u[k-m-1]`` per command column, with
    ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)``. Read-only.
    """
    A, B, lay = plant(system)
    N = B.shape[1] // 2
    T = 1.0 / fs
    Phi, Gamma = zoh(A, B, T)
    n = A.shape[0]
    splits = [split_dead_time(axis.dead_time, fs) for axis in system.axes]
    lines = [s + (f > 0) for s, f in splits]
    size = n + sum(lines)
    Phi2, Gamma2 = np.zeros((size, size)), np.zeros((size, 2 * N))
    Phi2[:n, :n] = Phi
    Gamma2[:n, :N] = Gamma[:, :N]
    names = list(lay.names)
    at = n
    labels = system.mechanics().names
    for a, (split, line) in enumerate(zip(splits, lines)):
        col = N + a
        Gamma2[:n, col], Phi2[:n, at : at + line] = dead_time_columns(A, B, Gamma, col, T, split)
        if line:
            Gamma2[at, col] = 1.0  # <axis>.dead1' = u
            Phi2[at : at + line, at : at + line] = np.eye(line, k=-1)  # <axis>.dead(j+1)' = <axis>.dead(j)
        names += [f"{labels[a]}.dead{j + 1}" for j in range(line)]
        at += line
    Phi2.flags.writeable = Gamma2.flags.writeable = False
    return Phi2, Gamma2, tuple(names)


@dataclass(frozen=True, eq=False)
class LoopModel(ArrayRecord):
    """The closed loop of N axes as one discrete state space (sample period ``1/fs``).

    ``z[k+1] = M z + Bf f + Bn n``; outputs ``o = C z + Dn n``: the N probe readings (m), then the N coil
    currents (A). ``f``: applied forces (N); ``n``: probe noise (m). ``poles``: the recorded forces'
    AC-coupling poles per axis (0: DC coupled).
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
def _loop_model(system: System, controller: ControllerMatrix) -> LoopModel:
    fs = controller.fs
    N = controller.size
    Phi, Gamma, states = discrete_plant(system, fs)
    Ac, Bc, Cc, Dc = controller_state_space(controller)
    n, m = Phi.shape[0], Ac.shape[0]
    S = np.zeros((N, n))
    S[:, : plant(system)[0].shape[0]] = sensor_rows(system)
    Gf, Gu = Gamma[:, :N], Gamma[:, N:]
    M = loop_matrix(Phi, Gu, S, Ac, Bc, Cc, Dc)
    Bf = np.vstack([Gf, np.zeros((m, N))])
    Bn = np.vstack([Gu @ Dc, Bc])
    command, command_noise = np.hstack([Dc @ S, Cc]), Dc
    C, Dn = np.zeros((2 * N, n + m)), np.zeros((2 * N, N))
    C[:N, :n] = S
    Dn[:N] = np.eye(N)
    _, _, lay = plant(system)
    for a, axis in enumerate(system.axes):
        whole = split_dead_time(axis.dead_time, fs)[0]
        if lay.coil[a] >= 0:
            C[N + a, lay.coil[a]] = 1.0
        elif whole > 0:
            C[N + a, states.index(f"{system.mechanics().names[a]}.dead{whole}")] = 1.0
        else:
            C[N + a], Dn[N + a] = command[a], command_noise[a]
    poles = np.array([0.0 if r.force_coupling_tau is None else np.exp(-1.0 / (fs * r.force_coupling_tau))
                      for r in system.axes])  # fmt: skip
    names = list(states) + [f"controller{j}" for j in range(m)]
    return LoopModel(M, Bf, Bn, C, Dn, names, fs, poles)


def loop_model(system: System, controller: ControllerSpec) -> LoopModel:
    """The closed loop of ``system`` under ``controller`` (cached per distinct value)."""
    return _loop_model(system, controller_matrix(controller, len(system.axes)))


def closed_loop(system: System, controller: ControllerSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The loop as one discrete state space ``(A, B, C, D)`` (sample period ``1/fs``): inputs the N applied
    forces (N); outputs the N probe readings (m), then the N coil currents (A). States:
    :attr:`LoopModel.states`."""
    model = loop_model(system, controller)
    N = model.Bf.shape[1]
    return model.M, model.Bf, model.C, np.zeros((2 * N, N))


def closed_loop_poles(system: System, controller: ControllerSpec) -> np.ndarray:
    """Poles of the linearised sampled-data loop in the z-plane (stable: all ``|z| < 1``), from the core's
    eigenvalue solver, as for one axis (a sweep checks its points with the same numbers)."""
    return eigenvalues(loop_model(system, controller).M[None])[0]


def require_stable(system: System, controller: ControllerSpec, what: str = "the closed loop") -> np.ndarray:
    """The closed-loop poles (read-only), or :class:`UnstableLoopError` naming the unstable ones."""
    return _require_stable(system, controller_matrix(controller, len(system.axes)), what)


@functools.lru_cache(maxsize=64)
def _require_stable(system: System, controller: ControllerMatrix, what: str) -> np.ndarray:
    return checked_poles(closed_loop_poles(system, controller), lambda: f"{what} is unstable")


def frequencies(freq: ArrayLike, fs: float) -> np.ndarray:
    """``freq`` as a 1-D array (a scalar too), checked below Nyquist (results are stacks of N x N matrices,
    one per frequency)."""
    f = np.atleast_1d(np.asarray(freq, dtype=float))
    ok = f.ndim == 1 and bool(np.all(np.isfinite(f))) and bool(np.all(f > 0)) and bool(np.all(f < fs / 2))
    require(ok, "freq", freq, f"a 1-D array of frequencies in (0, {fs / 2}) Hz")
    return f


def predict(system: System, controller: ControllerSpec, freq: ArrayLike) -> np.ndarray:
    """Exact N x N receptance Y/F (m/N) of the linearised loop, shape (len(freq), N, N).

    Y: the displacements the estimate reports (the probes' readings, lagged, through the structure's
    ``readout``: at the bearing planes for a rotor); F: the recorded forces at the bearing planes
    (through each axis' AC-coupled transducer). ``R[:, i, j] = dY_i / dF_j``.
    """
    model = loop_model(system, controller)
    N = model.Bf.shape[1]
    f = frequencies(freq, model.fs)
    z = np.exp(2j * np.pi * f / model.fs)
    P = system.mechanics().readout @ state_response(model.M, model.Bf, model.C[:N], z, frequency_first=True)
    T = np.stack([transducer_response(axis, model.fs, z) for axis in system.axes], axis=-1)  # (freq, N)
    return P / T[:, None, :]


def controller_frequency_response(controller: ControllerSpec, n: int, z: np.ndarray) -> np.ndarray:
    """The controller matrix's digital response ``K(z)`` (delays included), shape (len(z), N, N)."""
    Ac, Bc, Cc, Dc = controller_state_space(controller_matrix(controller, n))
    return Dc + (state_response(Ac, Bc, Cc, z, frequency_first=True) if Ac.size else 0.0)


def sensitivity(
    system: System, controller: ControllerSpec, freq: ArrayLike, *, at: Literal["controller", "sensors"] = "controller"
) -> np.ndarray:
    """Sensitivity of the loop, shape (len(freq), N, N): ``(I - K P)^-1`` at the controller outputs, or with
    ``at="sensors"`` ``(I - P K)^-1`` at the summing point of the sensors' signals (where ISO 14839-3 injects
    its test signal: :func:`measure_sensitivity`). One axis: both are the SISO ``1 / (1 - K P)``.

    ``P``: current commands to probe readings; ``K``: the controller matrix (delays included)."""
    require(at in ("controller", "sensors"), "at", at, "'controller' or 'sensors'")
    model = loop_model(system, controller)
    N = model.Bf.shape[1]
    f = frequencies(freq, model.fs)
    z = np.exp(2j * np.pi * f / model.fs)
    Phi, Gamma, _ = discrete_plant(system, model.fs)
    S = np.zeros((N, Phi.shape[0]))
    S[:, : plant(system)[0].shape[0]] = sensor_rows(system)
    P = state_response(Phi, Gamma[:, N:], S, z, frequency_first=True)
    K = controller_frequency_response(controller, N, z)
    return np.linalg.inv(np.eye(N) - (K @ P if at == "controller" else P @ K))


@dataclass(frozen=True)
class StabilityMarginN(StabilityMargin):
    """Peak sensitivity of N axes: MIMO (largest singular value) and per axis (ISO 14839-3).

    Attributes
    ----------
    peak, peak_db, frequency, zone, stable
        As :class:`amb_fast.StabilityMargin`, for ``max sigma_max(S)``.
    axes : tuple of StabilityMargin
        Per axis: the peak of the diagonal entry ``|S_ii|`` (that axis' loop opened, the others closed).
    """

    axes: tuple[StabilityMargin, ...] = ()


def stability_margin(system: System, controller: ControllerSpec, points: int = 20_000) -> StabilityMarginN:
    """Peaks of the sensitivity over ``points`` log-spaced frequencies from 0.01 Hz to just below Nyquist."""
    require(isinstance(points, int) and points >= 2, "points", points, "a whole number >= 2")
    N = len(system.axes)
    fs = controller_matrix(controller, N).fs
    if not np.all(np.abs(closed_loop_poles(system, controller)) < 1.0):
        unstable = StabilityMargin(np.inf, np.inf, np.nan, "D", False)
        return StabilityMarginN(np.inf, np.inf, np.nan, "D", False, (unstable,) * N)
    f = np.geomspace(0.01, fs / 2 * (1 - 1e-9), points)
    S = sensitivity(system, controller, f)

    def margin(values: np.ndarray) -> StabilityMargin:
        j = int(np.argmax(values))
        peak = float(values[j])
        return StabilityMargin(peak, float(20 * np.log10(peak)), float(f[j]), iso_zone(peak), True)

    top = margin(np.linalg.svd(S, compute_uv=False)[:, 0])
    axes = tuple(margin(np.abs(S[:, j, j])) for j in range(N))
    return StabilityMarginN(top.peak, top.peak_db, top.frequency, top.zone, True, axes)


def effective_coefficients(
    system: System, controller: ControllerSpec, freq: ArrayLike, *, discrete: bool = False, process: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Effective N x N stiffness (N/m) and damping (N s/m) matrices at ``freq`` (Hz), shape (len(freq), N, N),
    in the estimate's frame (the bearing planes for a rotor).

    Paper eq. 5 per axis and cross term: at the bearing planes the magnets' force is
    ``-(diag(Kyy) + diag(Kiy) G S A^-1) d`` (``G``: the controller matrix, each entry's theoretical G(jw),
    or with ``discrete=True`` its digital G(z) with the delay; ``S A^-1``: what the probes read of the
    bearing planes' displacements ``d``); ``process=True`` adds the structure's process at the bearing
    planes, which the actual coefficients contain too. Reported in the estimate's frame ``Y = E d``
    (:attr:`Mechanics.frame`) as ``K E^-1``, as an estimate ``F Y^-1`` reports them.
    """
    mech = system.mechanics()
    N = mech.axes
    spec = controller_matrix(controller, N)
    f = np.atleast_1d(np.asarray(freq, dtype=float))
    require(f.ndim == 1 and bool(np.all(np.isfinite(f) & (f > 0))), "freq", freq, "finite and > 0 (Hz)")
    G = np.zeros((f.size, N, N), dtype=complex)
    for i, j, c in spec:
        G[:, i, j] = controller_response(c, f, discrete=discrete)
    reads = mech.probes @ np.linalg.inv(mech.actuators)
    kyy = np.array([a.kyy for a in system.axes])
    kiy = np.array([a.kiy for a in system.axes])[:, None]
    w = 2 * np.pi * f[:, None, None]
    H = np.diag(kyy) + kiy * (G @ reads)
    if process:
        H = H + mech.at_bearings(mech.stiffness) + 1j * w * mech.at_bearings(mech.damping)
    H = H @ np.linalg.inv(mech.frame)
    return H.real, H.imag / w


def known_dynamics(mechanics: Mechanics, freq: np.ndarray) -> np.ndarray:
    """``-w^2 Mb + j w W Gb`` in the estimate's frame (the structure's own dynamic stiffness at the bearing
    planes: what ``k``, ``c`` remove from ``H``; no mass loading: paper eq. 9), shape (len(freq), N, N)."""
    w = (2 * np.pi * np.asarray(freq, dtype=float))[:, None, None]
    Mb, Gb = mechanics.at_bearings(mechanics.mass), mechanics.at_bearings(mechanics.gyroscopic)
    dynamics = -(w**2) * Mb + 1j * w * mechanics.speed * Gb
    # One product over all the lines' rows (a stacked product calls BLAS once per line).
    return (dynamics.reshape(-1, Mb.shape[1]) @ np.linalg.inv(mechanics.frame)).reshape(dynamics.shape)
