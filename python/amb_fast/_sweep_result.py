"""A sweep's results: :class:`SweepResult` (estimates of every point, labelled by the swept parameters; xarray,
NetCDF and npz) and :func:`load_sweep`. Running sweeps is ``amb_fast._sweep``."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._equality import UNITS as FIELD_UNITS
from ._equality import ArrayRecord
from ._params import UNITS
from ._validate import require

SWEPT = ("kp", "ki", "kd")  # the PID gains: swept together in closed form
STATUS = ("ok", "unstable", "touchdown", "saturated")  # index = the core's PointStatus


def unit_of(name: str) -> str:
    """Unit of a sweep axis: a rig or PID field's, Hz for a block's frequency, else ``""``."""
    if name in UNITS:
        return UNITS[name]
    return "Hz" if name.endswith("_freq") or name.endswith("_width") else ""


def sweep_grid(values: dict[str, ArrayLike], grid: str) -> tuple[dict, dict]:
    """The swept values, checked, and every point's: for ``grid="product"`` the axes crossed (C order)."""
    require(grid in ("product", "zip"), "grid", grid, "'product' or 'zip'")
    axes = {}
    for name, given in values.items():
        array = np.atleast_1d(np.asarray(given, dtype=float))
        require(array.ndim == 1 and array.size > 0, name, given, "a non-empty 1-D sequence")
        require(bool(np.isfinite(array).all()), name, given, f"finite ({unit_of(name) or 'no unit'})")
        axes[name] = array
    require(bool(axes), "axes", None, "at least one swept parameter (e.g. kp=[...], amp_bandwidth=[...])")
    if grid == "product" and len(axes) > 1:
        mesh = np.meshgrid(*axes.values(), indexing="ij")
        points = {name: m.ravel() for name, m in zip(axes, mesh)}
    else:  # zip, or one axis: the points are the axes' values
        sizes = {name: a.size for name, a in axes.items()}
        require(len(set(sizes.values())) == 1, "lengths", sizes, "equal for grid='zip'")
        points = {name: a.copy() for name, a in axes.items()}
    return axes, points


# Labelled in Python: the core reports a linear-law point whose state overflowed as "touchdown" (it
# reached an infinite clearance); without a clearance that is an overflow (saturation made it diverge).
OVERFLOW = "overflow"
STATUS_NAMES = (*STATUS, OVERFLOW)


