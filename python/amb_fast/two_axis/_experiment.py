"""Two-axis simulation, the two-experiment MIMO identification, and the 2x2 estimate."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._equality import ArrayRecord
from .._excitation import Multisine, period_samples
from .._experiment import _lines
from .._validate import integer, real, require, seed_value
from ..system._experiment import median_lines, settle_for
from ._model import ControllerSpec, LoopModel, controller_matrix, loop_model, require_stable
from ._rig import TwoAxisRig

#: Force signs of the two experiments (rows: experiment, columns: axis): x gets +s in both, y +s then
#: -s, so the 2x2 force matrix at every line is s [[1, 1], [1, -1]]: invertible.
SIGNS = np.array([[1.0, 1.0], [1.0, -1.0]])


@dataclass(frozen=True, eq=False)
class Trace2(ArrayRecord):
    """Recorded channels of one two-axis run, sampled at ``fs``; columns (x, y).

    Attributes
    ----------
    force : ndarray
        (n, 2) recorded forces on the actuator axes, N (through each transducer, plus its noise).
    displacement : ndarray
        (n, 2) probe readings, m (rotated by ``sensor_angle``, through each probe's lag, plus noise).
    current : ndarray
        (n, 2) coil control currents, A.
    fs : float
        Hz.
    """

    force: np.ndarray
    displacement: np.ndarray
    current: np.ndarray
    fs: float

    @cached_property
    def time(self) -> np.ndarray:
        """Sample instants kT, s (computed once, read-only)."""
        t = np.arange(self.force.shape[0]) / self.fs
        t.flags.writeable = False
        return t


def _core_args(model: LoopModel, rig: TwoAxisRig, outputs: int = 4) -> dict[str, np.ndarray]:
    """The core's model; ``outputs=2`` keeps only the probe readings (experiments need no currents)."""
    return dict(M=model.M, Bf=model.Bf, Bn=model.Bn, C=model.C[:outputs], Dn=model.Dn[:outputs],
                transducer_pole=model.poles, sensor_noise=np.array([a.sensor_noise for a in rig.axes]),
                force_noise=np.array([a.force_noise for a in rig.axes]))  # fmt: skip


def _forces(name: str, values: Any) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=np.float64)
    require(array.ndim == 2 and array.shape[1] == 2, f"{name} shape", array.shape, "(samples, 2): columns x, y")
    return array


def simulate(rig: TwoAxisRig, controller: ControllerSpec, force: ArrayLike, *, seed: int | None = None) -> Trace2:
    """Run the two-axis closed loop from rest on forces (n, 2) (N, columns x, y) at the controller's ``fs``.

    ``controller``: one controller for both axes, a pair ``(cx, cy)``, or a 2x2 matrix of them (cross
    feedback; ``None`` for an absent entry). The forces are zero-order held; the loop is discretised
    exactly. ``seed`` fixes the noise (one stream per probe and per transducer).
    """
    model = loop_model(rig, controller)
    force = _forces("force", force)
    recorded, out = _core.mimo_simulate(**_core_args(model, rig), force=force, seed=seed_value(seed))
    return Trace2(force=recorded, displacement=out[:, :2], current=out[:, 2:], fs=model.fs)


@dataclass(frozen=True, eq=False)
class Estimate2(ArrayRecord):
    """2x2 frequency-domain estimate at the excited lines; every matrix has shape (lines, 2, 2).

    Attributes
    ----------
    freq : ndarray
        Excited lines, Hz.
    H : ndarray
        Dynamic stiffness ``F Y^-1``, complex, N/m: ``H[:, i, j] = dF_i / dY_j`` with F the recorded
        forces on the actuator axes and Y the probe readings.
    receptance : ndarray
        ``Y F^-1 = H^-1``, m/N.
    k, c : ndarray
        Stiffness ``m w^2 I + Re H`` (N/m) and damping ``Im H / w`` (N s/m) matrices, ``k[:, i, j]`` is
        ROSS's ``k_ij`` (force on the rotor ``-K q - C dq/dt``).
    k_smooth, c_smooth : ndarray
        Median filtered across the lines per entry (window ``median_window``, ends repeat the edge).
    k_std, c_std : ndarray
        Standard errors (first-order propagation of the period-to-period deviations of both
        experiments' spectra through ``F Y^-1``; ``periods - 1`` degrees of freedom).
    force, displacement : ndarray
        Period-averaged complex amplitudes, ``[:, channel, experiment]``, N and m.
    periods : int
        Periods averaged per experiment.
    mass : float
        The known mass m used in ``k``, kg.
    """

    freq: np.ndarray
    H: np.ndarray
    receptance: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    force: np.ndarray
    displacement: np.ndarray
    periods: int
    mass: float

    def to_ross(self, n: int, *, smoothed: bool = False, **kwargs: Any) -> Any:
        """This estimate as a ``ross.BearingElement`` at node ``n`` (see :func:`amb_fast.two_axis.to_ross`)."""
        from .._ross import to_ross

        return to_ross(self, n, smoothed=smoothed, **kwargs)


