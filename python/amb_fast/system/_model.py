"""The linearised loop of N axes in closed form: one assembly for every structure.

The model (the plant, its sampled form, the closed loop under a controller matrix) is assembled by the
compiled core in :mod:`amb_fast._linear_loop`, where the one-axis analysis is its 1x1 case; its N-axis names
are importable from here. This module adds the N x N analysis: poles, receptance, sensitivity, margins and
effective coefficients.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._linear import (
    ControllerMatrix,
    ControllerSpec,
    Layout,
    LoopModel,
    StabilityMargin,
    System,
    checked_poles,
    controller_frequency_response,
    controller_matrix,
    controller_response,
    eigenvalues,
    loop_model,
    loop_models,
    peak_margin,
    plant,
    sampled_sensor_rows,
    sensor_rows,
    state_response,
    transducer_response,
)
from .._linear import sampled_plant as discrete_plant  # the N-axis name
from .._mechanics import Mechanics
from .._validate import require

# The model's N-axis names, importable from here as before.
__all__ = ["Layout", "LoopModel", "System", "discrete_plant", "loop_models", "plant", "sensor_rows"]


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
    P = state_response(Phi, Gamma[:, N:], sampled_sensor_rows(system, len(Phi)), z, frequency_first=True)
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
    top = peak_margin(f, np.linalg.svd(S, compute_uv=False)[:, 0])
    axes = tuple(peak_margin(f, np.abs(S[:, j, j])) for j in range(N))
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
