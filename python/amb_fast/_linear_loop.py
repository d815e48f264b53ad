"""The linearised loop as state spaces, for one axis and for N: the controllers the functions take (a
SISO controller with its delay line, an N x N matrix of them), the plant the core assembles and
discretises exactly (``_core.nd_loop``, dead time included), and the closed loop they make. The one-axis
functions are the 1x1 view of the N-axis model (:mod:`amb_fast.system` re-exports the N-axis names).

The N-axis plant joins the structure (:class:`Mechanics`) with each axis' chain of the one-axis rig
(amplifier and eddy-current lags, the probe's lag, mass loading at the bearing plane), discretised with
each axis' dead time (whole samples into that axis' command line, the fraction by the modified z-transform
of the hold). States, in order: per coordinate ``k`` its position ``<q>`` and velocity ``<q>'``, then the
chain of axis ``k`` (``i``, ``i_f``, ``ys`` as present); then each axis' command line (``dead1`` ..); then
the controller's. For one axis that is the one-axis plant's order; for two axes the two-axis rig's.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, Union, cast

import numpy as np

from . import _core
from ._dispatch import axes_aware
from ._equality import ArrayRecord
from ._mechanics import Mechanics
from ._params import PID, Rig
from ._validate import MAX_DELAY_SAMPLES, integer, require, rig_and_controller

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
    ``mass + mass_loading``. Written from the equations, apart from the core's assembly (:func:`plant`),
    for the pure-numpy reference (:mod:`amb_fast.reference`).
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
    late = np.floor(dead_time / T)
    expected = "at most 1000 samples of the controller (1000 / fs s): each sample of dead time is a state of the loop"
    require(bool(late <= MAX_DELAY_SAMPLES), "dead_time", dead_time, expected)
    samples = int(late)
    return samples, max(0.0, dead_time - samples * T)


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
    A = np.zeros((m + d, m + d))
    A[:m, :m], A[m:, m:], A[m, :m] = Ac, np.eye(d, k=-1), Cc[0]
    B = np.vstack([Bc, Dc, np.zeros((d - 1, 1))])
    return A, B, np.eye(1, m + d, m + d - 1), np.zeros((1, 1))


#: One controller for every axis, one per axis ``(c1, ..., cN)``, or an N x N matrix ``[[c11, c12, ...],
#: ...]`` of SISO controllers (``None`` or 0 for an absent entry): ``u_i = sum_j G_ij e_j``.
ControllerSpec = Union[AnyController, "ControllerMatrix", Sequence[Any]]


@dataclass(frozen=True)
class ControllerMatrix:
    """An N x N matrix of SISO digital controllers (``None`` where there is none), at one ``fs``."""

    entries: tuple[tuple[Any, ...], ...]
    fs: float

    @property
    def size(self) -> int:
        """N."""
        return len(self.entries)

    def __iter__(self) -> Iterator[tuple[int, int, Any]]:
        for i, row in enumerate(self.entries):
            for j, c in enumerate(row):
                if c is not None:
                    yield i, j, c


def _absent(c: Any) -> bool:
    return c is None or (isinstance(c, (int, float)) and c == 0)


def controller_matrix(controller: ControllerSpec, n: int) -> ControllerMatrix:
    """Reads a controller spec (see :data:`ControllerSpec`) for ``n`` axes into a :class:`ControllerMatrix`."""
    if isinstance(controller, ControllerMatrix):
        require(controller.size == n, "controller", f"{controller.size}x{controller.size} matrix",
                f"{n}x{n} (one row and column per axis)")  # fmt: skip
        return controller
    if is_controller(controller):
        entries: list[list[Any]] = [[controller if i == j else None for j in range(n)] for i in range(n)]
    else:
        expected = f"a controller, {n} of them (one per axis), or an {n}x{n} matrix of them"
        ok = isinstance(controller, Sequence) and not isinstance(controller, str) and len(controller) == n
        require(ok, "controller", controller, expected)
        items = list(cast(Sequence[Any], controller))
        if all(_absent(c) or is_controller(c) for c in items):
            entries = [[items[i] if i == j else None for j in range(n)] for i in range(n)]
        else:
            rows = [list(row) if isinstance(row, Sequence) else [] for row in items]
            require(all(len(row) == n for row in rows), "controller", controller, expected)
            entries = rows
    entries = [[None if _absent(c) else c for c in row] for row in entries]
    present = [c for row in entries for c in row if c is not None]
    for c in present:
        require(is_controller(c), "controller entry", c, "a PID or an amb_fast.Controller (or None)")
    require(bool(present), "controller", controller, "at least one controller")
    fs = float(present[0].fs)
    require(all(float(c.fs) == fs for c in present), "controller fs", [c.fs for c in present], "equal for all entries")
    return ControllerMatrix(tuple(tuple(row) for row in entries), fs)


def block_diag(*blocks: np.ndarray) -> np.ndarray:
    """scipy.linalg.block_diag of square matrices, without its array-API overhead (~50 us a call): a
    sweep builds one loop per point."""
    sizes = [b.shape[0] for b in blocks]
    out = np.zeros((sum(sizes), sum(sizes)))
    at = 0
    for b, size in zip(blocks, sizes):
        out[at : at + size, at : at + size] = b
        at += size
    return out


def _read_only(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.flags.writeable = False


@functools.lru_cache(maxsize=64)
def controller_state_space(controller: ControllerMatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The controller matrix as one discrete state space from the N probes' e[k] (m) to the N current
    commands (A), each entry's own states and delay line stacked block-diagonally; read-only, made once
    per distinct controller (a sweep of the rig keeps it)."""
    n = controller.size
    blocks = [(i, j, controller_matrices(c)) for i, j, c in controller]
    A = block_diag(*[b[2][0] for b in blocks])
    size = A.shape[0]
    B, C, D = np.zeros((size, n)), np.zeros((n, size)), np.zeros((n, n))
    at = 0
    for i, j, (_, Bc, Cc, Dc) in blocks:
        m = Bc.shape[0]
        B[at : at + m, j] = Bc[:, 0]
        C[i, at : at + m] = Cc[0]
        D[i, j] += Dc[0, 0]
        at += m
    _read_only(A, B, C, D)
    return A, B, C, D


