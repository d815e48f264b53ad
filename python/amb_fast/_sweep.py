"""Gain sweeps: many experiments in one batched C++ call, on threads or any executor."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._blas import one_blas_thread
from ._dispatch import two_axis_aware
from ._excitation import Multisine
from ._experiment import _plan, _window, automatic_settle
from ._linear import AnyController, core_controller, is_controller, loop_poles, spectral_radius
from ._params import PID, Rig
from ._validate import integer, require, rig_and_controller, seed_value


def _version() -> str:
    from . import __version__

    return __version__


SWEPT = ("kp", "ki", "kd")  # the PID gains: swept together in closed form
STATUS = ("ok", "unstable", "touchdown", "saturated")  # index = the core's PointStatus
UNITS = {
    "kp": "A/m", "ki": "A/(m s)", "kd": "A s/m", "derivative_cutoff": "Hz", "mass": "kg", "kyy": "N/m",
    "kiy": "N/A", "bias_current": "A", "amp_bandwidth": "Hz", "eddy_bandwidth": "Hz", "sensor_bandwidth": "Hz",
    "sensor_noise": "m rms", "force_noise": "N rms", "mass_loading": "kg", "force_coupling_tau": "s",
    "clearance": "m", "current_limit": "A",
}  # fmt: skip
RIG_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps"))
Factory = Callable[..., tuple[Rig, AnyController]]


def unit_of(name: str) -> str:
    """Unit of a sweep axis: a rig or PID field's, Hz for a block's frequency, else ``""``."""
    if name in UNITS:
        return UNITS[name]
    return "Hz" if name.endswith("_freq") or name.endswith("_width") else ""


# Labelled in Python: the core reports a linear-law point whose state overflowed as "touchdown" (it
# reached an infinite clearance); without a clearance that is an overflow (saturation made it diverge).
OVERFLOW = "overflow"
STATUS_NAMES = (*STATUS, OVERFLOW)


@dataclass(frozen=True)
class SweepResult:
    """Estimates of every point of a sweep, in grid order; what :func:`sweep` returns.

    Attributes
    ----------
    points : dict of str to ndarray
        Each swept parameter's value at every point (units: :func:`unit_of`, e.g. A/m for kp).
    axes : dict of str to ndarray
        The values given for each swept parameter; for ``grid="product"`` the grid's shape is their
        lengths (C order: the last name varies fastest).
    grid : {"product", "zip"}
        How the axes were combined.
    freq : ndarray
        Excited lines, Hz.
    H, k, c, k_smooth, c_smooth, k_std, c_std : ndarray
        Shape (points, lines), as in :class:`Estimate`: ``H`` (complex), ``k``, ``k_smooth``, ``k_std``
        in N/m; ``c``, ``c_smooth``, ``c_std`` in N s/m. NaN where status is not ok.
    status : ndarray of str
        "ok"; "unstable" (a linearised pole on or outside the unit circle, found before simulating);
        "touchdown" (the platform reached its clearance, or the air gap with the non-linear law);
        "saturated" (the amplifier clipped: ``Rig.current_limit``); "overflow" (a linear-law point whose
        state stopped being finite, e.g. diverging under saturation, with no clearance to touch).
    settle_periods, seeds : ndarray
        What each point ran with (periods; uint64 seeds): ``run_experiment(rig, pid_i, excitation,
        periods=periods, seed=int(seeds[i]))`` reproduces point i bit for bit.
    unexcited_freq : ndarray
        Unexcited harmonics, Hz; ``unexcited_displacement`` (points, lines) their levels, m.
    periods, blocks : int
        Periods averaged per point; independent groups behind the standard errors.
    meta : dict
        What produced the sweep, saved with it: the rig's fields, the controller, ``f0`` and ``fs``
        (Hz), the base seed and the amb_fast version.

    See Also
    --------
    sweep, load_sweep, plot_family

    Examples
    --------
    >>> result = af.sweep(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(), kp=[2000.0, 2400.0],
    ...                   kd=[2.0, 3.0, 4.0], seed=1, progress=False)
    >>> result.shape, result.k.shape                        # a 2 x 3 grid of 200 lines each
    ((2, 3), (6, 200))
    >>> k = result.k.reshape(*result.shape, -1)             # (kp, kd, lines), N/m
    >>> result.to_xarray().k.dims
    ('kp', 'kd', 'freq')
    """

    points: dict[str, np.ndarray]
    axes: dict[str, np.ndarray]
    grid: str
    freq: np.ndarray
    H: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    status: np.ndarray
    settle_periods: np.ndarray
    seeds: np.ndarray
    unexcited_freq: np.ndarray
    unexcited_displacement: np.ndarray
    periods: int
    blocks: int
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape: one axis per swept parameter for product grids, else (points,)."""
        if self.grid == "product":
            return tuple(len(v) for v in self.axes.values())
        return (len(self.status),)

    def to_xarray(self):  # noqa: ANN201 - xarray is optional
        """An ``xarray.Dataset`` with one dimension per swept parameter (product grids) or ``point``, and ``freq``."""
        try:
            import xarray as xr
        except ImportError as error:
            raise ImportError("to_xarray needs xarray: pip install 'amb_fast[xarray]'") from error
        if self.grid == "product":
            dims = list(self.axes)
            coords: dict[str, Any] = {
                name: (name, values, {"units": unit_of(name)}) for name, values in self.axes.items()
            }
        else:
            dims = ["point"]
            coords = {name: ("point", values, {"units": unit_of(name)}) for name, values in self.points.items()}
        coords["freq"] = ("freq", self.freq, {"units": "Hz"})
        coords["unexcited_freq"] = ("unexcited_freq", self.unexcited_freq, {"units": "Hz"})
        shape = self.shape

        def var(values: np.ndarray, units: str, lines: str = "freq") -> tuple:
            return ([*dims, lines], values.reshape(*shape, values.shape[-1]), {"units": units})

        data = {
            "H": var(self.H, "N/m"),
            "k": var(self.k, "N/m"),
            "c": var(self.c, "N s/m"),
            "k_smooth": var(self.k_smooth, "N/m"),
            "c_smooth": var(self.c_smooth, "N s/m"),
            "k_std": var(self.k_std, "N/m"),
            "c_std": var(self.c_std, "N s/m"),
            "unexcited_displacement": var(self.unexcited_displacement, "m", "unexcited_freq"),
            "status": (dims, self.status.reshape(shape)),
            "settle_periods": (dims, self.settle_periods.reshape(shape)),
            "seeds": (dims, self.seeds.reshape(shape)),
        }
        attrs = {"grid": self.grid, "periods": self.periods, "blocks": self.blocks, "meta": json.dumps(self.meta),
                 "axes": json.dumps(list(self.axes))}  # fmt: skip
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def to_dataframe(self):  # noqa: ANN201 - pandas is optional
        """A ``pandas.DataFrame``: one row per point and line (swapped gains, status, freq_Hz, estimates)."""
        from .io._results import sweep_to_dataframe

        return sweep_to_dataframe(self)

    def save(self, path: str | Path) -> None:
        """Write atomically to ``.nc`` (NetCDF via xarray and h5netcdf; H as real and imaginary parts;
        fletcher32 and a SHA-256 checked by :func:`load_sweep`) or ``.npz`` (zip CRC-32 per array)."""
        from .io import atomic_path, write_netcdf

        path = Path(path)
        if path.suffix == ".nc":
            ds = self.to_xarray()
            ds["H_real"], ds["H_imag"] = ds.H.real, ds.H.imag
            write_netcdf(ds.drop_vars("H").assign(status=ds.status.astype(str)), path)
        elif path.suffix == ".npz":
            arrays = {name: getattr(self, name) for name in _ARRAYS}
            arrays |= {f"point_{k}": v for k, v in self.points.items()} | {f"axis_{k}": v for k, v in self.axes.items()}
            header = {"grid": self.grid, "periods": self.periods, "blocks": self.blocks, "meta": self.meta}
            with atomic_path(path) as target, open(target, "wb") as handle:
                np.savez_compressed(handle, header=json.dumps(header), **arrays)
        else:
            raise ValueError(f"path must end in .nc or .npz, got {str(path)!r}")


