"""Sweeps of N axes: :func:`run_experiment` over a grid of points named by parameter paths.

A path names what a point changes: a number of the rig or of a part of it (``kxy``, ``sensor_angle`` of a
:class:`~amb_fast.TwoAxisRig`; ``rotor.mass``, ``rotor.polar_inertia``, ``speed`` (the rotor's spin,
rad/s) of a :class:`RotorRig`), ``<Rig field>`` on every axis' chain or ``<axis>.<Rig field>`` on one
(``A.x.amp_bandwidth``; ``x.amp_bandwidth`` or ``x_amp_bandwidth`` on two axes), ``kp``, ``ki``, ``kd``,
``derivative_cutoff`` on every diagonal PID of the controller matrix and ``cross_<gain>`` on every
off-diagonal one.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from concurrent.futures import Executor
from dataclasses import dataclass, fields, is_dataclass, replace
from numbers import Real
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._equality import ArrayRecord
from .._errors import UnstableLoopError
from .._excitation import Multisine
from .._experiment import run_options
from .._linear import checked_poles, eigenvalues
from .._params import PID, Rig
from .._sweep import point_seeds, run_or_split, run_points
from .._sweep_result import OVERFLOW, read_sweep_file, register_sweep_kind, sweep_grid, unit_of
from .._validate import require, seed_value
from ..io import RESULT_UNITS, complex_variable, pandas_module, split_complex, write_netcdf, write_npz, xarray_module
from ._control import ControllerMatrix, ControllerSpec, controller_matrix
from ._experiment import coefficients, core_args, experiment_forces, experiment_seeds, run_experiment, settle_for
from ._model import System, loop_models
from ._results import _long

_AXIS_FIELDS = tuple(f.name for f in fields(Rig) if f.name not in ("force_law", "substeps", "mass"))
_GAINS = ("kp", "ki", "kd", "derivative_cutoff")
_ESTIMATES = ("k", "c", "k_std", "c_std", "receptance")  # (points, lines, N, N) each
_KIND = "SweepResultN"  # an .npz header's ``kind``, a .nc file's ``amb_fast_kind``


@dataclass(frozen=True, eq=False)
class SweepResultN(ArrayRecord):
    """Estimates of N axes over a grid of points; matrices (points, lines, N, N), in grid order (for
    ``grid="product"`` the last name varies fastest).

    Attributes
    ----------
    params : dict of str to ndarray
        Each swept path's value per point, in its unit (``speed`` rad/s, ``kxy`` N/m, ``kp`` A/m, ...).
    freq : ndarray
        Lines, Hz.
    k, c, k_std, c_std : ndarray
        Actual stiffness (N/m), damping (N s/m) and their standard errors; ``k[p, :, i, j]`` is ROSS's
        ``k_ij`` at point p. NaN at unstable points.
    receptance : ndarray
        ``Y F^-1``, complex, m/N; NaN at unstable points.
    stable : ndarray
        Per point, bool (unstable points are not run).
    seeds : ndarray
        Per point, uint64: ``run_experiment(*point_model(rig, controller, point), excitation,
        seed=int(seeds[i]))`` reproduces point i bit for bit.
    axes : tuple of str
        The axes' names.

    Examples
    --------
    >>> rig, pid, sphs = af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine()
    >>> kxy = np.array([0.0, 1e4, 3e4])                                          # N/m
    >>> result = af.two_axis.sweep(rig, pid, sphs, grid="zip", kxy=kxy, kyx=-kxy, seed=1)
    >>> result.k.shape, result.stable                    # the circulatory 3e4 N/m destabilises the loop
    ((3, 200, 2, 2), array([ True,  True, False]))
    >>> bool(np.isnan(result.k[2]).all())
    True
    """

    params: dict[str, np.ndarray]
    freq: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    receptance: np.ndarray
    stable: np.ndarray
    seeds: np.ndarray
    axes: tuple[str, ...]

    @property
    def status(self) -> np.ndarray:
        """Per point: ``"ok"``; ``"unstable"`` (not run); ``"overflow"`` (stable, but its line spectra
        overflowed: a pole within rounding of the unit circle, whose stationary state cannot be computed;
        rows NaN)."""
        ran = np.isfinite(self.k).any(axis=tuple(range(1, self.k.ndim)))
        return np.where(~self.stable, "unstable", np.where(ran, "ok", OVERFLOW))

    def to_xarray(self):  # noqa: ANN201 - xarray is optional
        """An ``xarray.Dataset`` over ``(point, freq, out, in)``; the swept paths are coordinates along
        ``point`` (with their units), and ``status``, ``stable``, ``seeds`` per point."""
        names = np.array(self.axes)
        matrices = ("point", "freq", "out", "in")
        data = {name: (matrices, getattr(self, name), {"units": RESULT_UNITS[name]}) for name in _ESTIMATES}
        data |= {name: (("point",), getattr(self, name), {}) for name in ("stable", "seeds", "status")}
        coords = {
            name: (("point",), values, {"units": _param_unit(name, self.axes)}) for name, values in self.params.items()
        }
        coords |= {"freq": (("freq",), self.freq, {"units": "Hz"}), "out": (("out",), names, {}),
                   "in": (("in",), names, {})}  # fmt: skip
        attrs = {"amb_fast_kind": _KIND, "params": json.dumps(list(self.params)), "axes": json.dumps(self.axes)}
        return xarray_module().Dataset(data, coords=coords, attrs=attrs)

    def to_dataframe(self):  # noqa: ANN201 - pandas is optional
        """One row per point, line and matrix entry: the swept paths, ``status``, then as
        :meth:`EstimateN.to_dataframe`."""
        rows = self.freq.size * len(self.axes) ** 2
        head = {name: np.repeat(values, rows) for name, values in self.params.items()}
        head["status"] = np.repeat(self.status, rows)
        long = _long({name: getattr(self, name) for name in _ESTIMATES}, self.freq, self.axes)
        return pandas_module().DataFrame(head | long)

    def save(self, path: str | Path) -> Path:
        """Write atomically to ``.nc`` (xarray's writer: fletcher32, SHA-256s) or ``.npz`` (CRC-32 per
        array); :meth:`load` and :func:`amb_fast.load_sweep` read it back."""
        path = Path(path)
        require(path.suffix.lower() in (".nc", ".npz"), "path", str(path), "a file name ending in .nc or .npz")
        if path.suffix.lower() == ".nc":
            write_netcdf(split_complex(self.to_xarray()), path)
        else:
            arrays = {f"param_{i}": values for i, values in enumerate(self.params.values())}
            arrays |= {name: getattr(self, name) for name in ("freq", "stable", "seeds", *_ESTIMATES)}
            write_npz(path, {"kind": _KIND, "params": list(self.params), "axes": list(self.axes)}, arrays)
        return path

    @staticmethod
    def load(path: str | Path) -> SweepResultN:
        """Read a sweep of N axes written by :meth:`save`; a damaged file is refused, naming it."""
        kind, header, contents = read_sweep_file(path)
        npz = Path(path).suffix.lower() == ".npz"
        require(kind == _KIND, "path", str(path), f"a{'n .npz' if npz else ' .nc'} file written by {_KIND}.save")
        return _from_file(header, contents)


def _from_file(header: dict[str, Any], contents: Any) -> SweepResultN:  # noqa: ANN401 - an npz or a Dataset
    """The sweep in a file's contents: an ``.npz`` (its JSON header) or an xarray Dataset (its attributes)."""
    npz = "kind" in header  # else a Dataset and its attributes, lists written as JSON
    listed = {name: header[name] if npz else json.loads(header[name]) for name in ("params", "axes")}
    get = contents.__getitem__ if npz else lambda name: np.asarray(contents[name].values)  # noqa: E731
    params = {name: get(f"param_{i}" if npz else name) for i, name in enumerate(listed["params"])}
    arrays = {name: get(name) for name in ("freq", "stable", "seeds", *_ESTIMATES[: None if npz else -1])}
    if not npz:
        arrays["receptance"] = complex_variable(contents, "receptance")
    arrays["stable"], arrays["seeds"] = arrays["stable"].astype(bool), arrays["seeds"].astype(np.uint64)
    return SweepResultN(params=params, axes=tuple(str(a) for a in listed["axes"]), **arrays)