class System(Protocol):
    """What the N-axis functions take: a structure (``mechanics()``) and one :class:`Rig` chain per axis;
    hashable (a frozen dataclass), as the models are cached per distinct system. A :class:`Rig` is one."""

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
_STRUCTURE = ("mass", "gyroscopic", "stiffness", "damping", "actuators", "probes", "speed")
_LAYOUT = ("position", "velocity", "coil", "eddy", "sensor")


@functools.lru_cache(maxsize=256)
def _core_args(system: System) -> tuple[Mechanics, dict[str, Any]]:
    """The structure and the core's arguments for it: its matrices and each axis' chain as arrays (NaN where a
    stage is ideal, where the transducer is DC coupled); made once per system (a search over controllers)."""
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


def _names(mech: Mechanics, parts: dict[str, Any]) -> tuple[Layout, tuple[str, ...]]:
    """The plant's layout (from the core's indices) and the names of the axes' command lines."""
    return _named(mech.coordinate_names, mech.names, *(parts[key] for key in _LAYOUT), parts.get("lines", ()))


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


def sampled_sensor_rows(system: System, states: int) -> np.ndarray:
    """(N, states): :func:`sensor_rows` over the sampled plant's ``states`` (its command lines read nothing)."""
    rows = sensor_rows(system)
    return np.hstack([rows, np.zeros((len(rows), states - rows.shape[1]))])


@functools.lru_cache(maxsize=256)
def sampled_plant(system: System, fs: float) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs: N forces, N commands) with each axis' dead time.

    An axis with dead time ``m T + delta`` gets a command line ``<axis>.dead1 ..`` (one more when
    ``delta > 0``): ``x[k+1] = Phi x + Gf f + G0 u[k-m] + G1 u[k-m-1]`` per command column, with
    ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)``. Read-only, made once per
    distinct ``(system, fs)`` (a PID's affine loop takes four loops of one plant; sweeps over the rig
    make many). :func:`amb_fast.system.discrete_plant`.
    """
    mech, args = _core_args(system)
    parts = _core.nd_loop(**args, fs=float(fs))
    _read_only(parts["Phi"], parts["Gamma"])
    layout, lines = _names(mech, parts)
    return parts["Phi"], parts["Gamma"], layout.names + lines


def discrete_plant(rig: Rig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact zero-order-hold ``Phi``, ``Gamma`` over ``1/fs`` (inputs: force N, current command A), read-only.

    With a dead time ``tau = m T + delta`` the plant carries it inside as a line of commands
    ``dead1 .. dead(m)`` (and one more, ``dead(m+1)``, when ``delta > 0``): over ``[kT, kT + delta)``
    the amplifier still receives the previous command, so ``x[k+1] = Phi x + Gf f + G0 u[k-m] +
    G1 u[k-m-1]`` with ``G0 = Gamma_u(T - delta)``, ``G1 = Phi(T - delta) Gamma_u(delta)`` (the modified
    z-transform of the zero-order hold). States: ``y, v`` then ``i``, ``i_f``, ``ys`` as present.
    """
    Phi, Gamma, names = sampled_plant(rig, float(fs))
    # The one-axis names: "y", "v", "i", .., "dead1" for the N-axis "y", "y'", "y.i", .., "y.dead1".
    return Phi, Gamma, ["v" if s.endswith("'") else s.rpartition(".")[2] for s in names]


@dataclass(frozen=True, eq=False)
class LoopModel(ArrayRecord):
    """The closed loop of N axes as one discrete state space (sample period ``1/fs``).

    ``z[k+1] = M z + Bf f + Bn n``; outputs ``o = C z + Dn n``: the N probe readings (m), then the N coil
    currents (A). ``f``: applied forces (N); ``n``: probe noise (m). ``poles``: the recorded forces'
    AC-coupling poles per axis (0: DC coupled). Read-only.
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
    M, Bf, Bn, C, Dn, poles = (parts[key] for key in ("M", "Bf", "Bn", "C", "Dn", "poles"))
    _read_only(M, Bf, Bn, C, Dn, poles)  # cached: a caller writing into closed_loop's A would change it
    return LoopModel(M, Bf, Bn, C, Dn, names, controller.fs, poles)


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


@axes_aware
def closed_loop(rig: Rig, controller: AnyController) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The linear loop as one discrete state space ``(A, B, C, D)`` with sample period ``1/fs``.

    Input: force f[k] (N). Outputs: sensor displacement ys(kT) (m) and coil current (A). State: the
    plant's, then the controller's (see :func:`controller_matrices`). ``controller``: a :class:`PID`
    or any :class:`~amb_fast.Controller`. Read-only (made once per distinct rig and controller).
    """
    rig_and_controller(rig, controller, "closed_loop")
    model = loop_model(rig, controller)
    return model.M, model.Bf, model.C, np.zeros((2, 1))