_ARRAYS = ("freq", "H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "status", "settle_periods", "seeds",
           "unexcited_freq", "unexcited_displacement")  # fmt: skip


def load_sweep(path: str | Path) -> SweepResult:
    """Read a sweep written by :meth:`SweepResult.save` (``.nc`` or ``.npz``).

    Parameters
    ----------
    path : str or path-like
        A ``.nc`` (NetCDF: needs the ``xarray`` extra) or ``.npz`` file written by :meth:`SweepResult.save`.

    Returns
    -------
    SweepResult
        The sweep as saved: gains in their units (A/m, A/(m s), A s/m, Hz), ``freq`` in Hz, ``k`` N/m,
        ``c`` N s/m, statuses and seeds. A file whose checksums do not match (fletcher32 and SHA-256 in
        NetCDF, CRC-32 in ``.npz``) is refused with a ``ValueError``, and so is another suffix.

    See Also
    --------
    SweepResult.save, sweep

    Examples
    --------
    >>> import tempfile, pathlib
    >>> result = af.sweep(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(), kd=[2.0, 3.0],
    ...                   seed=1, progress=False)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "kd.npz"
    >>> result.save(path)
    >>> back = af.load_sweep(path)
    >>> bool(np.array_equal(back.k, result.k)), back.points["kd"]
    (True, array([2., 3.]))
    """
    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    from .io import read_netcdf
    from .io._results import read_npz

    if path.suffix == ".npz":
        f = read_npz(path)  # a damaged member fails its CRC-32 and is refused
        header = json.loads(str(f["header"]))
        arrays = {name: f[name] for name in _ARRAYS}
        points = {k[6:]: f[k] for k in f if k.startswith("point_")}
        axes = {k[5:]: f[k] for k in f if k.startswith("axis_")}
        return SweepResult(points=points, axes=axes, **arrays, **header)
    if path.suffix != ".nc":
        raise ValueError(f"path must end in .nc or .npz, got {str(path)!r}")
    ds = read_netcdf(path)  # refuses a file whose checksums do not match
    grid = ds.attrs["grid"]
    names = json.loads(ds.attrs["axes"]) if "axes" in ds.attrs else [n for n in SWEPT if n in ds.coords]
    n_dims = len(names) if grid == "product" else 1

    n_points = int(ds.status.size)

    def rows(name: str) -> np.ndarray:
        values = np.asarray(ds[name].values)
        return values.reshape(n_points, *values.shape[n_dims:])

    if grid == "product":
        axes = {n: np.asarray(ds[n].values) for n in names}
        mesh = np.meshgrid(*axes.values(), indexing="ij")
        points = {n: m.ravel() for n, m in zip(names, mesh)}
    else:
        points = {n: np.asarray(ds[n].values) for n in names}
        axes = dict(points)
    return SweepResult(
        points=points,
        axes=axes,
        grid=grid,
        freq=np.asarray(ds.freq.values),
        H=rows("H_real") + 1j * rows("H_imag"),
        k=rows("k"),
        c=rows("c"),
        k_smooth=rows("k_smooth"),
        c_smooth=rows("c_smooth"),
        k_std=rows("k_std"),
        c_std=rows("c_std"),
        status=rows("status").astype(str),
        settle_periods=rows("settle_periods"),
        seeds=rows("seeds").astype(np.uint64),
        unexcited_freq=np.asarray(ds.unexcited_freq.values),
        unexcited_displacement=rows("unexcited_displacement"),
        periods=int(ds.attrs["periods"]),
        blocks=int(ds.attrs["blocks"]),
        meta=json.loads(ds.attrs["meta"]),
    )


