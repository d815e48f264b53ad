"""The :class:`Controller`: a causal SISO discrete LTI controller, its contract, parameters and algebra.

The class (its fields and checks, its constructors from raw representations: ``from_tf``, ``from_zpk``,
..., its state space, transfer function and responses, its named parameters, its operators and display),
the combinations it is built from (:func:`series`, :func:`parallel`) and the blocks without states
(:func:`gain`, :func:`pure_delay`). The realisations are in ``_statespace``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from numbers import Real
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validate import delay_samples, integer, real, require
from ._statespace import (
    MAX_ORDER,
    Matrices,
    _conjugate_pairs,
    _delay_ss,
    _discretise,
    _join,
    _proper_pair,
    _real_array,
    _sections_ss,
    _static,
    _zpk_ss,
)

Poly = tuple[float, ...]

# Leaves are rebuilt by kind: kind -> function(controller, **new local params) -> Controller. Kept in a
# module-level table (not closures) so that a Controller pickles and can go to a process pool or dask.
_REBUILDERS: dict[str, Callable[..., Controller]] = {}
# Kinds whose single parameter is "gain" (numbered together: gain, gain2, ...), and the raw representations.
_GAIN_KINDS = ("gain", "tf", "zpk", "ss", "sos", "continuous")
_RAW_KINDS = ("tf", "zpk", "ss", "sos", "continuous")


# ------------------------------------------------------------------------------------------------ the class
def _poly_tuple(poly: ArrayLike) -> Poly:
    return tuple(float(v) for v in np.ravel(poly))


@dataclass(frozen=True)
class Controller:
    """A causal SISO discrete LTI controller from measured displacement e (m) to current command (A).

    ``x[k+1] = A x[k] + B e[k]``, ``u[k] = C x[k] + D e[k]``, and the command ``i[k] = u[k - delay]``:
    a state space of ``order`` states (at most 24) plus a whole-sample computation ``delay``. Frozen,
    hashable and compared by value; build it with a constructor (:meth:`from_tf`, :meth:`from_zpk`,
    :meth:`from_ss`, :meth:`from_sos`, :meth:`from_continuous`, :meth:`from_control`), a block
    (:func:`notch`, :func:`low_pass`, :func:`lead_lag`, :func:`second_order`, :func:`gain`,
    :func:`pid_controller` / ``PID.to_controller()``) or by combining others: ``a * b`` in series,
    ``a + b`` in parallel, ``2.0 * a`` scaled, all at one ``fs``. Open-loop unstable controllers (an
    integrator) are allowed.

    Realisation: from a transfer function, zeros/poles/gain or second-order sections the state space
    is a series of first- and second-order sections (conjugate pole pairs, each with its nearest
    zeros), each in controllable canonical form, never the companion form of a high-order polynomial;
    a state space given to :meth:`from_ss` is kept as it is. A series stacks the parts' states
    block-triangularly, a parallel block-diagonally (a branch's extra delay as a shift register).

    Parameters for sweeps (:attr:`params`, :meth:`with_params`), named by this rule:

    - a block's own parameters are ``<block>_<param>``: ``notch_freq``, ``notch_width``,
      ``notch_depth``, ``low_pass_freq``, ``low_pass_damping``, ``lead_lag_gain``, ``lead_lag_zero``,
      ``lead_lag_pole``, ``second_order_num_freq``, ...;
    - the PID's are unprefixed: ``kp``, ``ki``, ``kd``, ``derivative_cutoff`` (``inf`` for no
      derivative filter);
    - a gain block has ``gain``, and so has a controller made from a raw representation (``from_tf``,
      ``from_zpk``, ``from_ss``, ``from_sos``, ``from_continuous``, ``from_control``): an overall
      multiplier of what was given, 1.0 at first;
    - in a combination, counted left to right, the n-th block (n >= 2) of a kind gets the kind
      numbered: ``notch2_freq``, ``gain2``, ``pid2_kp``. Raw representations count as gains.

    Attributes
    ----------
    fs : float
        Sampling frequency, Hz.
    delay : int
        Whole-sample computation delay, samples (not part of the state space).
    """

    fs: float
    delay: int
    _a: Poly
    _b: Poly
    _c: Poly
    _d: float
    _continuous: tuple[Poly, Poly] | None = None
    _kind: str = "ss"
    _local: tuple[tuple[str, float], ...] = ()
    _parts: tuple[Controller, ...] = ()
    _fixed: tuple[Any, ...] = field(default=(), repr=False)

    __array_ufunc__ = None  # numpy scalars and arrays defer to the operators below (2.0 * c, np.float64(2) * c)

    def __post_init__(self) -> None:
        object.__setattr__(self, "fs", real("fs", self.fs, "Hz", positive=True))
        object.__setattr__(self, "delay", delay_samples("delay", self.delay))
        n = len(self._b)
        require(n <= MAX_ORDER, "order", n, f"<= {MAX_ORDER} states (the delay not counted)")
        values = (*self._a, *self._b, *self._c, self._d)
        require(all(math.isfinite(v) for v in values), "state space", self._kind, "finite (no NaN or inf)")

    # ---- construction from matrices
    @classmethod
    def _make(
        cls, ss: Matrices, fs: float, delay: int, *, continuous: tuple[ArrayLike, ArrayLike] | None = None,
        kind: str = "ss", local: tuple[tuple[str, float], ...] = (), parts: tuple[Controller, ...] = (),
        fixed: tuple[Any, ...] = (),
    ) -> Controller:  # fmt: skip
        A, B, C, D = (_poly_tuple(m) for m in ss)  # fs and delay are checked by __post_init__
        cont = None if continuous is None else (_poly_tuple(continuous[0]), _poly_tuple(continuous[1]))
        return cls(fs, delay, A, B, C, D[0], cont, kind, local, parts, fixed)

    @classmethod
    def _raw(
        cls, kind: str, ss: Matrices, fs: float, delay: int, continuous: tuple[np.ndarray, np.ndarray] | None = None
    ) -> Controller:
        """A leaf from a raw representation, with the overall multiplier ``gain`` = 1."""
        base = cls._make(ss, fs, delay, continuous=continuous)
        return cls._make(ss, fs, delay, continuous=continuous, kind=kind, local=(("gain", 1.0),), fixed=(base,))

    # ---- construction from raw representations, each a leaf whose one parameter is the multiplier ``gain``
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
        if poles.size > MAX_ORDER:
            raise ValueError(f"p must be at most {MAX_ORDER} poles (the largest controller order), got {poles.size}")
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
        if ss[0].shape[0] > MAX_ORDER:
            raise ValueError(f"sos must be of total order <= {MAX_ORDER}, got order {ss[0].shape[0]}")
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
        if n > MAX_ORDER:
            raise ValueError(f"A must be of order <= {MAX_ORDER} (the largest controller order), got order {n}")
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
        delay_samples("delay", delay)
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

    # ---- the contract
    @property
    def order(self) -> int:
        """Number of states of A (the delay not counted)."""
        return len(self._b)

    def to_ss(self) -> Matrices:
        """``(A (n, n), B (n, 1), C (1, n), D (1, 1))``, float64, without the delay."""
        n = self.order
        return (
            np.array(self._a, dtype=float).reshape(n, n),
            np.array(self._b, dtype=float).reshape(n, 1),
            np.array(self._c, dtype=float).reshape(1, n),
            np.array([[self._d]]),
        )

    def to_tf(self) -> tuple[np.ndarray, np.ndarray]:
        """``(num, den)`` in z, highest power first, ``den[0] = 1``, equal lengths, delay included
        (a delay of d multiplies den by z^d)."""
        A, B, C, D = self.to_ss()
        # den = det(zI - A); num = den * (D + C B z^-1 + C A B z^-2 + ...) truncated: the Markov parameters
        # keep exact zeros exact (a strictly proper controller's leading coefficients), unlike ss2tf.
        den = np.real(np.poly(A)) if self.order else np.ones(1)
        markov, x = [D[0, 0]], B[:, 0]
        for _ in range(self.order):
            markov.append(float(C[0] @ x))
            x = A @ x
        num = np.convolve(den, markov)[: self.order + 1]
        den = np.concatenate([den, np.zeros(self.delay)])
        return np.concatenate([np.zeros(den.size - num.size), num]), den

    def response(self, freq: ArrayLike) -> np.ndarray:
        """G(e^{jwT}) z^-delay (A/m) at ``freq`` (Hz), complex, in the shape of ``freq``."""
        f = np.asarray(freq, dtype=float)
        require(bool(np.all(np.isfinite(f))), "freq", freq, "finite (Hz)")
        z = np.exp(2j * np.pi * f.ravel() / self.fs)
        A, B, C, D = self.to_ss()
        G = np.full(z.shape, D[0, 0], dtype=complex)
        if self.order:
            M = z[:, None, None] * np.eye(self.order) - A
            X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (z.size, *B.shape)))
            G += np.einsum("n,fn->f", C[0], X[:, :, 0])
        return (G * z ** (-self.delay)).reshape(f.shape)

    @property
    def continuous(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The continuous design ``(num, den)`` in s (highest power first) when known, else None. The
        computation delay is not part of it."""
        if self._continuous is None:
            return None
        return np.array(self._continuous[0]), np.array(self._continuous[1])

    def continuous_response(self, freq: ArrayLike) -> np.ndarray:
        """G(jw) of the continuous design at ``freq`` (Hz), in the shape of ``freq``."""
        if self._continuous is None:
            raise ValueError(f"controller {self!r} has no continuous design (made from a discrete representation)")
        s = 2j * np.pi * np.asarray(freq, dtype=float)
        num, den = self._continuous
        return np.polyval(num, s) / np.polyval(den, s)

    # ---- parameters
    def _leaves(self) -> list[Controller]:
        if self._kind in ("series", "parallel"):
            return [leaf for part in self._parts for leaf in part._leaves()]
        return [self]

    def _names(self) -> list[list[tuple[str, str]]]:
        """For each leaf, (full name, local name) of its parameters, by the naming rule."""
        counts: dict[str, int] = {}
        names = []
        for leaf in self._leaves():
            group = "gain" if leaf._kind in _GAIN_KINDS else leaf._kind
            counts[group] = counts.get(group, 0) + 1
            n = counts[group]
            own = []
            for local, _ in leaf._local:
                if group == "gain":
                    full = "gain" if n == 1 else f"gain{n}"
                elif group == "pid":
                    full = local if n == 1 else f"pid{n}_{local}"
                else:
                    full = f"{group}_{local}" if n == 1 else f"{group}{n}_{local}"
                own.append((full, local))
            names.append(own)
        return names

    @property
    def params(self) -> dict[str, float]:
        """The named design parameters (see the class docstring for the naming rule)."""
        return {
            full: value
            for leaf, names in zip(self._leaves(), self._names())
            for (full, _), (_, value) in zip(names, leaf._local)
        }

    def with_params(self, **values: float) -> Controller:
        """A copy rebuilt with some parameters changed, e.g. ``with_params(kp=2600.0, notch_freq=650.0)``."""
        names = self._names()
        known = [full for own in names for full, _ in own]
        unknown = sorted(set(values) - set(known))
        if unknown:
            raise ValueError(
                f"unknown controller parameter(s) {', '.join(unknown)}; known: {', '.join(known) or 'none'}"
            )
        leaves = self._leaves()
        rebuilt = []
        for leaf, own in zip(leaves, names):
            changed = {local: values[full] for full, local in own if full in values}
            rebuilt.append(_REBUILDERS[leaf._kind](leaf, **{**dict(leaf._local), **changed}) if changed else leaf)
        return self._reassemble(iter(rebuilt))

    def _reassemble(self, leaves: Any) -> Controller:
        if self._kind in ("series", "parallel"):
            return _combine([part._reassemble(leaves) for part in self._parts], self._kind)
        leaf: Controller = next(leaves)
        return leaf

    # ---- algebra: a number is a gain block at this fs; a PID composes as its Controller
    def _operand(self, other: Any) -> Controller | None:
        other = _converted(other)
        if isinstance(other, Controller):
            return other
        return gain(float(other), self.fs) if _is_number(other) else None

    def __mul__(self, other: Any) -> Controller:
        block = self._operand(other)
        return NotImplemented if block is None else series(self, block)

    def __rmul__(self, other: Any) -> Controller:
        block = self._operand(other)
        return NotImplemented if block is None else series(block, self)

    def __add__(self, other: Any) -> Controller:
        if _is_number(other) and other == 0:
            return self  # so that sum(controllers) works
        block = self._operand(other)
        return NotImplemented if block is None else parallel(self, block)

    def __radd__(self, other: Any) -> Controller:
        if _is_number(other) and other == 0:
            return self
        block = self._operand(other)
        return NotImplemented if block is None else parallel(block, self)

    def __neg__(self) -> Controller:
        return -1.0 * self

    def __sub__(self, other: Any) -> Controller:
        other = _converted(other)
        return self + (-1.0) * other if isinstance(other, Controller) or _is_number(other) else NotImplemented

    # ---- display
    def _describe(self, top: bool = False) -> str:
        if self._kind in ("series", "parallel"):
            inner = (" * " if self._kind == "series" else " + ").join(p._describe() for p in self._parts)
            return inner if top or self._kind == "series" else f"({inner})"
        shown = ", ".join(f"{name}={value:.6g}" for name, value in self._local)
        if self._kind == "gain":
            shown = f"{self._d:.6g}"
        if self._kind in _RAW_KINDS:
            shown = f"order={self.order}" + (f", {shown}" if shown else "")
        if self.delay:
            shown += f", delay={self.delay}" if shown else f"{self.delay}"
        return f"{self._kind}({shown})"

    def __repr__(self) -> str:
        return f"Controller({self._describe(top=True)}; fs={self.fs:g} Hz, order={self.order}, delay={self.delay})"


