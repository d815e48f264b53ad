"""Weighted least squares of the exact loop model against measured estimates: :func:`fit_rig`."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Union

import numpy as np
from scipy import optimize, stats

from .._blas import one_blas_thread
from .._experiment import Estimate
from .._linear import (
    AnyController,
    _plant_responses,
    _response,
    controller_matrices,
    is_controller,
    predict,
    transducer_response,
)
from .._params import Rig

# Rig fields the linear response depends on: (scale of the fit, unit). "log": fitted as ln(value)
# (strictly positive); "linear": fitted as value / scale (kyy keeps its sign; mass_loading and
# dead_time may be 0 and are bounded below by 0).
FITTABLE: dict[str, tuple[str, str]] = {
    "mass": ("log", "kg"),
    "kyy": ("linear", "N/m"),
    "kiy": ("log", "N/A"),
    "amp_bandwidth": ("log", "Hz"),
    "eddy_bandwidth": ("log", "Hz"),
    "sensor_bandwidth": ("log", "Hz"),
    "mass_loading": ("linear", "kg"),
    "force_coupling_tau": ("log", "s"),
    "dead_time": ("linear", "s"),
}
# Smallest scale of the linear parameters that may start at 0.
_LINEAR_SCALE = {"kyy": 1.0, "mass_loading": 0.01, "dead_time": 1e-4}
_OPTIONAL = ("amp_bandwidth", "eddy_bandwidth", "sensor_bandwidth", "force_coupling_tau")
CORRELATED = 0.9  # |correlation| above which two parameters are named as not separately identifiable
MISFIT_P = 1e-3  # p-value below which the model is said not to fit

ControllerArg = Union[AnyController, Sequence[AnyController]]


@dataclass(frozen=True)
class _Space:
    """How the free parameters map to the optimiser's coordinates x (and back)."""

    names: tuple[str, ...]
    kinds: tuple[str, ...]
    scales: tuple[float, ...]

    def to_x(self, values: Sequence[float]) -> np.ndarray:
        return np.array([np.log(v) if k == "log" else v / s for v, k, s in zip(values, self.kinds, self.scales)])

    def to_values(self, x: np.ndarray) -> np.ndarray:
        return np.array([np.exp(v) if k == "log" else v * s for v, k, s in zip(x, self.kinds, self.scales)])

    def derivative(self, x: np.ndarray) -> np.ndarray:
        """d value / d x for each parameter."""
        return np.array([np.exp(v) if k == "log" else s for v, k, s in zip(x, self.kinds, self.scales)])

    def rig(self, base: Rig, x: np.ndarray) -> Rig:
        changes: dict[str, Any] = {n: float(v) for n, v in zip(self.names, self.to_values(x))}
        return replace(base, **changes)


@dataclass(frozen=True)
class RigFit:
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
        J = np.empty((*centre.shape, len(self.names)))
        for j in range(len(self.names)):
            h = 1e-5 * max(1.0, abs(self._x[j]))
            up, down = self._x.copy(), self._x.copy()
            up[j] = min(self._x[j] + h, self._upper[j])
            down[j] = max(self._x[j] - h, self._lower[j])
            J[..., j] = (evaluate(self._space.rig(self.rig, up)) - evaluate(self._space.rig(self.rig, down))) / (
                up[j] - down[j]
            )
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
        w = 2 * np.pi * np.asarray(freq, dtype=float)

        def evaluate(rig: Rig) -> np.ndarray:
            H = 1.0 / predict(rig, controller, freq)
            return np.stack([rig.mass * w**2 + H.real, H.imag / w])

        (k, c), (k_std, c_std) = self._propagate(evaluate)
        return k, c, k_std, c_std

    def report(self) -> str:
        """A text table of the fitted parameters (value, standard error, 95 % interval, unit), the goodness
        of fit, and the pairs of parameters the data cannot tell apart."""
        out = [
            f"Rig calibrated to {self.estimates} estimate(s), {self.lines} lines, {len(self.names)} free parameter(s)",
            "",
            f"{'parameter':<20} {'start':>12} {'value':>12} {'std':>10} {'95 % interval':>27}  unit",
        ]
        for n in self.names:
            lo, hi = self.interval[n]
            out.append(f"{n:<20} {self.start[n]:12.6g} {self.values[n]:12.6g} {self.std[n]:10.3g} "
                       f"{f'[{lo:.6g}, {hi:.6g}]':>27}  {self.units[n]}")  # fmt: skip
        ratio = self.chi2 / self.dof if self.dof > 0 else float("nan")
        out += ["", f"goodness of fit     chi2 = {self.chi2:.1f} for {self.dof} degrees of freedom "
                    f"(chi2/dof = {ratio:.3f}), p = {self.p_value:.3g}"]  # fmt: skip
        if self.fits:
            out.append("                    the model is consistent with the data")
        else:
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