def point_seeds(seed: int, count: int) -> np.ndarray:
    """One 64-bit seed per point from a base seed (splitmix64 of base + index): the same point gets
    the same noise however the sweep is split across workers."""
    z = np.uint64(seed) + (np.arange(1, count + 1, dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15))
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def _grid(values: dict[str, ArrayLike], grid: str) -> tuple[dict, dict]:
    require(grid in ("product", "zip"), "grid", grid, "'product' or 'zip'")
    axes = {}
    for name, given in values.items():
        array = np.atleast_1d(np.asarray(given, dtype=float))
        require(array.ndim == 1 and array.size > 0, name, given, "a non-empty 1-D sequence")
        require(bool(np.all(np.isfinite(array))), name, given, f"finite ({unit_of(name) or 'no unit'})")
        axes[name] = array
    require(bool(axes), "axes", None, "at least one swept parameter (e.g. kp=[...], amp_bandwidth=[...])")
    if grid == "product":
        mesh = np.meshgrid(*axes.values(), indexing="ij")
        points = {name: m.ravel() for name, m in zip(axes, mesh)}
    else:
        sizes = {name: a.size for name, a in axes.items()}
        require(len(set(sizes.values())) == 1, "lengths", sizes, "equal for grid='zip'")
        points = dict(axes)
    return axes, points


