"""Weighted least squares of the exact loop model against measured estimates: :func:`fit_rig`.

The problem it solves (parameters, bounds, weighted data, model) is in ``_problem``, the
:class:`RigFit` it returns in ``_result``.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Union

import numpy as np
from scipy import optimize, stats

from .._blas import one_blas_thread
from .._experiment import Estimate
from .._linear import AnyController, is_controller
from .._params import Rig
from ..controllers import recorded_controller
from ._problem import (
    _LINEAR_SCALE,
    FITTABLE,
    _as_list,
    _bounds,
    _check_controller,
    _check_rig,
    _data,
    _free_start,
    _jacobian,
    _Model,
    _Space,
    same_controller,
)
from ._result import MISFIT_P, RigFit

ControllerArg = Union[AnyController, Sequence[AnyController]]


@one_blas_thread
def fit_rig(
    estimates: Estimate | Sequence[Estimate],
    rig: Rig,
    controllers: ControllerArg | None = None,
    *,
    free: Sequence[str] | Mapping[str, float],
    bounds: Mapping[str, tuple[float, float]] | None = None,
) -> RigFit:
    """Fit rig parameters to measured estimates by weighted least squares of the exact loop model.

    Parameters
    ----------
    estimates : Estimate or sequence of Estimate
        Measured (or simulated) estimates, each with its standard errors. Several estimates with different
        controllers (the baseline and another gain set) decorrelate parameters.
    rig : Rig
        Start values of the free parameters and the fixed values of all others.
    controllers : PID or Controller, or a sequence of them, optional
        The controller of each estimate (one per estimate, all at one ``fs``). By default the controller
        each estimate records (``estimate.meta["controller"]``: :func:`amb_fast.run_experiment` and a file
        saved by :meth:`Estimate.save <amb_fast.Estimate.save>` record it). A controller given for an
        estimate that records another one (a different response at its lines, or another ``fs``) is an
        error: the fit would model the wrong loop. :attr:`RigFit.inputs` says which was used.
    free : sequence of str, or dict of str to float
        The rig fields to fit: ``mass``, ``kyy``, ``kiy``, ``amp_bandwidth``, ``eddy_bandwidth``,
        ``sensor_bandwidth``, ``mass_loading``, ``force_coupling_tau``, ``dead_time``. A dict gives start
        values (needed for a stage that is ``None`` in ``rig``). Positive parameters are fitted as their
        logarithm; ``kyy`` (keeping its sign), ``mass_loading`` (kg) and ``dead_time`` (s) on a linear scale,
        the last two bounded below by 0 (they may be 0).
    bounds : dict of str to (low, high), optional
        Limits in SI units for some free parameters. The defaults: > 0 (>= 0 for ``mass_loading`` and
        ``dead_time``), ``kyy`` keeps its sign, bandwidths below ``20 fs``, ``force_coupling_tau`` below
        1000 s and ``dead_time`` below 100 samples (or twice the start value), which keeps the optimiser out
        of the flat regions where a stage no longer acts.

    Returns
    -------
    RigFit

    Notes
    -----
    *What is fitted.* The residual at each line is ``H_meas - H_model`` with ``H = F/Y = 1/receptance``
    (N/m) and ``H_model = 1 / predict(rig, controller, freq)``, real and imaginary parts. ``k`` and ``c``
    are affine in ``H`` (``Re H = k - m w^2``, ``Im H = w c``), so this is the same as fitting k and c with
    their standard errors; H is where the estimator's errors are made (first-order, ``dH = (dF - H dY)/Y``)
    and where the model is exact. Stationary noise at a DFT line is circular complex Gaussian, so the
    variance of Re H and of Im H are one: the weight of a line is ``sigma^2 = (k_std^2 + (w c_std)^2) / 2``
    with ``nu = 2 (blocks - 1)`` degrees of freedom (each of ``k_std^2``, ``(w c_std)^2`` has ``blocks - 1``).

    *Estimated weights.* With ``s^2 ~ sigma^2 chi2(nu)/nu`` independent of the residual, the naive
    covariance ``(J^T W J)^-1`` is too small: ``E[1/s^2] = nu/(nu - 2)/sigma^2`` overweights, and the noisy
    weights lose efficiency. To first order the estimator's covariance is ``nu/(nu - 4) (J^T W J)^-1``
    (``E[g^2]/E[g]`` for ``g = nu/chi2(nu)``), which is reported (1.29 at 10 periods, 1.05 at 40); with
    estimates of different ``nu`` a sandwich of the same factors. Covariances are propagated from the fit's
    scale to SI units with ``d value / d x`` (``value`` for log parameters).

    *Goodness of fit.* For a correct model the squared residual of a line over its estimated variance,
    ``T = |e|^2 / (2 s^2)``, is exactly F(2, nu) distributed (numerator ``chi2(2)/2``, denominator
    ``chi2(nu)/nu``, independent because a Gaussian sample's mean and variance are). A plain chi-square of
    the normalised residuals would treat it as ``chi2(2)/2`` and, with 10 or even 40 periods, call a correct
    model a misfit far too often. Each line is instead mapped to the chi-square(2) variable of the same
    tail probability, ``q = -2 ln P(F > T) = nu ln(1 + 2T/nu)``, and ``chi2 = sum q`` is compared with a
    chi-square of ``dof = 2 lines - p`` (the p fitted parameters take p degrees of freedom, as in any least
    squares). The test suite checks that these p-values are uniform for a correct model. A model with
    ``p < 1e-3`` is reported as a misfit, with a ``UserWarning``.
    """
    _check_rig(rig)
    est_list = _as_list(estimates, lambda v: hasattr(v, "H"))
    if not est_list:
        raise ValueError("estimates must hold at least one Estimate, got none")
    ctrl_list, inputs = _controllers(est_list, controllers)
    start = _free_start(rig, free)
    names = tuple(start)
    space = _Space(
        names=names,
        kinds=tuple(FITTABLE[n][0] for n in names),
        scales=tuple(max(abs(start[n]), _LINEAR_SCALE[n]) if FITTABLE[n][0] == "linear" else 1.0 for n in names),
    )
    data = _data(est_list, ctrl_list)
    lower, upper = _bounds(space, start, bounds, float(ctrl_list[0].fs))
    x0 = np.clip(space.to_x([start[n] for n in names]), lower, upper)

    model_H = _Model(data)

    def normalized(x: np.ndarray) -> list[np.ndarray]:
        """Per estimate, (measured - model) H over the line's standard error, complex."""
        return [(d.H - H) / d.sigma for d, H in zip(data, model_H(space.rig(rig, x)))]

    def residuals(x: np.ndarray) -> np.ndarray:
        return np.concatenate([part for e in normalized(x) for part in (e.real, e.imag)])

    result = optimize.least_squares(residuals, x0, bounds=(lower, upper), method="trf", x_scale=1.0,
                                    xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200 * (len(names) + 1))  # fmt: skip
    x = result.x
    J = _jacobian(residuals, x, lower, upper, 1e-6)
    inflation = np.concatenate([np.full(2 * d.freq.size, d.nu / (d.nu - 4.0)) for d in data])
    A_inv = np.linalg.pinv(J.T @ J)
    cov_x = A_inv @ (J.T * inflation) @ J @ A_inv
    D = space.derivative(x)
    covariance = cov_x * np.outer(D, D)
    std_si = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        sx = np.sqrt(np.maximum(np.diag(cov_x), 0.0))
        correlation = np.where(np.outer(sx, sx) > 0, cov_x / np.outer(sx, sx), 0.0)
    z = stats.norm.ppf(0.975)
    lo_x, hi_x = np.maximum(x - z * sx, lower), np.minimum(x + z * sx, upper)
    lo, hi = space.to_values(lo_x), space.to_values(hi_x)
    values = space.to_values(x)

    # Goodness of fit: each line's F(2, nu) statistic mapped to chi-square(2).
    errors = normalized(x)
    chi2 = 0.0
    for d, e in zip(data, errors):
        T = 0.5 * np.abs(e) ** 2
        chi2 += float(np.sum(d.nu * np.log1p(2.0 * T / d.nu)))
    lines = sum(d.freq.size for d in data)
    dof = 2 * lines - len(names)
    p_value = float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan")

    fit = RigFit(
        rig=space.rig(rig, x),
        names=names,
        values={n: float(v) for n, v in zip(names, values)},
        std={n: float(s) for n, s in zip(names, std_si)},
        interval={n: (float(a), float(b)) for n, a, b in zip(names, lo, hi)},
        covariance=covariance,
        correlation=correlation,
        chi2=chi2,
        dof=dof,
        p_value=p_value,
        normalized_residuals=tuple(errors),
        units={n: FITTABLE[n][1] for n in names},
        lines=lines,
        estimates=len(data),
        start=dict(start),
        inputs=tuple(inputs),
        _space=space,
        _x=x,
        _cov_x=cov_x,
        _lower=lower,
        _upper=upper,
    )
    if dof > 0 and not fit.fits:
        warnings.warn(
            f"the fitted model cannot fit the data: chi2 = {chi2:.1f} for {dof} degrees of freedom, "
            f"p = {p_value:.3g} < {MISFIT_P:g}; see RigFit.report()",
            UserWarning,
            stacklevel=2,
        )
    return fit


def _controllers(estimates: list[Estimate], controllers: ControllerArg | None) -> tuple[list[AnyController], list[str]]:
    """The controller of each estimate (given, or the one it records) and a line per estimate saying which
    controller and how many periods the fit uses, and where they come from."""
    recorded = [recorded_controller((getattr(e, "meta", None) or {}).get("controller")) for e in estimates]
    if controllers is None:
        missing = [i for i, c in enumerate(recorded) if c is None]
        if missing:
            raise ValueError(
                f"controllers: estimates{missing} record no controller (an estimate identified from a recording, "
                "or a plain CSV table): give controllers=, one per estimate"
            )
        ctrl_list, source = recorded, ["recorded in the estimate"] * len(recorded)
    else:
        ctrl_list = _as_list(controllers, is_controller)
        for i, c in enumerate(ctrl_list):
            _check_controller(c, f"controllers[{i}]")
        if len(ctrl_list) != len(estimates):
            raise ValueError(f"controllers must give one controller per estimate: {len(estimates)} estimate(s), "
                             f"{len(ctrl_list)} controller(s)")  # fmt: skip
        source = []
        for i, (given, record, est) in enumerate(zip(ctrl_list, recorded, estimates)):
            if record is None:
                source.append("given (the estimate records none)")
                continue
            if not same_controller(given, record, np.asarray(est.freq, dtype=float)):
                raise ValueError(
                    f"controllers[{i}] is {given!r}, but estimates[{i}] was measured with {record!r} (its record): "
                    "leave controllers out to use the recorded ones, or give the controller of the measurement"
                )
            source.append("given, the one the estimate records")
    inputs = [f"estimates[{i}]: {c!r} ({s}); {getattr(e, 'blocks', '?')} periods averaged"
              for i, (c, s, e) in enumerate(zip(ctrl_list, source, estimates))]  # fmt: skip
    return ctrl_list, inputs
