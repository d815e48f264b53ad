"""What moves, in its own coordinates, and where each controlled axis acts and reads.

A structure gives ``M q'' + (C + speed G) q' + K q = A^T f`` (``q``: its coordinates; ``f``: one force
per controlled axis, acting at that axis' bearing plane in its direction), the map ``A`` from ``q`` to
the displacement at each axis' bearing plane, the map ``S`` from ``q`` to what each probe reads, and the
``readout`` that turns the probes' readings into the displacements an estimate reports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._equality import ArrayRecord


@dataclass(frozen=True, eq=False)
class Mechanics(ArrayRecord):
    """A structure's matrices (SI) and its axes' geometry; ``n`` coordinates, ``N`` controlled axes.

    Attributes
    ----------
    mass : ndarray
        (n, n) mass matrix, kg (and kg m^2 for rotations), without any axis' mass loading.
    gyroscopic : ndarray
        (n, n) gyroscopic matrix per rad/s of spin, kg m^2 (skew-symmetric).
    stiffness, damping : ndarray
        (n, n) process acting on the structure (a seal, a fluid film): N/m, N s/m.
    actuators : ndarray
        (N, n): the displacement at each axis' bearing plane in its direction (m per unit of ``q``). The
        axis' magnet force, its shaker's force and its mass loading act there.
    probes : ndarray
        (N, n): what each probe reads (before its lag and noise).
    readout : ndarray
        (N, N): the estimate's displacements from the probes' readings (the identity where the probes'
        readings are reported as they are).
    speed : float
        Spin, rad/s.
    names : tuple of str
        The controlled axes' names (``"x"``, ``"A.x"``, ...).
    coordinate_names : tuple of str
        The coordinates' names (``"x"``, ``"tx"``, ...).
    """

    mass: np.ndarray
    gyroscopic: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    actuators: np.ndarray
    probes: np.ndarray
    readout: np.ndarray
    speed: float
    names: tuple[str, ...]
    coordinate_names: tuple[str, ...]

    @property
    def coordinates(self) -> int:
        """n."""
        return int(self.mass.shape[0])

    @property
    def axes(self) -> int:
        """N."""
        return int(self.actuators.shape[0])

    @property
    def frame(self) -> np.ndarray:
        """(N, N) ``E``: the estimate's displacements are ``E`` times the displacements at the bearing
        planes (``readout S A^-1``; the identity when the probes sit at the bearings and are read as they
        are). Needs as many coordinates as axes."""
        return self.readout @ self.probes @ np.linalg.inv(self.actuators)

    def at_bearings(self, matrix: np.ndarray) -> np.ndarray:
        """A matrix over ``q`` (mass, gyroscopic, a process) in bearing-plane coordinates, ``A^-T X A^-1``."""
        inverse = np.linalg.inv(self.actuators)
        return inverse.T @ matrix @ inverse
