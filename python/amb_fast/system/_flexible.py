"""A flexible rotor from ROSS: its finite-element model reduced to the rigid-body modes and its first
free-free bending modes, on two radial magnetic bearings (four controlled axes ``A.x, A.y, B.x, B.y``).

Coordinates: the rigid-body motions at the centre of mass ``(x, y, tx, ty)`` (as :class:`RigidRotor`'s,
exactly), then per bending mode kept its x-plane and y-plane modal coordinates (mass-normalised, 1 kg^0.5
m per unit). The reduction is a Ritz projection of ROSS's free-free mass, stiffness and gyroscopic
matrices onto these shapes: it keeps the rotor's mass, inertias and gyroscopics of the rigid body exactly,
each kept mode's frequency and shape exactly, and every gyroscopic coupling among the kept shapes; it
loses the modes above those kept (their static flexibility too: a stiff support converges with the modes
kept) and ROSS's elements other than the shaft and disks (bearings, seals, point masses: the magnetic
bearings are the supports here).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from .._equality import ArrayRecord
from .._mechanics import Mechanics
from .._ross import import_ross
from .._validate import integer, real, require
from ._rotor import bearing_mechanics

NODE_TOLERANCE = 1e-9  # m: an unbalance plane within this of a node's axial position is at that node


def _nodes(name: str, value: Any, nodes: Sequence[int]) -> tuple[int, int]:
    ok = isinstance(value, Sequence) and not isinstance(value, str) and len(value) == 2
    require(ok, name, value, "a pair (A, B) of rotor node numbers")
    for j, node in enumerate(value):
        ok = isinstance(node, (int, np.integer)) and not isinstance(node, bool) and int(node) in nodes
        require(ok, f"{name}[{j}]", node, f"a node of the rotor ({nodes[0]} .. {nodes[-1]})")
    a, b = int(value[0]), int(value[1])
    require(a != b, name, value, "two different nodes (one plane cannot hold the rotor's tilt)")
    return a, b


@dataclass(frozen=True, eq=False)
class FlexibleRotor(ArrayRecord):
    """A flexible rotor reduced from a finite-element model (:meth:`from_ross`), for :class:`RotorRig`.

    Attributes
    ----------
    modal_mass, modal_stiffness, modal_gyroscopic : ndarray
        (n, n) over the coordinates ``(x, y, tx, ty, <mode 1 x>, <mode 1 y>, ...)``: the rigid-body block
        ``diag(m, m, It, It)`` (kg, kg m^2), then the identity (mass-normalised modes); the free-free bending
        stiffness (zero on the rigid body, ``w_k^2`` (rad/s)^2 on mode k); the gyroscopic matrix per rad/s
        of spin (``Ip`` kg m^2 between ``tx`` and ``ty``, and the couplings of the modes).
    shapes : ndarray
        (nodes, 2, n): the displacement ``(x, y)`` at each node per unit of each coordinate, m.
    positions : tuple of float
        The nodes' axial positions, m from the centre of mass.
    bearings, sensors : pair of int
        The nodes of bearings A and B and of their probes.
    speed : float
        Spin ``W``, rad/s, positive from x towards y.
    damping_ratio : float
        Every bending mode's material damping ratio (modal damping ``2 zeta w_k``; 0: undamped, as ROSS's
        shaft elements without damping).
    """

    modal_mass: np.ndarray
    modal_stiffness: np.ndarray
    modal_gyroscopic: np.ndarray
    shapes: np.ndarray
    positions: tuple[float, ...]
    bearings: tuple[int, int]
    sensors: tuple[int, int]
    speed: float = 0.0
    damping_ratio: float = 0.0

    def __post_init__(self) -> None:
        n = self.modal_mass.shape[0] if np.ndim(self.modal_mass) == 2 else -1
        for name in ("modal_mass", "modal_stiffness", "modal_gyroscopic"):
            value = np.array(getattr(self, name), dtype=float)
            require(value.shape == (n, n) and n >= 4 and n % 2 == 0 and bool(np.all(np.isfinite(value))), name,
                    value.shape, f"a finite (n, n) matrix, n = 4 + 2 modes >= 4 (as modal_mass: {n})")  # fmt: skip
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        shapes = np.array(self.shapes, dtype=float)
        positions = tuple(real(f"positions[{j}]", z, "m") for j, z in enumerate(self.positions))
        require(shapes.shape == (len(positions), 2, n), "shapes", shapes.shape, f"({len(positions)}, 2, {n})")
        shapes.flags.writeable = False
        object.__setattr__(self, "shapes", shapes)
        object.__setattr__(self, "positions", positions)
        nodes = list(range(len(positions)))
        object.__setattr__(self, "bearings", _nodes("bearings", self.bearings, nodes))
        object.__setattr__(self, "sensors", _nodes("sensors", self.sensors, nodes))
        object.__setattr__(self, "speed", real("speed", self.speed, "rad/s"))
        zeta = real("damping_ratio", self.damping_ratio, "a ratio")
        require(0 <= zeta < 1, "damping_ratio", zeta, "in [0, 1)")
        object.__setattr__(self, "damping_ratio", zeta)

    def __hash__(self) -> int:  # type: ignore[override]  # by value, as the loop's models are cached per distinct rig
        arrays = (self.modal_mass, self.modal_stiffness, self.modal_gyroscopic, self.shapes)
        rest = (self.positions, self.bearings, self.sensors, self.speed, self.damping_ratio)
        return hash((*(a.tobytes() for a in arrays), *rest))

    @property
    def mass(self) -> float:
        """The rotor's mass, kg."""
        return float(self.modal_mass[0, 0])

    @property
    def modes(self) -> int:
        """The bending modes kept (each in the x and the y plane)."""
        return (self.modal_mass.shape[0] - 4) // 2

    @property
    def frequencies(self) -> np.ndarray:
        """The kept bending modes' free-free natural frequencies at standstill, Hz (one per mode)."""
        return np.sqrt(np.diag(self.modal_stiffness)[4::2]) / (2 * np.pi)

    @classmethod
    def from_ross(
        cls,
        rotor: Any,
        bearings: tuple[int, int],
        sensors: tuple[int, int],
        modes: int,
        speed: float = 0.0,
        damping_ratio: float = 0.0,
    ) -> FlexibleRotor:
        """The rigid-body modes and the first ``modes`` free-free bending modes of a ROSS ``Rotor``.

        Parameters
        ----------
        rotor : ross.Rotor
            Its shaft and disk elements make the free-free mass, stiffness and gyroscopic matrices
            (``M0``, ``K0``, ``G0``), of which the lateral degrees of freedom ``(x, y, alpha, beta)`` of every
            node are kept (ROSS's axial and torsional ones are uncoupled from them). Its bearings, seals and
            point masses are left out: the magnetic bearings support the rotor.
        bearings, sensors : pair of int
            The nodes of bearings A and B (where their forces act) and of their probes.
        modes : int
            Bending modes kept, each in the x and the y plane (2 coordinates each), >= 0.
        speed : float
            Spin, rad/s.
        damping_ratio : float
            Every bending mode's material damping ratio (0: undamped, ROSS's shaft without damping).

        The bending modes are ROSS's free-free eigenvectors of ``K v = w^2 M v`` per plane, made exactly
        M-orthogonal to the rigid-body motions and mass-normalised; the rigid-body motions are exact
        (translation and tilt about the centre of mass), so the rotor's mass, ``It`` and ``Ip`` are ROSS's.
        What the reduction leaves out is stated in the module's docstring (:doc:`/rotors`).
        """
        ross = import_ross("FlexibleRotor.from_ross")
        require(isinstance(rotor, ross.Rotor), "rotor", type(rotor).__name__, "a ross.Rotor")
        nodes = [int(n) for n in rotor.nodes]
        bearings, sensors = _nodes("bearings", bearings, nodes), _nodes("sensors", sensors, nodes)
        modes = integer("modes", modes, 0)
        offsets = rotor.shaft_elements[0].dof_mapping()
        width = int(rotor.number_dof)
        # The x plane (x, beta) and the y plane (y, alpha) of every node, in node order.
        plane_x = np.array([[width * n + offsets["x_0"], width * n + offsets["beta_0"]] for n in nodes]).ravel()
        plane_y = np.array([[width * n + offsets["y_0"], width * n + offsets["alpha_0"]] for n in nodes]).ravel()
        available = len(nodes) * 2 - 2
        require(modes <= available, "modes", modes, f"at most {available} (the bending modes of the rotor's "
                f"{len(nodes)} nodes per plane)")  # fmt: skip
        M0, K0, G0 = (np.asarray(m, dtype=float) for m in (rotor.M0, rotor.K0, rotor.G0))
        cross = max(np.abs(X[np.ix_(plane_x, plane_y)]).max() for X in (M0, K0))
        require(cross == 0.0, "rotor", f"x-y coupling {cross:g}", "isotropic elements (x and y planes uncoupled)")
        lateral = np.concatenate([plane_x, plane_y])
        others = np.setdiff1d(np.arange(width * len(nodes)), lateral)  # axial, torsional
        axial = max(np.abs(X[np.ix_(lateral, others)]).max(initial=0.0) for X in (M0, K0, G0))
        require(axial == 0.0, "rotor", f"lateral-axial/torsional coupling {axial:g}", "uncoupled lateral dofs")
        z = np.asarray(rotor.nodes_pos, dtype=float)
        M, K = M0[np.ix_(plane_x, plane_x)], K0[np.ix_(plane_x, plane_x)]
        # Rigid body in the x plane: x = 1; x = z - zc, beta = 1 (tilt about the centre of mass zc).
        ones, zeros = np.ones_like(z), np.zeros_like(z)
        translation = np.column_stack([ones, zeros]).ravel()
        mass = translation @ M @ translation
        zc = translation @ M @ np.column_stack([z, ones]).ravel() / mass
        R = np.column_stack([translation, np.column_stack([z - zc, ones]).ravel()])
        shapes = [_bending(M, K, R, modes)]
        My, Ky = M0[np.ix_(plane_y, plane_y)], K0[np.ix_(plane_y, plane_y)]
        Ry = np.column_stack([translation, np.column_stack([-(z - zc), ones]).ravel()])  # tx: y = -z tx, alpha
        shapes.append(_bending(My, Ky, Ry, modes))
        # The basis over (x, y, alpha, beta) of every node: (x, y, tx, ty, mode1 x, mode1 y, ...).
        T = np.zeros((lateral.size, 4 + 2 * modes))
        half = plane_x.size
        T[:half, 0], T[half:, 1], T[half:, 2], T[:half, 3] = R[:, 0], Ry[:, 0], Ry[:, 1], R[:, 1]
        T[:half, 4::2], T[half:, 5::2] = shapes
        M_r, K_r, G_r = (T.T @ X[np.ix_(lateral, lateral)] @ T for X in (M0, K0, G0))
        K_r[:4], K_r[:, :4] = 0.0, 0.0  # the rigid body strains nothing (exactly; round-off otherwise)
        at_nodes = np.stack([T[0:half:2], T[half::2]], axis=1)  # (nodes, 2, n): x and y of every node
        return cls((M_r + M_r.T) / 2, (K_r + K_r.T) / 2, (G_r - G_r.T) / 2, at_nodes, tuple(z - zc), bearings,
                   sensors, speed, damping_ratio)  # fmt: skip

    def mechanics(self) -> Mechanics:
        """The rotor's matrices over its modal coordinates and its four axes' geometry (A.x, A.y, B.x, B.y)."""
        return _flexible_mechanics(self)

    def plane(self, z: float, name: str = "z") -> np.ndarray:
        """(2, n): the coordinates to the displacement ``(x, y)`` at axial position ``z`` (m from the centre
        of mass), which must be a node's (:attr:`positions`)."""
        z = real(name, z, "m")
        at = np.abs(np.asarray(self.positions) - z)
        node = int(np.argmin(at))
        require(at[node] <= NODE_TOLERANCE, name, z, f"a node's axial position (m from the centre of mass): one "
                f"of {', '.join(f'{p:.6g}' for p in self.positions)}")  # fmt: skip
        return self.shapes[node]

    @staticmethod
    def example_ross() -> Any:
        """The ROSS rotor of :meth:`example`: a steel shaft 0.8 m long, 40 mm across, in 30 Timoshenko
        elements, with two 60 mm wide disks of 100 mm at nodes 8 and 22 (9.9 kg in all)."""
        ross = import_ross("FlexibleRotor.example")
        steel = ross.Material(name="amb_fast_steel", rho=7810.0, E=211e9, G_s=81.2e9)
        shaft = [ross.ShaftElement(0.8 / 30, idl=0.0, odl=0.04, material=steel, shear_effects=True,
                                   rotary_inertia=True, gyroscopic=True) for _ in range(30)]  # fmt: skip
        disks = [ross.DiskElement.from_geometry(n=n, material=steel, width=0.02, i_d=0.04, o_d=0.1) for n in (8, 22)]
        supports = [ross.BearingElement(n=n, kxx=1e6, kyy=1e6, cxx=0.0) for n in (4, 26)]  # left out by from_ross
        return ross.Rotor(shaft, disks, supports)

    @classmethod
    def example(cls, modes: int = 8, speed: float = 0.0) -> FlexibleRotor:
        """:meth:`example_ross` with bearings at nodes 4 and 26 (0.107 m from either end, 0.587 m apart), their
        probes one node outboard (3 and 27, 26.7 mm), ``modes`` bending modes kept, each damped at 0.5 %
        (a steel shaft's material damping; ROSS needed).

        Free-free bending modes at 282, 672, 1331, 2316 Hz (and 3.2 - 6.5 kHz: 8 modes); under
        :meth:`RotorRig.example_controller` on :meth:`Rig.paper`'s chains the loop is stable (peak
        sensitivity 2.6 at 22 Hz, as the rigid example's). Undamped it is not: the digital loop pumps the
        second bending mode (672 Hz) a little; 0.2 % of material damping is enough.
        """
        return cls.from_ross(cls.example_ross(), bearings=(4, 26), sensors=(3, 27), modes=modes, speed=speed,
                             damping_ratio=0.005)  # fmt: skip


