"""The closed-loop poles as every run and sweep computes them: the core's eigenvalues of the closed-loop
matrix (for a PID, affine in its gains, so many gain sets cost one stack), the stability check of a run,
and the settling time the poles set.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._blas import one_blas_thread
from ._dispatch import axes_aware
from ._errors import UnstableLoopError
from ._linear_loop import AnyController, closed_loop, controller_matrices, sampled_plant, sampled_sensor_rows
from ._params import PID, Rig
from ._validate import require, rig_and_controller


@axes_aware
def closed_loop_poles(rig: Rig, controller: AnyController) -> np.ndarray:
    """Poles of the linearised sampled-data loop in the z-plane (stable: all ``|z| < 1``).

    The equivalent continuous-time poles are ``log(z) * fs`` (rad/s).
    """
    rig_and_controller(rig, controller, "closed_loop_poles")
    return np.linalg.eigvals(closed_loop(rig, controller)[0])


def loop_poles(rig: Rig, controller: AnyController) -> np.ndarray:
    """The closed-loop poles as every run and sweep computes them (so they choose the same settling and
    flag the same points unstable): the core's eigenvalues (:func:`eigenvalues`) of, for a PID, the
    affine stack of :func:`spectral_radius`, else :func:`closed_loop`'s matrix."""
    if isinstance(controller, PID):
        ((_, stack),) = _closed_loop_stacks(rig, controller, _gain_arrays(controller, None, None, None))
        return eigenvalues(stack)[0]
    # closed_loop's matrix closed here around the cached plant: a sweep of the controller (a notch's
    # frequency) would have the core discretise the same plant again at each point.
    Phi, Gamma, _ = sampled_plant(rig, controller.fs)
    M = _loop_matrix(Phi, Gamma[:, 1:2], sampled_sensor_rows(rig, len(Phi)), *controller_matrices(controller))
    return eigenvalues(M[None])[0]