register_sweep_kind(_KIND, _from_file)  # amb_fast.load_sweep reads these files too


#: Units of the numbers a path names beyond a Rig's and a PID's (:func:`unit_of`): a rotor's, a two-axis process's.
_UNITS = {"speed": "rad/s", "transverse_inertia": "kg m^2", "polar_inertia": "kg m^2", "kxy": "N/m", "kyx": "N/m",
          "cxy": "N s/m", "cyx": "N s/m", "sensor_angle": "rad"}  # fmt: skip


def _param_unit(path: str, axes: tuple[str, ...]) -> str:
    """The unit of the number at ``path`` (``A.x.amp_bandwidth``, ``x_amp_bandwidth``, ``cross_kp``, ``kxy``)."""
    field = path.rpartition(".")[2]
    for prefix in ("cross_", *(f"{axis}_" for axis in axes)):  # an off-diagonal gain; an axis' field (two axes)
        field = field.removeprefix(prefix)
    return _UNITS.get(field) or unit_of(field)


def _with(part: Any, path: str, value: float, whole: str, expected: str) -> Any:
    """``part`` with the number at ``path`` (``a.b``: field ``b`` of its field ``a``) set to ``value``."""
    head, _, rest = path.partition(".")
    known = is_dataclass(part) and head in {f.name for f in fields(part)}
    current = getattr(part, head, None) if known else None
    leaf = isinstance(current, Real) and not isinstance(current, bool)
    require(known and (leaf if not rest else is_dataclass(current)), "sweep axis", whole, expected)
    return replace(part, **{head: _with(current, rest, value, whole, expected) if rest else value})


