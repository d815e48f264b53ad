"""NetCDF out and in, with checksums: estimates (:meth:`Estimate.save`) and sweeps (:meth:`SweepResult.save`).

A dataset is described once, as ``(data_vars, coords, attrs)`` with every variable ``name: (dims, values,
attrs)`` (``io._results.estimate_dataset_parts``, ``SweepResult._dataset_parts``): ``to_xarray`` builds its
``xarray.Dataset`` from that, and :func:`write_dataset_netcdf` writes the file xarray would write from that
Dataset, with h5netcdf alone. Building and writing the Dataset through xarray imports xarray (~0.4 s) and,
where they are installed, dask, distributed and pint (~0.6 s: xarray probes for their array types).
:func:`write_netcdf` (xarray's writer) stays the reference, and the writer of what the direct one does not
lay out; the tests compare their files' HDF5 content.

Every file carries a SHA-256 of its variables and attributes (attribute ``sha256``), HDF5's fletcher32 on
every data variable, and the SHA-256 of its bytes after its end (:data:`FILE_TRAILER`), all checked by
:func:`read_netcdf`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._atomic import atomic_path
from ._results import (
    _jsonable,
    digest,
    estimate_dataset_parts,
    estimate_to_xarray,
    optional_module,
    version,
    xarray_module,
)

if TYPE_CHECKING:
    from .._experiment import Estimate
    from .._sweep_result import SweepResult

#: A variable of a dataset's description: ``(dims, values, attrs)``.
Part = tuple[Any, Any, dict[str, Any]]


def _dataset_digest(ds) -> str:  # noqa: ANN001
    return _variables_digest({name: ds[name].values for name in ds.variables}, ds.attrs)


def _variables_digest(variables: dict[Any, Any], attrs: dict[str, Any]) -> str:
    """The SHA-256 of a Dataset's variables (coordinates too: name -> values) and attributes (but ``sha256``)."""
    chunks: list[bytes] = []
    for name in sorted(variables):
        values = np.asarray(variables[name])
        chunks.append(str(name).encode())
        if values.dtype.kind in "OUS":
            chunks.append("\x1f".join(str(v) for v in values.ravel()).encode())
        else:
            kind = {"f": "<f8", "i": "<i8", "u": "<u8", "b": "<i8", "c": "<c16"}[values.dtype.kind]
            chunks.append(np.ascontiguousarray(values.astype(kind)).tobytes())
    chunks.append(json.dumps(_jsonable({k: v for k, v in attrs.items() if k != "sha256"}), sort_keys=True).encode())
    return digest(chunks)


def require_space(path: str | Path, nbytes: int) -> None:
    """Refuse (OSError) before writing when the disk cannot hold ``nbytes`` plus a margin: HDF5 writers can crash
    the process on a full disk instead of raising, and an atomic write needs room for the new file beside the old."""
    import shutil

    directory = Path(path).parent if str(Path(path).parent) else Path(".")
    try:
        free = shutil.disk_usage(directory).free
    except OSError:  # pragma: no cover - a missing directory is reported by the write itself
        return
    need = int(1.5 * nbytes) + (1 << 20)
    if free < need:
        raise OSError(f"could not write {str(path)!r}: {free} bytes free on its disk, {need} needed (the old file, if "
                      "any, is unchanged)")  # fmt: skip


# -- writers --------------------------------------------------------------------------------------------------------


def write_netcdf(ds, path: str | Path) -> Path:  # noqa: ANN001
    """Write an xarray Dataset atomically with fletcher32 on every variable and a SHA-256 attribute."""
    require_space(path, int(ds.nbytes))
    ds = ds.copy()
    ds.attrs["amb_fast_version"] = version()
    ds.attrs["sha256"] = _dataset_digest(ds)
    encoding = {
        name: {"fletcher32": True}
        for name in ds.data_vars
        if np.asarray(ds[name].values).dtype.kind in "fiucb" and ds[name].ndim >= 1 and ds[name].size > 0
    }
    with atomic_path(path) as target:
        ds.to_netcdf(target, engine="h5netcdf", encoding=encoding)
        _append_file_digest(target)
    return Path(path)


_CF_ENCODING = frozenset({"_FillValue", "missing_value", "scale_factor", "add_offset", "_Unsigned", "coordinates"})