# ---------------------------------------------------------------------------------------------- combinations
def as_controller(value: Any, name: str) -> Controller:
    """``value`` as a :class:`Controller`: a Controller as it is, a PID (anything with ``to_controller``)
    converted; else a ValueError naming ``name``."""
    converted = _converted(value)
    if isinstance(converted, Controller):
        return converted
    raise ValueError(f"{name} must be a PID or an amb_fast.Controller, got {type(value).__name__}")


def _converted(block: Any) -> Any:
    """A PID (anything with ``to_controller``) as its Controller; anything else as it is (checked later)."""
    convert = getattr(block, "to_controller", None)
    return convert() if not isinstance(block, Controller) and callable(convert) else block


def _is_number(value: Any) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def _polymul(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """``np.polymul``'s numbers without its two poly1d objects (each input's leading zeros trimmed, all
    zeros kept as ``[0]``): 40 us a call in sweeps that rebuild a controller per point."""

    def trimmed(given: ArrayLike) -> np.ndarray:
        p = np.atleast_1d(given)
        nonzero = np.flatnonzero(p)
        return p[nonzero[0] :] if nonzero.size else np.zeros(1, dtype=p.dtype)

    return np.convolve(trimmed(a), trimmed(b))


def _combine(blocks: Sequence[Controller], kind: str) -> Controller:
    """The blocks (PIDs converted) in series or in parallel, nested combinations of the same kind flattened."""
    what = "series" if kind == "series" else "parallel connection"
    require(len(blocks) >= 1, "blocks", blocks, "at least one Controller")
    blocks = tuple(_converted(b) for b in blocks)
    for block in blocks:
        require(isinstance(block, Controller), "blocks", block, f"Controllers or PIDs (in a {what})")
    rates = sorted({b.fs for b in blocks})
    require(len(rates) == 1, "fs", rates, f"the same for every block of a {what}")
    if len(blocks) == 1:
        return blocks[0]
    parts = tuple(p for b in blocks for p in (b._parts if b._kind == kind else (b,)))
    # in parallel, the common delay is the result's; the rest of a branch's is a shift register in series
    delay = sum(p.delay for p in parts) if kind == "series" else min(p.delay for p in parts)
    ss: Matrices | None = None
    for p in parts:
        part = p.to_ss()
        if kind == "parallel" and p.delay > delay:
            part = _join(part, _delay_ss(p.delay - delay), series=True)
        ss = part if ss is None else _join(ss, part, series=kind == "series")
    assert ss is not None
    require(ss[0].shape[0] <= MAX_ORDER, "order", ss[0].shape[0], f"<= {MAX_ORDER} for the {what}")
    continuous = None
    if all(p._continuous is not None for p in parts):  # the product or the sum of the continuous designs
        num, den = (np.ones(1) if kind == "series" else np.zeros(1)), np.ones(1)
        for p in parts:
            assert p._continuous is not None
            pn, pd = p._continuous
            if kind == "series":
                num, den = _polymul(num, pn), _polymul(den, pd)
            else:
                num, den = np.polyadd(_polymul(num, pd), _polymul(pn, den)), _polymul(den, pd)
        continuous = (num, den)
    return Controller._make(ss, fs=rates[0], delay=delay, continuous=continuous, kind=kind, parts=parts)


def series(*blocks: Controller) -> Controller:
    """The blocks in series (``a * b * ...``): responses multiply, delays add. Equal ``fs`` required.

    The continuous design is kept (the product) when every block has one.
    """
    return _combine(blocks, "series")


def parallel(*blocks: Controller) -> Controller:
    """The blocks in parallel (``a + b + ...``): responses add. Equal ``fs`` required.

    Each branch keeps its own delay: the common part becomes the result's ``delay`` and the rest of a
    branch's delay is realised as extra states (a shift register). The continuous design is kept (the
    sum) when every block has one.
    """
    return _combine(blocks, "parallel")


def gain(value: float, fs: float = 4000.0) -> Controller:
    """A static gain ``value`` (no states); parameter ``gain``. Continuous prototype: ``value``.

    Parameters
    ----------
    value : float
        The gain (A/m alone; dimensionless in a series with other blocks).
    fs : float
        Sampling frequency, Hz.
    """
    k = real("value", value, "gain")
    return Controller._make(_static(k), fs, 0, continuous=([k], [1.0]), kind="gain", local=(("gain", k),))


def pure_delay(samples: int, fs: float = 4000.0) -> Controller:
    """z^-samples: a whole-sample delay with no states and no parameters (continuous prototype 1)."""
    d = integer("samples", samples, 0)
    return Controller._make(_static(1.0), fs, d, continuous=([1.0], [1.0]), kind="delay")


def _rebuild_raw(leaf: Controller, gain: float) -> Controller:
    base: Controller = leaf._fixed[0]
    k = real("gain", gain, "multiplier")
    A, B, C, D = base.to_ss()
    continuous = None
    if base._continuous is not None:
        continuous = (tuple(k * v for v in base._continuous[0]), base._continuous[1])
    return Controller._make(
        (A, B, k * C, k * D),
        base.fs,
        base.delay,
        continuous=continuous,
        kind=leaf._kind,
        local=(("gain", k),),
        fixed=(base,),
    )


_REBUILDERS["gain"] = lambda leaf, **p: gain(p["gain"], leaf.fs)
for _kind in _RAW_KINDS:
    _REBUILDERS[_kind] = _rebuild_raw
