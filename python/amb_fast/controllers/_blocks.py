"""Blocks of the field, each a :class:`Controller` discretised from a documented continuous prototype."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .._validate import integer, real, require
from ._controller import _REBUILDERS, Controller
from ._statespace import MAX_ORDER, _below_nyquist, _discretise

if TYPE_CHECKING:
    from .._params import PID

SQRT_HALF = math.sqrt(0.5)


def _block(
    kind: str, num: list[float], den: list[float], fs: float, prewarp: float, local: dict[str, float], fixed: tuple = ()
) -> Controller:
    """A block: the continuous prototype ``num/den`` discretised by Tustin, prewarped at ``prewarp`` (Hz)."""
    real("fs", fs, "Hz", positive=True)
    _below_nyquist("freq", prewarp, fs)
    n, d = np.asarray(num, dtype=float), np.asarray(den, dtype=float)
    ss = _discretise(n, d, float(fs), "tustin", prewarp)
    return Controller._make(
        ss, fs, 0, continuous=(n, d), kind=kind, local=tuple((k, float(v)) for k, v in local.items()), fixed=fixed
    )


def lead_lag(gain: float = 1.0, zero: float = 100.0, pole: float = 1000.0, fs: float = 4000.0) -> Controller:
    """A lead (``zero < pole``) or lag (``zero > pole``) compensator.

    Continuous prototype ``gain (1 + s/wz) / (1 + s/wp)``, ``wz = 2 pi zero``, ``wp = 2 pi pole``:
    DC gain ``gain``, high-frequency gain ``gain pole/zero``, the largest phase change at
    ``sqrt(zero pole)``. Tustin, prewarped at ``sqrt(zero pole)`` (the centre, where the discrete
    response equals the continuous one exactly). Parameters ``lead_lag_gain``, ``lead_lag_zero``,
    ``lead_lag_pole``.

    Parameters
    ----------
    gain : float
        DC gain (A/m alone; dimensionless in a series).
    zero, pole : float
        Corner frequencies of the zero and the pole, Hz, each > 0 and below fs/2.
    fs : float
        Sampling frequency, Hz.
    """
    k = real("gain", gain, "DC gain")
    fz, fp = real("zero", zero, "Hz", positive=True), real("pole", pole, "Hz", positive=True)
    _below_nyquist("zero", fz, fs)
    _below_nyquist("pole", fp, fs)
    wz, wp = 2 * math.pi * fz, 2 * math.pi * fp
    local = {"gain": k, "zero": fz, "pole": fp}
    return _block("lead_lag", [k / wz, k], [1 / wp, 1.0], fs, math.sqrt(fz * fp), local)


def notch(freq: float, width: float | None = None, depth: float = 0.01, fs: float = 4000.0) -> Controller:
    """A notch (band-stop) filter.

    Continuous prototype ``(s^2 + 2 depth zeta w0 s + w0^2) / (s^2 + 2 zeta w0 s + w0^2)`` with
    ``w0 = 2 pi freq`` and ``zeta = width / (2 freq)``: gain 1 at DC and at high frequency, ``depth``
    at the centre. Tustin, prewarped at ``freq``, so the discrete gain at ``freq`` is exactly
    ``depth``. Parameters ``notch_freq``, ``notch_width``, ``notch_depth``.

    Parameters
    ----------
    freq : float
        Centre frequency, Hz (below fs/2).
    width : float or None
        Bandwidth of the poles, Hz (2 zeta w0 / 2 pi): for a full notch (``depth=0``) exactly the
        -3 dB bandwidth; the quality factor is ``freq / width``. None: ``freq / 5`` (Q = 5).
    depth : float
        Gain at the centre as a ratio (0.01 = -40 dB; 0 = a full notch; > 1 makes a peak), >= 0.
    fs : float
        Sampling frequency, Hz.
    """
    f0 = real("freq", freq, "Hz", positive=True)
    bw = f0 / 5 if width is None else real("width", width, "Hz", positive=True)
    g = real("depth", depth, "gain at the centre")
    require(g >= 0, "depth", depth, ">= 0 (the gain at the centre, a ratio)")
    w0, zeta = 2 * math.pi * f0, bw / (2 * f0)
    num = [1.0, 2 * g * zeta * w0, w0**2]
    den = [1.0, 2 * zeta * w0, w0**2]
    return _block("notch", num, den, fs, f0, {"freq": f0, "width": bw, "depth": g})


def low_pass(freq: float, order: int = 1, damping: float | None = None, fs: float = 4000.0) -> Controller:
    """A low-pass filter of unit DC gain with its corner at ``freq``.

    Continuous prototype: order 1, ``w / (s + w)``; order 2, ``w^2 / (s^2 + 2 damping w s + w^2)``
    (damping 1/sqrt(2) by default: Butterworth, -3 dB at ``freq``); order >= 3, Butterworth
    (``scipy.signal.butter``, -3 dB at ``freq``); ``w = 2 pi freq``. Tustin, prewarped at ``freq``.
    Parameters ``low_pass_freq`` and, for order 2, ``low_pass_damping``.

    Parameters
    ----------
    freq : float
        Corner frequency, Hz (below fs/2).
    order : int
        1 to 24.
    damping : float or None
        Order 2 only: damping ratio of the poles, > 0. None: 1/sqrt(2).
    fs : float
        Sampling frequency, Hz.
    """
    fc = real("freq", freq, "Hz", positive=True)
    n = integer("order", order, 1)
    require(n <= MAX_ORDER, "order", order, f"<= {MAX_ORDER}")
    require(damping is None or n == 2, "damping", damping, "None unless order == 2")
    w = 2 * math.pi * fc
    local = {"freq": fc}
    if n == 1:
        num, den = [w], [1.0, w]
    elif n == 2:
        zeta = SQRT_HALF if damping is None else real("damping", damping, "damping ratio", positive=True)
        local["damping"] = zeta
        num, den = [w**2], [1.0, 2 * zeta * w, w**2]
    else:
        from scipy import signal  # on first use: importing it takes half a second

        b, a = signal.butter(n, w, analog=True)
        num, den = list(np.atleast_1d(b)), list(a)
    return _block("low_pass", num, den, fs, fc, local, fixed=(n,))


def second_order(
    num_freq: float,
    den_freq: float,
    num_damping: float = SQRT_HALF,
    den_damping: float = SQRT_HALF,
    gain: float = 1.0,
    fs: float = 4000.0,
) -> Controller:
    """A general biquad from the natural frequencies and damping ratios of its zeros and poles.

    Continuous prototype ``gain (s^2/wn^2 + 2 num_damping s/wn + 1) / (s^2/wd^2 + 2 den_damping s/wd + 1)``,
    ``wn = 2 pi num_freq``, ``wd = 2 pi den_freq``: DC gain ``gain``, high-frequency gain
    ``gain (den_freq/num_freq)^2``. Tustin, prewarped at ``sqrt(num_freq den_freq)``. Parameters
    ``second_order_num_freq``, ``second_order_den_freq``, ``second_order_num_damping``,
    ``second_order_den_damping``, ``second_order_gain``.

    Parameters
    ----------
    num_freq, den_freq : float
        Natural frequencies of the zeros and the poles, Hz (below fs/2).
    num_damping, den_damping : float
        Damping ratios (finite; negative makes a right-half-plane pair).
    gain : float
        DC gain.
    fs : float
        Sampling frequency, Hz.
    """
    fn, fd = real("num_freq", num_freq, "Hz", positive=True), real("den_freq", den_freq, "Hz", positive=True)
    _below_nyquist("num_freq", fn, fs)
    _below_nyquist("den_freq", fd, fs)
    zn, zd = real("num_damping", num_damping, "damping ratio"), real("den_damping", den_damping, "damping ratio")
    k = real("gain", gain, "DC gain")
    wn, wd = 2 * math.pi * fn, 2 * math.pi * fd
    num = [k / wn**2, 2 * k * zn / wn, k]
    den = [1 / wd**2, 2 * zd / wd, 1.0]
    local = {"num_freq": fn, "den_freq": fd, "num_damping": zn, "den_damping": zd, "gain": k}
    return _block("second_order", num, den, fs, math.sqrt(fn * fd), local)


def pid_controller(pid: PID) -> Controller:
    """The digital PID of ``pid`` as a :class:`Controller` (behind ``PID.to_controller()``).

    The state space is exactly :meth:`PID.state_space` (the PID without its delay: integral, derivative
    memory and filter states only where they carry something); ``pid.delay`` becomes
    :attr:`Controller.delay`. Continuous design ``kp + ki/s + kd s/(1 + s/wd)``, ``wd = 2 pi
    derivative_cutoff`` (``kd s`` without a cutoff). Parameters ``kp``, ``ki``, ``kd``,
    ``derivative_cutoff`` (``inf`` when there is no derivative filter; setting ``inf`` removes it).
    """
    ss = pid.state_space()
    kp, ki, kd = pid.kp, pid.ki, pid.kd
    if pid.derivative_cutoff is None:
        num, den = [kd, kp, ki], [1.0, 0.0]
    else:
        wd = 2 * math.pi * pid.derivative_cutoff
        num, den = [kp + kd * wd, kp * wd + ki, ki * wd], [1.0, wd, 0.0]
    if ki == 0:  # no integrator: cancel the common factor s
        num, den = num[:-1], den[:-1]
    cutoff = math.inf if pid.derivative_cutoff is None else pid.derivative_cutoff
    local = (("kp", kp), ("ki", ki), ("kd", kd), ("derivative_cutoff", cutoff))
    return Controller._make(
        ss, pid.fs, pid.delay, continuous=(np.array(num), np.array(den)), kind="pid", local=local, fixed=(pid,)
    )


def _rebuild_pid(leaf: Controller, kp: float, ki: float, kd: float, derivative_cutoff: float) -> Controller:
    cutoff = None if derivative_cutoff == math.inf else derivative_cutoff
    return pid_controller(replace(leaf._fixed[0], kp=kp, ki=ki, kd=kd, derivative_cutoff=cutoff))


_REBUILDERS["pid"] = _rebuild_pid
_REBUILDERS["lead_lag"] = lambda leaf, **p: lead_lag(**p, fs=leaf.fs)
_REBUILDERS["notch"] = lambda leaf, **p: notch(**p, fs=leaf.fs)
_REBUILDERS["low_pass"] = lambda leaf, **p: low_pass(**p, order=leaf._fixed[0], fs=leaf.fs)
_REBUILDERS["second_order"] = lambda leaf, **p: second_order(**p, fs=leaf.fs)
