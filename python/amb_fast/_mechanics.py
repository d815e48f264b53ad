"""What moves, in its own coordinates, and where each controlled axis acts and reads.

A structure gives ``M q'' + (C + speed G) q' + K q = A^T f`` (``q``: its coordinates; ``f``: one force
per controlled axis, acting at that axis' bearing plane in its direction), the map ``A`` from ``q`` to
the displacement at each axis' bearing plane, the map ``S`` from ``q`` to what each probe reads, and the
``readout`` that turns the probes' readings into the displacements an estimate reports. A flexible
structure (more coordinates than axes) adds its own ``elastic`` stiffness; its rigid-body motions (the null
space of ``elastic``) say what the probes read of the bearing planes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

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
    elastic : ndarray or None
        (n, n) the structure's own stiffness (a flexible shaft's bending), part of the structure and not a
        process: the known dynamics an estimate removes include it. Its null space (N-dimensional) is the
        structure's rigid-body motions. None: a rigid structure with as many coordinates as axes.
    elastic_damping : ndarray or None
        (n, n) the structure's own damping (a flexible shaft's material damping), N s/m, part of the
        structure as ``elastic`` is. None: none.
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
    elastic: np.ndarray | None = None
    elastic_damping: np.ndarray | None = None

    @property
    def coordinates(self) -> int:
        """n."""
        return int(self.mass.shape[0])

    @property
    def axes(self) -> int:
        """N."""
        return int(self.actuators.shape[0])

    def rigid(self) -> np.ndarray:
        """(n, N) the rigid-body motions: the null space of ``elastic`` (the identity for a rigid structure)."""
        if self.elastic is None:
            return np.eye(self.coordinates)
        return scipy.linalg.null_space(self.elastic, rcond=1e-12)

    @property
    def reads(self) -> np.ndarray:
        """(N, N) what the probes read of the bearing planes' displacements under rigid-body motion
        (``S R (A R)^-1``, ``R`` the rigid-body motions; ``S A^-1`` for a rigid structure)."""
        R = self.rigid()
        return self.probes @ R @ np.linalg.inv(self.actuators @ R)

    @property
    def frame(self) -> np.ndarray:
        """(N, N) ``E``: the estimate's displacements are ``E`` times the displacements at the bearing
        planes (``readout`` times :attr:`reads`; the identity when the probes sit at the bearings and are read
        as they are)."""
        return self.readout @ self.reads

    def at_bearings(self, matrix: np.ndarray) -> np.ndarray:
        """A matrix over ``q`` (mass, gyroscopic, a process) in bearing-plane coordinates, ``A^-T X A^-1``
        (a flexible structure: its rigid-body part, ``(A R)^-T R^T X R (A R)^-1``)."""
        R = self.rigid()
        inverse = R @ np.linalg.inv(self.actuators @ R)
        return inverse.T @ matrix @ inverse

    def dynamic_stiffness(self, freq: np.ndarray) -> np.ndarray:
        """The structure's own dynamic stiffness at the bearing planes (no process, no mass loading),
        ``(A D^-1 A^T)^-1`` with ``D = elastic - w^2 M + j w (elastic_damping + W G)``, shape
        (len(freq), N, N) (``A^-T D A^-1`` for a rigid structure)."""
        w = (2 * np.pi * np.asarray(freq, dtype=float))[:, None, None]
        D = -(w**2) * self.mass + 1j * w * self.speed * self.gyroscopic
        if self.elastic is None:
            inverse = np.linalg.inv(self.actuators)
            return inverse.T @ D @ inverse
        if self.elastic_damping is not None:
            D = D + 1j * w * self.elastic_damping
        receptance = self.actuators @ np.linalg.solve(D + self.elastic, self.actuators.T)
        return np.linalg.inv(receptance)