def _check_controller(controller: Any, name: str) -> None:
    if not is_controller(controller):
        raise ValueError(f"{name} must be a PID or an amb_fast.Controller, got {type(controller).__name__}")


def _as_list(value: Any, kind: Callable[[Any], bool]) -> list[Any]:
    if kind(value):
        return [value]
    if isinstance(value, (list, tuple)):
        return list(value)
    return [value]


def _free_start(rig: Rig, free: Sequence[str] | Mapping[str, float]) -> dict[str, float]:
    if isinstance(free, str):
        free = [n.strip() for n in free.split(",") if n.strip()]
    if not isinstance(free, (Mapping, Sequence)) or len(free) == 0:
        raise ValueError(f"free must name at least one rig field ({', '.join(FITTABLE)}), got {free!r}")
    names = list(free)
    if len(set(names)) != len(names):
        raise ValueError(f"free names a parameter twice: {names!r}")
    start: dict[str, float] = {}
    for name in names:
        if name not in FITTABLE:
            raise ValueError(
                f"free: {name!r} is not a rig parameter of the linear response; choose from {', '.join(FITTABLE)}"
            )
        value = free[name] if isinstance(free, Mapping) else getattr(rig, name)
        if value is None:
            raise ValueError(
                f"free: {name!r} is None in rig (the stage is switched off) and has no start value: set it in rig "
                f"(dataclasses.replace(rig, {name}=...)) or pass free={{{name!r}: start, ...}}"
            )
        value = float(value)
        kind = FITTABLE[name][0]
        if not np.isfinite(value) or (kind == "log" and value <= 0) or (name == "kyy" and value == 0):
            expected = "> 0" if kind == "log" else "non-zero"
            raise ValueError(f"free: the start value of {name!r} must be finite and {expected}, got {value!r}")
        if name in ("mass_loading", "dead_time") and value < 0:
            raise ValueError(f"free: the start value of {name!r} must be >= 0, got {value!r}")
        start[name] = value
    return start


def _bounds(space: _Space, start: dict[str, float], bounds: Mapping[str, tuple[float, float]] | None, fs: float):
    lower, upper = [], []
    for name, kind, scale in zip(space.names, space.kinds, space.scales):
        # Default limits keep the optimiser out of the flat regions where a stage stops acting (a lag
        # far above the band, a transducer no longer AC coupled), where it could stall.
        if name.endswith("_bandwidth"):
            lo, hi = 0.0, max(20 * fs, 2 * start[name])
        elif name == "force_coupling_tau":
            lo, hi = 0.0, max(1e3, 2 * start[name])
        elif name == "dead_time":
            lo, hi = 0.0, max(100 / fs, 2 * start[name])
        elif kind == "log":
            lo, hi = 0.0, np.inf
        elif name == "kyy":
            lo, hi = (-np.inf, 0.0) if start[name] < 0 else (0.0, np.inf)
        else:
            lo, hi = 0.0, np.inf
        if bounds is not None and name in bounds:
            try:
                given_lo, given_hi = (float(b) for b in bounds[name])
            except (TypeError, ValueError):
                raise ValueError(
                    f"bounds[{name!r}] must be a (low, high) pair of numbers, got {bounds[name]!r}"
                ) from None
            lo, hi = max(lo, given_lo), min(hi, given_hi)
            if not lo < hi or not lo <= start[name] <= hi:
                raise ValueError(f"bounds[{name!r}] must be low < high around the start value {start[name]:g}, "
                                 f"got {bounds[name]!r}")  # fmt: skip
        if kind == "log":
            lower.append(np.log(lo) if lo > 0 else -np.inf)
            upper.append(np.log(hi))
        else:
            lower.append(lo / scale)
            upper.append(hi / scale)
    if bounds is not None:
        extra = set(bounds) - set(space.names)
        if extra:
            raise ValueError(f"bounds names parameters that are not free: {sorted(extra)!r}")
    return np.array(lower), np.array(upper)