@dataclass(frozen=True, eq=False)
class SweepResult(ArrayRecord):
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

    def _repr_head(self) -> list[str]:
        """The repr's first items: the grid, each axis's values with its unit, the points' status counts."""
        grid = " x ".join(str(n) for n in self.shape)
        axes = []
        for name, values in self.axes.items():
            shown = [f"{v:.6g}" for v in np.asarray(values, dtype=float)]
            shown = shown if len(shown) <= 6 else [*shown[:3], "...", shown[-1]]
            axes.append(f"{name}: [{', '.join(shown)}] {unit_of(name)}".rstrip())
        names, counts = np.unique(self.status, return_counts=True)
        status = ", ".join(f"{n}={c}" for n, c in zip(names, counts))
        return [f"points={len(self.status)} ({self.grid} {grid})", *axes, status, *super()._repr_head()]

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape: one axis per swept parameter for product grids, else (points,)."""
        if self.grid == "product":
            return tuple(len(v) for v in self.axes.values())
        return (len(self.status),)

    def to_xarray(self):  # noqa: ANN201 - xarray is optional
        """An ``xarray.Dataset`` with one dimension per swept parameter (product grids) or ``point``, and ``freq``."""
        from .io import xarray_module

        data, coords, attrs = self._dataset_parts()
        return xarray_module().Dataset(data, coords=coords, attrs=attrs)

    def _dataset_parts(self) -> tuple[dict[str, tuple], dict[str, tuple], dict[str, Any]]:
        """The dataset's data variables and coordinates as ``name: (dims, values, attrs)``, and its
        attributes: the one description of it, for :meth:`to_xarray` and for the direct NetCDF writer."""
        product = self.grid == "product"  # a dimension per swept parameter, else the points along one
        dims = list(self.axes) if product else ["point"]
        labels = self.axes if product else self.points
        coords = {
            name: ([name] if product else dims, values, {"units": unit_of(name)}) for name, values in labels.items()
        }
        coords["freq"] = (["freq"], self.freq, {"units": "Hz"})
        coords["unexcited_freq"] = (["unexcited_freq"], self.unexcited_freq, {"units": "Hz"})
        shape = self.shape

        def var(values: np.ndarray, units: str, lines: str = "freq") -> tuple:
            return ([*dims, lines], values.reshape(*shape, values.shape[-1]), {"units": units})

        data = {name: var(getattr(self, name), FIELD_UNITS[name]) for name in _ARRAYS[1:8]}  # H, k, ..., c_std
        data["unexcited_displacement"] = var(self.unexcited_displacement, "m", "unexcited_freq")
        data |= {name: (dims, getattr(self, name).reshape(shape), {}) for name in ("status", "settle_periods", "seeds")}
        attrs = {"grid": self.grid, "periods": self.periods, "blocks": self.blocks, "meta": json.dumps(self.meta),
                 "axes": json.dumps(list(self.axes))}  # fmt: skip
        return data, coords, attrs

    def to_dataframe(self):  # noqa: ANN201 - pandas is optional
        """A ``pandas.DataFrame``: one row per point and line (swapped gains, status, freq_Hz, estimates)."""
        from .io._results import sweep_to_dataframe

        return sweep_to_dataframe(self)

    def save(self, path: str | Path) -> None:
        """Write atomically to ``.nc`` (NetCDF through h5netcdf; H as real and imaginary parts;
        fletcher32 and a SHA-256 checked by :func:`load_sweep`), ``.npz`` (zip CRC-32 per array) or ``.csv``
        (for other tools: one row per point and line, see :meth:`to_csv`; :func:`load_sweep` reads the
        other two)."""
        from .io import atomic_path
        from .io._netcdf import write_sweep_netcdf

        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".nc":
            write_sweep_netcdf(self, path)
        elif suffix == ".npz":
            arrays = {name: getattr(self, name) for name in _ARRAYS}
            arrays |= {f"point_{k}": v for k, v in self.points.items()} | {f"axis_{k}": v for k, v in self.axes.items()}
            header = {"grid": self.grid, "periods": self.periods, "blocks": self.blocks, "meta": self.meta}
            with atomic_path(path) as target, open(target, "wb") as handle:
                np.savez_compressed(handle, header=json.dumps(header), **arrays)
        elif suffix == ".csv":
            self.to_csv(path)
        else:
            raise ValueError(f"path must end in .nc, .npz or .csv, got {str(path)!r}")

    def to_csv(self, path: str | Path) -> None:
        """Write a CSV atomically: a header row, then one row per point and line (the swept parameters, status,
        ``freq_Hz``, ``k_N_per_m``, ``c_Ns_per_m``, ``k_std_N_per_m``, ``c_std_Ns_per_m``,
        ``receptance_abs_m_per_N`` = abs(Y/F) = 1/abs(H)); NaN in the estimates of points whose status is not ok;
        the metadata (version, rig, controller, seed) in trailing ``#`` lines."""
        from .io import atomic_path
        from .io._results import sweep_columns, trailer

        header = [*self.points, "status", "freq_Hz", "k_N_per_m", "c_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m",
                  "receptance_abs_m_per_N"]  # fmt: skip
        columns = sweep_columns(self)
        with np.errstate(invalid="ignore"):  # NaN rows of points that are not ok: NaN is their documented value
            columns["receptance_abs_m_per_N"] = np.abs(1 / self.H).ravel()
        with atomic_path(Path(path)) as target, target.open("w") as handle:
            handle.write(",".join(header) + "\n")
            for row in zip(*(columns[name] for name in header)):
                handle.write(",".join(str(v) for v in row) + "\n")
            handle.write(trailer(self.meta))


def save_netcdf_with_xarray(result: SweepResult, path: Path) -> None:
    """The sweep's ``.nc`` file as xarray writes :meth:`SweepResult.to_xarray`'s Dataset: for grids the
    direct writer (``io._netcdf.write_sweep_netcdf``) does not lay out, and its reference in the tests."""
    from .io import write_netcdf
    from .io._netcdf import split_complex

    ds = split_complex(result.to_xarray())
    write_netcdf(ds.assign(status=ds.status.astype(str)), path)


_ARRAYS = ("freq", "H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "status", "settle_periods", "seeds",
           "unexcited_freq", "unexcited_displacement")  # fmt: skip


