"""The linearised loop of N axes in closed form: one assembly for every structure.

The continuous plant joins the structure (:class:`Mechanics`) with each axis' chain of the one-axis rig
(amplifier and eddy-current lags, the probe's lag, mass loading at the bearing plane); it is discretised
exactly (matrix exponential of the augmented ``[[A, B], [0, 0]] T``), with each axis' dead time as on one
axis (whole samples into that axis' command line, the fraction by the modified z-transform of the hold).
The compiled core assembles all of it (``_core.nd_loop``; many points on its threads: :func:`loop_models`).
States, in order: per coordinate ``k`` its position ``<q>`` and velocity ``<q>'``, then the chain of axis ``k``
(``i``, ``i_f``, ``ys`` as present); then each axis' command line (``dead1`` ..). For one axis that is
the one-axis plant's order; for two axes the two-axis rig's.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._equality import ArrayRecord
from .._linear import (
    StabilityMargin,
    checked_poles,
    controller_response,
    eigenvalues,
    iso_zone,
    state_response,
    transducer_response,
)
from .._mechanics import Mechanics
from .._params import Rig
from .._validate import integer, require
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


_CHAIN = ("kyy", "kiy", "amp_bandwidth", "eddy_bandwidth", "sensor_bandwidth", "mass_loading", "dead_time",
          "force_coupling_tau")  # fmt: skip


def _core_args(system: System) -> tuple[Mechanics, dict[str, Any]]:
    """The structure and the core's arguments for it: its matrices and each axis' chain as arrays (NaN where a
    stage is ideal, where the transducer is DC coupled)."""
    mech, axes = system.mechanics(), tuple(system.axes)
    N = mech.axes
    require(len(axes) == N, "axes", len(axes), f"{N} (one chain per controlled axis)")
    require(mech.coordinates >= N, "structure", f"{mech.coordinates} coordinates", f">= {N} (its axes)")
    chains = np.array([[getattr(a, name) for a in axes] for name in _CHAIN], dtype=float)  # None -> NaN
    structure = {name: getattr(mech, name) for name in _STRUCTURE}
    # A flexible structure's own elastic stiffness and damping act beside its process.
    if mech.elastic is not None:
        structure["stiffness"] = mech.stiffness + mech.elastic
    if mech.elastic_damping is not None:
        structure["damping"] = mech.damping + mech.elastic_damping
    return mech, {**structure, **dict(zip(_CHAIN, chains))}


_STRUCTURE = ("mass", "gyroscopic", "stiffness", "damping", "actuators", "probes", "speed")


def _names(mech: Mechanics, parts: dict[str, Any]) -> tuple[Layout, tuple[str, ...]]:
    """The plant's layout (from the core's indices) and the names of the axes' command lines."""
    return _named(mech.coordinate_names, mech.names, *(parts[key] for key in _LAYOUT), parts.get("lines", ()))


_LAYOUT = ("position", "velocity", "coil", "eddy", "sensor")


@functools.lru_cache(maxsize=256)
def _named(
    coordinates: tuple[str, ...], axes: tuple[str, ...], *indices: tuple[int, ...]
) -> tuple[Layout, tuple[str, ...]]:
    *stages, lines = indices
    names = [""] * sum(i >= 0 for at in stages for i in at)
    for k, coordinate in enumerate(coordinates):
        names[stages[0][k]], names[stages[1][k]] = coordinate, f"{coordinate}'"
    for stage, at in zip(("i", "i_f", "ys"), stages[2:]):
        for label, i in zip(axes, at):
            if i >= 0:
                names[i] = f"{label}.{stage}"
    dead = tuple(f"{label}.dead{j + 1}" for label, line in zip(axes, lines) for j in range(line))
    position, velocity, coil, eddy, sensor = stages
    return Layout(position, velocity, coil, eddy, sensor, tuple(names)), dead