@dataclass(frozen=True)
class _Data:
    freq: np.ndarray
    H: np.ndarray
    sigma: np.ndarray  # per-component standard error of H at each line, N/m (pooled Re and Im)
    nu: int  # degrees of freedom of sigma^2: 2 (blocks - 1)
    controller: Any


def _data(estimates: Sequence[Any], controllers: Sequence[Any]) -> list[_Data]:
    out = []
    fs = {float(c.fs) for c in controllers}
    if len(fs) > 1:
        raise ValueError(f"controllers: the estimates were recorded at different sample rates fs {sorted(fs)} Hz; "
                         "fit estimates of one rig at one fs")  # fmt: skip
    for i, (est, ctrl) in enumerate(zip(estimates, controllers)):
        name = f"estimates[{i}]"
        if not all(hasattr(est, a) for a in ("freq", "H", "k_std", "c_std", "blocks")):
            raise ValueError(f"{name} must be an amb_fast.Estimate, got {type(est).__name__}")
        freq = np.asarray(est.freq, dtype=float)
        H = np.asarray(est.H, dtype=complex)
        w = 2 * np.pi * freq
        k_std, c_std = np.asarray(est.k_std, dtype=float), np.asarray(est.c_std, dtype=float)
        if not (freq.ndim == 1 and freq.size and H.shape == freq.shape == k_std.shape == c_std.shape):
            raise ValueError(f"{name}: freq, H, k_std and c_std must be 1-D arrays of one length")
        if not np.all(np.isfinite(H)) or not np.all(np.isfinite(freq)) or not np.all(freq > 0):
            raise ValueError(f"{name}: freq and H must be finite, freq > 0")
        if np.any(freq >= ctrl.fs / 2):
            raise ValueError(
                f"{name}: lines up to {freq.max():g} Hz are not below the Nyquist frequency "
                f"{ctrl.fs / 2:g} Hz of controllers[{i}] (estimate and controller of different fs?)"
            )
        if not (np.all(np.isfinite(k_std)) and np.all(np.isfinite(c_std)) and np.all(k_std > 0) and np.all(c_std > 0)):
            raise ValueError(f"{name}: k_std and c_std must be finite and > 0 (a noise-free estimate has no weights)")
        blocks = int(est.blocks)
        if blocks < 4:
            raise ValueError(f"{name}: blocks must be >= 4 (standard errors from 3 or fewer periods cannot weight "
                             f"a fit), got {blocks}")  # fmt: skip
        if getattr(est, "saturated_samples", None):
            warnings.warn(f"{name} is saturated: it is not the linear loop's estimate", UserWarning, stacklevel=3)
        # Stationary noise at a DFT line is circular complex Gaussian: Re and Im have one variance, so
        # pooling the two estimates doubles its degrees of freedom.
        sigma = np.sqrt(0.5 * (k_std**2 + (w * c_std) ** 2))
        out.append(_Data(freq, H, sigma, 2 * (blocks - 1), ctrl))
    return out