def _controller_params(controller: AnyController) -> dict[str, float]:
    if isinstance(controller, PID):
        return {"kp": controller.kp, "ki": controller.ki, "kd": controller.kd,
                "derivative_cutoff": controller.derivative_cutoff}  # type: ignore[dict-item]  # fmt: skip
    return dict(getattr(controller, "params", {}))


def _check_names(rig: Rig, controller: AnyController, names: list[str]) -> None:
    known = [*RIG_FIELDS, *_controller_params(controller)]
    for name in names:
        require(name in known, "sweep axis", name,
                f"a numeric Rig field or a controller parameter: one of {', '.join(known)}")  # fmt: skip


def point_model(
    rig: Rig, controller: AnyController, values: dict[str, float], factory: Factory | None = None
) -> tuple[Rig, AnyController]:
    """The rig and controller of one sweep point: ``factory(**values)``, or ``rig`` and ``controller``
    with the named fields (rig fields first, then controller parameters) replaced."""
    if factory is not None:
        made = factory(**values)
        require(isinstance(made, tuple) and len(made) == 2 and isinstance(made[0], Rig), "factory result",
                made, "a (Rig, controller) pair")  # fmt: skip
        return made
    on_rig = {k: v for k, v in values.items() if k in RIG_FIELDS}
    on_controller = {k: v for k, v in values.items() if k not in RIG_FIELDS}
    if on_rig:
        rig = replace(rig, **on_rig)  # type: ignore[arg-type]
    if on_controller:
        if isinstance(controller, PID):
            controller = replace(controller, **on_controller)  # type: ignore[arg-type]
        else:
            controller = controller.with_params(**on_controller)
    return rig, controller


