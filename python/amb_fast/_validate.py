"""One way to reject bad input: name the parameter, the value and what was expected."""

from __future__ import annotations

import math
import secrets
from numbers import Integral, Real
from typing import Any

import numpy as np


def require(ok: bool, name: str, value: Any, expected: str) -> None:
    if not ok:
        raise ValueError(f"{name} must be {expected}, got {value!r}")


def real(name: str, value: Any, unit: str, *, positive: bool = False) -> float:
    """A finite real number (optionally > 0), returned as float."""
    is_number = isinstance(value, Real) and not isinstance(value, bool)
    ok = is_number and math.isfinite(value) and (not positive or value > 0)
    require(ok, name, value, f"a finite number{' > 0' if positive else ''} ({unit})")
    return float(value)


def non_negative(name: str, value: Any, unit: str) -> float:
    """A finite real number >= 0, returned as float."""
    number = real(name, value, unit)
    require(number >= 0, name, value, f">= 0 ({unit})")
    return number


def optional_positive(name: str, value: Any, unit: str) -> float | None:
    return None if value is None else real(name, value, unit, positive=True)


def integer(name: str, value: Any, minimum: int) -> int:
    ok = isinstance(value, Integral) and not isinstance(value, bool) and int(value) >= minimum
    require(ok, name, value, f"a whole number >= {minimum}")
    return int(value)


MAX_DELAY_SAMPLES = 1000  # the core's max_dead_samples: each delayed sample is a state of the loop


def delay_samples(name: str, value: Any) -> int:
    """A whole number of samples of delay, 0 to 1000: beyond, the loop's poles and steady start (cubic in its
    states) would take minutes (a mistyped delay), not a clear error."""
    samples = integer(name, value, 0)
    expected = f"at most {MAX_DELAY_SAMPLES} samples (each is a state of the loop)"
    require(samples <= MAX_DELAY_SAMPLES, name, value, expected)
    return samples


def series(name: str, values: Any) -> np.ndarray:
    """A 1-D contiguous float64 array (the core checks finiteness sample by sample as it reads)."""
    array = np.ascontiguousarray(values, dtype=np.float64)
    require(array.ndim == 1, f"{name} shape", array.shape, "one-dimensional (samples,)")
    return array


def seed_value(seed: Any) -> int:
    """A 64-bit seed for the core's noise generator; ``None`` draws a fresh one."""
    if seed is None:
        return secrets.randbits(64)
    return integer("seed", seed, 0) % 2**64


def rig_and_controller(rig: Any, controller: Any, function: str) -> None:
    """A ``TypeError`` naming the arguments when ``(rig, controller)`` are missing or swapped.

    The controller is a ``PID`` or an :class:`~amb_fast.Controller`.
    """
    from ._linear import is_controller
    from ._params import Rig

    if isinstance(rig, Rig) and is_controller(controller):
        return
    if is_controller(rig) and isinstance(controller, Rig):
        raise TypeError(f"{function}(rig, pid, ...) takes the Rig first and the controller second; got them swapped "
                        f"({type(rig).__name__}, {type(controller).__name__})")  # fmt: skip
    if not isinstance(rig, Rig):
        raise TypeError(f"{function}: rig must be an amb_fast.Rig, got {type(rig).__name__}")
    raise TypeError(f"{function}: pid must be an amb_fast.PID or Controller, got {type(controller).__name__}")
