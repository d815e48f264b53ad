"""The two-axis loop in closed form: the N-axis model (:mod:`amb_fast.system`) of a :class:`TwoAxisRig`.

The names and signatures of the one-axis API, with 2x2 results; the model itself (plant, exact
discretisation with each axis' dead time, controller matrix, closed loop, responses) is the N-axis one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Union

import numpy as np
from numpy.typing import ArrayLike

from .. import system as nd
from .._linear import AnyController, StabilityMargin
from .._validate import require
from ..system import ControllerMatrix, LoopModel
from ._rig import TwoAxisRig

#: One controller for both axes, one per axis ``(cx, cy)``, or a 2x2 matrix ``[[cxx, cxy], [cyx, cyy]]``
#: of SISO controllers (``None`` or 0 for an absent entry): ``u_i = sum_j G_ij e_j``.
ControllerSpec = Union[AnyController, ControllerMatrix, Sequence[Any]]

__all__ = ["ControllerMatrix", "LoopModel"]


def controller_matrix(controller: ControllerSpec) -> ControllerMatrix:
    """Reads a controller spec (see :data:`ControllerSpec`) into a 2x2 :class:`ControllerMatrix`."""
    return nd.controller_matrix(controller, 2)


def _rig(rig: Any) -> TwoAxisRig:
    require(isinstance(rig, TwoAxisRig), "rig", type(rig).__name__, "a TwoAxisRig")
    return rig


def plant_matrices2(rig: TwoAxisRig) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Continuous ``A``, ``B`` of the coupled plant; inputs ``(fx, fy, ux, uy)`` (N, N, A, A).

    States: ``x, x'``, then axis x's chain (``x.i``, ``x.i_f``, ``x.ys`` as present), then y's likewise.
    """
    A, B, layout = nd.plant(_rig(rig))
    return A, B, list(layout.names)


def discrete_plant2(rig: TwoAxisRig, fs: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Exact one-sample ``Phi``, ``Gamma`` (inputs ``fx, fy, ux, uy``) with each axis' dead time
    (:func:`amb_fast.system.discrete_plant`)."""
    Phi, Gamma, names = nd.discrete_plant(_rig(rig), float(fs))
    return Phi, Gamma, list(names)


def loop_model(rig: TwoAxisRig, controller: ControllerSpec) -> LoopModel:
    """The closed loop of ``rig`` under ``controller`` (cached per distinct value)."""
    return nd.loop_model(_rig(rig), controller)


def closed_loop(rig: TwoAxisRig, controller: ControllerSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two-axis loop as one discrete state space ``(A, B, C, D)`` (sample period ``1/fs``), as
    :func:`amb_fast.closed_loop` for one axis: inputs the applied forces ``fx, fy`` (N); outputs the probe
    readings (m) and the coil currents (A) of x and y. States: :attr:`LoopModel.states`."""
    return nd.closed_loop(_rig(rig), controller)


def closed_loop_poles(rig: TwoAxisRig, controller: ControllerSpec) -> np.ndarray:
    """Poles of the linearised two-axis sampled-data loop in the z-plane (stable: all ``|z| < 1``), from
    the core's eigenvalue solver, as for one axis (a sweep checks its points with the same numbers)."""
    return nd.closed_loop_poles(_rig(rig), controller)


def require_stable(rig: TwoAxisRig, controller: ControllerSpec) -> np.ndarray:
    """The closed-loop poles (read-only), or :class:`UnstableLoopError` naming the unstable ones."""
    return nd.require_stable(_rig(rig), controller, "the two-axis closed loop")


def predict(rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike) -> np.ndarray:
    """Exact 2x2 receptance Y/F (m/N) of the linearised two-axis loop, shape (len(freq), 2, 2).

    Y: the probe readings (rotated, lagged, as recorded); F: the recorded forces on the actuator axes
    (through each axis' AC-coupled transducer). ``R[:, i, j] = dY_i / dF_j``.
    """
    return nd.predict(_rig(rig), controller, freq)


def sensitivity(rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike) -> np.ndarray:
    """Sensitivity ``S = (I - K P)^-1`` at the controller outputs, shape (len(freq), 2, 2).

    ``P``: current commands to probe readings; ``K``: the controller matrix (delays included)."""
    return nd.sensitivity(_rig(rig), controller, freq)


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
    m = nd.stability_margin(_rig(rig), controller, points)
    return StabilityMargin2(m.peak, m.peak_db, m.frequency, m.zone, m.stable, *m.axes)


def effective_coefficients(
    rig: TwoAxisRig, controller: ControllerSpec, freq: ArrayLike, *, discrete: bool = False, process: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Effective 2x2 stiffness (N/m) and damping (N s/m) matrices at ``freq`` (Hz), shape (len(freq), 2, 2),
    in the estimate's frame (the probes' axes).

    Paper eq. 5 per axis and cross term: ``K_eff + j w C_eff = (diag(Kyy) + diag(Kiy) G R^T + P) R``,
    with ``G`` the controller matrix (each entry's theoretical G(jw), or with ``discrete=True`` its
    digital G(z) with the delay), ``R^T`` the probes' rotation and ``P = K_p + j w C_p`` the process, which
    the actual coefficients contain too (``process=True``). The final ``R`` expresses them per probe axis,
    as the estimate ``F Y^-1`` (Y: the probes' readings) does; with aligned probes it is the identity.
    """
    return nd.effective_coefficients(_rig(rig), controller, freq, discrete=discrete, process=process)
