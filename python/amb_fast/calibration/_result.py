"""The :class:`RigFit` that :func:`fit_rig` returns: the fitted rig, its parameters' covariance and
goodness of fit, predictions and coefficients with standard errors propagated from the covariance, and
the text report.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._blas import one_blas_thread
from .._equality import ArrayRecord
from .._linear import AnyController, predict
from .._params import Rig
from .._toml import save_rig
from ._problem import _actual, _check_controller, _jacobian, _Space

CORRELATED = 0.9  # |correlation| above which two parameters are named as not separately identifiable
MISFIT_P = 1e-3  # p-value below which the model is said not to fit


@dataclass(frozen=True, eq=False)
class RigFit(ArrayRecord):
    """A rig calibrated to measured estimates by :func:`fit_rig`.

    Attributes
    ----------
    rig : Rig
        The fitted rig: the start rig with the free fields replaced by their fitted values.
    names : tuple of str
        The free parameters, in the order of ``covariance``.
    values, std : dict of str to float
        Fitted values and their standard errors in the parameters' own units (SI: N/m, N/A, kg, Hz, s).
    interval : dict of str to (float, float)
        95 % confidence intervals, symmetric in the fit's scale (log for positive parameters, so they stay
        positive), clipped at the bounds.
    covariance, correlation : ndarray
        Covariance (SI units) and correlation of the free parameters, (p, p). The covariance includes the
        inflation ``nu / (nu - 4)`` for weights estimated with ``nu`` degrees of freedom (see :func:`fit_rig`).
    chi2, dof, p_value : float, int, float
        Goodness of fit: ``chi2`` is the sum over lines of each line's residual mapped to a chi-square(2)
        quantile through its exact F(2, nu) distribution; ``dof`` = 2 x lines - free parameters;
        ``p_value`` = P(chi-square(dof) > chi2). ``chi2/dof`` near 1 for a model that fits.
    normalized_residuals : tuple of ndarray
        Per estimate, complex: (measured - fitted) H over the per-component standard error of the line,
        real and imaginary parts (each Student-t like with ``nu`` degrees of freedom for a correct model).
    units : dict of str to str
        Unit of each free parameter.
    inputs : tuple of str
        One line per estimate: the controller the fit modelled it with (given, or recorded in the
        estimate) and the periods averaged (the degrees of freedom of its weights).
    """

    rig: Rig
    names: tuple[str, ...]
    values: dict[str, float]
    std: dict[str, float]
    interval: dict[str, tuple[float, float]]
    covariance: np.ndarray
    correlation: np.ndarray
    chi2: float
    dof: int
    p_value: float
    normalized_residuals: tuple[np.ndarray, ...]
    units: dict[str, str]
    lines: int
    estimates: int
    start: dict[str, float]
    inputs: tuple[str, ...]
    _space: _Space = field(repr=False)
    _x: np.ndarray = field(repr=False)
    _cov_x: np.ndarray = field(repr=False)
    _lower: np.ndarray = field(repr=False)
    _upper: np.ndarray = field(repr=False)

    @property
    def fits(self) -> bool:
        """Whether the model is consistent with the data (``p_value >= 1e-3``)."""
        return bool(self.p_value >= MISFIT_P)

    def correlated_pairs(self, threshold: float = CORRELATED) -> list[tuple[str, str, float]]:
        """Pairs of free parameters with |correlation| above ``threshold``: not separately identifiable."""
        p = len(self.names)
        return [(self.names[i], self.names[j], float(self.correlation[i, j])) for i in range(p) for j in range(i + 1, p)
                if abs(self.correlation[i, j]) > threshold]  # fmt: skip

    def _propagate(self, evaluate: Callable[[Rig], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """``evaluate`` at the fitted rig and its standard error from the parameter covariance (central
        differences in the fit's scale, one-sided at a bound). ``evaluate`` returns a real (q, n) array."""
        centre = evaluate(self.rig)
        J = _jacobian(lambda x: evaluate(self._space.rig(self.rig, x)), self._x, self._lower, self._upper, 1e-5)
        var = np.einsum("...i,ij,...j->...", J, self._cov_x, J)
        return centre, np.sqrt(np.maximum(var, 0.0))

    @one_blas_thread
    def predict(self, controller: AnyController, freq: Any) -> tuple[np.ndarray, np.ndarray]:
        """Receptance Y/F (m/N) of the calibrated rig under ``controller`` at ``freq`` (Hz), and its standard
        error ``sqrt(E|dR|^2)`` (m/N, real) propagated from the parameter covariance."""
        _check_controller(controller, "controller")

        def evaluate(rig: Rig) -> np.ndarray:
            R = predict(rig, controller, freq)
            return np.stack([R.real, R.imag])

        (re, im), (re_std, im_std) = self._propagate(evaluate)
        return re + 1j * im, np.hypot(re_std, im_std)

    @one_blas_thread
    def coefficients(
        self, controller: AnyController, freq: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Actual stiffness k (N/m) and damping c (N s/m) that ``controller`` will show on the calibrated rig
        at ``freq`` (Hz), as an :class:`~amb_fast.Estimate` computes them (``k = rig.mass w^2 + Re F/Y``,
        ``c = Im F/Y / w``; mass loading and the transducer's coupling included), with standard errors
        ``k_std``, ``c_std`` propagated from the parameter covariance."""
        _check_controller(controller, "controller")
        (k, c), (k_std, c_std) = self._propagate(lambda rig: np.stack(_actual(rig, controller, freq)))
        return k, c, k_std, c_std

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the fitted rig to a TOML rig file (:func:`amb_fast.load_rig`, ``amb-fast design --rig`` and
        ``amb-fast run --rig`` read it): every :class:`~amb_fast.Rig` field, and a ``[fit]`` table recording
        the free parameters' values, standard errors and the goodness of fit (not read back)."""
        record: dict[str, Any] = {"free": list(self.names)}
        for n in self.names:
            record[n] = self.values[n]
            record[f"{n}_std"] = self.std[n]
        record.update(chi2=self.chi2, dof=self.dof, p_value=self.p_value, fits=self.fits, estimates=self.estimates,
                      lines=self.lines)  # fmt: skip
        return save_rig(self.rig, path, extra={"fit": record})

    def report(self) -> str:
        """A text table of the fitted parameters (value, standard error, 95 % interval, unit), the goodness
        of fit, and the pairs of parameters the data cannot tell apart."""
        out = [
            f"Rig calibrated to {self.estimates} estimate(s), {self.lines} lines, {len(self.names)} free parameter(s)",
            "",
            *self.inputs,
            "",
            f"{'parameter':<20} {'start':>12} {'value':>12} {'std':>10} {'95 % interval':>27}  unit",
        ]
        for n in self.names:
            lo, hi = self.interval[n]
            out.append(f"{n:<20} {self.start[n]:12.6g} {self.values[n]:12.6g} {self.std[n]:10.3g} "
                       f"{f'[{lo:.6g}, {hi:.6g}]':>27}  {self.units[n]}")  # fmt: skip
        if self.dof <= 0:  # as many parameters as data: nothing left to test the model with (no NaN printed)
            out += ["", f"goodness of fit     not testable: {2 * self.lines} values for {len(self.names)} free "
                        "parameters leave no degrees of freedom"]  # fmt: skip
        else:
            out += ["", f"goodness of fit     chi2 = {self.chi2:.1f} for {self.dof} degrees of freedom "
                        f"(chi2/dof = {self.chi2 / self.dof:.3f}), p = {self.p_value:.3g}"]  # fmt: skip
        if self.dof > 0 and self.fits:
            out.append("                    the model is consistent with the data")
        elif self.dof > 0:
            out.append(
                f"                    MISFIT: the model cannot fit the data (p < {MISFIT_P:g}): an effect the "
                "model leaves out (a lag, a stage switched off, a non-linearity) or standard errors that are "
                "too small; the values and errors above are not to be trusted"
            )
        tol = 1e-6 * np.maximum(1.0, np.abs(self._x))
        edge = (np.abs(self._x - self._lower) <= tol) | (np.abs(self._x - self._upper) <= tol)
        at_bound = [n for n, e in zip(self.names, edge) if e]
        if at_bound:
            out.append("")
            out.append(f"at a bound: {', '.join(at_bound)} (the data may not determine it, or the bound is too tight;"
                       " its standard error is that of the unconstrained fit)")  # fmt: skip
        pairs = self.correlated_pairs()
        if pairs:
            out.append("")
            for a, b, r in pairs:
                out.append(
                    f"{a} and {b}: correlation {r:+.3f}, not separately identifiable from these data"
                    + (" (on 1-200 Hz an amplifier lag and a dead time act alike)" if {a, b} & {"dead_time"}
                       and {a, b} & {"amp_bandwidth", "eddy_bandwidth", "sensor_bandwidth"} else "")
                )  # fmt: skip
            out.append("fix one of each pair at a value known otherwise, or add an estimate that separates them "
                       "(another gain set, a wider band)")  # fmt: skip
        return "\n".join(out)