def point_model(rig: System, controller: ControllerSpec, values: dict[str, float]) -> tuple[Any, ControllerMatrix]:
    """The rig and controller of one point (the paths: see the module's docstring)."""
    names = rig.mechanics().names
    N = len(names)
    spec = controller_matrix(controller, N)
    entries = [list(row) for row in spec.entries]
    axis_changes: list[dict[str, Any]] = [{} for _ in names]
    expected = (f"a number of the rig (kxy, rotor.mass, speed, ...), a Rig field (every axis) or <axis>.<Rig field> "
                f"with an axis of {names}, or a PID gain ([cross_]{'|'.join(_GAINS)})")  # fmt: skip
    for path, value in values.items():
        head, _, field = path.rpartition(".")
        for axis in names:  # <axis>_<field>: the two-axis spelling
            if path.startswith(axis + "_") and path[len(axis) + 1 :] in _AXIS_FIELDS:
                head, field = axis, path[len(axis) + 1 :]
        if head in names and field in _AXIS_FIELDS:
            axis_changes[names.index(head)][field] = value
        elif not head and path in _AXIS_FIELDS:
            for changes in axis_changes:
                changes[path] = value
        elif path in _GAINS:
            require(all(isinstance(entries[i][i], PID) for i in range(N)), "sweep axis", path,
                    "a PID gain swept on a controller matrix whose diagonal entries are all PIDs")  # fmt: skip
            for i in range(N):
                entries[i][i] = replace(entries[i][i], **{path: value})
        elif path.startswith("cross_") and path[6:] in _GAINS:  # the off-diagonal PIDs (absent ones stay absent)
            for i, j in np.ndindex(N, N):
                if i != j and isinstance(entries[i][j], PID):
                    entries[i][j] = replace(entries[i][j], **{path[6:]: value})
        else:
            rotor_speed = path == "speed" and hasattr(rig, "rotor")
            rig = _with(rig, "rotor.speed" if rotor_speed else path, value, path, expected)
    if any(axis_changes):
        axes = tuple(replace(a, **changes) if changes else a for a, changes in zip(rig.axes, axis_changes))
        # A rig holds its chains as a tuple ``axes`` (a rotor), one field per axis named as the axis (x, y),
        # or is its own one chain (a Rig).
        if tuple(rig.axes) == (rig,):
            rig = axes[0]
        else:
            given = {"axes": axes} if "axes" in {f.name for f in fields(rig)} else dict(zip(names, axes))  # type: ignore[arg-type]
            rig = replace(rig, **given)  # type: ignore[type-var]
    return rig, ControllerMatrix(tuple(tuple(row) for row in entries), spec.fs)