class _Model:
    """F/Y of one rig under each estimate's controller, as :func:`amb_fast.predict` gives it, with the
    plant's responses computed once for all estimates and each controller's G(z) z^-d once for all rigs:
    ``Y/F = Pf / (1 - Pu G z^-d) / transducer``."""

    def __init__(self, data: Sequence[_Data]) -> None:
        self.fs = float(data[0].controller.fs)
        self.freq, inverse = np.unique(np.concatenate([d.freq for d in data]), return_inverse=True)
        self.index = np.split(inverse, np.cumsum([d.freq.size for d in data])[:-1])
        self.z = np.exp(2j * np.pi * self.freq / self.fs)
        self.G = []
        for d, rows in zip(data, self.index):
            A, B, C, D = controller_matrices(d.controller)
            G = D[0, 0] + (_response(A, B, C, self.z[rows])[0, 0] if A.size else 0.0)
            self.G.append(G)

    def __call__(self, rig: Rig) -> list[np.ndarray]:
        Pf, Pu = _plant_responses(rig, self.fs, self.freq)
        Tr = transducer_response(rig, self.fs, self.z)
        return [(1.0 - Pu[rows] * G) * Tr[rows] / Pf[rows] for rows, G in zip(self.index, self.G)]


@one_blas_thread
def fit_rig(
    estimates: Estimate | Sequence[Estimate],
    rig: Rig,
    controllers: ControllerArg,
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
    controllers : PID or Controller, or a sequence of them
        The controller of each estimate (one per estimate, all at one ``fs``).
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
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be an amb_fast.Rig, got {type(rig).__name__}")
    est_list = _as_list(estimates, lambda v: hasattr(v, "H"))
    ctrl_list = _as_list(controllers, is_controller)
    if not est_list:
        raise ValueError("estimates must hold at least one Estimate, got none")
    for i, c in enumerate(ctrl_list):
        _check_controller(c, f"controllers[{i}]")
    if len(ctrl_list) != len(est_list):
        raise ValueError(f"controllers must give one controller per estimate: {len(est_list)} estimate(s), "
                         f"{len(ctrl_list)} controller(s)")  # fmt: skip
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

    def residuals(x: np.ndarray) -> np.ndarray:
        parts = []
        for d, H in zip(data, model_H(space.rig(rig, x))):
            e = (d.H - H) / d.sigma
            parts += [e.real, e.imag]
        return np.concatenate(parts)

    result = optimize.least_squares(residuals, x0, bounds=(lower, upper), method="trf", x_scale=1.0,
                                    xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200 * (len(names) + 1))  # fmt: skip
    x = result.x
    fitted = space.rig(rig, x)
    r = residuals(x)

    # Jacobian at the solution by central differences (one-sided at a bound).
    J = np.empty((r.size, len(names)))
    for j in range(len(names)):
        h = 1e-6 * max(1.0, abs(x[j]))
        up, down = x.copy(), x.copy()
        up[j] = min(x[j] + h, upper[j])
        down[j] = max(x[j] - h, lower[j])
        J[:, j] = (residuals(up) - residuals(down)) / (up[j] - down[j])
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
    chi2 = 0.0
    normalized: list[np.ndarray] = []
    offset = 0
    for d in data:
        n = d.freq.size
        e = r[offset : offset + n] + 1j * r[offset + n : offset + 2 * n]
        offset += 2 * n
        normalized.append(e)
        T = 0.5 * np.abs(e) ** 2
        chi2 += float(np.sum(d.nu * np.log1p(2.0 * T / d.nu)))
    lines = sum(d.freq.size for d in data)
    dof = 2 * lines - len(names)
    p_value = float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan")

    fit = RigFit(
        rig=fitted,
        names=names,
        values={n: float(v) for n, v in zip(names, values)},
        std={n: float(s) for n, s in zip(names, std_si)},
        interval={n: (float(a), float(b)) for n, a, b in zip(names, lo, hi)},
        covariance=covariance,
        correlation=correlation,
        chi2=chi2,
        dof=dof,
        p_value=p_value,
        normalized_residuals=tuple(normalized),
        units={n: FITTABLE[n][1] for n in names},
        lines=lines,
        estimates=len(data),
        start=dict(start),
        _space=space,
        _x=x,
        _cov_x=cov_x,
        _lower=lower,
        _upper=upper,
    )
    if not fit.fits:
        warnings.warn(
            f"the fitted model cannot fit the data: chi2 = {chi2:.1f} for {dof} degrees of freedom, "
            f"p = {p_value:.3g} < {MISFIT_P:g}; see RigFit.report()",
            UserWarning,
            stacklevel=2,
        )
    return fit
