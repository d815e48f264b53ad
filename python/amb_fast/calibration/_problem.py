"""The least-squares problem that :func:`fit_rig` solves: which rig fields can be fitted and on what
scale (``_Space``), their start values and bounds, the estimates as weighted data (``_Data``), and the
exact loop model F/Y evaluated for a rig (``_Model``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._experiment import actual_coefficients
from .._linear import controller_matrices, is_controller, plant_responses, predict, state_response, transducer_response
from .._params import Rig
from ..controllers import as_controller

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


def _check_rig(rig: Any) -> None:
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be an amb_fast.Rig, got {type(rig).__name__}")


def _check_controller(controller: Any, name: str) -> None:
    if not is_controller(controller):
        raise ValueError(f"{name} must be a PID or an amb_fast.Controller, got {type(controller).__name__}")


def _as_list(value: Any, kind: Callable[[Any], bool]) -> list[Any]:
    return list(value) if isinstance(value, (list, tuple)) and not kind(value) else [value]


def _names(free: Any) -> Any:
    """``free`` with a comma-separated string (as the command line gives it) split into names."""
    return [n.strip() for n in free.split(",") if n.strip()] if isinstance(free, str) else free


def _actual(rig: Rig, controller: Any, freq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Actual stiffness k (N/m) and damping c (N s/m) at ``freq`` (Hz), as an estimate computes them from
    :func:`amb_fast.predict`: ``k = rig.mass w^2 + Re F/Y``, ``c = Im F/Y / w``."""
    return actual_coefficients(1.0 / predict(rig, controller, freq), np.asarray(freq, dtype=float), rig.mass)


def _jacobian(
    function: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lower: np.ndarray, upper: np.ndarray, step: float
) -> np.ndarray:
    """d function / d x (on a last axis) by central differences of relative ``step``, one-sided at a bound."""
    columns = []
    for j in range(x.size):
        h = step * max(1.0, abs(x[j]))
        up, down = x.copy(), x.copy()
        up[j] = min(x[j] + h, upper[j])
        down[j] = max(x[j] - h, lower[j])
        columns.append((function(up) - function(down)) / (up[j] - down[j]))
    return np.stack(columns, axis=-1)


def _free_start(rig: Rig, free: Sequence[str] | Mapping[str, float]) -> dict[str, float]:
    free = _names(free)
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
        if name == "kyy":
            lo, hi = (-np.inf, 0.0) if start[name] < 0 else (0.0, np.inf)
        else:
            ceiling = {"force_coupling_tau": 1e3, "dead_time": 100 / fs}.get(name, np.inf)
            lo, hi = 0.0, max(20 * fs if name.endswith("_bandwidth") else ceiling, 2 * start[name])
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
            G = D[0, 0] + (state_response(A, B, C, self.z[rows])[0, 0] if A.size else 0.0)
            self.G.append(G)

    def __call__(self, rig: Rig) -> list[np.ndarray]:
        Pf, Pu = plant_responses(rig, self.fs, self.freq)
        Tr = transducer_response(rig, self.fs, self.z)
        return [(1.0 - Pu[rows] * G) * Tr[rows] / Pf[rows] for rows, G in zip(self.index, self.G)]


def same_controller(a: Any, b: Any, freq: np.ndarray, rtol: float = 1e-9) -> bool:
    """Whether two controllers have one ``fs`` and the same response (delay included) at ``freq`` (Hz),
    to ``rtol`` of the largest |G|: a PID and its Controller are the same controller."""
    ca, cb = as_controller(a, "controller"), as_controller(b, "controller")
    if ca.fs != cb.fs:
        return False
    f = freq[freq < ca.fs / 2] if freq.size else np.array([1.0])
    ga, gb = ca.response(f), cb.response(f)
    return bool(np.max(np.abs(ga - gb), initial=0.0) <= rtol * max(np.max(np.abs(ga), initial=0.0), 1e-300))