def sweep(
    rig: System,
    controller: ControllerSpec,
    excitation: Multisine,
    *,
    grid: Literal["product", "zip"] = "product",
    periods: int = 10,
    settle_periods: int | None = None,
    seed: int | None = None,
    median_window: int = 5,
    start: Literal["steady", "rest"] = "steady",
    workers: int | None = None,
    executor: Executor | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    **axes: ArrayLike,
) -> SweepResultN:
    """:func:`run_experiment` over a grid of points named by parameter paths, e.g. ``sweep(rig, pid, sphs,
    speed=np.linspace(0, 3000, 7), kd=[8.0, 10.0])`` (paths: see :func:`point_model`; a path with a dot is
    passed as ``**{"A.x.amp_bandwidth": [...]}``). Unstable points are flagged and left NaN. Point i runs
    with ``seeds[i]``, so it reruns alone bit for bit.

    Points run on ``executor`` (any :class:`concurrent.futures.Executor`: threads, processes, a dask
    cluster's ``client.get_executor()``) in chunks of ``chunk_size`` points (default: as
    :func:`amb_fast.sweep`), or by default each a :func:`run_experiment` on ``workers`` threads (one per
    core). Two axes run in calls of the compiled core: the points' loops are made here and the core's
    threads claim the points in turn with the GIL released; without an executor a call takes up to ~32 MB
    of estimates (about 500 points of 200 lines), so a large grid is never held twice, and ~20 calls with a
    progress bar (``progress``: a tqdm bar; default when stderr is a terminal).
    """
    require(callable(getattr(rig, "mechanics", None)), "rig", type(rig).__name__, "a rig of N axes (TwoAxisRig, ...)")
    require(isinstance(excitation, Multisine), "excitation", type(excitation).__name__, "a Multisine")
    options = run_options(periods, settle_periods, median_window, start)
    _, points = sweep_grid(dict(axes), grid)
    seeds = point_seeds(seed_value(seed), next(iter(points.values())).size)
    names = rig.mechanics().names
    results = run_points(_run_points, (rig, controller, excitation, options), points, seeds, workers=workers,
                         executor=executor, progress=progress, bytes_per_point=320 * excitation.freq.size,
                         chunk_size=chunk_size, here=len(names) == 2)  # fmt: skip
    return SweepResultN(points, excitation.freq, **results, seeds=seeds, axes=names)


def _run_points(
    values: dict[str, np.ndarray], seeds: np.ndarray, workers: int, rig: System, controller: ControllerSpec,
    excitation: Multisine, options: dict[str, Any],
) -> dict[str, np.ndarray]:  # fmt: skip
    """The N-axis sweep's chunk for :func:`run_points`: per point its (lines, N, N) estimates (NaN where
    unstable or where its spectra overflowed: a pole within rounding of |z| = 1) and whether it is stable."""
    models = [point_model(rig, controller, {n: float(v[i]) for n, v in values.items()}) for i in range(seeds.size)]
    N = len(rig.mechanics().names)
    shape = (seeds.size, excitation.freq.size, N, N)
    out: dict[str, np.ndarray] = {name: np.full(shape, np.nan) for name in _ESTIMATES[:-1]}
    out["receptance"] = np.full(shape, np.nan, dtype=complex)
    out["stable"] = np.zeros(seeds.size, dtype=bool)
    for j, estimates in (_core_sweep if N == 2 else _one_by_one)(models, excitation, seeds, workers, **options):
        out["stable"][j] = True  # its poles are inside the unit circle
        for name, array in zip(_ESTIMATES, estimates or ()):
            out[name][j] = array
    return out


