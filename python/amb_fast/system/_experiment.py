"""N axes on the compiled dense loop: simulation, the N experiments with Hadamard signs, the N x N estimate.

Experiment ``e`` drives axis ``j``'s shaker with ``signs[e, j] s`` (``s``: the multisine), so the force
matrix at every line is ``s`` times a Hadamard matrix: invertible. ``H = F Y^-1`` per line with ``F`` the
recorded forces at the bearing planes and ``Y`` the displacements the structure reports (the probes'
readings through its ``readout``: at the bearing planes for a rotor); the actual coefficients remove the
structure's own known dynamics, ``K + j w C = H + w^2 Mb - j w W Gb`` (paper eq. 9).
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar, Literal

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from .. import _core
from .._equality import ArrayRecord
from .._excitation import Multisine
from .._experiment import EstimateBase, run_options, settle_from
from .._mechanics import Mechanics
from .._ross import to_ross
from .._simulate import Channels
from .._validate import require, seed_value
from ..plots import plot_coefficients_n
from . import _results
from ._control import ControllerSpec, controller_matrix
from ._exciter import amb_args, amb_lines, corrected_process, current_rows
from ._model import LoopModel, System, known_dynamics, loop_model, require_stable
from ._unbalance import with_unbalance


@functools.lru_cache(maxsize=8)
def hadamard_signs(n: int) -> np.ndarray:
    """(n experiments, n axes) force signs: the first ``n`` rows and columns of a Sylvester Hadamard matrix
    (one axis ``[[1]]``; two ``[[1, 1], [1, -1]]``), invertible for every ``n`` up to 4 and all powers of 2.
    Read-only (made once per ``n``)."""
    size = 1 << max(0, (n - 1).bit_length())
    signs = scipy.linalg.hadamard(size).astype(float)[:n, :n]
    signs.flags.writeable = False
    return signs


@dataclass(frozen=True, eq=False)
class TraceN(Channels):
    """Recorded channels of one run of N axes, sampled at ``fs``; one column per axis.

    Attributes
    ----------
    force : ndarray
        (n, N) recorded forces at the bearing planes, N (through each transducer, plus its noise).
    displacement : ndarray
        (n, N) probe readings, m (at the probes' planes, through each probe's lag, plus noise).
    current : ndarray
        (n, N) coil control currents, A.
    fs : float
        Hz.
    axes : tuple of str
        The axes' names.
    """

    axes: tuple[str, ...]


def core_args(model: LoopModel, system: System, outputs: int | None = None) -> dict[str, np.ndarray]:
    """The core's model; ``outputs`` keeps the first rows only (experiments need the probes' N)."""
    rows = model.C.shape[0] if outputs is None else outputs
    return dict(M=model.M, Bf=model.Bf, Bn=model.Bn, C=model.C[:rows], Dn=model.Dn[:rows],
                transducer_pole=model.poles, sensor_noise=np.array([a.sensor_noise for a in system.axes]),
                force_noise=np.array([a.force_noise for a in system.axes]))  # fmt: skip


def simulate(
    system: System, controller: ControllerSpec, force: ArrayLike, *, seed: int | None = None, unbalance: Any = None,
    exciter: Literal["shaker", "amb"] = "shaker",
) -> TraceN:  # fmt: skip
    """Run the closed loop of N axes from rest on forces (n, N) (N, one column per axis' shaker) at the
    controller's ``fs``: zero-order held, the loop discretised exactly; ``seed`` fixes the noise.

    A rotor may carry ``unbalance=[(m_e, z, phase), ...]`` (kg m, m, rad; as :func:`unbalance_response`)
    at its constant speed ``W``: the force ``m_e W^2`` rotating from ``phase`` at ``t = 0``, continuous in
    time (not held), exact at the samples; the recorded forces stay the shakers'.

    ``exciter="amb"``: ``force`` is read as current (A) added to each axis' current command, as
    ``run_experiment(..., exciter="amb")`` does; ``TraceN.force`` is then that injection and ``current`` the
    coil currents it is in (no unbalance with it yet)."""
    require(exciter in ("shaker", "amb"), "exciter", exciter, "'shaker' (the shakers' forces) or 'amb' (the bearings)")
    require(unbalance is None or exciter == "shaker", "unbalance", unbalance, "None with exciter='amb' (not yet)")
    model = loop_model(system, controller)
    N = model.Bf.shape[1]
    array = np.ascontiguousarray(force, dtype=np.float64)
    names = system.mechanics().names
    require(array.ndim == 2 and array.shape[1] == N, "force shape", array.shape, f"(samples, {N}): columns {names}")
    args = core_args(model, system) if exciter == "shaker" else amb_args(model, system)
    if unbalance is not None:
        args, array = with_unbalance(system, controller, args, array, unbalance)
    recorded, out = _core.mimo_simulate(**args, force=array, seed=seed_value(seed))
    current = out[:, N : 2 * N] + (current_rows(system, model.fs)[1] * array if exciter == "amb" else 0.0)
    return TraceN(force=recorded[:, :N], displacement=out[:, :N], current=current, fs=model.fs, axes=names)


@dataclass(frozen=True, eq=False)
class EstimateN(EstimateBase):
    """N x N frequency-domain estimate at the excited lines; every matrix has shape (lines, N, N).

    Attributes
    ----------
    freq : ndarray
        Excited lines, Hz.
    H : ndarray
        Dynamic stiffness ``F Y^-1``, complex, N/m: ``H[:, i, j] = dF_i / dY_j`` (F: the recorded forces at
        the bearing planes; Y: the structure's reported displacements, at the bearing planes for a rotor).
    receptance : ndarray
        ``Y F^-1 = H^-1``, m/N.
    k, c : ndarray
        Actual stiffness ``Re(H + w^2 Mb - j w W Gb)`` (N/m) and damping ``Im(...) / w`` (N s/m): the
        structure's known mass and gyroscopic matrices at the bearing planes removed (paper eq. 9; mass
        loading not removed). ``k[:, i, j]`` is ROSS's ``k_ij`` (force ``-K q - C dq/dt``).
    k_smooth, c_smooth : ndarray
        Median filtered across the lines per entry (window ``median_window``, ends repeat the edge).
    k_std, c_std : ndarray
        Standard errors (first-order propagation of the period-to-period deviations of every
        experiment's spectra through ``F Y^-1``; ``periods - 1`` degrees of freedom).
    force, displacement : ndarray
        Period-averaged complex amplitudes, ``[:, channel, experiment]``, N and m.
    periods : int
        Periods averaged per experiment.
    axes : tuple of str
        The axes' names (``A.x, A.y, B.x, B.y`` for a rotor).
    process : ndarray or None
        With ``exciter="amb"``: the process ``K + j w C`` (complex, N/m) at the bearing planes in the
        estimate's frame, corrected for the hold, the amplifier's, eddy-current and probes' lags, the dead
        time and the mass loading, as the model knows them; None from shakers.
    """

    periods: int
    axes: tuple[str, ...]
    process: np.ndarray | None = None
    _units: ClassVar[dict[str, str]] = {"process": "N/m"}

    def bearing(self, name: str) -> BearingEstimate:
        """The 2x2 view of one bearing (``"A"`` or ``"B"`` of a rotor): its ``x`` and ``y`` axes' rows and
        columns of every matrix (the cross-bearing entries left out)."""
        groups = bearing_axes(self.axes)
        rows = groups.get(name, [])
        bearings = [g for g in groups if g]
        require(len(rows) == 2, "bearing", name, f"one of {bearings} (the estimate's axes: {self.axes})")
        pick = np.ix_(range(self.freq.size), rows, rows)
        return BearingEstimate(name, self.freq, self.k[pick], self.c[pick], self.k_smooth[pick], self.c_smooth[pick],
                               self.k_std[pick], self.c_std[pick], self.H[pick])  # fmt: skip

    def to_ross(self, nodes: int | Sequence[int], *, smoothed: bool = False, **kwargs: Any) -> Any:
        """``ross.BearingElement`` s holding the coefficients over the lines (the ``ross`` extra; see
        :func:`amb_fast.two_axis.to_ross`): two axes ``x``, ``y`` (one bearing) give one element at node
        ``nodes``; a rotor's bearings one each, A at ``nodes[0]``, B at ``nodes[1]``, as a list.

        ROSS's bearing element couples the two axes of one node only: the entries between the bearings
        (A's force from B's displacement, non-zero with probes off the bearing planes or a process between
        them) cannot go into it, and a :class:`UserWarning` says how large they are."""
        groups = bearing_axes(self.axes)
        require(all(len(rows) == 2 for rows in groups.values()), "estimate axes", self.axes,
                "two axes (x, y) per bearing for ROSS")  # fmt: skip
        if len(groups) == 1:
            return to_ross(self, nodes, smoothed=smoothed, **kwargs)  # type: ignore[arg-type]
        require(isinstance(nodes, (tuple, list)) and len(nodes) == len(groups), "nodes", nodes,
                f"one node per bearing {tuple(groups)}")  # fmt: skip
        k = self.k_smooth if smoothed else self.k
        bearing_of = np.array([axis.split(".")[0] for axis in self.axes])
        cross = bearing_of[:, None] != bearing_of[None, :]
        worst = float(np.max(np.abs(k[:, cross]))) / float(np.max(np.abs(k[:, ~cross])))
        if worst > 1e-9:
            warnings.warn(f"to_ross: the cross-bearing stiffness (A from B and B from A), up to {worst:.3g} of the "
                          "largest within-bearing entry, cannot go into ROSS's BearingElement and is left out",
                          UserWarning, stacklevel=2)  # fmt: skip
        return [to_ross(self.bearing(name), n, smoothed=smoothed, tag=f"amb_{name}", **kwargs)
                for name, n in zip(groups, nodes)]  # type: ignore[arg-type]  # fmt: skip

    def summary(self, at: Sequence[float] = (10.0, 40.0, 100.0, 200.0)) -> str:
        """A text table of every entry of K (N/m) and C (N s/m) at the lines nearest ``at`` (Hz)."""
        names = [a + b for a in self.axes for b in self.axes]
        out = [f"{'f (Hz)':>8} " + " ".join(f"{'k' + n + ' (N/m)':>14}" for n in names) + " "
               + " ".join(f"{'c' + n + ' (Ns/m)':>14}" for n in names)]  # fmt: skip
        for f in at:
            j = int(np.argmin(np.abs(self.freq - f)))
            out.append(f"{self.freq[j]:8.1f} " + " ".join(f"{v:14.6g}" for v in self.k[j].ravel()) + " "
                       + " ".join(f"{v:14.6g}" for v in self.c[j].ravel()))  # fmt: skip
        return "\n".join(out)

    save = _results.save_estimate  # .nc, .npz or .csv, checksummed; amb_fast.load_estimate reads it back
    to_xarray = _results.estimate_to_xarray
    to_dataframe = _results.estimate_to_dataframe
    plot = plot_coefficients_n


def bearing_axes(axes: tuple[str, ...]) -> dict[str, list[int]]:
    """Each bearing's axes (indices), by the name before the dot (``A.x``: bearing ``A``); axes without a
    dot (``x``, ``y``) are one bearing, named ``""``."""
    groups: dict[str, list[int]] = {}
    for j, axis in enumerate(axes):
        groups.setdefault(axis.split(".")[0] if "." in axis else "", []).append(j)
    return groups


@dataclass(frozen=True, eq=False)
class BearingEstimate(ArrayRecord):
    """The 2x2 view of one bearing of an :class:`EstimateN`: arrays (lines, 2, 2) over its ``x``, ``y``.

    Attributes
    ----------
    name : str
    freq : ndarray
        Hz.
    k, c, k_smooth, c_smooth, k_std, c_std : ndarray
        N/m, N s/m.
    H : ndarray
        N/m, complex.
    """

    name: str
    freq: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    H: np.ndarray

    def to_ross(self, n: int, *, smoothed: bool = False, **kwargs: Any) -> Any:
        """This bearing as a ``ross.BearingElement`` at node ``n`` (:func:`amb_fast.two_axis.to_ross`)."""
        return to_ross(self, n, smoothed=smoothed, **kwargs)


def line_spectra(x: np.ndarray, period: int, harmonics: Any = slice(None)) -> np.ndarray:  # noqa: ANN401
    """(experiments, periods * period, channels) to per-period line spectra (periods, lines, channel,
    experiment) at ``harmonics`` (default: every bin), unscaled DFT bins as the core's."""
    E, n, N = x.shape
    bins = np.fft.rfft(x.reshape(E, n // period, period, N), axis=2)[:, :, harmonics]
    return np.ascontiguousarray(bins.transpose(1, 2, 3, 0))


def median_lines(x: np.ndarray, window: int) -> np.ndarray:
    """Running median across the lines (axis 0) per entry; the ends repeat the edge value."""
    return _core.median_filter(np.ascontiguousarray(x.reshape(x.shape[0], -1)), window).reshape(x.shape)


def estimate(
    force_lines: np.ndarray, displacement_lines: np.ndarray, freq: np.ndarray, mechanics: Mechanics, period: int,
    median_window: int = 5,
) -> EstimateN:  # fmt: skip
    """The N x N estimate from every experiment's per-period line spectra (periods, lines, channel,
    experiment), complex, unscaled DFT bins; the displacements are the probes' readings (the structure's
    ``readout`` is applied here). ``H = F Y^-1`` per line with F, Y the period means; its standard errors
    from the linearised ``dH = (dF - H dY) Y^-1`` of every period."""
    N = mechanics.axes
    require(force_lines.shape[0] >= 2, "periods", force_lines.shape[0], ">= 2 (standard errors need at least two)")
    if N == 2:  # the core's closed-form 2x2 (a seventh of the general solve's time; the same to rounding)
        as_read = np.array_equal(mechanics.readout, np.eye(N))  # the probes' readings as they are: no product
        Yp = displacement_lines if as_read else np.ascontiguousarray(mechanics.readout @ displacement_lines)
        H, receptance, F, Y, var_re, var_im = _core.estimate_2x2(force_lines, Yp)
    else:  # the readout applied in the core
        H, receptance, F, Y, var_re, var_im = _core.estimate_nxn(force_lines, displacement_lines, mechanics.readout)
    k, c, k_std, c_std = coefficients(H, var_re, var_im, freq, mechanics)
    amplitude = 2.0 / period
    return EstimateN(freq=freq, H=H, receptance=receptance, k=k, c=c, k_smooth=median_lines(k, median_window),
                     c_smooth=median_lines(c, median_window), k_std=k_std, c_std=c_std, force=amplitude * F,
                     displacement=amplitude * Y, periods=int(force_lines.shape[0]), axes=mechanics.names)  # fmt: skip


def coefficients(
    H: np.ndarray, var_re: np.ndarray, var_im: np.ndarray, freq: np.ndarray, mechanics: Mechanics
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Actual k (N/m), c (N s/m) and their standard errors from ``H = F Y^-1`` and the variances of its
    parts, per line (``freq``, Hz, along the third axis from the end: (..., lines, N, N))."""
    actual = H - _known_dynamics(mechanics, freq)
    w = (2 * np.pi * freq)[:, None, None]
    return actual.real, actual.imag / w, np.sqrt(var_re), np.sqrt(var_im) / w


_known: dict[tuple, np.ndarray] = {}


def _known_dynamics(mechanics: Mechanics, freq: np.ndarray) -> np.ndarray:
    """:func:`known_dynamics`, read-only, kept per structure and lines: repeated experiments and a sweep's
    points over a process or a gain share them (the key costs a twentieth of making them)."""
    parts = (mechanics.mass, mechanics.gyroscopic, mechanics.actuators, mechanics.probes, mechanics.readout, freq,
             mechanics.elastic, mechanics.elastic_damping)  # a flexible structure's bending too  # fmt: skip
    key = (mechanics.coordinates, mechanics.axes, mechanics.speed,
           b"".join(b"-" if a is None else a.tobytes() for a in parts))  # fmt: skip
    known = _known.get(key)
    if known is None:
        if len(_known) >= 64:
            _known.clear()
        known = _known[key] = known_dynamics(mechanics, freq)
        known.flags.writeable = False
    return known


_last_forces: tuple[np.ndarray, np.ndarray] | None = None


def experiment_forces(excitation: Multisine, n: int) -> np.ndarray:
    """The n experiments' forces, (experiment, sample, axis): experiment ``e`` drives axis ``j`` with
    ``hadamard_signs(n)[e, j] s``. Read-only; the last one is kept, as repeated experiments and a sweep's
    points share their excitation, and comparing the samples costs a quarter of making them."""
    global _last_forces
    last, samples = _last_forces, excitation.samples
    if last is not None and last[1].shape[0] == n and last[0].shape == samples.shape:
        if np.array_equal(last[0], samples):
            return last[1]
    forces, signs = np.empty((n, samples.size, n)), hadamard_signs(n)
    for e, j in np.ndindex(n, n):  # a broadcast product over a short last axis takes ten times as long
        np.multiply(signs[e, j], samples, out=forces[e, :, j])
    forces.flags.writeable = False
    _last_forces = (samples.copy(), forces)
    return forces


def experiment_seeds(seed: int | None, n: int) -> list[int]:
    """The N experiments' seeds: the run's, then one of its own per further experiment (two axes: the seeds
    the two-axis experiment has always used)."""
    s = seed_value(seed)
    return [s] + [(s ^ (0xA5A5A5A5DEADBEEF * e)) % 2**64 for e in range(1, n)]


def settle_for(system: System, fs: float, poles: np.ndarray, period: int) -> int:
    """Periods from rest for the slowest pole (or transducer pole) to decay below 1e-9."""
    slowest = float(np.max(np.abs(poles), initial=0.0))
    for axis in system.axes:
        if axis.force_coupling_tau is not None:
            slowest = max(slowest, float(np.exp(-1.0 / (fs * axis.force_coupling_tau))))
    return settle_from(slowest, period)


def run_experiment(
    system: System,
    controller: ControllerSpec,
    excitation: Multisine,
    *,
    periods: int = 10,
    settle_periods: int | None = None,
    seed: int | None = None,
    median_window: int = 5,
    start: Literal["steady", "rest"] = "steady",
    exciter: Literal["shaker", "amb"] = "shaker",
) -> EstimateN:
    """The SPHS identification of N axes: N experiments with Hadamard signs on the shakers, then ``H = F Y^-1``.

    Each experiment records ``periods`` periods from the exact periodic steady state (``start="steady"``:
    the line spectra drawn directly, exact in distribution) or from rest after ``settle_periods``
    (default: enough for the slowest pole to decay below 1e-9). ``seed`` fixes the noise of all
    experiments. Raises :class:`UnstableLoopError` for an unstable loop (naming the speed for a rotor).

    ``exciter="amb"``: the bearings excite instead (:mod:`._exciter`): the excitation's samples, read as
    current in A, are added to each axis' current command after the controller (Hadamard signs); the force
    is estimated from the coil current and the probes, ``F = -kyy d - kiy i``, so ``H``, ``k``, ``c`` hold
    the structure's own dynamic stiffness at the bearings as the sampled signals give it, and
    ``EstimateN.process`` its process with the hold and the known lags removed. The current is the
    amplifier's output: ``H``, ``k``, ``c`` carry the eddy-current lag (``Rig.eddy_bandwidth``) between it and
    the force; ``process`` removes it as the model knows it.
    """
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    options = run_options(periods, settle_periods, median_window, start)
    periods, settle_periods, window = options["periods"], options["settle_periods"], options["median_window"]
    require(exciter in ("shaker", "amb"), "exciter", exciter, "'shaker' (the shakers' forces) or 'amb' (the bearings)")
    mech = system.mechanics()
    N = mech.axes
    spec = controller_matrix(controller, N)
    require(excitation.fs == spec.fs, "excitation.fs", excitation.fs, f"equal to the controller's fs ({spec.fs} Hz)")
    what = "the closed loop" + (f" at speed {mech.speed:g} rad/s" if mech.speed else "")
    poles = require_stable(system, spec, what)
    model = loop_model(system, spec)
    settle = settle_periods
    if settle is None:
        settle = 0 if start == "steady" else settle_for(system, spec.fs, poles, excitation.period_samples)
    forces = experiment_forces(excitation, N)  # (experiment, sample, axis)
    seeds = experiment_seeds(seed, N)
    harmonics = excitation.harmonics
    args = amb_args(model, system) if exciter == "amb" else core_args(model, system, outputs=N)
    # Drawn from the steady state, all N experiments in one call (the per-line solves once); from rest the
    # core runs up to two in lock step.
    step = N if start == "steady" else 2
    try:
        parts = [_core.mimo_line_experiments(**args, period_forces=np.ascontiguousarray(forces[first : first + step]),
                                             settle_periods=settle, periods=periods, seeds=seeds[first : first + step],
                                             steady_start=start == "steady", bins=harmonics)
                 for first in range(0, N, step)]  # fmt: skip
    except OverflowError as error:  # poles inside the circle, yet the spectra overflowed: say which pole, how close
        radius = float(np.max(np.abs(poles)))
        raise OverflowError(f"{what} has its slowest pole at |z| = 1 - {1.0 - radius:.3g}, within rounding of the "
                            f"unit circle: its stationary state cannot be computed ({error})") from error  # fmt: skip
    Fp, Yp = parts[0] if len(parts) == 1 else (np.concatenate([part[i] for part in parts], axis=-1) for i in (0, 1))
    if exciter == "shaker":
        return estimate(Fp, Yp, harmonics * excitation.f0, mech, excitation.period_samples, window)
    est = estimate(*amb_lines(system, spec.fs, Fp, Yp), harmonics * excitation.f0, mech, excitation.period_samples,
                   window)  # fmt: skip
    return replace(est, process=corrected_process(system, spec.fs, est.freq, est.H))