def period_spectra(x: np.ndarray, harmonics: np.ndarray, period: int) -> np.ndarray:
    """Line spectra of every period: (2 experiments, 2 channels, periods * period) to
    (periods, lines, channel, experiment), unscaled DFT bins."""
    P = x.shape[2] // period
    return np.fft.rfft(x.reshape(2, 2, P, period), axis=3)[..., harmonics].transpose(2, 3, 1, 0)


def estimate2(
    force: np.ndarray, displacement: np.ndarray, harmonics: np.ndarray, period: int, f0: float, mass: float,
    median_window: int = 5,
) -> Estimate2:  # fmt: skip
    """The 2x2 estimate from both experiments' recorded periods.

    ``force``, ``displacement``: (2 experiments, 2 channels, periods * period), or already their
    per-period line spectra (periods, lines, channel, experiment), complex. ``H = F Y^-1`` per line with
    F, Y the period means; its standard errors from the linearised ``dH = (dF - H dY) Y^-1`` of every
    period (the compiled core's ``estimate_2x2``).
    """
    Fp = force if np.iscomplexobj(force) else period_spectra(force, harmonics, period)
    Yp = displacement if np.iscomplexobj(displacement) else period_spectra(displacement, harmonics, period)
    H, receptance, F, Y, var_re, var_im = _core.estimate_2x2(Fp, Yp)
    k, c, k_std, c_std = coefficients2(H, var_re, var_im, harmonics * f0, mass)
    scale = 2.0 / period
    return Estimate2(
        freq=harmonics * f0,
        H=H,
        receptance=receptance,
        k=k,
        c=c,
        k_smooth=median_lines(k, median_window),
        c_smooth=median_lines(c, median_window),
        k_std=k_std,
        c_std=c_std,
        force=scale * F,
        displacement=scale * Y,
        periods=Fp.shape[0],
        mass=mass,
    )