# What load_sweep says of another amb_fast file given to it.
_NOT_A_SWEEP = "a file written by SweepResult.save or SweepResultN.save (estimates load with load_estimate)"

#: Readers of the other kinds of sweep file (an .npz header's ``kind``, a .nc file's ``amb_fast_kind``):
#: ``reader(header, contents)``, registered by the layer that defines them (this one imports none).
_READERS: dict[str, Callable[[dict[str, Any], Any], Any]] = {}


def register_sweep_kind(kind: str, reader: Callable[[dict[str, Any], Any], Any]) -> None:
    """Let :func:`load_sweep` read the files of another kind of sweep."""
    _READERS[kind] = reader


def read_sweep_file(path: str | Path) -> tuple[str | None, dict[str, Any], Any]:
    """A sweep file's kind (None for a :class:`SweepResult`), header (an ``.npz``'s JSON header, a ``.nc``
    file's attributes) and contents (the npz or the xarray Dataset), its checksums checked."""
    from .io import read_netcdf
    from .io._results import read_npz

    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    note = " (a sweep's .csv is for other tools: it keeps no complex H or seeds; save .nc or .npz to load it back)"
    expected = "a file name ending in .nc or .npz" + (note if suffix == ".csv" else "")
    require(suffix in (".nc", ".npz"), "path", str(path), expected)
    if suffix == ".npz":
        f = read_npz(path)  # a damaged member fails its CRC-32 and is refused
        header = json.loads(str(f["header"])) if "header" in f else {}  # a plain .npz: refused by kind below
        return header.get("kind"), header, f
    ds = read_netcdf(path)  # refuses a file whose checksums do not match
    return ds.attrs.get("amb_fast_kind"), dict(ds.attrs), ds


def load_sweep(path: str | Path) -> Any:  # noqa: ANN401 - a SweepResult or a SweepResultN
    """Read a sweep written by :meth:`SweepResult.save` or :meth:`SweepResultN.save` (``.nc`` or ``.npz``).

    Parameters
    ----------
    path : str or path-like
        A ``.nc`` (NetCDF: needs the ``xarray`` extra) or ``.npz`` file written by :meth:`SweepResult.save`
        or by :meth:`SweepResultN.save` (a sweep of N axes).

    Returns
    -------
    SweepResult
        The sweep as saved: gains in their units (A/m, A/(m s), A s/m, Hz), ``freq`` in Hz, ``k`` N/m,
        ``c`` N s/m, statuses and seeds (a :class:`SweepResultN` for a sweep of N axes). A file whose
        checksums do not match (fletcher32 and SHA-256 in NetCDF, CRC-32 in ``.npz``) is refused with a
        ``ValueError``, and so is another suffix.

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
    from .io import complex_array

    kind, header, contents = read_sweep_file(path)
    if kind in _READERS:
        return _READERS[kind](header, contents)
    require("grid" in header, "path", str(path), _NOT_A_SWEEP)
    if Path(path).suffix.lower() == ".npz":
        arrays = {name: contents[name] for name in _ARRAYS}
        points = {k[6:]: contents[k] for k in contents if k.startswith("point_")}
        axes = {k[5:]: contents[k] for k in contents if k.startswith("axis_")}
        return SweepResult(points=points, axes=axes, **arrays, **header)
    ds, grid = contents, header["grid"]
    names = json.loads(header["axes"]) if "axes" in header else [n for n in SWEPT if n in ds.coords]
    axes, points = sweep_grid({name: ds[name].values for name in names}, grid)
    dims = len(names) if grid == "product" else 1

    def rows(name: str) -> np.ndarray:
        values = np.asarray(ds[name].values)
        return values.reshape(ds.status.size, *values.shape[dims:])

    arrays = {name: rows(name) for name in _ARRAYS if name not in ("freq", "unexcited_freq", "H")}
    arrays["status"], arrays["seeds"] = arrays["status"].astype(str), arrays["seeds"].astype(np.uint64)
    return SweepResult(
        points=points,
        axes=axes,
        grid=grid,
        freq=np.asarray(ds.freq.values),
        H=complex_array(rows("H_real"), rows("H_imag")),
        unexcited_freq=np.asarray(ds.unexcited_freq.values),
        periods=int(header["periods"]),
        blocks=int(header["blocks"]),
        meta=json.loads(header["meta"]),
        **arrays,
    )
