"""The ISO 14839-3 sensitivity, measured: a test signal added to each axis' sensor signal in turn.

The signal enters at the summing point before the controller (where the probe's reading becomes the
controller's input); per line ``Gs = (the signal after the sum) / (the test signal)``, an N x N matrix over
the N experiments (``Gs = A E^-1``, as an estimate's ``F Y^-1``, with its standard errors from the
period-to-period scatter). ISO 14839-3 grades the peak of each axis' ``|Gs|``: zone A below 3 (9.5 dB),
B below 4 (12 dB), C below 5 (14 dB), D above.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._equality import ArrayRecord
from .._excitation import Multisine, period_samples
from .._linear import iso_zone
from .._validate import integer, real, require
from ._control import ControllerSpec, controller_matrix
from ._experiment import core_args, experiment_seeds, line_spectra
from ._model import System, loop_model, require_stable


@dataclass(frozen=True, eq=False)
class SensitivityMeasurement(ArrayRecord):
    """The measured sensitivity at the sensors' summing point; matrices (lines, N, N).

    Attributes
    ----------
    freq : ndarray
        Lines, Hz.
    S : ndarray
        ``Gs[:, i, j]``: the signal after the sum at axis i per test signal at axis j, complex.
    S_std : ndarray
        Standard error of ``|Gs|`` (first order, from the period-to-period scatter; ``periods - 1`` dof).
    peak, peak_frequency, zone : tuple
        Per axis: the peak of ``|Gs_ii|`` over the lines, its line (Hz) and its ISO 14839-3 zone.
    sigma_max : ndarray
        (lines,) the largest singular value of ``Gs``.
    periods : int
    axes : tuple of str
    """

    freq: np.ndarray
    S: np.ndarray
    S_std: np.ndarray
    peak: tuple[float, ...]
    peak_frequency: tuple[float, ...]
    zone: tuple[str, ...]
    sigma_max: np.ndarray
    periods: int
    axes: tuple[str, ...]

    def table(self) -> str:
        """One row per axis: peak ``|Gs|`` (ratio and dB), its frequency, its ISO 14839-3 zone; then the
        largest singular value's peak."""
        rows = [f"{'axis':<8}{'peak |Gs|':>10}{'dB':>8}{'at (Hz)':>10}  zone"]
        for name, peak, at, zone in zip(self.axes, self.peak, self.peak_frequency, self.zone):
            rows.append(f"{name:<8}{peak:>10.3f}{20 * np.log10(peak):>8.2f}{at:>10.1f}  {zone}")
        j = int(np.argmax(self.sigma_max))
        top = float(self.sigma_max[j])
        rows.append(f"{'sigma':<8}{top:>10.3f}{20 * np.log10(top):>8.2f}{self.freq[j]:>10.1f}  {iso_zone(top)}")
        return "\n".join(rows)


def _measurement(
    S: np.ndarray, var_re: np.ndarray, var_im: np.ndarray, freq: np.ndarray, periods: int, axes: tuple[str, ...]
) -> SensitivityMeasurement:
    """``Gs`` per line with the variances of its parts: the standard error of ``|Gs|``, the peaks and zones."""
    magnitude = np.abs(S)
    safe = np.maximum(magnitude, 1e-300)
    S_std = np.sqrt((S.real / safe) ** 2 * var_re + (S.imag / safe) ** 2 * var_im)
    diagonal = np.abs(np.diagonal(S, axis1=1, axis2=2))  # (lines, N)
    best = np.argmax(diagonal, axis=0)
    peak = tuple(float(diagonal[j, i]) for i, j in enumerate(best))
    sigma = np.sqrt(np.linalg.eigvalsh(np.conj(np.swapaxes(S, 1, 2)) @ S)[:, -1])  # sigma_max: faster than svd
    return SensitivityMeasurement(freq, S, S_std, peak, tuple(float(freq[j]) for j in best),
                                  tuple(iso_zone(p) for p in peak), sigma, periods, axes)  # fmt: skip


