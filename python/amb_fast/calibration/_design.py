"""Controller design for the actual stiffness and damping: :func:`design_controller`."""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy import optimize

from .._blas import one_blas_thread
from .._equality import ArrayRecord
from .._linear import AnyController, closed_loop_poles, effective_coefficients, iso_zone, sensitivity, stability_margin
from .._params import PID, Rig
from .._sweep import RIG_FIELDS, point_model
from .._sweep_result import unit_of
from ..controllers import save_controller
from ._problem import _actual, _check_controller, _check_rig, _jacobian, _names

GAINS = ("kp", "ki", "kd")
_GRID_POINTS = 1500  # sensitivity grid of the constraint during the search (the result is checked on 20000)
_NYQUIST_FRACTION = 0.999  # a block frequency's upper limit, as a fraction of fs/2


@dataclass(frozen=True, eq=False)
class Design(ArrayRecord):
    """A controller designed by :func:`design_controller`.

    Attributes
    ----------
    controller : PID or Controller
        The designed controller (the start controller with the free parameters replaced).
    params, start : dict of str to float
        The free parameters' designed and start values (units: A/m, A/(m s), A s/m, Hz, ...).
    freq : ndarray
        Design frequencies, Hz.
    k_target, c_target : ndarray or None
        Targets, N/m and N s/m (``None``: not part of the design).
    k, c : ndarray
        Actual stiffness (N/m) and damping (N s/m) the design gives on the rig (:func:`amb_fast.predict`:
        every lag, the mass loading and the transducer included), as an estimate would measure them.
    k_effective, c_effective : ndarray
        The controller's effective coefficients (paper eq. 5), N/m and N s/m.
    peak_sensitivity : float
        max |S| (``inf`` if unstable); ``stable``: whether the loop is stable.
    residual : float
        Root mean square of the weighted relative misses (the objective; 0 when the targets are met).
    k_miss, c_miss : float
        Root mean square of ``k - k_target`` (N/m) and ``c - c_target`` (N s/m); NaN without a target.
    constrained : bool
        Whether a limit (stability or ``max_sensitivity``) kept the design from the unconstrained optimum.
    unconstrained_residual : float
        The objective at the unconstrained optimum (equal to ``residual`` when not constrained).
    exact : bool
        Whether the unconstrained optimum came from an exact linear least-squares solve (F/Y affine in the
        free parameters: PID gains).
    basis : {"actual", "effective"}
        What was matched to the targets.
    """

    controller: AnyController
    params: dict[str, float]
    start: dict[str, float]
    freq: np.ndarray
    k_target: np.ndarray | None
    c_target: np.ndarray | None
    k: np.ndarray
    c: np.ndarray
    k_effective: np.ndarray
    c_effective: np.ndarray
    peak_sensitivity: float
    stable: bool
    residual: float
    k_miss: float
    c_miss: float
    constrained: bool
    unconstrained_residual: float
    exact: bool
    basis: str
    max_sensitivity: float | None = None
    feasible: bool = True
    start_peak: float = float("nan")

    def __repr__(self) -> str:
        # A summary, not the arrays: the parameters, the misses of the targets set, the peak |S|.
        params = ", ".join(f"{n}={v:.6g}" for n, v in self.params.items())
        state = "feasible" if self.feasible else "NOT feasible"
        return (
            f"Design({params}; {self.misses_text()}; peak |S| {self.peak_sensitivity:.3f}, {state}; "
            f"{self.freq.size} frequencies {self.freq.min():g}-{self.freq.max():g} Hz, basis {self.basis!r})"
        )

    def _misses(self) -> list[tuple[str, float, np.ndarray, str]]:
        """(name, rms miss, target, unit) of each target the design has."""
        both = (("stiffness", self.k_miss, self.k_target, "N/m"), ("damping", self.c_miss, self.c_target, "N s/m"))
        return [(name, miss, target, unit) for name, miss, target, unit in both if target is not None]

    def _reached(self) -> str:
        if self.stable:
            return f"the lowest sensitivity peak reached is {self.peak_sensitivity:.3f}"
        return "no stable design was reached"

    def misses_text(self) -> str:
        """How far the actual coefficients miss their targets (rms), for the targets the design has:
        ``"stiffness misses by 288.8 N/m rms"``; never a NaN for a target that is not set."""
        return " and ".join(f"{name} misses by {miss:.4g} {unit} rms" for name, miss, _, unit in self._misses())

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the designed controller to a TOML controller file that :func:`amb_fast.load_controller`
        (and ``amb-fast run --controller``) reads back to the same response."""
        return save_controller(self.controller, path)

    def report(self) -> str:
        """Parameters (start and designed), the targets against the actual and effective coefficients at a
        few frequencies, how far the design misses, and its sensitivity peak."""
        out = [f"Controller designed for the {self.basis} stiffness and damping on "
               f"{self.freq.min():g}-{self.freq.max():g} Hz ({self.freq.size} frequencies)", "",
               f"{'parameter':<20} {'start':>12} {'designed':>12}  unit"]  # fmt: skip
        for n, v in self.params.items():
            out.append(f"{n:<20} {self.start[n]:12.6g} {v:12.6g}  {unit_of(n)}")
        out += ["", f"{'f (Hz)':>8} {'k target':>11} {'k actual':>11} {'k eff':>11} "
                    f"{'c target':>10} {'c actual':>10} {'c eff':>10}"]  # fmt: skip
        for i in np.unique(np.linspace(0, self.freq.size - 1, min(self.freq.size, 6)).round().astype(int)):
            kt = f"{self.k_target[i]:11.5g}" if self.k_target is not None else f"{'-':>11}"
            ct = f"{self.c_target[i]:10.4g}" if self.c_target is not None else f"{'-':>10}"
            out.append(f"{self.freq[i]:8g} {kt} {self.k[i]:11.5g} {self.k_effective[i]:11.5g} {ct} "
                       f"{self.c[i]:10.4g} {self.c_effective[i]:10.4g}")  # fmt: skip
        out.append("(N/m, N s/m; actual: on the rig with its lags; eff: paper eq. 5)")
        out.append("")
        for name, miss, target, unit in self._misses():
            scale = _rms(target)
            rel = f" ({100 * miss / scale:.3g} % of the target)" if scale > 0 else ""
            out.append(f"{name:<10} misses by {miss:.4g} {unit} rms{rel}")
        zone = iso_zone(self.peak_sensitivity) if self.stable else "unstable"
        limit = f" (limit {self.max_sensitivity:g})" if self.max_sensitivity is not None else ""
        out.append(f"sensitivity peak |S| = {self.peak_sensitivity:.3f}{limit}, ISO 14839-3 zone {zone}")
        if not self.feasible:
            what = "stable" if self.max_sensitivity is None else f"stable with |S| <= {self.max_sensitivity:g}"
            out.append(f"NO FEASIBLE DESIGN: no values of {', '.join(self.params)} found that make the loop {what}; "
                       f"{self._reached()} (this design); free more parameters or relax the limit")  # fmt: skip
        elif self.constrained:
            out.append(
                "the targets are not feasible: the unconstrained optimum (objective "
                f"{self.unconstrained_residual:.4g}) is unstable or over the sensitivity limit; this is the best "
                f"feasible design (objective {self.residual:.4g})"
            )
        if self.feasible and self.max_sensitivity is not None and self.max_sensitivity < self.start_peak < np.inf:
            out.append(f"the start controller's sensitivity peak {self.start_peak:.3f} is over the limit: the design "
                       "started from a feasible point found by minimising the peak from it")  # fmt: skip
        if self.feasible and not self.constrained and self.residual > 1e-3:
            out.append("the targets cannot be met exactly by these parameters: best fit, objective "
                       f"{self.residual:.4g} (rms weighted relative miss)")  # fmt: skip
        return "\n".join(out)


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2)))


def _values(controller: AnyController, names: Sequence[str]) -> dict[str, float]:
    out = {}
    params = getattr(controller, "params", None)
    for name in names:
        if name in RIG_FIELDS:
            raise ValueError(f"free: {name!r} is a rig field; design_controller chooses controller parameters")
        if isinstance(controller, PID):
            if name not in ("kp", "ki", "kd", "derivative_cutoff"):
                raise ValueError(f"free: {name!r} is not a PID parameter (kp, ki, kd, derivative_cutoff)")
            value = getattr(controller, name)
        else:
            if not isinstance(params, dict) or name not in params:
                known = ", ".join(params) if isinstance(params, dict) else "none"
                raise ValueError(f"free: {name!r} is not a parameter of the controller (its params: {known})")
            value = params[name]
        if value is None:
            raise ValueError(f"free: {name!r} is None in the controller; give it a start value there")
        out[name] = float(value)
    return out


def _target(name: str, value: Any, freq: np.ndarray) -> np.ndarray | None:
    if value is None:
        return None
    array = np.asarray(value, dtype=float)
    try:
        array = np.broadcast_to(array, freq.shape).copy()
    except ValueError:
        raise ValueError(f"{name} must be a number or an array like freq ({freq.size} values), "
                         f"got shape {array.shape}") from None  # fmt: skip
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite")
    return array


@one_blas_thread
def design_controller(
    rig: Rig,
    controller: AnyController,
    *,
    freq: ArrayLike,
    stiffness: ArrayLike | None = None,
    damping: ArrayLike | None = None,
    free: Sequence[str] = ("kp", "kd"),
    max_sensitivity: float | None = None,
    weights: tuple[ArrayLike, ArrayLike] | None = None,
    basis: Literal["actual", "effective"] = "actual",
) -> Design:
    """Choose controller parameters so that the actual stiffness and damping on ``rig`` meet targets.

    Parameters
    ----------
    rig : Rig
        The rig to design for, ideally a calibrated one (:attr:`RigFit.rig`): its lags, mass loading and
        transducer decide the actual coefficients.
    controller : PID or Controller
        Start controller: the structure, and the values of every parameter not in ``free``.
    freq : array_like
        Design frequencies, Hz (below ``fs/2``).
    stiffness, damping : float or array_like, optional
        Targets for the actual k(f) (N/m) and c(f) (N s/m) at ``freq``; at least one.
    free : sequence of str
        Controller parameters to choose, named as in sweeps (:func:`amb_fast._sweep.point_model`): ``kp``,
        ``ki``, ``kd``, ``derivative_cutoff`` for a PID, any of ``controller.params`` for a Controller.
    max_sensitivity : float, optional
        Upper limit of the sensitivity peak max |S| (ISO 14839-3: 3 for zone A). Stability is always
        required.
    weights : (wk, wc), optional
        Weights (scalars or arrays at ``freq``) of the stiffness and damping misses. The misses are
        relative: ``(k - k_target) / rms(k_target)``, ``(c - c_target) / rms(c_target)``, times the weights
        (default 1).
    basis : {"actual", "effective"}
        ``"effective"`` matches the effective coefficients of paper eq. 5 instead: the naive design that
        ignores the lags, for comparison.

    Returns
    -------
    Design

    Notes
    -----
    ``F/Y = (1 - P_u G z^-d) / P_f`` (times the transducer's response) is affine in the controller's
    transfer function, so k and c are affine in the PID gains. With only gains free the unconstrained
    optimum is an exact linear least-squares solve (verified affine numerically); otherwise trust-region
    least squares from the start values (positive non-gain parameters in log scale). If the optimum is
    unstable or over ``max_sensitivity``, the design moves from the start controller (made feasible
    first if it is not) towards it as far as the limits allow, then minimises with the limits as
    constraints (SLSQP in a box around its start that grows while its results are feasible): the best
    feasible design, and the report says by how much it misses. The sensitivity limit is one smooth
    inequality per frequency of a 1500-point grid, ``max_sensitivity^2 |1 - L|^2 >= 1`` (the peak itself
    kinks as its frequency moves between grid points, and SLSQP then fails to converge), tightened by
    what the grid misses of the peak on :func:`amb_fast.stability_margin`'s 20000 points.
    """
    _check_rig(rig)
    _check_controller(controller, "controller")
    f = np.asarray(freq, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(f >= controller.fs / 2):
        raise ValueError(f"freq must be a 1-D array of frequencies in (0, {controller.fs / 2:g}) Hz, got {freq!r}")
    if basis not in ("actual", "effective"):
        raise ValueError(f"basis must be 'actual' or 'effective', got {basis!r}")
    k_target, c_target = _target("stiffness", stiffness, f), _target("damping", damping, f)
    if k_target is None and c_target is None:
        raise ValueError("stiffness and damping are both None: give at least one target")
    free = _names(free)
    names = list(free)
    if not names or len(set(names)) != len(names):
        raise ValueError(f"free must name one or more distinct controller parameters, got {free!r}")
    start = _values(controller, names)
    if max_sensitivity is not None and not (np.isfinite(max_sensitivity) and max_sensitivity > 1):
        raise ValueError(f"max_sensitivity must be a number > 1 (|S| peak), got {max_sensitivity!r}")
    try:
        given_k, given_c = (1.0, 1.0) if weights is None else weights
    except (TypeError, ValueError):
        raise ValueError(f"weights must be a (stiffness weight, damping weight) pair, got {weights!r}") from None
    wk, wc = _target("weights[0]", given_k, f), _target("weights[1]", given_c, f)
    w = 2 * np.pi * f
    sk = (_rms(k_target) if k_target is not None else 1.0) or 1.0
    sc = (_rms(c_target) if c_target is not None else 1.0) or 1.0

    # Coordinates: gains (and parameters that may change sign) linear, scaled by their start; other
    # positive parameters in log scale.
    logs = np.array([n not in GAINS and start[n] > 0 for n in names])
    scale = np.array([1.0 if lg else max(abs(start[n]), 1e-12) for n, lg in zip(names, logs)])
    # A gain that starts at 0 gets the scale of its effect: that of kp's start in the band.
    x0 = np.array([np.log(start[n]) if lg else 1.0 for n, lg in zip(names, logs)])
    for i, n in enumerate(names):
        if not logs[i] and start[n] == 0:
            scale[i] = _zero_scale(n, start, w)
            x0[i] = 0.0

    # A block's frequency (notch_freq, low_pass_freq, lead_lag_zero, ...) must stay below the Nyquist
    # frequency (the block is prewarped there): the search keeps it inside that range.
    lower = np.full(len(names), -np.inf)
    is_frequency = [lg and n.endswith(("_freq", "_zero", "_pole")) for n, lg in zip(names, logs)]
    upper = np.where(is_frequency, np.log(_NYQUIST_FRACTION * controller.fs / 2), np.inf)

    def values(x: np.ndarray) -> dict[str, float]:
        return {n: float(np.exp(v) if lg else v * s) for n, v, lg, s in zip(names, x, logs, scale)}

    def model(x: np.ndarray) -> tuple[Rig, AnyController]:
        return point_model(rig, controller, values(x))

    def coefficients(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, ctrl = model(x)
        return effective_coefficients(r, ctrl, f) if basis == "effective" else _actual(r, ctrl, f)

    def residuals(x: np.ndarray) -> np.ndarray:
        k, c = coefficients(x)
        misses = ((wk, k, k_target, sk), (wc, c, c_target, sc))
        return np.concatenate([wt * (v - target) / s for wt, v, target, s in misses if target is not None])

    def objective(x: np.ndarray) -> float:
        return _rms(residuals(x))

    # Unconstrained optimum: exact when the residuals are affine in x (checked at two other points). Only
    # linear coordinates are probed: a unit step of a log one (a factor e) can put a block's frequency
    # past Nyquist.
    r0 = residuals(x0)
    M = np.column_stack([residuals(x0 + e) - r0 for e in np.eye(len(names))]) if not logs.any() else None
    probe = x0 + np.linspace(0.3, -0.2, len(names))
    exact = M is not None and bool(
        np.linalg.norm(residuals(probe) - (r0 + M @ (probe - x0))) <= 1e-8 * (np.linalg.norm(r0) + np.linalg.norm(M))
    )
    if M is not None and exact:
        x_star = x0 + np.linalg.lstsq(M, -r0, rcond=None)[0]
    else:
        x_star = optimize.least_squares(residuals, x0, method="trf", bounds=(lower, upper), xtol=1e-12, ftol=1e-12).x

    def radius(x: np.ndarray) -> float:
        return float(np.max(np.abs(closed_loop_poles(*model(x))), initial=0.0))

    grid = np.geomspace(0.01, controller.fs / 2 * (1 - 1e-9), _GRID_POINTS)

    def peak(x: np.ndarray) -> float:
        return float(np.max(np.abs(sensitivity(*model(x), grid))))

    def loop(x: np.ndarray) -> np.ndarray:
        return 1.0 / sensitivity(*model(x), grid)  # 1 - L on the grid

    def slopes(x: np.ndarray) -> np.ndarray:
        # With the loop affine in x (PID gains), the constant M; else central differences.
        return M if M is not None and exact else _jacobian(residuals, x, lower, upper, 1e-6)

    def search(x: np.ndarray, limit: float | None, size: float) -> np.ndarray:
        """SLSQP from x inside the box x +- size: the least squares, stable, and |S| <= limit at every grid
        frequency as one inequality each, ``limit^2 |1 - L|^2 - 1 >= 0``: smooth in x (quadratic in PID
        gains), where the peak of |S| kinks each time its frequency moves past a grid point. The limit is
        lowered by 1e-9 so that SLSQP's tolerance cannot leave the result over it."""
        constraints: list[dict[str, Any]] = [{"type": "ineq", "fun": lambda y: 1.0 - 1e-6 - radius(y)}]
        if limit is not None:
            square = (limit * (1.0 - 1e-9)) ** 2
            # d(1 - L)/dx: unit steps when the loop is affine in x, else central differences at each point.
            unit = np.column_stack([loop(x + e) - loop(x) for e in np.eye(x.size)]) if exact else None

            def margins(y: np.ndarray) -> np.ndarray:
                return square * np.abs(loop(y)) ** 2 - 1.0

            def margin_slopes(y: np.ndarray) -> np.ndarray:
                if unit is None:
                    return _jacobian(margins, y, lower, upper, 1e-6)
                return 2.0 * square * (np.conj(loop(y))[:, None] * unit).real

            constraints.append({"type": "ineq", "fun": margins, "jac": margin_slopes})
        # The sum of squares over the largest eigenvalue of its Gauss-Newton Hessian at x: SLSQP's first
        # Hessian (the identity) then overestimates the curvature, and its first step does not overshoot.
        J = slopes(x)
        scale = 1.0 / max(2.0 * float(np.linalg.eigvalsh(J.T @ J)[-1]), 1e-300)

        def gradient(y: np.ndarray) -> np.ndarray:
            return 2.0 * scale * slopes(y).T @ residuals(y)

        box = list(zip(np.maximum(x - size, lower), np.minimum(x + size, upper)))
        result = optimize.minimize(lambda y: scale * float(np.sum(residuals(y) ** 2)), x, method="SLSQP",
                                   jac=gradient, bounds=box, constraints=constraints,
                                   options={"maxiter": 200, "ftol": 1e-12})  # fmt: skip
        return np.asarray(result.x, dtype=float)

    def feasible(x: np.ndarray) -> bool:
        if np.any(x > upper) or radius(x) >= 1.0 - 1e-9:
            return False
        return max_sensitivity is None or peak(x) <= max_sensitivity

    x_best, constrained, found = x_star, False, True
    start_peak = peak(x0) if radius(x0) < 1.0 else float("inf")
    if not feasible(x_star):
        constrained = True
        if not feasible(x0):
            # The usual reason: a limit below the start's peak. Phase 1: the nearest feasible point from
            # the start (the peak minimised); without one, the design of lowest peak, said so.
            x0, found = _feasible_start(x0, x_star, radius, peak, max_sensitivity, lower, upper)
        if found:
            # SLSQP's start: the furthest feasible point on the segment from the start to the optimum, to 1e-6
            # of its length (SLSQP's constraints do the rest).
            lo, hi = 0.0, 1.0
            for _ in range(20):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if feasible(x0 + mid * (x_star - x0)) else (lo, mid)
            x_line = x_best = x0 + lo * (x_star - x0)
            # SLSQP inside a box around its start (a trust region) that grows while its results are stable
            # and within the limit and shrinks when not: SLSQP lets its iterates leave the constraints, and
            # from a long step it can land beyond the ridge of |S| in an unstable region where |S| is small
            # again (small gains: |S| near 1). The search's grid misses the peak between its points: the
            # limit is tightened by the miss that stability_margin's grid finds, and the search repeated.
            tightened, size, bar = max_sensitivity, 0.5, objective(x_line)
            for _ in range(12):
                x = search(x_best, tightened, size)
                if not (np.all(np.isfinite(x)) and feasible(x) and objective(x) <= bar):
                    size /= 4
                    if size < 1e-3:
                        break
                    continue
                inside = bool(np.all(np.abs(x - x_best) < 0.999 * size))
                x_best, bar = x, objective(x)
                checked = stability_margin(*model(x)).peak
                if max_sensitivity is not None and tightened is not None and checked > max_sensitivity:
                    tightened *= max_sensitivity / checked
                    bar = objective(x_line)
                elif inside:
                    break
                else:
                    size *= 2
        else:
            x_best = x0

    r_model, designed = model(x_best)
    k, c = _actual(r_model, designed, f)  # the actual ones whatever the basis
    k_eff, c_eff = effective_coefficients(r_model, designed, f)
    margin = stability_margin(r_model, designed)
    if max_sensitivity is not None and margin.peak > max_sensitivity * (1 + 1e-3):
        constrained = True
    design = Design(
        controller=designed,
        params=values(x_best),
        start=start,
        freq=f,
        k_target=k_target,
        c_target=c_target,
        k=k,
        c=c,
        k_effective=k_eff,
        c_effective=c_eff,
        peak_sensitivity=float(margin.peak),
        stable=bool(margin.stable),
        residual=objective(x_best),
        k_miss=_rms(k - k_target) if k_target is not None else float("nan"),
        c_miss=_rms(c - c_target) if c_target is not None else float("nan"),
        constrained=constrained,
        unconstrained_residual=objective(x_star),
        exact=exact,
        basis=basis,
        max_sensitivity=max_sensitivity,
        feasible=found,
        start_peak=start_peak,
    )
    if not found:
        limit = "" if max_sensitivity is None else f" with |S| <= {max_sensitivity:g}"
        warnings.warn(f"design_controller: no values of {', '.join(names)} make the loop stable{limit}; "
                      f"{design._reached()} (Design.feasible is False)", UserWarning, stacklevel=3)  # fmt: skip
    elif max_sensitivity is None and constrained and iso_zone(design.peak_sensitivity) == "D":
        # Without a limit, targets beyond reach pull the design onto the stability boundary (a damping target
        # of 0 gives |S| ~ 2e4): stable on paper, unusable on a rig.
        warnings.warn(f"design_controller: only stability held the design back: its |S| peak is "
                      f"{design.peak_sensitivity:.4g} (ISO 14839-3 zone D, >= 5), barely stable; give "
                      "max_sensitivity (e.g. 3, zone A) to keep a margin", UserWarning, stacklevel=3)  # fmt: skip
    return design


def _zero_scale(name: str, start: dict[str, float], w: np.ndarray) -> float:
    """A scale for a gain that starts at 0: the gain whose effect in the band matches kp's (or 1000 A/m)."""
    kp = abs(start.get("kp", 0.0)) or 1000.0
    wm = float(np.sqrt(w.min() * w.max()))
    return {"kp": kp, "ki": kp * wm, "kd": kp / wm}.get(name, 1.0)


def _feasible_start(
    x0: np.ndarray,
    x_star: np.ndarray,
    radius: Any,
    peak: Any,
    max_sensitivity: float | None,
    lower: np.ndarray,
    upper: np.ndarray,
) -> tuple[np.ndarray, bool]:
    """A stable point (with |S| <= max_sensitivity) near ``x0``: the best of the segment to ``x_star``, then
    the sensitivity peak minimised from it (Nelder-Mead, a few parameters), stopping once inside the limit
    with a margin. Returns the point and whether it is feasible (if not: the lowest peak reached)."""
    target = (max_sensitivity if max_sensitivity is not None else np.inf) * (1.0 - 1e-3)

    def phase1(x: np.ndarray) -> float:
        if np.any(x > upper) or np.any(x < lower):
            return 1e9
        try:
            r = radius(x)
        except ValueError:
            return 1e9
        if r >= 1.0 - 1e-6:
            return 1e3 * (1.0 + r)  # unstable: towards stability first
        return peak(x) if max_sensitivity is not None else 0.0

    candidates = [x0 + t * (x_star - x0) for t in np.linspace(0.0, 1.0, 11)]
    scores = [phase1(x) for x in candidates]
    best = candidates[int(np.argmin(scores))]
    if min(scores) <= target:
        return best, True

    def stop(intermediate_result: optimize.OptimizeResult) -> None:
        if intermediate_result.fun <= target:
            raise StopIteration

    n = x0.size
    simplex = np.vstack([best] + [best + 0.2 * np.eye(n)[j] for j in range(n)])
    result = optimize.minimize(phase1, best, method="Nelder-Mead", callback=stop,
                               options={"initial_simplex": simplex, "maxfev": 400 * n, "xatol": 1e-4,
                                        "fatol": 1e-4})  # fmt: skip
    x = result.x if phase1(result.x) <= phase1(best) else best
    return x, bool(phase1(x) <= target)