def _file_variables(data: dict[str, Part], coords: dict[str, Part]) -> dict[str, tuple] | None:
    """The variables, in order, of the file :func:`write_netcdf` writes from ``xarray.Dataset(data,
    coords=coords)`` with its complex variables split as ``name_real``, ``name_imag`` (after the others, the
    attributes of both those of ``name``); None for what :func:`write_dataset_netcdf` does not lay out as
    xarray does: coordinates that are not dimension coordinates (xarray lists them in a ``coordinates``
    attribute), scalars, dtypes but floats, integers, booleans, strings and complex numbers, and attributes
    that drive xarray's CF encoding."""
    variables: dict[str, tuple] = {}
    split: dict[str, tuple] = {}
    for name, (dims, values, attrs) in {**data, **coords}.items():
        dims = (dims,) if isinstance(dims, str) else tuple(dims)
        values = np.asarray(values)
        if name in coords and dims != (name,):
            return None
        if values.ndim == 0 or values.dtype.kind not in "fiubUc" or not _CF_ENCODING.isdisjoint(attrs):
            return None
        if values.dtype.kind == "b" and "dtype" in attrs:  # xarray would not encode it
            return None
        if values.dtype.kind == "c" and name in data:
            split[name] = (dims, values, attrs)
        elif values.dtype.kind == "c":
            return None
        else:
            variables[name] = (dims, values, attrs)
    for name, (dims, values, attrs) in split.items():  # as save_estimate and SweepResult.save split them
        variables[f"{name}_real"] = (dims, values.real, dict(attrs))
        variables[f"{name}_imag"] = (dims, values.imag, dict(attrs))
    return variables


def _encoded(values: np.ndarray, attrs: dict[str, Any]) -> tuple[np.ndarray, dict[str, Any]]:
    """A variable's values and attributes as xarray encodes them in the file: booleans as int8 with the attribute
    ``dtype: "bool"`` (its ``BooleanCoder``; no ``_FillValue``), which ``xarray.open_dataset`` decodes back to
    bool; the other dtypes laid out here as they are (floats get their ``_FillValue`` NaN on creation)."""
    if values.dtype.kind == "b":
        return values.astype("i1"), {**attrs, "dtype": "bool"}
    return values, attrs


def write_dataset_netcdf(path: str | Path, data: dict[str, Part], coords: dict[str, Part],
                         attrs: dict[str, Any]) -> bool:  # fmt: skip
    """Write, atomically and with h5netcdf alone, the file that :func:`write_netcdf` writes from
    ``xarray.Dataset(data, coords=coords, attrs=attrs)`` with its complex variables split (``name_real``,
    ``name_imag``): the same variables, dimensions, attributes, fill values, encodings (booleans as xarray's
    int8 with ``dtype: "bool"``), fletcher32 filters and checksums, so ``xarray.open_dataset`` and
    :func:`read_netcdf` read the same Dataset.

    Returns False, writing nothing, for a dataset it does not lay out (see ``_file_variables``): the caller
    writes that one through xarray.
    """
    variables = _file_variables(data, coords)
    if variables is None:
        return False
    needs = "writing .nc needs h5netcdf and h5py"
    h5netcdf = optional_module("h5netcdf", needs, "xarray")
    h5py = optional_module("h5py", needs, "xarray")
    attrs = {**attrs, "amb_fast_version": version()}
    attrs["sha256"] = _variables_digest({name: values for name, (_, values, _) in variables.items()}, attrs)
    require_space(path, sum(values.nbytes for _, values, _ in variables.values()))
    with atomic_path(path) as target:
        with h5netcdf.File(target, "w") as f:  # xarray's order: attributes, dimensions, variables
            for key, value in attrs.items():
                f.attrs[key] = value
            for dims, values, _ in variables.values():
                for dim, size in zip(dims, values.shape):
                    if dim not in f.dimensions:
                        f.dimensions[dim] = size
            for name, (dims, values, vattrs) in variables.items():
                values, vattrs = _encoded(values, vattrs)
                kind = values.dtype.kind
                var = f.create_variable(
                    name,
                    dims,
                    dtype=h5py.string_dtype() if kind == "U" else values.dtype,
                    fillvalue=np.array(np.nan, values.dtype) if kind == "f" else None,  # xarray's default
                    chunks=None,
                    fletcher32=name not in coords and kind in "fiu" and values.size > 0,  # as write_netcdf
                )
                for key, value in vattrs.items():
                    var.attrs[key] = value
                var[...] = values.astype(object) if kind == "U" else values
        _append_file_digest(target)
    return True