def coefficients2(
    H: np.ndarray, var_re: np.ndarray, var_im: np.ndarray, freq: np.ndarray, mass: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """k (N/m), c (N s/m) and their standard errors from H = F Y^-1 and the variances of its parts, per
    line (freq, Hz, along the third axis from the end: (..., lines, 2, 2))."""
    w = (2 * np.pi * freq)[:, None, None]
    return mass * w**2 * np.eye(2) + H.real, H.imag / w, np.sqrt(var_re), np.sqrt(var_im) / w


_last_pair: tuple[np.ndarray, np.ndarray] | None = None


def _core_pair(excitation: Multisine) -> np.ndarray:
    """:func:`excitation_pair`, read-only, kept for the last samples seen: repeated experiments and a
    sweep's points share their excitation, and comparing the samples costs a quarter of building it."""
    global _last_pair
    last, samples = _last_pair, excitation.samples
    if last is not None and last[0].shape == samples.shape and np.array_equal(last[0], samples):
        return last[1]
    pair = excitation_pair(excitation)
    pair.flags.writeable = False
    _last_pair = (samples.copy(), pair)
    return pair


def excitation_pair(excitation: Multisine) -> np.ndarray:
    """The two experiments' forces, (2, period, 2): x = +s, +s and y = +s, -s."""
    pair = np.empty((2, excitation.samples.size, 2))
    for experiment, axis in np.ndindex(2, 2):  # a broadcast product over an axis of 2 takes ten times as long
        np.multiply(SIGNS[experiment, axis], excitation.samples, out=pair[experiment, :, axis])
    return pair


def _window(median_window: int) -> int:
    window = integer("median_window", median_window, 1)
    require(window % 2 == 1, "median_window", median_window, "odd")
    return window


def run_experiment(
    rig: TwoAxisRig,
    controller: ControllerSpec,
    excitation: Multisine,
    *,
    periods: int = 10,
    settle_periods: int | None = None,
    seed: int | None = None,
    median_window: int = 5,
    start: Literal["steady", "rest"] = "steady",
) -> Estimate2:
    """The two-axis SPHS identification: two experiments, then ``H = F Y^-1`` per line.

    Experiment 1 drives both axes with the multisine ``s``, experiment 2 drives x with ``s`` and y with
    ``-s`` (:data:`SIGNS`), each ``periods`` recorded periods from the exact periodic steady state
    (``start="steady"``, no settling needed) or from rest after ``settle_periods`` (default: enough for
    the slowest pole, or transducer pole, to decay below 1e-9). ``seed`` fixes the noise of both
    experiments. Raises :class:`UnstableLoopError` for an unstable loop.

    From the steady state the recorded periods' line spectra are drawn directly rather than simulated
    sample by sample: the loop is linear, so this is exact in distribution (the same means, variances
    and correlations across lines, probes and periods; noise-free, the same numbers to rounding), but a
    seed gives other numbers than :func:`simulate` would. ``start="rest"`` runs the loop sample by
    sample.
    """
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    periods = integer("periods", periods, 2)
    window = _window(median_window)
    require(start in ("steady", "rest"), "start", start, "'steady' or 'rest'")
    args, settle, seeds = _point_args(rig, controller, excitation, settle_periods, seed, start)
    harmonics = excitation.harmonics
    # Per-period line spectra in the core. In the periodic steady state they are drawn directly, exact in
    # distribution: the loop is linear, so each period's spectrum at a line is the steady response to the
    # excitation, plus the response to that period's noise spectrum, plus what the change of the state over
    # the period leaks into the line (docs/model.md); from rest the loop runs sample by sample.
    Fp, Yp = _core.mimo_line_experiments(**args, period_forces=_core_pair(excitation), settle_periods=settle,
                                         periods=periods, seeds=seeds, steady_start=start == "steady",
                                         bins=harmonics)  # fmt: skip
    return estimate2(Fp, Yp, harmonics, excitation.period_samples, excitation.f0, rig.mass, window)


def _point_args(
    rig: TwoAxisRig, controller: ControllerSpec, excitation: Multisine, settle_periods: int | None, seed: int | None,
    start: str, checked: tuple[LoopModel, np.ndarray] | None = None,
) -> tuple[dict[str, np.ndarray], int, list[int]]:  # fmt: skip
    """What the core needs of one experiment pair (run_experiment, a sweep's point): the loop's model, the
    settle periods and both experiments' seeds; :class:`UnstableLoopError` for an unstable loop. ``checked``:
    the loop and its poles, where a sweep has already built it and found it stable as :func:`require_stable`
    does (its loops outnumber loop_model's cache)."""
    spec = controller_matrix(controller)
    require(excitation.fs == spec.fs, "excitation.fs", excitation.fs, f"equal to the controller's fs ({spec.fs} Hz)")
    loop, poles = checked if checked is not None else (loop_model(rig, spec), require_stable(rig, spec))
    if settle_periods is None:
        settle_periods = 0 if start == "steady" else settle_for(rig, spec.fs, poles, excitation.period_samples)
    settle = integer("settle_periods", settle_periods, 0)
    s = seed_value(seed)
    return _core_args(loop, rig, outputs=2), settle, [s, (s ^ 0xA5A5A5A5DEADBEEF) % 2**64]


def identify(
    force: ArrayLike,
    displacement: ArrayLike,
    *,
    fs: float,
    f0: float,
    mass: float,
    f_max: float | None = None,
    lines: ArrayLike | None = None,
    settle_periods: int = 0,
    median_window: int = 5,
) -> Estimate2:
    """The 2x2 estimate from two recorded experiments of a real two-axis rig.

    ``force``, ``displacement``: one (n, 2) recording per experiment (N and m; columns x, y), given as a
    pair or an array of shape (2, n, 2). The two experiments' force matrices must be invertible at
    every line (drive them as :func:`run_experiment` does: x = +s, +s; y = +s, -s). ``mass``: the
    rotor's known mass (kg). Lines as in :func:`amb_fast.identify` (``lines``, ``f_max``, else the
    harmonics the first experiment's x force excites). Trailing samples short of a whole period are
    dropped with a warning.
    """
    F = np.asarray(force, dtype=np.float64)
    Y = np.asarray(displacement, dtype=np.float64)
    require(F.ndim == 3 and F.shape[0] == 2 and F.shape[2] == 2, "force shape", F.shape,
            "(2 experiments, samples, 2 axes)")  # fmt: skip
    require(Y.shape == F.shape, "displacement shape", Y.shape, f"{F.shape} like force")
    fs = real("fs", fs, "Hz", positive=True)
    f0 = real("f0", f0, "Hz", positive=True)
    mass = real("mass", mass, "kg", positive=True)
    window = _window(median_window)
    settle_periods = integer("settle_periods", settle_periods, 0)
    period = period_samples(fs, f0)
    start = settle_periods * period
    n = F.shape[1]
    whole = start + max(0, n - start) // period * period
    require((whole - start) // period >= 2, "periods after settling", (whole - start) // period,
            ">= 2 (standard errors need at least two)")  # fmt: skip
    if whole < n:
        warnings.warn(f"recordings are not a whole number of periods of {period} samples: dropped the last "
                      f"{n - whole} samples", stacklevel=2)  # fmt: skip
    F = np.ascontiguousarray(F[:, start:whole].transpose(0, 2, 1))
    Y = np.ascontiguousarray(Y[:, start:whole].transpose(0, 2, 1))
    for name, x in (("force", F), ("displacement", Y)):
        require(bool(np.all(np.isfinite(x))), name, "non-finite samples", "finite")
    harmonics = _lines(F[0, 0], period, f0, fs, f_max, lines)
    return estimate2(F, Y, harmonics, period, f0, mass, window)
