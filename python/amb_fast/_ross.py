"""Export of an estimate to ROSS (``ross-rotordynamics``, an optional extra) as a ``BearingElement``."""

from __future__ import annotations

import os
import sys
from typing import Any

import numpy as np

from ._validate import require


def coefficient_arrays(estimate: Any, *, smoothed: bool = False) -> dict[str, np.ndarray]:
    """The eight coefficient arrays ``kxx .. cyx`` (N/m, N s/m) over the lines, and ``frequency`` (rad/s).

    An :class:`~amb_fast.two_axis.Estimate2` gives its 2x2 matrices (``k[:, i, j]`` is ``k_ij``); a
    one-axis :class:`~amb_fast.Estimate` gives a symmetric bearing: its k and c on both axes, no cross terms.
    """
    k = estimate.k_smooth if smoothed else estimate.k
    c = estimate.c_smooth if smoothed else estimate.c
    if k.ndim == 1:  # one axis: the same on x and y, no cross terms
        k, c = (np.where(np.eye(2, dtype=bool), v[:, None, None], 0.0) for v in (k, c))
    pairs = [(i, j, f"{a}{b}") for i, a in enumerate("xy") for j, b in enumerate("xy")]
    out = {f"{q}{ab}": np.array(m[:, i, j]) for q, m in (("k", k), ("c", c)) for i, j, ab in pairs}
    out["frequency"] = 2 * np.pi * np.asarray(estimate.freq, dtype=float)
    return out


def to_ross(estimate: Any, n: int, *, smoothed: bool = False, **kwargs: Any) -> Any:
    """A ``ross.BearingElement`` at node ``n`` holding the estimate's coefficients over frequency.

    Parameters
    ----------
    estimate : Estimate2 or Estimate
        A two-axis estimate (its 2x2 K, C per line), or a one-axis one (a symmetric bearing with its
        k, c on both axes and no cross terms).
    n : int
        The rotor node of the bearing.
    smoothed : bool
        The median-filtered coefficients (``k_smooth``, ``c_smooth``) instead of the raw ones.
    **kwargs
        Passed on to ``BearingElement`` (``tag``, ``scale_factor``, ``n_link``, ...).

    The coefficients are ROSS's: the force on the shaft is ``-K q - C dq/dt`` with ``K[i, j] = k_ij``
    (N/m, N s/m), and the frequency axis is the estimate's lines in rad/s. In ROSS >= 3 (Python >= 3.12)
    that axis is the whirl frequency, which is what the identified coefficients depend on. In ROSS 2
    (Python 3.11) a bearing's only frequency axis is the rotor speed: ROSS evaluates the table at the
    running speed, so the element then serves synchronous response (whirl at the running speed, as in
    unbalance response), where the two coincide. The element interpolates the identified values
    exactly (linearly between lines; ROSS's own smoothing spline would not pass through them) and holds
    the edge values outside the band: run the rotor within the identified band.
    """
    ross = import_ross()
    require(isinstance(n, (int, np.integer)) and n >= 0, "n", n, "a rotor node number >= 0")
    arrays = coefficient_arrays(estimate, smoothed=smoothed)
    omega = arrays["frequency"]
    require(omega.size >= 2, "estimate lines", omega.size, "at least 2 for ROSS")
    element = ross.BearingElement(n=int(n), **arrays, **kwargs)
    # ROSS fits a smoothing spline through the table (UnivariateSpline with its default smoothing), which
    # does not pass through the identified values; interpolate them exactly instead: linearly between
    # lines, the edge values held outside the band.
    from scipy.interpolate import interp1d

    for name, values in arrays.items():
        if name != "frequency" and hasattr(element, f"{name}_interpolated"):
            exact = interp1d(omega, values, kind="linear", bounds_error=False, fill_value=(values[0], values[-1]))
            setattr(element, f"{name}_interpolated", exact)
    return element


def import_ross(what: str = "to_ross") -> Any:
    """``import ross``, with the REFPROP banner that a C library among its dependencies (CoolProp, through
    ccp) prints to the process's standard output on first import silenced: it is about fluid properties,
    nothing a bearing export needs, and it would land in the middle of the caller's output."""
    if sys.modules.get("ross") is not None:
        return sys.modules["ross"]
    sys.stdout.flush()
    try:
        saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    except OSError:  # pragma: no cover - no file descriptor 1 (some embedded interpreters)
        saved = null = -1
    try:
        if saved >= 0:
            os.dup2(null, 1)
        import ross
    except ImportError as error:  # pragma: no cover - only without the extra
        raise ImportError(f"{what} needs ROSS: pip install 'amb_fast[ross]' (ross-rotordynamics)") from error
    finally:
        if saved >= 0:
            os.dup2(saved, 1)
            os.close(saved)
            os.close(null)
    return ross