def _run_chunk(
    rig: Rig | None, controller: AnyController | None, factory: Factory | None, excitation: Multisine,
    values: dict[str, np.ndarray], seeds: np.ndarray, periods: int, settle_periods: int | None, window: int,
    workers: int, start: str = "steady", cancel: _core.CancelToken | None = None,
) -> dict[str, np.ndarray]:  # fmt: skip
    """One unit of work, for a thread or any executor (picklable arguments, numpy results): each
    point's rig and controller, the stability check (an unstable point is flagged, never simulated),
    the settling time, then one batched core call for the stable points."""
    n = len(seeds)
    names = list(values)
    if factory is None and isinstance(controller, PID) and set(names) <= set(SWEPT):
        # PID gains only: the closed loop is affine in them, so all radii come in one call.
        assert rig is not None
        radius = spectral_radius(rig, controller, **{name: values[name] for name in names})
        gains: list[dict[str, Any]] = [{k: float(values[k][j]) for k in names} for j in range(n)]
        models: list[tuple[Rig, AnyController]] = [(rig, replace(controller, **point)) for point in gains]
    else:
        models = [point_model(rig, controller, {k: float(values[k][j]) for k in names}, factory)  # type: ignore[arg-type]
                  for j in range(n)]  # fmt: skip
        radius = np.array([np.max(np.abs(loop_poles(r, c)), initial=0.0) for r, c in models])
    fs = excitation.fs
    for _, c in models:
        require(c.fs == fs, "controller fs", c.fs, f"equal to the excitation's fs ({fs} Hz)")
    stable = radius < 1.0
    if settle_periods is None:  # the rule of run_experiment, so every point reruns bit for bit
        period = excitation.period_samples
        settle = np.array([automatic_settle(r, c, float(rad), period, start) if ok else 0
                           for (r, c), rad, ok in zip(models, radius, stable)])  # fmt: skip
    else:
        settle = np.full(n, settle_periods)
    plan, unexcited = _plan(excitation.harmonics, excitation.period_samples)
    lines = len(excitation.harmonics)
    out: dict[str, np.ndarray] = {name: np.full((n, lines), np.nan) for name in _CORE_FIELDS[:-2]}
    out["H"] = np.full((n, lines), np.nan + 0j)
    out["unexcited_displacement"] = np.full((n, len(unexcited)), np.nan)
    out["status"] = np.full(n, STATUS.index("unstable"), dtype=np.int32)
    out["settle_periods"] = settle.astype(np.int64)
    rows = np.flatnonzero(stable)
    if rows.size:
        masses = {models[j][0].mass for j in rows}
        require(len(masses) == 1, "mass", sorted(masses), "the same at every point of a sweep (kg)")

        def core_call(pick: np.ndarray):  # noqa: ANN202
            at = rows[pick]
            return _core.run_sweep(excitation.samples, [models[j][0]._to_core() for j in at],
                                   [core_controller(models[j][1]) for j in at], out["settle_periods"][at],
                                   seeds[at], periods, plan, window, workers, start == "steady", cancel)  # fmt: skip

        everything = np.arange(rows.size)
        try:
            parts = [(everything, core_call(everything))]
        except (ValueError, OverflowError):  # a point diverged (e.g. under saturation): find it, flag it
            parts = []
            for j in everything:
                try:
                    parts.append((everything[j : j + 1], core_call(everything[j : j + 1])))
                except (ValueError, OverflowError):
                    out["status"][rows[j]] = STATUS_NAMES.index(OVERFLOW)
        for pick, core in parts:
            for name in _CORE_FIELDS:
                out[name][rows[pick]] = np.asarray(getattr(core, name))
        for j in rows:  # no clearance to touch on the linear law: the state overflowed
            point_rig = models[j][0]
            unbounded = point_rig.force_law == "linear" and point_rig.clearance is None
            if out["status"][j] == STATUS.index("touchdown") and unbounded:
                out["status"][j] = STATUS_NAMES.index(OVERFLOW)
    return out