def measure_sensitivity(
    rig: System, controller: ControllerSpec, excitation: Multisine, *, periods: int = 10, seed: int | None = None
) -> SensitivityMeasurement:
    """ISO 14839-3's sensitivity measurement on the simulated loop: ``excitation`` (a multisine, in m: it is
    added to a sensor's signal) injected at each axis' summing point in turn, N experiments from the
    periodic steady state, with the probes' noise; ``Gs = (signal after the sum) / (test signal)`` per line.

    Noise-free it equals :func:`amb_fast.sensitivity` with ``at="sensors"`` at the lines (to rounding). Any
    rig: one axis (a :class:`~amb_fast.Rig`), two axes, a rotor. Raises :class:`UnstableLoopError` for an
    unstable loop."""
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    periods = integer("periods", periods, 2)
    mech = rig.mechanics()
    N = mech.axes
    spec = controller_matrix(controller, N)
    require(excitation.fs == spec.fs, "excitation.fs", excitation.fs, f"equal to the controller's fs ({spec.fs} Hz)")
    require_stable(rig, spec, "the closed loop" + (f" at speed {mech.speed:g} rad/s" if mech.speed else ""))
    model = loop_model(rig, spec)
    # The test signal enters where probe noise does: into the controller (Bn) and onto the reading (added
    # below, as the loop's output has no direct path from its inputs).
    forces = np.zeros((N, excitation.period_samples, N))
    for j in range(N):
        forces[j, :, j] = excitation.samples
    args = core_args(model, rig, outputs=N) | dict(Bf=model.Bn, transducer_pole=np.zeros(N), force_noise=np.zeros(N))
    seeds = experiment_seeds(seed, N)
    Fp, Yp = _core.mimo_line_experiments(**args, period_forces=forces, settle_periods=0, periods=periods, seeds=seeds,
                                         steady_start=True, bins=excitation.harmonics)  # fmt: skip
    # Each experiment injects at its own axis, the same every period: per period Gs = (Y + E) / e with e the
    # test signal's line (no inverse), and its scatter is the core's linearised one (dE = 0) to rounding.
    e = np.diagonal(Fp[0], axis1=1, axis2=2)[:, None, :]  # (lines, 1, experiment)
    G = Yp / e
    S = G.mean(axis=0)
    G -= S
    var_re, var_im = (np.sum(part**2, axis=0) / (periods * (periods - 1)) for part in (G.real, G.imag))
    return _measurement(S + np.eye(N), var_re, var_im, excitation.harmonics * excitation.f0, periods, mech.names)


def identify_sensitivity(
    injection: ArrayLike, signal: ArrayLike, *, fs: float, f0: float, settle_periods: int = 0,
    axes: tuple[str, ...] | None = None,
) -> SensitivityMeasurement:  # fmt: skip
    """The ISO 14839-3 sensitivity from a recording: ``injection`` the test signal and ``signal`` the signal
    after the summing point, each (samples,) for one axis or (N experiments, samples, N axes) for N
    (experiment j injecting at axis j, or any invertible pattern); ``fs``, ``f0`` as for
    :func:`amb_fast.identify`; ``settle_periods`` skipped. Lines: the harmonics the test signal excites."""
    E = np.asarray(injection, dtype=float)
    A = np.asarray(signal, dtype=float)
    if E.ndim == 1:
        E, A = E[None, :, None], A[None, :, None]
    require(E.ndim == 3 and E.shape[0] == E.shape[2], "injection shape", E.shape,
            "(samples,) or (N experiments, samples, N axes)")  # fmt: skip
    require(A.shape == E.shape, "signal shape", A.shape, f"{E.shape} like the injection")
    require(bool(np.all(np.isfinite(E)) and np.all(np.isfinite(A))), "recordings", "non-finite samples", "finite")
    fs, f0 = real("fs", fs, "Hz", positive=True), real("f0", f0, "Hz", positive=True)
    L = period_samples(fs, f0)
    start = integer("settle_periods", settle_periods, 0) * L
    P = (E.shape[1] - start) // L
    require(P >= 2, "periods after settling", P, ">= 2 (standard errors need at least two)")
    N = E.shape[0]
    El, Al = (line_spectra(x[:, start : start + P * L], L) for x in (E, A))
    level = np.abs(El.mean(axis=0)).max(axis=(1, 2))
    excited = np.flatnonzero(level > 1e-3 * level.max())
    excited = excited[(excited > 0) & (excited < L // 2)]
    require(excited.size > 0, "injection", "no line", "a periodic test signal with lines between 0 and fs/2")
    names = axes if axes is not None else tuple(f"axis {j}" for j in range(N))
    # Gs = A E^-1 per line with its variances: the core's N x N estimate
    S, _, _, _, var_re, var_im = _core.estimate_nxn(np.ascontiguousarray(Al[:, excited]),
                                                    np.ascontiguousarray(El[:, excited]))  # fmt: skip
    return _measurement(S, var_re, var_im, excited * f0, P, names)
