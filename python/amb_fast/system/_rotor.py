"""The rigid rotor on two radial magnetic bearings: four controlled axes ``A.x, A.y, B.x, B.y``.

Coordinates at the centre of mass ``q = (x, y, tx, ty)``; the displacement at axial position ``z`` (m,
from the centre of mass) is ``(x + z ty, y - z tx)``. ``m x'' = Qx``, ``m y'' = Qy``,
``It tx'' + Ip W ty' = Qtx``, ``It ty'' - Ip W tx' = Qty``; a force ``(Fx, Fy)`` at ``z`` gives
``Qx = Fx``, ``Qy = Fy``, ``Qtx = -z Fy``, ``Qty = z Fx`` (``docs/model.md``, "Rotors").
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._mechanics import Mechanics
from .._params import PID, Rig
from .._validate import real, require

AXES = ("A.x", "A.y", "B.x", "B.y")


def plane_map(z: float) -> np.ndarray:
    """(2, 4): ``(x, y, tx, ty)`` to the displacement ``(x + z ty, y - z tx)`` at axial position ``z``."""
    return np.array([[1.0, 0.0, 0.0, z], [0.0, 1.0, -z, 0.0]])


def _pair(name: str, value: Any, unit: str) -> tuple[float, float]:
    ok = isinstance(value, Sequence) and not isinstance(value, str) and len(value) == 2
    require(ok, name, value, f"a pair (A, B) of axial positions, {unit}")
    a, b = (real(f"{name}[{j}]", v, unit) for j, v in enumerate(value))
    require(a != b, name, value, "two different planes (one plane cannot hold the rotor's tilt)")
    return a, b


def linear_chains(axes: Sequence[Any], names: Sequence[str], structure: str) -> tuple[Rig, ...]:
    """Each axis a :class:`Rig` of the linear law without clearance or current limit, as N axes are modelled
    (``names``: the parameters; ``structure``: where the rest is not modelled yet, "on rotors")."""
    for name, axis in zip(names, axes):
        require(isinstance(axis, Rig), name, type(axis).__name__, "an amb_fast.Rig")
        require(axis.force_law == "linear", f"{name}.force_law", axis.force_law,
                f"'linear' (the non-linear law is not modelled {structure} yet)")  # fmt: skip
        require(axis.clearance is None, f"{name}.clearance", axis.clearance,
                f"None (touchdown is not modelled {structure} yet)")  # fmt: skip
        require(axis.current_limit is None, f"{name}.current_limit", axis.current_limit,
                f"None (saturation is not modelled {structure} yet)")  # fmt: skip
    return tuple(axes)


def bearing_mechanics(
    rotor: Any, at: Callable[[Any], np.ndarray], mass: np.ndarray, gyroscopic: np.ndarray,
    process: tuple[np.ndarray, np.ndarray], names: tuple[str, ...],
    elastic: np.ndarray | None = None, elastic_damping: np.ndarray | None = None,
) -> Mechanics:  # fmt: skip
    """A rotor's :class:`Mechanics` (read-only): its matrices (``process``: the stiffness, then the damping)
    and ``at(plane)``, (2, n), the displacement at each of its bearings' and probes' planes."""
    actuators = np.vstack([at(p) for p in rotor.bearings])
    probes = np.vstack([at(p) for p in rotor.sensors])
    # The probes' readings moved to the bearing planes by the rigid-body map (the first four coordinates).
    readout = actuators[:, :4] @ np.linalg.inv(probes[:, :4])
    for matrix in (mass, gyroscopic, *process, actuators, probes, readout, elastic, elastic_damping):
        if matrix is not None:
            matrix.flags.writeable = False
    return Mechanics(mass, gyroscopic, *process, actuators, probes, readout, float(rotor.speed), AXES, names,
                     elastic, elastic_damping)  # fmt: skip


@dataclass(frozen=True)
class RigidRotor:
    """A rigid rotor: mass, inertias, the planes of its bearings and probes, its spin.

    Parameters
    ----------
    mass : float
        kg.
    transverse_inertia, polar_inertia : float
        ``It``, ``Ip`` about the centre of mass, kg m^2 (``0 <= Ip <= 2 It`` for a rigid body).
    bearings, sensors : pair of float
        Axial positions of bearings A and B and of their probes, m from the centre of mass.
    speed : float
        Spin ``W``, rad/s, positive from x towards y.
    process : sequence of (z, kxy, kyx, cxy, cyx)
        Cross-coupled processes (a seal, an impeller, a fluid film) at axial position ``z`` (m): at that
        plane ``F_x = -kxy y - cxy y'``, ``F_y = -kyx x - cyx x'`` (N/m, N s/m; ROSS's convention, as
        :class:`~amb_fast.TwoAxisRig`).
    """

    mass: float
    transverse_inertia: float
    polar_inertia: float
    bearings: tuple[float, float] = (-0.2, 0.2)
    sensors: tuple[float, float] = (-0.23, 0.23)
    speed: float = 0.0
    process: tuple[tuple[float, float, float, float, float], ...] = ()

    def __post_init__(self) -> None:
        real("mass", self.mass, "kg", positive=True)
        It = real("transverse_inertia", self.transverse_inertia, "kg m^2", positive=True)
        Ip = real("polar_inertia", self.polar_inertia, "kg m^2")
        require(0 <= Ip <= 2 * It, "polar_inertia", Ip, f"within [0, 2 transverse_inertia] = [0, {2 * It}] kg m^2 "
                "(a rigid body's polar inertia is at most twice its transverse one)")  # fmt: skip
        object.__setattr__(self, "bearings", _pair("bearings", self.bearings, "m"))
        object.__setattr__(self, "sensors", _pair("sensors", self.sensors, "m"))
        real("speed", self.speed, "rad/s")
        entries = []
        for j, entry in enumerate(self.process):
            ok = isinstance(entry, Sequence) and len(entry) == 5
            require(ok, f"process[{j}]", entry, "(z m, kxy N/m, kyx N/m, cxy N s/m, cyx N s/m)")
            entries.append(tuple(real(f"process[{j}][{k}]", v, "SI") for k, v in enumerate(entry)))
        object.__setattr__(self, "process", tuple(entries))

    def mechanics(self) -> Mechanics:
        """The rotor's matrices over ``(x, y, tx, ty)`` and its four axes' geometry (A.x, A.y, B.x, B.y)."""
        return _rotor_mechanics(self)

    def plane(self, z: float, name: str = "z") -> np.ndarray:
        """(2, 4): the coordinates to the displacement ``(x, y)`` at axial position ``z`` (m from the centre of
        mass), within twice the outermost bearing or probe."""
        z = real(name, z, "m")
        span = 2 * max(abs(p) for p in self.bearings + self.sensors)
        require(abs(z) <= span, name, z, f"within the rotor's model, |z| <= {span:g} m (twice its outermost "
                "bearing or probe)")  # fmt: skip
        return plane_map(z)


@functools.lru_cache(maxsize=64)
def _rotor_mechanics(rotor: RigidRotor) -> Mechanics:
    """:meth:`RigidRotor.mechanics`, once per distinct rotor (every model of a loop asks for it); read-only."""
    m, It, Ip = rotor.mass, rotor.transverse_inertia, rotor.polar_inertia
    G = np.zeros((4, 4))
    G[2, 3], G[3, 2] = Ip, -Ip  # It tx'' + Ip W ty' ; It ty'' - Ip W tx'
    K, C = np.zeros((4, 4)), np.zeros((4, 4))
    for z, kxy, kyx, cxy, cyx in rotor.process:
        P = plane_map(z)
        K += P.T @ np.array([[0.0, kxy], [kyx, 0.0]]) @ P
        C += P.T @ np.array([[0.0, cxy], [cyx, 0.0]]) @ P
    return bearing_mechanics(rotor, plane_map, np.diag([m, m, It, It]), G, (K, C), ("x", "y", "tx", "ty"))


@runtime_checkable
class Rotor(Protocol):
    """What :class:`RotorRig` takes as its rotor (:class:`RigidRotor`, :class:`FlexibleRotor`): a frozen
    dataclass with a ``speed`` field (rad/s), hashable, giving its :class:`Mechanics` with the four axes
    ``A.x, A.y, B.x, B.y``, its ``mass`` (kg) and the map from its coordinates to the displacement at an
    axial position (``plane(z, name)``, (2, n), where unbalances act)."""

    @property
    def speed(self) -> float: ...

    @property
    def mass(self) -> float: ...

    def mechanics(self) -> Mechanics: ...

    def plane(self, z: float, name: str = "z") -> np.ndarray: ...


@dataclass(frozen=True)
class RotorRig:
    """A rotor on two radial magnetic bearings, each axis with the one-axis rig's chain.

    Parameters
    ----------
    rotor : RigidRotor or FlexibleRotor
        Any frozen-dataclass rotor with a ``speed`` field, a ``mass`` (kg), ``mechanics()`` (its four axes
        ``A.x, A.y, B.x, B.y``) and ``plane(z)`` (where an unbalance acts).
    axes : Rig or sequence of 4 Rig
        Each axis' actuator (kyy, kiy, amplifier and eddy-current lags, dead time), probe (lag, noise) and
        shaker force transducer (AC coupling, noise, mass loading at the bearing plane), in the order
        ``A.x, A.y, B.x, B.y``; one Rig for all four. A Rig's ``mass`` is not used: the rotor has the
        mass. Only the linear force law, without clearance or current limit.
    """

    rotor: Rotor
    axes: Any = field(default_factory=Rig)

    def __post_init__(self) -> None:
        require(
            isinstance(self.rotor, Rotor),
            "rotor",
            type(self.rotor).__name__,
            "a rotor (amb_fast.RigidRotor, amb_fast.FlexibleRotor)",
        )
        axes = (self.axes,) * 4 if isinstance(self.axes, Rig) else self.axes
        ok = isinstance(axes, Sequence) and len(axes) == 4
        require(ok, "axes", self.axes, "a Rig, or 4 of them (A.x, A.y, B.x, B.y)")
        object.__setattr__(self, "axes", linear_chains(axes, [f"axes[{name}]" for name in AXES], "on rotors"))

    @classmethod
    def example(cls, speed: float = 0.0) -> RotorRig:
        """A 10 kg rotor (a steel shaft 0.5 m long, 50 mm radius) on two of the paper's magnet pairs.

        Bearings at +-0.2 m, probes 30 mm outboard (+-0.23 m), every axis :meth:`Rig.paper`'s chain;
        stable under :meth:`example_controller` on every axis (rigid modes near 20 Hz, parallel, and 29 Hz,
        conical, at standstill). ``It = m (3 r^2 + L^2) / 12``, ``Ip = m r^2 / 2``.
        """
        m, r, length = 10.0, 0.05, 0.5
        rotor = RigidRotor(m, m * (3 * r**2 + length**2) / 12, m * r**2 / 2, (-0.2, 0.2), (-0.23, 0.23), speed)
        return cls(rotor, Rig.paper())

    @staticmethod
    def example_controller() -> Any:
        """A PID for :meth:`example` on every axis: ``kp = 3000 A/m``, ``ki = 5000 A/(m s)``, ``kd = 10 A s/m``
        filtered at 1 kHz, 4 kHz, no whole-sample delay (:meth:`PID.paper`'s form, stiffer and more damped
        for 5 kg a bearing: peak sensitivity 2.6, zone A, damping ratios 0.32 and 0.47 at standstill)."""
        return PID(kp=3000.0, ki=5000.0, kd=10.0, derivative_cutoff=1000.0, fs=4000.0, delay=0)

    def mechanics(self) -> Mechanics:
        """The rotor's :class:`Mechanics`."""
        return self.rotor.mechanics()

    @property
    def mass(self) -> float:
        """The rotor's mass, kg."""
        return float(self.rotor.mass)

    def at_speed(self, speed: float) -> RotorRig:
        """This rig with the rotor spinning at ``speed`` rad/s."""
        return replace(self, rotor=replace(self.rotor, speed=speed))  # type: ignore[type-var]