_CORE_FIELDS = ("H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "unexcited_displacement", "status")


def _progress_bar(progress: bool | None, total: int):  # noqa: ANN202
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError as error:
        raise ImportError("progress=True needs tqdm: pip install 'amb_fast[progress]'") from error
    return tqdm(total=total, unit="point", desc="sweep")


@two_axis_aware
@one_blas_thread
def sweep(
    rig: Rig | Factory,
    controller: AnyController | Multisine,
    excitation: Multisine | None = None,
    *,
    grid: Literal["product", "zip"] = "product",
    periods: int = 10,
    settle_periods: int | None = None,
    workers: int | None = None,
    executor: Executor | None = None,
    progress: bool | None = None,
    seed: int | None = None,
    median_window: int = 5,
    chunk_size: int | None = None,
    start: Literal["steady", "rest"] = "steady",
    **axes: ArrayLike,
) -> SweepResult:
    """Run the experiment of :func:`run_experiment` for many rigs and controllers.

    ``sweep(rig, controller, excitation, kp=[...], amp_bandwidth=[...])``: each keyword names what it
    sweeps: a numeric field of the :class:`Rig` (``kyy``, ``amp_bandwidth``, ``mass_loading``, ...),
    a field of a :class:`PID` (``kp``, ``ki``, ``kd``, ``derivative_cutoff``) or a parameter of a
    :class:`~amb_fast.Controller` (its ``params``: ``kp``, ``notch_freq``, ``low_pass_freq``, ...;
    the names are ``<block>_<parameter>``, see :class:`~amb_fast.Controller`). Everything not swept
    stays as given. ``sweep(factory, excitation, x=[...], y=[...])`` takes any callable
    ``factory(**point) -> (rig, controller)`` instead, for anything else.

    Parameters
    ----------
    rig : Rig, or callable
        The rig every point starts from; or ``factory(**point) -> (rig, controller)``, called for each
        point with its values (then the next argument is the excitation).
    controller : PID or Controller
        The controller every point starts from (with a factory: the :class:`Multisine`).
    excitation : Multisine
        The periodic excitation (N), at the controller's ``fs``.
    grid : {"product", "zip"}
        ``"product"`` crosses the axes (one grid dimension each, the last varying fastest), ``"zip"``
        pairs them (all of one length).
    periods : int
        Periods averaged per point (as in :func:`run_experiment`).
    settle_periods : int, optional
        Periods run before recording, with ``start="rest"`` (default: from the slowest pole, per point).
    workers : int, optional
        Core threads per batched call (default: all cores here; one per chunk on an ``executor``).
    executor : concurrent.futures.Executor, optional
        Runs the chunks: threads, processes, or a dask cluster's ``client.get_executor()``.
    progress : bool, optional
        A tqdm progress bar (default: when stderr is a terminal).
    seed : int, optional
        Fixes the measurement noise; each point gets its own seed (``SweepResult.seeds``).
    median_window : int
        Odd window (lines) of ``k_smooth``, ``c_smooth``.
    chunk_size : int, optional
        Points per chunk (default: see below).
    start : {"steady", "rest"}
        As in :func:`run_experiment`: from the exact periodic steady state, or from rest.
    **axes : array_like
        The swept values, in each parameter's unit (``kp`` A/m, ``ki`` A/(m s), ``kd`` A s/m, frequencies
        Hz, ``kyy`` N/m, ``mass_loading`` kg, ...).

    Returns
    -------
    SweepResult
        Every point's estimate (``k`` N/m, ``c`` N s/m over ``freq`` Hz) and status, in grid order.

    Notes
    -----
    Points whose linearised loop is unstable are flagged and not simulated; the rest run in a batched
    C++ core (points with the same rig and controller shape advance in lock step), ``workers`` threads
    per call, with the GIL released. Every point equals :func:`run_experiment` of that point bit for bit.

    The grid is cut into chunks of ``chunk_size`` points (default: equal chunks, a multiple of the
    number of workers, up to eight per worker and of at least 32 points where there are enough), each run
    by the batched core: on ``workers`` threads here, or on ``executor`` (each chunk then uses
    ``workers`` core threads, default one). Results come back in grid order.

    See Also
    --------
    SweepResult, run_experiment, load_sweep, amb_fast.two_axis.sweep

    Examples
    --------
    >>> rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine()
    >>> result = af.sweep(rig, pid, sphs, kp=[2000.0, 2400.0, 2800.0], seed=1, progress=False)
    >>> result.status
    array(['ok', 'ok', 'ok'], dtype='<U9')
    >>> one = af.run_experiment(rig, af.PID.paper(), sphs, seed=int(result.seeds[1]))   # kp = 2400
    >>> bool(np.array_equal(one.k, result.k[1]))                                      # bit for bit
    True
    >>> notched = af.sweep(rig, pid.to_controller() * af.notch(700.0), sphs, notch_freq=[500.0, 900.0],
    ...                    seed=1, progress=False)
    >>> notched.points["notch_freq"]
    array([500., 900.])
    """
    require(start in ("steady", "rest"), "start", start, "'steady' or 'rest'")
    factory: Factory | None = None
    base_controller: Any
    if callable(rig) and not isinstance(rig, Rig) and not is_controller(rig):
        require(excitation is None, "excitation", excitation, "given once: sweep(factory, excitation, **axes)")
        factory, excitation, base_rig, base_controller = rig, controller, None, None  # type: ignore[assignment]
    else:
        rig_and_controller(rig, controller, "sweep")
        assert isinstance(rig, Rig)
        base_rig, base_controller = rig, controller
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    assert isinstance(excitation, Multisine)
    if base_controller is not None:
        require(excitation.fs == base_controller.fs, "excitation.fs", excitation.fs,
                f"equal to the controller's fs ({base_controller.fs} Hz)")  # fmt: skip
    axes_values, points = _grid(axes, grid)
    if factory is None:
        _check_names(base_rig, base_controller, list(points))  # type: ignore[arg-type]
    periods = integer("periods", periods, 2)
    window = _window(median_window)
    n = len(next(iter(points.values())))

    if settle_periods is not None:
        settle_periods = integer("settle_periods", settle_periods, 0)
    base_seed = seed_value(seed)
    seeds = point_seeds(base_seed, n)
    threads = integer("workers", workers if workers is not None else (os.cpu_count() or 1), 1)
    require(executor is None or callable(getattr(executor, "submit", None)), "executor", executor,
            "a concurrent.futures.Executor (with submit)")  # fmt: skip
    require(progress in (None, True, False), "progress", progress, "True, False or None")
    if chunk_size is not None:
        size = integer("chunk_size", chunk_size, 1)
    else:  # equal work per thread: a multiple of `threads` chunks, up to eight each, of at least 32 points
        count = min(8 * threads, max(1, -(-n // 32)))
        count = -(-count // threads) * threads
        size = -(-n // count)
    chunks = [np.arange(i, min(i + size, n)) for i in range(0, n, size)]
    # Threads here (the core releases the GIL), or the executor's workers with `workers` core
    # threads per chunk (default one).
    core_threads = workers if (executor is not None and workers is not None) else 1
    run_on: Executor = executor if executor is not None else ThreadPoolExecutor(threads)
    _, unexcited = _plan(excitation.harmonics, excitation.period_samples)
    results: dict[str, np.ndarray] = {}
    bar = _progress_bar(progress, n)
    # Chunks on our own threads stop between periods when the sweep is interrupted (Ctrl-C reaches
    # this thread while it waits); an executor's workers finish their chunks.
    cancel = _core.CancelToken() if executor is None else None
    try:
        futures = [
            run_on.submit(
                _run_chunk,
                base_rig,
                base_controller,
                factory,
                excitation,
                {name: values[rows] for name, values in points.items()},
                seeds[rows],
                periods,
                settle_periods,
                window,
                core_threads,
                start,
                cancel,
            )  # fmt: skip
            for rows in chunks
        ]
        for rows, future in zip(chunks, futures):
            for name, values in future.result().items():
                if name not in results:
                    results[name] = np.empty((n, *values.shape[1:]), dtype=values.dtype)
                results[name][rows] = values
            if bar is not None:
                bar.update(rows.size)
    except BaseException:
        if cancel is not None:
            cancel.cancel()
        raise
    finally:
        if executor is None:
            run_on.shutdown(cancel_futures=True)
        if bar is not None:
            bar.close()
    status = np.array(STATUS_NAMES)[results.pop("status")]
    settle = results.pop("settle_periods")
    if isinstance(base_controller, PID):
        described: Any = base_controller.__dict__
    else:
        described = repr(factory if factory is not None else base_controller)

    return SweepResult(
        points=points,
        axes=axes_values,
        grid=grid,
        freq=excitation.freq,
        status=status,
        settle_periods=settle,
        seeds=seeds,
        unexcited_freq=unexcited * excitation.f0,
        periods=periods,
        blocks=periods // max(1, periods // 32),
        meta={
            "rig": None if base_rig is None else base_rig.__dict__,
            "controller": described,
            "f0": excitation.f0,
            "fs": excitation.fs,
            "seed": base_seed,
            "amb_fast_version": _version(),
        },  # fmt: skip
        **results,
    )