def _read_only(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.flags.writeable = False


@functools.lru_cache(maxsize=64)
def _plant(system: System) -> tuple[np.ndarray, np.ndarray, np.ndarray, Layout]:
    mech, args = _core_args(system)
    parts = _core.nd_loop(**args)
    _read_only(parts["A"], parts["B"], parts["S"])
    return parts["A"], parts["B"], parts["S"], _names(mech, parts)[0]


def plant(system: System) -> tuple[np.ndarray, np.ndarray, Layout]:
    """Continuous ``A``, ``B`` of the plant; inputs: the N shaker forces (N), then the N current commands
    (A). Read-only, made once per distinct system (by the core: :func:`amb_fast._core.nd_loop`)."""
    A, B, _, layout = _plant(system)
    return A, B, layout


def sensor_rows(system: System) -> np.ndarray:
    """(N, plant states): what the N probes read, before noise (their lag's output, or the structure)."""
    return _plant(system)[2]


@functools.lru_cache(maxsize=64)
def discrete_plant(system: System, fs: float) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs: N forces, N commands) with each axis' dead time.

    An axis with dead time ``m T + delta`` gets a command line ``<axis>.dead1 ..`` (one more when
    ``delta > 0``): ``x[k+1] = Phi x + Gf f + G0 u[k-m] + G1 u[k-m-1]`` per command column, with
    ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)``. Read-only.
    """
    mech, args = _core_args(system)
    parts = _core.nd_loop(**args, fs=float(fs))
    _read_only(parts["Phi"], parts["Gamma"])
    layout, lines = _names(mech, parts)
    return parts["Phi"], parts["Gamma"], layout.names + lines


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


def _loop_args(system: System, controller: ControllerMatrix) -> tuple[Mechanics, dict[str, Any]]:
    mech, args = _core_args(system)
    Ac, Bc, Cc, Dc = controller_state_space(controller)
    return mech, {**args, "fs": controller.fs, "Ac": Ac, "Bc": Bc, "Cc": Cc, "Dc": Dc}


def _loop_of(mech: Mechanics, controller: ControllerMatrix, parts: dict[str, Any]) -> LoopModel:
    layout, lines = _names(mech, parts)
    names = [*layout.names, *lines] + [f"controller{j}" for j in range(parts["M"].shape[0] - parts["Phi"].shape[0])]
    return LoopModel(
        parts["M"], parts["Bf"], parts["Bn"], parts["C"], parts["Dn"], names, controller.fs, parts["poles"]
    )


@functools.lru_cache(maxsize=64)
def _loop_model(system: System, controller: ControllerMatrix) -> LoopModel:
    mech, args = _loop_args(system, controller)
    return _loop_of(mech, controller, _core.nd_loop(**args))


def loop_models(points: Sequence[tuple[System, ControllerSpec]], workers: int = 1) -> list[LoopModel]:
    """The closed loops of many ``(system, controller)`` points (a sweep's), assembled in one call of the core
    on ``workers`` threads (the GIL released): each equal to :func:`loop_model`'s for that point."""
    specs = [(system, controller_matrix(c, len(system.axes))) for system, c in points]
    given = [_loop_args(system, spec) for system, spec in specs]
    parts = _core.nd_loops([args for _, args in given], integer("workers", workers, 1))
    return [_loop_of(mech, spec, p) for (mech, _), (_, spec), p in zip(given, specs, parts)]


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
    P = state_response(Phi, Gamma[:, N:], model.C[:N, : Phi.shape[0]], z, frequency_first=True)  # probe rows
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
    reads = mech.reads
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
    planes, a flexible one's with its bending: what ``k``, ``c`` remove from ``H``; no mass loading: paper
    eq. 9), shape (len(freq), N, N)."""
    dynamics = mechanics.dynamic_stiffness(freq)
    frame = mechanics.frame
    if np.array_equal(frame, np.eye(len(frame))):  # the identity: no product
        return dynamics
    # One product over all the lines' rows (a stacked product calls BLAS once per line).
    return (dynamics.reshape(-1, dynamics.shape[-1]) @ np.linalg.inv(frame)).reshape(dynamics.shape)
