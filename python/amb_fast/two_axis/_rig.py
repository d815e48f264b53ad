"""The two-axis rig: two one-axis magnet pairs on one rotor, a process coupling them, rotated probes."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .._mechanics import Mechanics
from .._params import Rig
from .._validate import real, require
from ..system import linear_chains


@dataclass(frozen=True)
class TwoAxisRig:
    """A rotor of mass m at the bearing plane, q = (x, y), held by two magnet pairs (``docs/model.md``).

    Parameters
    ----------
    x, y : Rig
        Each axis' magnet pair with its lags, measurement chain, noise and mass loading. They may differ
        in everything but ``mass`` (the rotor's, shared; ``x.mass != y.mass`` is refused). The mass
        loading of an axis acts on that axis only: the dynamics move ``diag(m + dm_x, m + dm_y)``.
    kxy, kyx : float
        Cross stiffness of a process acting on the rotor, N/m: ``F_x = -kxy y``, ``F_y = -kyx x``
        (ROSS's convention; a seal or fluid film has ``kxy = -kyx``).
    cxy, cyx : float
        Cross damping of that process, N s/m: ``F_x = -cxy dy/dt``, ``F_y = -cyx dx/dt``.
    sensor_angle : float
        Rotation of the displacement probes from the actuator axes, rad: the probes read
        ``R(angle)^T q`` (then each its own axis' sensor lag and noise).

    Only the linear force law is modelled on two axes, without clearance or current limit
    (a ``ValueError`` says so).
    """

    x: Rig = field(default_factory=Rig)
    y: Rig = field(default_factory=Rig)
    kxy: float = 0.0
    kyx: float = 0.0
    cxy: float = 0.0
    cyx: float = 0.0
    sensor_angle: float = 0.0

    def __post_init__(self) -> None:
        linear_chains(self.axes, ("x", "y"), "on two axes")
        require(self.x.mass == self.y.mass, "y.mass", self.y.mass, f"equal to x.mass ({self.x.mass} kg): one rotor")
        for name, unit in (("kxy", "N/m"), ("kyx", "N/m"), ("cxy", "N s/m"), ("cyx", "N s/m"), ("sensor_angle", "rad")):
            real(name, getattr(self, name), unit)

    @classmethod
    def paper(cls) -> TwoAxisRig:
        """Both axes :meth:`Rig.paper`, no process, aligned probes."""
        return cls(x=Rig.paper(), y=Rig.paper())

    @property
    def axes(self) -> tuple[Rig, Rig]:
        """``(x, y)``."""
        return self.x, self.y

    @property
    def mass(self) -> float:
        """The rotor's known mass m, kg (what eq. 9 subtracts: ``K = m w^2 I + Re H``)."""
        return self.x.mass

    @property
    def process_stiffness(self) -> np.ndarray:
        """``K_p = [[0, kxy], [kyx, 0]]``, N/m."""
        return np.array([[0.0, self.kxy], [self.kyx, 0.0]])

    @property
    def process_damping(self) -> np.ndarray:
        """``C_p = [[0, cxy], [cyx, 0]]``, N s/m."""
        return np.array([[0.0, self.cxy], [self.cyx, 0.0]])

    @property
    def rotation(self) -> np.ndarray:
        """``R(sensor_angle)``: probe axes in actuator coordinates (columns)."""
        c, s = np.cos(self.sensor_angle), np.sin(self.sensor_angle)
        return np.array([[c, -s], [s, c]])

    def mechanics(self) -> Mechanics:
        """The rotor at the bearing plane as a structure of two coordinates ``(x, y)``: mass ``m I``, the
        process, actuators on ``x`` and ``y``, probes reading ``R^T q`` and reported as they read."""
        return planar_mechanics(self.mass, self.kxy, self.kyx, self.cxy, self.cyx, self.sensor_angle)


@functools.lru_cache(maxsize=64)
def planar_mechanics(
    mass: float, kxy: float = 0.0, kyx: float = 0.0, cxy: float = 0.0, cyx: float = 0.0, angle: float = 0.0
) -> Mechanics:
    """A :class:`TwoAxisRig`'s structure (mass kg, the process N/m and N s/m, the probes' angle rad), once
    per distinct one (every model of its loop and every estimate asks for it); read-only."""
    c, s = np.cos(angle), np.sin(angle)
    matrices = (mass * np.eye(2), np.zeros((2, 2)), np.array([[0.0, kxy], [kyx, 0.0]]),
                np.array([[0.0, cxy], [cyx, 0.0]]), np.eye(2), np.array([[c, s], [-s, c]]), np.eye(2))  # fmt: skip
    for matrix in matrices:
        matrix.flags.writeable = False
    return Mechanics(*matrices, 0.0, ("x", "y"), ("x", "y"))