def eigenvalues(stack: np.ndarray, workers: int = 1) -> np.ndarray:
    """Eigenvalues of a stack of square matrices (count, m, m), in the core on up to ``workers`` threads
    (one per 128 matrices of 7x7, the work growing as m^3: starting a thread costs about fifty 7x7
    solves): one function for single runs and sweeps, so both see the same digits."""
    stack = np.ascontiguousarray(stack, dtype=float)
    work = len(stack) * (stack.shape[-1] / 7) ** 3 if stack.ndim == 3 else 0.0
    return _core.eigenvalues(stack, max(1, min(workers, int(work // 128))))


@functools.lru_cache(maxsize=256)
def require_stable(rig: Rig, controller: AnyController) -> np.ndarray:
    """The closed-loop poles (as :func:`loop_poles` computes them, read-only), or
    :class:`UnstableLoopError` naming the unstable ones and the controller."""

    def loop() -> str:
        if isinstance(controller, PID):
            what = (f"kp={controller.kp} A/m, ki={controller.ki} A/(m s), kd={controller.kd} A s/m, "
                    f"delay={controller.delay}")  # fmt: skip
        else:
            what = repr(controller)
        return f"the closed loop is unstable with {what}"

    return checked_poles(loop_poles(rig, controller), loop)


def checked_poles(poles: np.ndarray, loop: Callable[[], str]) -> np.ndarray:
    """``poles``, made read-only, or :class:`UnstableLoopError` naming the ones on or outside the unit circle
    (the first four) after ``loop()`` ("the closed loop is unstable with ..."): the stability test of runs
    and of N-axis sweeps (one-axis sweeps compare each point's spectral radius with 1)."""
    poles.flags.writeable = False
    bad = poles[np.abs(poles) >= 1.0]
    if bad.size:
        shown = ", ".join(f"{p:.6g} (|z|={abs(p):.6g})" for p in bad[:4])
        raise UnstableLoopError(f"{loop()}: pole(s) on or outside the unit circle: {shown}", bad)
    return poles


def _gain_arrays(pid: PID, kp: ArrayLike | None, ki: ArrayLike | None, kd: ArrayLike | None) -> np.ndarray:
    """Gain sets as an (N, 3) array: given arrays broadcast together, the rest from ``pid``."""
    given = {"kp": kp, "ki": ki, "kd": kd}
    arrays = [np.asarray(pid.__dict__[n] if v is None else v, dtype=float) for n, v in given.items()]
    for name, array in zip(given, arrays):
        if given[name] is not None:  # (the PID's own gains are finite: checked when it was made)
            require(bool(np.isfinite(array).all()), name, array, "finite")
    gains = np.empty((*np.broadcast(*arrays).shape, 3))  # (sweeps lay out 40 points in a few us, not 20)
    for j, array in enumerate(arrays):
        gains[..., j] = array
    return gains.reshape(-1, 3)


def _loop_matrix(
    Phi: np.ndarray, Gu: np.ndarray, S: np.ndarray, Ac: np.ndarray, Bc: np.ndarray, Cc: np.ndarray, Dc: np.ndarray
) -> np.ndarray:
    """The closed loop's state matrix ``[[Phi + Gu Dc S, Gu Cc], [Bc S, Ac]]`` (``Gu``: the command's column
    of ``Gamma``, ``S``: the sensor row), assembled in place (np.block costs more than the products)."""
    n, m = Phi.shape[0], Ac.shape[0]
    A = np.empty((n + m, n + m))
    A[:n, :n], A[:n, n:], A[n:, :n], A[n:, n:] = Phi + Gu @ Dc @ S, Gu @ Cc, Bc @ S, Ac
    return A


@functools.lru_cache(maxsize=64)
@one_blas_thread  # on a miss (sweeps of PID gains enter no BLAS guard of their own)
def _affine_closed_loop(
    rig: Rig, pid: PID, with_integral: bool, with_derivative: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The closed-loop matrix is affine in (kp, ki, kd) for a given set of controller states:
    ``A = base + kp S0 + (ki - ki0) S1 + (kd - kd0) S2`` with ki0, kd0 = 1 where the state exists.
    ``pid``'s own gains do not matter here (callers pass them as zero, for the cache).

    :func:`closed_loop`'s matrix, specialised: the loop of the core's plant (:func:`sampled_plant`) at the
    base gains and one step in each, so a sweep of many gain sets combines four matrices instead of
    assembling a loop per set."""
    Phi, Gamma, _ = sampled_plant(rig, pid.fs)
    sensor, gu = sampled_sensor_rows(rig, len(Phi)), Gamma[:, 1:2]
    first, *rest = _pid_steps(pid, with_integral, with_derivative)
    base = _loop_matrix(Phi, gu, sensor, *first)
    return base, np.array([np.zeros_like(base) if m is None else _loop_matrix(Phi, gu, sensor, *m) - base
                           for m in rest])  # fmt: skip


@functools.lru_cache(maxsize=64)
def _pid_steps(pid: PID, with_integral: bool, with_derivative: bool) -> list[Any]:
    """The controller matrices of ``pid`` at the base gains of :func:`_affine_closed_loop`, then one step
    in kp, ki, kd (None where the state is absent): once per PID, whatever the rig (sweeps over the rig)."""
    ki0, kd0 = float(with_integral), float(with_derivative)
    gains = [(0.0, ki0, kd0), (1.0, ki0, kd0), (0.0, 2.0, kd0) if with_integral else None,
             (0.0, ki0, 2.0) if with_derivative else None]  # fmt: skip
    steps = [None if g is None else controller_matrices(replace(pid, kp=g[0], ki=g[1], kd=g[2])) for g in gains]
    for matrices in filter(None, steps):
        for matrix in matrices:
            matrix.flags.writeable = False
    return steps


@functools.lru_cache(maxsize=64)
def _without_gains(pid: PID) -> PID:
    """``pid`` with kp = ki = kd = 0: the key of :func:`_affine_closed_loop`'s cache (made once per PID:
    a sweep's serial Python)."""
    return replace(pid, kp=0.0, ki=0.0, kd=0.0)


def _closed_loop_stacks(rig: Rig, pid: PID, gains: np.ndarray):  # noqa: ANN202
    """(rows, stack of closed-loop matrices) per pattern of controller states among the gain sets."""
    structure = _without_gains(pid)
    pattern = (gains[:, 1] != 0) * 1 + (gains[:, 2] != 0) * 2
    codes = np.flatnonzero(np.bincount(pattern, minlength=4))  # the patterns present, in order
    for code in codes:
        # (one pattern, as in most sweeps: every row, without picking them out)
        rows = np.flatnonzero(pattern == code) if codes.size > 1 else np.arange(len(gains))
        base, slopes = _affine_closed_loop(rig, structure, bool(code & 1), bool(code >> 1))
        offsets = (gains[rows] if codes.size > 1 else gains) - np.array([0.0, float(code & 1), float(code >> 1)])
        yield rows, base + np.einsum("nk,kij->nij", offsets, slopes)


def spectral_radius(
    rig: Rig,
    pid: PID,
    *,
    kp: ArrayLike | None = None,
    ki: ArrayLike | None = None,
    kd: ArrayLike | None = None,
    workers: int = 1,
) -> np.ndarray:
    """Largest |z| of the closed-loop poles for many gain sets at once (the rest of ``pid`` fixed).

    The closed-loop matrix is affine in the gains, so each gain set's matrix is a combination of four
    cached ones, and the eigenvalues of the whole stack come in one call (on ``workers`` threads).
    Returns one radius per gain set (stable: < 1), in the broadcast shape of the gains, flattened. A
    single run and a sweep use this same computation, so they choose the same settling time.
    """
    return _radius_of_gains(rig, pid, _gain_arrays(pid, kp, ki, kd), workers)


def _radius_of_gains(rig: Rig, pid: PID, gains: np.ndarray, workers: int = 1) -> np.ndarray:
    """:func:`spectral_radius` of the gain sets already laid out by :func:`_gain_arrays` (sweeps)."""
    radius = np.empty(len(gains))
    for rows, stack in _closed_loop_stacks(rig, pid, gains):
        radius[rows] = np.max(np.abs(eigenvalues(stack, workers)), axis=-1)
    return radius


def settling_radius(rig: Rig, pid: AnyController, radius: ArrayLike) -> np.ndarray:
    """The slowest decay per sample of a run: the loop's spectral ``radius``, or the force transducer's
    AC-coupling pole ``exp(-1/(fs tau))`` when that is slower (it settles on the applied force)."""
    if rig.force_coupling_tau is None:
        return np.asarray(radius, dtype=float)
    return np.maximum(radius, np.exp(-1.0 / (pid.fs * rig.force_coupling_tau)))


def settle_periods_for(radius: np.ndarray, period_samples: int, decay: float = 1e-9) -> np.ndarray:
    """Periods of ``period_samples`` for poles of the given spectral ``radius`` (< 1) to decay below
    ``decay``: ``ceil(ln(decay) / ln(radius) / period_samples) + 1``."""
    radius = np.asarray(radius, dtype=float)
    with np.errstate(divide="ignore"):
        samples = np.where(radius > 0, np.log(decay) / np.log(np.where(radius > 0, radius, 0.5)), 0.0)
    return np.ceil(samples / period_samples).astype(np.int64) + 1