def write_estimate_netcdf(estimate: Estimate, path: str | Path) -> Path:
    """An estimate's ``.nc`` file (:meth:`Estimate.save`), written without xarray: the file of
    :func:`save_estimate_with_xarray` (a test compares them)."""
    path = Path(path)
    if not write_dataset_netcdf(path, *estimate_dataset_parts(estimate)):
        save_estimate_with_xarray(estimate, path)  # pragma: no cover - an estimate's arrays are all laid out
    return path


def save_estimate_with_xarray(estimate: Estimate, path: str | Path) -> Path:
    """The estimate's ``.nc`` file as xarray writes :meth:`Estimate.to_xarray`'s Dataset, its complex variables
    split: the reference of :func:`write_estimate_netcdf` in the tests."""
    return write_netcdf(split_complex(estimate_to_xarray(estimate)), path)


def split_complex(ds):  # noqa: ANN001, ANN201 - an xarray Dataset
    """``ds`` with each complex data variable ``name`` as ``name_real`` and ``name_imag`` (after the others, with
    the attributes of ``name``): how amb_fast's ``.nc`` files hold complex numbers (``complex_variable`` joins
    them back)."""
    for name in [n for n in ds.data_vars if np.iscomplexobj(ds[n])]:
        ds[f"{name}_real"], ds[f"{name}_imag"] = ds[name].real, ds[name].imag
        ds[f"{name}_real"].attrs = ds[f"{name}_imag"].attrs = dict(ds[name].attrs)
        ds = ds.drop_vars(name)
    return ds


def write_sweep_netcdf(result: SweepResult, path: str | Path) -> Path:
    """A sweep's ``.nc`` file (:meth:`SweepResult.save`), written without xarray for product grids: the file
    of ``save_netcdf_with_xarray`` (a test compares them), which writes the others (zip grids: their swept
    parameters are coordinates along ``point``)."""
    from .._sweep_result import save_netcdf_with_xarray

    path = Path(path)
    data, coords, attrs = result._dataset_parts()
    dims, status, status_attrs = data["status"]
    data["status"] = (dims, np.asarray(status).astype(str), status_attrs)  # as save_netcdf_with_xarray
    if not write_dataset_netcdf(path, data, coords, attrs):
        save_netcdf_with_xarray(result, path)
    return path


# -- the file's own checksum, and the reader ------------------------------------------------------------------------

#: Written after the HDF5 data: the SHA-256 of every byte before it, checked before HDF5 sees the file.
#: (HDF5 can loop forever on damaged metadata, and fletcher32 covers only the data.)
FILE_TRAILER = b"\n# amb_fast sha256 "
_TRAILER_SIZE = len(FILE_TRAILER) + 64 + 1


def _append_file_digest(target: Path) -> None:
    with open(target, "ab") as handle:  # HDF5 ignores bytes past its end of file
        handle.write(FILE_TRAILER + _file_digest(target, target.stat().st_size).encode() + b"\n")


def _file_digest(path: Path, size: int) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as handle:
        while size > 0:
            chunk = handle.read(min(size, 1 << 22))
            if not chunk:
                break
            h.update(chunk)
            size -= len(chunk)
    return h.hexdigest()


def _check_file_digest(path: Path) -> None:
    """Refuse a file whose trailer's SHA-256 does not match (files without a trailer pass to the other checks)."""
    size = path.stat().st_size
    if size < _TRAILER_SIZE:
        return
    with open(path, "rb") as handle:
        handle.seek(size - _TRAILER_SIZE)
        tail = handle.read()
    if not tail.startswith(FILE_TRAILER):
        return
    stored = tail[len(FILE_TRAILER) : -1].decode(errors="replace")
    if tail[-1:] != b"\n" or stored != _file_digest(path, size - _TRAILER_SIZE):
        raise ValueError(f"{path.name} is damaged: its bytes do not match the SHA-256 checksum at its end")


def read_netcdf(path: str | Path):  # noqa: ANN201
    """Read a Dataset written by :func:`write_netcdf`, refusing one whose checksums do not match."""
    xr = xarray_module("reading .nc needs xarray and h5netcdf")
    path = Path(path)
    _check_file_digest(path)
    try:
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            ds = ds.load()
    except ImportError:
        raise
    except Exception as error:  # h5py reports damage as OSError, KeyError, ValueError ...
        raise ValueError(f"{path.name} is damaged or not a NetCDF file written by amb_fast: {error}") from None
    stored = ds.attrs.get("sha256")
    if stored is None:
        raise ValueError(f"{path.name} has no amb_fast checksum (written by an older amb_fast, or damaged)")
    if stored != _dataset_digest(ds):
        raise ValueError(f"{path.name} is damaged: its content does not match its SHA-256 checksum")
    return ds