def _bending(M: np.ndarray, K: np.ndarray, R: np.ndarray, modes: int) -> np.ndarray:
    """The first ``modes`` free-free bending modes of one plane (its 2 rigid-body motions ``R`` dropped),
    exactly M-orthogonal to ``R``, mass-normalised, each with its largest displacement positive."""
    if modes == 0:
        return np.zeros((len(M), 0))
    V = scipy.linalg.eigh(K, M, subset_by_index=[0, 1 + modes])[1][:, 2:]
    V = V - R @ np.linalg.solve(R.T @ M @ R, R.T @ M @ V)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, M @ V))
    sign = np.sign(V[0::2][np.argmax(np.abs(V[0::2]), axis=0), np.arange(V.shape[1])])
    return V * np.where(sign == 0, 1.0, sign)


@functools.lru_cache(maxsize=64)
def _flexible_mechanics(rotor: FlexibleRotor) -> Mechanics:
    """:meth:`FlexibleRotor.mechanics`, once per distinct rotor; read-only."""
    zero = np.zeros(rotor.modal_mass.shape)
    rates = 2 * rotor.damping_ratio * np.sqrt(np.diag(rotor.modal_stiffness))  # 2 zeta w_k, mass-normalised
    damping = np.diag(rates) if rotor.damping_ratio else None
    names = ("x", "y", "tx", "ty") + tuple(f"mode{k}{p}" for k in range(1, rotor.modes + 1) for p in "xy")
    mass, gyroscopic, elastic = rotor.modal_mass, rotor.modal_gyroscopic, rotor.modal_stiffness
    return bearing_mechanics(rotor, rotor.shapes.__getitem__, mass, gyroscopic, (zero, zero), names, elastic, damping)
