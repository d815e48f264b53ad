"""The constructors of :class:`~amb_fast.Controller` from raw representations: a z-domain transfer
function, zeros/poles/gain, second-order sections, a discrete state space, a continuous design
(discretised and remembered) and a python-control system. Each checks its input, realises it with
``_statespace`` and makes a leaf whose one parameter is the overall multiplier ``gain``.

They are the classmethods of :class:`_Constructors`, which :class:`~amb_fast.Controller` inherits.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from .._validate import integer, real, require
from ._statespace import (
    MAX_ORDER,
    Matrices,
    _conjugate_pairs,
    _discretise,
    _proper_pair,
    _real_array,
    _sections_ss,
    _zpk_ss,
)

if TYPE_CHECKING:
    from ._controller import Controller


class _Constructors:
    """``Controller.from_tf``, ``from_zpk``, ``from_sos``, ``from_ss``, ``from_continuous``, ``from_control``."""

    if TYPE_CHECKING:  # defined by Controller (_controller.py)

        @classmethod
        def _raw(
            cls, kind: str, ss: Matrices, fs: float, delay: int, continuous: tuple[np.ndarray, np.ndarray] | None = None
        ) -> Controller: ...

    @classmethod
    def from_tf(cls, num: ArrayLike, den: ArrayLike, fs: float, delay: int = 0) -> Controller:
        """From a z-domain transfer function num(z)/den(z), positive powers, highest first.

        As ``scipy.signal.dlti`` takes it: a shorter ``num`` is padded with leading zeros, so
        ``num=[1], den=[1, -0.5]`` is ``1/(z - 0.5)``, one sample of lag in the states. The response is
        ``num(z)/den(z) z^-delay``.

        Parameters
        ----------
        num, den : array_like
            Coefficients; ``num`` no longer than ``den`` after leading zeros (causal), degree <= 24.
        fs : float
            Sampling frequency, Hz.
        delay : int
            Extra whole-sample computation delay.
        """
        n, d = _proper_pair(num, den, "z-domain transfer function")
        k = float(n[0] / d[0])
        ss = _zpk_ss(np.roots(n), np.roots(d), k) if k != 0 else _zpk_ss(np.zeros(0), np.roots(d), 0.0)
        return cls._raw("tf", ss, fs, delay)

    @classmethod
    def from_zpk(cls, z: ArrayLike, p: ArrayLike, k: float, fs: float, delay: int = 0) -> Controller:
        """From zeros ``z``, poles ``p`` (z-plane, real or in conjugate pairs, ``len(z) <= len(p) <= 24``)
        and gain ``k``: ``k prod(z - z_i) / prod(z - p_j) z^-delay``; ``fs`` in Hz."""
        zeros, poles = (np.atleast_1d(np.asarray(v, dtype=complex)) for v in (z, p))
        for name, roots, given in (("z", zeros, z), ("p", poles, p)):
            require(roots.ndim == 1 and bool(np.all(np.isfinite(roots))), name, given, "a 1-D sequence of finite roots")
            _conjugate_pairs(name, roots, given)
        require(zeros.size <= poles.size, "z", z, f"no more zeros than poles ({poles.size}): otherwise non-causal")
        require(poles.size <= MAX_ORDER, "p", poles.size, f"at most {MAX_ORDER} poles (the largest controller order)")
        return cls._raw("zpk", _zpk_ss(zeros, poles, real("k", k, "gain")), fs, delay)

    @classmethod
    def from_sos(cls, sos: ArrayLike, fs: float, delay: int = 0) -> Controller:
        """From second-order sections in series (rows ``b0 b1 b2 a0 a1 a2``, ``scipy.signal`` layout),
        realised section by section; ``fs`` in Hz. Each row is ``(b0 z^2 + b1 z + b2) / (a0 z^2 + a1 z +
        a2)``, the same as in powers of z^-1; ``a0 != 0``, or ``b0 = a0 = 0`` for a first-order section
        (as ``scipy.signal.zpk2sos(..., pairing="minimal")`` writes them)."""
        try:
            array = np.atleast_2d(np.asarray(sos, dtype=float))
        except (TypeError, ValueError):
            raise ValueError(f"sos must be an array of shape (sections, 6), got {sos!r}") from None
        require(array.ndim == 2 and array.shape[1] == 6 and array.shape[0] > 0, "sos", sos, "of shape (sections, 6)")
        require(bool(np.all(np.isfinite(array))), "sos", sos, "finite (no NaN or inf)")
        lead = [int(np.argmax(row[3:] != 0)) if np.any(row[3:] != 0) else 3 for row in array]
        causal = all(k < 3 and not np.any(row[:k]) for k, row in zip(lead, array))
        require(causal, "sos", sos, "causal in every section: a0 != 0, or b0 = a0 = 0 for a first-order one")
        ss = _sections_ss([(row[:3], row[3:]) for row in array])
        require(ss[0].shape[0] <= MAX_ORDER, "sos", ss[0].shape[0], f"of total order <= {MAX_ORDER} (its states)")
        return cls._raw("sos", ss, fs, delay)

    @classmethod
    def from_ss(cls, A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, fs: float, delay: int = 0) -> Controller:
        """From a discrete state space (kept as given): A (n, n), B (n, 1), C (1, n), D (1, 1); a 1-D B or
        C and a scalar D are read as a column, a row and 1x1. n <= 24; ``fs`` in Hz."""
        arrays = {}
        for name, value in (("A", A), ("B", B), ("C", C), ("D", D)):
            arrays[name] = _real_array(name, value, "a real matrix")
            require(bool(np.all(np.isfinite(arrays[name]))), name, value, "finite (no NaN or inf)")
        a = arrays["A"].reshape(0, 0) if arrays["A"].size == 0 else np.atleast_2d(arrays["A"])
        require(a.ndim == 2 and a.shape[0] == a.shape[1], "A", A, "square")
        n = a.shape[0]
        require(n <= MAX_ORDER, "A", n, f"of order <= {MAX_ORDER} (the largest controller order)")
        b, c, d = arrays["B"], arrays["C"], arrays["D"]
        b = b.reshape(n, 1) if b.ndim == 1 and b.size == n else b.reshape(0, 1) if n == 0 else b
        c = c.reshape(1, n) if c.ndim == 1 and c.size == n else c.reshape(1, 0) if n == 0 else c
        d = d.reshape(1, 1) if d.size == 1 else d
        require(b.shape == (n, 1), "B", B, f"of shape ({n}, 1): one input (a SISO controller)")
        require(c.shape == (1, n), "C", C, f"of shape (1, {n}): one output (a SISO controller)")
        require(d.shape == (1, 1), "D", D, "a scalar or of shape (1, 1) (a SISO controller)")
        return cls._raw("ss", (a, b, c, d), fs, delay)

    @classmethod
    def from_continuous(
        cls,
        num: ArrayLike,
        den: ArrayLike,
        fs: float,
        method: str = "tustin",
        prewarp: float | None = None,
        delay: int = 0,
    ) -> Controller:
        """Discretise a proper continuous design num(s)/den(s) (highest power first), and remember it.

        Parameters
        ----------
        num, den : array_like
            Coefficients in s; ``num`` no longer than ``den`` (proper), degree <= 24.
        fs : float
            Sampling frequency, Hz.
        method : {"tustin", "zoh", "matched"}
            Bilinear (Tustin); zero-order hold (exact for a held input); matched pole-zero
            (z = exp(sT) for every finite pole and zero, no zeros added at z = -1, DC gain matched,
            roots at s = 0 matched as s <-> (z - 1)/T), as python-control's "matched".
        prewarp : float or None
            Tustin only: the frequency, Hz (< fs/2), where the discrete response equals the continuous
            one exactly (s = 2 fw (z-1)/(z+1), fw = pi f0 / tan(pi f0/fs)).
        delay : int
            Whole-sample computation delay (not part of the continuous design).
        """
        real("fs", fs, "Hz", positive=True)
        integer("delay", delay, 0)
        n, d = _proper_pair(num, den, "continuous transfer function")
        return cls._raw("continuous", _discretise(n, d, float(fs), method, prewarp), fs, delay, (n, d))

    @classmethod
    def from_control(
        cls,
        sys: Any,
        fs: float | None = None,
        method: str = "tustin",
        prewarp: float | None = None,
        delay: int = 0,
    ) -> Controller:
        """From a python-control ``TransferFunction`` or ``StateSpace`` (SISO; needs the ``bench`` extra).

        A discrete ``sys`` keeps its coefficients: its ``dt`` must equal ``1/fs`` (``fs`` is taken from
        ``dt`` when None). A continuous one (``dt`` 0 or None) is discretised at ``fs`` by ``method`` and
        ``prewarp`` (Hz), as :meth:`from_continuous`, and remembered.
        """
        try:
            import control
        except ImportError:  # pragma: no cover - the optional extra
            raise ImportError("Controller.from_control needs python-control: pip install 'amb_fast[bench]'") from None
        require(
            isinstance(sys, (control.TransferFunction, control.StateSpace)),
            "sys",
            sys,
            "a python-control TransferFunction or StateSpace",
        )
        require(sys.ninputs == 1 and sys.noutputs == 1, "sys", sys, "SISO (one input, one output), not MIMO")
        dt = sys.dt
        discrete = dt is not None and dt is not False and dt != 0
        if discrete:
            if dt is True:
                require(fs is not None, "fs", fs, "given when sys.dt is True (unspecified sampling time)")
            elif fs is None:
                fs = 1.0 / float(dt)
            else:
                real("fs", fs, "Hz", positive=True)
                require(math.isclose(float(dt), 1.0 / fs, rel_tol=1e-12), "dt", dt, f"1/fs = {1.0 / fs!r} s")
            assert fs is not None
            if isinstance(sys, control.StateSpace):
                return cls.from_ss(sys.A, sys.B, sys.C, sys.D, fs, delay)
            return cls.from_tf(sys.num[0][0], sys.den[0][0], fs, delay)
        require(fs is not None, "fs", fs, "given for a continuous sys (the sampling frequency to discretise at, Hz)")
        assert fs is not None
        if isinstance(sys, control.StateSpace):
            from scipy import signal  # on first use: importing it takes half a second

            num, den = signal.ss2tf(sys.A, sys.B, sys.C, sys.D)
            num = num[0]
        else:
            num, den = sys.num[0][0], sys.den[0][0]
        return cls.from_continuous(num, den, fs, method, prewarp, delay)
