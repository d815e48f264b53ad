"""Rig and controller parameters (SI units; frequencies in Hz)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from . import _core
from ._mechanics import Mechanics
from ._validate import delay_samples, integer, non_negative, optional_positive, real, require

if TYPE_CHECKING:
    from .controllers import Controller

ForceLaw = Literal["linear", "nonlinear"]
#: The unit of each number of a Rig and a PID (their checks' messages, rig files).
UNITS = {
    "mass": "kg", "kyy": "N/m", "kiy": "N/A", "bias_current": "A", "amp_bandwidth": "Hz", "eddy_bandwidth": "Hz",
    "sensor_bandwidth": "Hz", "sensor_noise": "m rms", "force_noise": "N rms", "mass_loading": "kg",
    "force_coupling_tau": "s", "clearance": "m", "current_limit": "A", "dead_time": "s",
    "kp": "A/m", "ki": "A/(m s)", "kd": "A s/m", "derivative_cutoff": "Hz", "fs": "Hz",
}  # fmt: skip


@dataclass(frozen=True)
class Rig:
    """The one-axis suspension of MODEL.md.

    ``Rig()`` is the bare model: the paper's m, Kyy, Kiy and bias current with no lags, no noise, no
    mass loading, DC coupling and the linear force law (what tests compare with exact answers).
    ``Rig.paper()`` is the paper's rig as simulated. Side by side (also in the README, "Defaults")::

        field                 Rig()       Rig.paper()
        mass, kyy, kiy        0.92 kg, -53.3 kN/m, 47.19 N/A in both
        bias_current          0.65 A      0.65 A
        amp_bandwidth         None        3000 Hz
        eddy_bandwidth        None        2000 Hz
        sensor_bandwidth      None        10000 Hz
        mass_loading          0           0.06 kg
        force_coupling_tau    None        1 s
        sensor_noise          0           20e-9 m rms
        force_noise           0           1e-3 N rms
        force_law             linear      linear

    Parameters
    ----------
    mass : float
        Moving mass m, kg.
    kyy : float
        Position stiffness of the biased magnet pair, N/m (negative: destabilising).
    kiy : float
        Current stiffness, N/A.
    bias_current : float
        Bias current i0 of the magnet pair, A (used by the non-linear force law).
    force_law : {"linear", "nonlinear"}
        Linearised magnet force, or the differential magnet-pair law that linearises to kyy, kiy.
    amp_bandwidth, eddy_bandwidth, sensor_bandwidth : float or None
        First-order lags of the amplifier current loop, the eddy-current force and the displacement
        sensor, Hz. ``None`` makes the stage ideal.
    sensor_noise : float
        White noise on the displacement sensor output, m rms (the controller sees it too).
    force_noise : float
        White noise on the recorded force (force transducer), N rms; the applied force is clean.
    mass_loading : float
        Mass moving with the platform beyond ``mass``, kg: the part of the force transducer and stinger
        between the sensing element and the platform. The dynamics move ``mass + mass_loading``; the
        estimate (paper eq. 9) uses the known ``mass``, so it shows up in k(w) as ``-mass_loading w^2``.
    force_coupling_tau : float or None
        Discharge time constant of the AC-coupled (piezoelectric) force transducer, s: a first-order
        high-pass that leads the recorded force in phase at the lowest lines. ``None``: DC coupled.
    clearance : float or None
        Mechanical clearance, m: reaching |y| >= clearance is a touchdown (:class:`TouchdownError`).
        ``None``: the air gap with the non-linear force law, no limit with the linear one.
    current_limit : float or None
        Amplifier limit on the control current |i|, A; the command is clipped there and the clipped
        samples are counted (``Estimate.saturated_samples``). With the non-linear force law the coil
        currents i0 +/- i cannot go negative, so |i| <= ``bias_current`` always. ``None``: no other limit.
    dead_time : float
        Transport delay from the current command to the amplifier, s (DSP and converter latency; rarely
        a whole number of samples). Discretised exactly: whole samples plus a fraction (modified
        z-transform of the zero-order hold). Default 0.
    substeps : int
        Integrator steps per controller sample for the non-linear force law (integrating-factor RK4:
        the linear part is exact, the non-linear remainder is fourth order; 2 steps keep the relative
        error near 3e-7 at a quarter of the air gap).
    """

    mass: float = 0.92
    kyy: float = -53.3e3
    kiy: float = 47.19
    bias_current: float = 0.65
    force_law: ForceLaw = "linear"
    amp_bandwidth: float | None = None
    eddy_bandwidth: float | None = None
    sensor_bandwidth: float | None = None
    substeps: int = 2
    sensor_noise: float = 0.0
    force_noise: float = 0.0
    mass_loading: float = 0.0
    force_coupling_tau: float | None = None
    clearance: float | None = None
    current_limit: float | None = None
    dead_time: float = 0.0

    def __post_init__(self) -> None:
        real("mass", self.mass, "kg", positive=True)
        require(real("kyy", self.kyy, "N/m") != 0, "kyy", self.kyy, "non-zero (N/m)")
        real("kiy", self.kiy, "N/A", positive=True)
        real("bias_current", self.bias_current, "A", positive=True)
        require(self.force_law in ("linear", "nonlinear"), "force_law", self.force_law, "'linear' or 'nonlinear'")
        if self.force_law == "nonlinear":
            require(self.kyy < 0, "kyy", self.kyy, "< 0 for the non-linear force law (N/m)")
        integer("substeps", self.substeps, 1)
        for name in ("amp_bandwidth", "eddy_bandwidth", "sensor_bandwidth", "force_coupling_tau", "current_limit"):
            optional_positive(name, getattr(self, name), UNITS[name])
        for name in ("sensor_noise", "force_noise", "mass_loading", "dead_time"):
            non_negative(name, getattr(self, name), UNITS[name])
        clearance = optional_positive("clearance", self.clearance, "m")
        if clearance is not None and self.force_law == "nonlinear":
            require(clearance < self.gap, "clearance", clearance, f"below the air gap {self.gap:.6g} m")

    @classmethod
    def paper(cls) -> Rig:
        """The paper's rig (m = 0.92 kg, Kyy = -53.3 kN/m, Kiy = 47.19 N/A, i0 = 0.65 A) with lags
        and a measurement chain chosen to be physically plausible; ``docs/model.md`` gives the
        reasoning and sources for every value.

        Amplifier current loop 3 kHz, eddy-current force lag 2 kHz, eddy-current probe 10 kHz,
        60 g of transducer and stinger moving with the platform, a piezoelectric force transducer
        AC coupled with a 1 s discharge time constant, 20 nm rms probe noise and 1 mN rms force
        noise. The force law stays linearised: the excitation moves the platform by under 1 % of the
        air gap (use ``replace(Rig.paper(), force_law="nonlinear")`` for the magnet pair's law).
        """
        return cls(
            amp_bandwidth=3000.0,
            eddy_bandwidth=2000.0,
            sensor_bandwidth=10_000.0,
            mass_loading=0.06,
            force_coupling_tau=1.0,
            sensor_noise=20e-9,
            force_noise=1e-3,
        )

    @property
    def gap(self) -> float:
        """Nominal air gap g = i0 Kiy / (-Kyy) of the non-linear force law, m."""
        return self.bias_current * self.kiy / -self.kyy

    def _to_core(self) -> _core.Rig:
        return _core_rig(self)

    @property
    def moving_mass(self) -> float:
        """Mass the dynamics move, kg: ``mass + mass_loading``."""
        return self.mass + self.mass_loading

    @property
    def axes(self) -> tuple[Rig]:
        """``(self,)``: the one axis' chain, as the model of N axes reads a rig (this is its 1x1 case)."""
        return (self,)

    def mechanics(self) -> Mechanics:
        """The platform as a structure of one coordinate ``y``: mass ``m``, its actuator, shaker and probe on
        it (the model of N axes, :mod:`amb_fast.system`, for N = 1)."""
        return _platform(self.mass)


def _as_controller(operator: str) -> Callable[[PID, Any], Controller]:
    """A PID's ``operator``: the same operator of its :class:`~amb_fast.Controller`."""

    def method(self: PID, other: Any) -> Controller:
        return getattr(self.to_controller(), operator)(other)

    return method


@dataclass(frozen=True)
class PID:
    """The digital PID controller of MODEL.md section 2.

    ``PID(kp=..., ki=..., kd=...)`` has no derivative filter and a computation delay of one sample;
    ``PID.paper()`` is the paper rig's baseline. Side by side (also in the README, "Defaults")::

        field                 PID(kp, ki, kd)     PID.paper()
        kp, ki, kd            required            2400 A/m, 20000 A/(m s), 3 A s/m
        derivative_cutoff     None                1000 Hz
        fs                    4000 Hz             4000 Hz
        delay                 1 sample            0 samples

    Parameters
    ----------
    kp, ki, kd : float
        Gains from measured displacement to control current: A/m, A/(m s), A s/m.
    derivative_cutoff : float or None
        Corner of the first-order derivative filter, Hz; ``None`` = plain backward difference.
    fs : float
        Sampling frequency, Hz.
    delay : int
        Computation delay, whole samples.
    """

    kp: float
    ki: float
    kd: float
    derivative_cutoff: float | None = None
    fs: float = 4000.0
    delay: int = 1

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd"):
            real(name, getattr(self, name), UNITS[name])
        optional_positive("derivative_cutoff", self.derivative_cutoff, "Hz")
        real("fs", self.fs, "Hz", positive=True)
        delay_samples("delay", self.delay)

    @classmethod
    def paper(cls) -> PID:
        """Baseline gains for the paper's rig (which does not state its own): kp = 2400 A/m gives a
        net stiffness Kiy kp + Kyy = 60 kN/m and a natural frequency near 38 Hz, mid-band of the
        1-200 Hz excitation; kd = 3 A s/m (about 140 N s/m, damping ratio near 0.3), filtered at
        1 kHz; ki = 20000 A/(m s) puts the integral corner ki/kp near 1.3 Hz, well below resonance.
        Stable with any one gain anywhere from 0.67x to 1.5x (tested). No whole-sample computation
        delay: the DS1103 computes a PID within a few tens of microseconds of the sample, a small
        fraction of the 250 us period (the zero-order hold's half sample remains).
        """
        return cls(kp=2400.0, ki=20000.0, kd=3.0, derivative_cutoff=1000.0, fs=4000.0, delay=0)

    def to_controller(self) -> Controller:
        """This PID as a general :class:`~amb_fast.Controller`: the same difference equations (a run
        with either is bit for bit the same), its continuous design ``kp + ki/s + kd s/(1 + s/wd)``
        and its parameters ``kp``, ``ki``, ``kd``, ``derivative_cutoff`` for sweeps and design."""
        from .controllers import pid_controller

        return pid_controller(self)

    # A PID composes like any controller: as its Controller (``pid * notch``, ``notch * pid``, ``pid + c``,
    # ``2.0 * pid``); the result is a Controller.
    __array_ufunc__ = None  # numpy scalars defer to these operators
    __mul__ = _as_controller("__mul__")
    __rmul__ = _as_controller("__rmul__")
    __add__ = _as_controller("__add__")
    __radd__ = _as_controller("__radd__")
    __sub__ = _as_controller("__sub__")

    def __rsub__(self, other: Any) -> Controller:
        return (-1.0 * self.to_controller()).__add__(other)

    def __neg__(self) -> Controller:
        return -1.0 * self.to_controller()

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The digital PID without its delay as ``(A, B, C, D)`` from e[k] (m) to u[k] (A).

        The law of MODEL.md: ``u = kp e + I + Dd`` with the backward-Euler integral
        ``I[k] = I[k-1] + ki T e[k]`` and the filtered difference ``Dd[k] = a Dd[k-1] + kd (1 - a)/T
        (e[k] - e[k-1])``, ``a = exp(-2 pi fd T)`` (0 without a filter). Realised in modal form with
        at most two states, each only where its gain is non-zero: the integral's (pole 1) and the
        derivative's (pole a), using ``(1 - z^-1)/(1 - a z^-1) = 1 + (a - 1) z^-1/(1 - a z^-1)``.
        """
        integral_in, derivative_out, D = self._terms(self.kp, self.ki, self.kd)
        i, d = int(self.ki != 0), int(self.kd != 0)
        m = i + d
        A = np.diag([1.0] * i + [self._derivative_pole()] * d).reshape(m, m)
        B = np.array([integral_in] * i + [1.0] * d, dtype=float).reshape(m, 1)
        C = np.array([1.0] * i + [derivative_out] * d, dtype=float).reshape(1, m)
        return A, B, C, np.array([[D]])

    def _derivative_pole(self) -> float:
        """The derivative filter's pole a = exp(-2 pi fd T) (0 without a filter)."""
        cutoff = self.derivative_cutoff
        return 0.0 if cutoff is None else float(np.exp(-2 * np.pi * cutoff * (1.0 / self.fs)))

    def _terms(self, kp: Any, ki: Any, kd: Any) -> tuple[Any, Any, Any]:
        """The integral's input ki T, the derivative's output kd_gain (a - 1) and the direct term
        kp + ki T + kd_gain, for these gains (floats, or arrays: the same operations element by element,
        so the same digits) with this PID's fs and derivative filter; kd_gain = kd (1 - a) / T."""
        T = 1.0 / self.fs
        a = self._derivative_pole()
        kd_gain = kd * (1 - a) / T
        return ki * T, kd_gain * (a - 1.0), kp + ki * T + kd_gain

    def _core_controllers(self, gains: np.ndarray) -> list[_core.Controller]:
        """The core's controllers of this PID with each row of ``gains`` (kp, ki, kd): the numbers of
        ``replace(self, kp=..., ki=..., kd=...)._to_core()``, without making the PIDs (sweeps)."""
        kp, ki, kd = np.ascontiguousarray(gains.T, dtype=float)
        # the core assembles what state_space lays out, entry by entry (the terms are arrays of kp's shape)
        return _core.pid_controllers(*self._terms(kp, ki, kd), ki=ki, kd=kd, pole=self._derivative_pole(), fs=self.fs,
                                     delay=self.delay)  # fmt: skip

    def _to_core(self) -> _core.Controller:
        return _core_pid(self)


_RIG_FIELDS = tuple(f.name for f in fields(Rig))


# The core's copies of the parameters, made once per distinct value (the dataclasses are frozen).
@functools.lru_cache(maxsize=256)
def _core_rig(rig: Rig) -> _core.Rig:
    values = {name: getattr(rig, name) for name in _RIG_FIELDS}  # all scalars: no deep copy (asdict: 60 us)
    values["force_law"] = _core.ForceLaw.__members__[rig.force_law]
    return _core.Rig(**values)


@functools.lru_cache(maxsize=256)
def _core_pid(pid: PID) -> _core.Controller:
    return _core_controller(*pid.state_space(), pid.fs, pid.delay)


def _core_controller(
    A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, fs: float, delay: int
) -> _core.Controller:
    """The core's copy of a controller's state space (delay-free matrices plus whole-sample delay)."""
    return _cached_core_controller(A.tobytes(), B.tobytes(), C.tobytes(), float(D[0, 0]), A.shape[0], fs, delay)


@functools.lru_cache(maxsize=256)
def _cached_core_controller(A: bytes, B: bytes, C: bytes, D: float, n: int, fs: float, delay: int) -> _core.Controller:
    return _core.Controller(
        A=np.frombuffer(A).reshape(n, n), B=np.frombuffer(B), C=np.frombuffer(C), D=D, fs=fs, delay=delay
    )


@functools.lru_cache(maxsize=64)
def _platform(mass: float) -> Mechanics:
    one, zero = np.ones((1, 1)), np.zeros((1, 1))
    for matrix in (one, zero):
        matrix.flags.writeable = False
    return Mechanics(mass * one, zero, zero, zero, one, one, one, 0.0, ("y",), ("y",))