Models = list[tuple[Any, ControllerMatrix]]  # each point's rig and controller
Points = Iterator[tuple[int, tuple[np.ndarray, ...] | None]]  # each stable point's index and estimates


def _one_by_one(models: Models, excitation: Multisine, seeds: np.ndarray, workers: int, **options: Any) -> Points:
    """Each stable point's :func:`run_experiment` (None: its spectra overflowed); one thread per point."""
    for j, model in enumerate(models):
        try:
            est = run_experiment(*model, excitation, seed=int(seeds[j]), **options)
        except UnstableLoopError:
            continue
        except OverflowError:
            est = None
        yield j, None if est is None else (est.k, est.c, est.k_std, est.c_std, est.receptance)


def _core_sweep(
    models: Models, excitation: Multisine, seeds: np.ndarray, workers: int, *, periods: int, settle_periods: int | None,
    start: str, median_window: int,
) -> Points:  # fmt: skip
    """Two-axis points in one call of the core on ``workers`` threads, as :func:`run_experiment` makes
    them, bit for bit (an unstable point is not run). The loops are assembled here, each once, in one
    call of the core (a call's points outnumber loop_model's cache); their poles come from the core in a
    stack per loop size, the numbers with which run_experiment checks one."""
    loops = loop_models(models, workers)
    poles: list[np.ndarray] = [np.empty(0)] * len(models)
    sizes: dict[int, list[int]] = {}
    for j, loop in enumerate(loops):
        sizes.setdefault(loop.M.shape[0], []).append(j)
    for same in sizes.values():
        for j, values in zip(same, eigenvalues(np.stack([loops[j].M for j in same]), workers)):
            poles[j] = values
    given = []  # (index, rig, core arguments, settle periods, the two experiments' seeds) per stable point
    for j, ((system, spec), seed, loop, p) in enumerate(zip(models, seeds, loops, poles)):
        try:
            checked_poles(p, str)  # run_experiment's stability test
        except UnstableLoopError:
            continue
        require(excitation.fs == spec.fs, "excitation.fs", excitation.fs, f"the controller's fs ({spec.fs} Hz)")
        settle = settle_periods
        if settle is None:
            settle = 0 if start == "steady" else settle_for(system, spec.fs, p, excitation.period_samples)
        given.append((j, system, core_args(loop, system, outputs=2), settle, experiment_seeds(int(seed), 2)))
    freq = excitation.harmonics * excitation.f0  # as run_experiment computes them, to the bit

    def run(pick: slice) -> tuple[np.ndarray, ...]:
        part = given[pick]
        args: dict[str, Any] = {name: [g[2][name] for g in part] for name in part[0][2]}  # a list per matrix
        return _core.mimo_line_sweep(
            **args, period_forces=experiment_forces(excitation, 2), settle_periods=[g[3] for g in part],
            periods=periods, seeds=np.array([g[4] for g in part], dtype=np.uint64), steady_start=start == "steady",
            bins=excitation.harmonics, workers=workers)  # fmt: skip

    parts, failed = run_or_split(run, len(given), OverflowError)  # overflow: a point within rounding of |z| = 1
    yield from ((given[at][0], None) for at in failed)
    for pick, (H, receptance, var_re, var_im) in parts:
        for at, (j, system, *_) in enumerate(given[pick]):
            yield j, (*coefficients(H[at], var_re[at], var_im[at], freq, system.mechanics()), receptance[at])
