"""Results out: estimates as CSV (a metadata header) or NetCDF, xarray and pandas views, checksummed files.

Every file written here is written atomically and carries a SHA-256 of its content (NetCDF: also HDF5's
fletcher32 per variable), so a file with flipped bytes is refused on load instead of read as other numbers.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import zipfile
import zlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validate import require
from ._atomic import atomic_path, atomic_text

if TYPE_CHECKING:
    from .._experiment import Estimate
    from .._sweep_result import SweepResult

ESTIMATE_SUFFIXES = (".csv", ".nc")
_COLUMNS = (  # CSV column -> (Estimate field or expression, unit)
    "freq_Hz", "excited", "weak", "H_real_N_per_m", "H_imag_N_per_m", "k_N_per_m", "c_Ns_per_m", "k_smooth_N_per_m",
    "c_smooth_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m", "force_real_N", "force_imag_N", "displacement_real_m",
    "displacement_imag_m", "force_abs_N", "displacement_abs_m", "receptance_abs_m_per_N",
)  # fmt: skip
_REAL = ("k", "c", "k_smooth", "c_smooth", "k_std", "c_std")
UNITS = {"H": "N/m", "receptance": "m/N", "k": "N/m", "c": "N s/m", "k_smooth": "N/m", "c_smooth": "N s/m",
         "k_std": "N/m", "c_std": "N s/m", "force": "N", "displacement": "m"}  # fmt: skip


def version() -> str:
    from .. import __version__

    return __version__


def describe(obj: Any) -> Any:
    """A JSON-able description of a rig or controller (dataclass fields, else its repr)."""
    if obj is None:
        return None
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {"class": type(obj).__name__, **dataclasses.asdict(obj)}
    return {"class": type(obj).__name__, "repr": repr(obj)}


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _jsonable(describe(value))
    return value


def metadata(estimate: Estimate) -> dict[str, Any]:
    """What a saved estimate records besides its arrays."""
    return _jsonable({"amb_fast_version": version(), "periods": estimate.periods, "blocks": estimate.blocks,
                      "saturated_samples": estimate.saturated_samples, **estimate.meta})  # fmt: skip


def digest(chunks: list[bytes]) -> str:
    h = hashlib.sha256()
    for chunk in chunks:
        h.update(len(chunk).to_bytes(8, "little"))
        h.update(chunk)
    return h.hexdigest()


# -- xarray and pandas views ----------------------------------------------------------------------------------------


def estimate_to_xarray(estimate: Estimate):  # noqa: ANN201 - xarray is optional
    try:
        import xarray as xr
    except ImportError as error:
        raise ImportError("to_xarray needs xarray: pip install 'amb_fast[xarray]'") from error
    data: dict[str, Any] = {name: ("freq", getattr(estimate, name), {"units": unit}) for name, unit in UNITS.items()}
    data["weak"] = ("freq", _weak(estimate), {"description": "force or displacement under 10x the unexcited level"})
    data["unexcited_force"] = ("unexcited_freq", estimate.unexcited.force, {"units": "N"})
    data["unexcited_displacement"] = ("unexcited_freq", estimate.unexcited.displacement, {"units": "m"})
    coords = {"freq": ("freq", estimate.freq, {"units": "Hz"}),
              "unexcited_freq": ("unexcited_freq", estimate.unexcited.freq, {"units": "Hz"})}  # fmt: skip
    return xr.Dataset(data, coords=coords, attrs={"amb_fast": json.dumps(metadata(estimate))})


def estimate_to_dataframe(estimate: Estimate):  # noqa: ANN201 - pandas is optional
    """One row per line (excited and unexcited), indexed by frequency (Hz), units in the column names."""
    pd = _pandas()
    table = _table(estimate)
    frame = pd.DataFrame({name: table[:, j] for j, name in enumerate(_COLUMNS)})
    frame["excited"] = frame["excited"].astype(bool)
    return frame.set_index("freq_Hz")


def sweep_to_dataframe(result: Any):  # noqa: ANN201, ANN401
    """One row per point and line: the swept gains, status, freq_Hz and the estimates."""
    pd = _pandas()
    n, lines = result.k.shape
    columns: dict[str, Any] = {name: np.repeat(values, lines) for name, values in result.points.items()}
    columns["status"] = np.repeat(result.status, lines)
    columns["freq_Hz"] = np.tile(result.freq, n)
    for name, unit in (("k", "N_per_m"), ("c", "Ns_per_m"), ("k_smooth", "N_per_m"), ("c_smooth", "Ns_per_m"),
                       ("k_std", "N_per_m"), ("c_std", "Ns_per_m")):  # fmt: skip
        columns[f"{name}_{unit}"] = getattr(result, name).ravel()
    columns["H_real_N_per_m"], columns["H_imag_N_per_m"] = result.H.real.ravel(), result.H.imag.ravel()
    return pd.DataFrame(columns)


def _pandas():  # noqa: ANN202
    try:
        import pandas as pd
    except ImportError as error:
        raise ImportError("to_dataframe needs pandas: pip install 'amb_fast[dataframe]'") from error
    return pd


def _weak(estimate: Estimate) -> np.ndarray:
    return np.zeros(estimate.freq.size, bool) if estimate.weak is None else np.asarray(estimate.weak, bool)


def _table(estimate: Estimate) -> np.ndarray:
    e, u = estimate, estimate.unexcited
    excited = np.column_stack([
        e.freq, np.ones_like(e.freq), _weak(e).astype(float), e.H.real, e.H.imag, *(getattr(e, n) for n in _REAL),
        e.force.real, e.force.imag, e.displacement.real, e.displacement.imag, np.abs(e.force), np.abs(e.displacement),
        np.abs(e.receptance),
    ])  # fmt: skip
    rest = np.full((u.freq.size, len(_COLUMNS)), np.nan)
    rest[:, 0], rest[:, 1], rest[:, 2] = u.freq, 0.0, 0.0
    rest[:, _COLUMNS.index("force_abs_N")] = u.force
    rest[:, _COLUMNS.index("displacement_abs_m")] = u.displacement
    table = np.vstack([excited, rest])
    return table[np.argsort(table[:, 0], kind="stable")]


# -- save and load --------------------------------------------------------------------------------------------------


def save_estimate(estimate: Estimate, path: str | Path) -> Path:
    """Write an estimate atomically: ``.csv`` (metadata and a SHA-256 in ``#`` lines) or ``.nc`` (NetCDF)."""
    path = Path(path)
    suffix = path.suffix.lower()
    require(suffix in ESTIMATE_SUFFIXES, "path", str(path), "a file name ending in .csv or .nc")
    if suffix == ".csv":
        lines = [f"# amb_fast estimate, version {version()}", "# meta: " + json.dumps(metadata(estimate)),
                 ",".join(_COLUMNS)]  # fmt: skip
        lines += [",".join(f"{v:.17g}" for v in row) for row in _table(estimate)]
        body = "\n".join(lines) + "\n"
        atomic_text(path, f"# sha256: {digest([body.encode()])}\n" + body)
        return path
    ds = estimate_to_xarray(estimate)
    write_netcdf(_split_complex(ds), path)
    return path


def _split_complex(ds):  # noqa: ANN001, ANN202
    for name in [n for n in ds.data_vars if np.iscomplexobj(ds[n])]:
        ds[f"{name}_real"], ds[f"{name}_imag"] = ds[name].real, ds[name].imag
        ds[f"{name}_real"].attrs = ds[f"{name}_imag"].attrs = dict(ds[name].attrs)
        ds = ds.drop_vars(name)
    return ds


def load_estimate(path: str | Path) -> Estimate:
    """Read an estimate written by :meth:`Estimate.save` (``.csv`` or ``.nc``); a damaged file is refused."""
    from .._experiment import Estimate, UnexcitedLines

    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    require(suffix in ESTIMATE_SUFFIXES, "path", str(path), "a file name ending in .csv or .nc")
    if suffix == ".csv":
        raw = path.read_bytes()
        first, _, body = raw.partition(b"\n")
        if not first.startswith(b"# sha256: "):
            raise ValueError(f"{path.name} is not an estimate written by amb_fast (no '# sha256:' first line)")
        if first[10:].strip().decode(errors="replace") != digest([body]):
            raise ValueError(f"{path.name} is damaged: its content does not match its SHA-256 checksum")
        text = body.decode()
        meta = json.loads(next(line for line in text.splitlines() if line.startswith("# meta: "))[8:])
        table = _csv_rows(text)
        col = {name: table[:, j] for j, name in enumerate(_COLUMNS)}
        excited = col["excited"] == 1.0
        pick = {name: values[excited] for name, values in col.items()}
        rest = {name: values[~excited] for name, values in col.items()}
        arrays = {
            "freq": pick["freq_Hz"], "H": pick["H_real_N_per_m"] + 1j * pick["H_imag_N_per_m"],
            "force": pick["force_real_N"] + 1j * pick["force_imag_N"],
            "displacement": pick["displacement_real_m"] + 1j * pick["displacement_imag_m"],
            "weak": pick["weak"] == 1.0,
            **{n: pick[c] for n, c in zip(_REAL, _COLUMNS[5:11])},
        }  # fmt: skip
        unexcited = UnexcitedLines(rest["freq_Hz"], rest["force_abs_N"], rest["displacement_abs_m"])
    else:
        ds = read_netcdf(path)
        meta = json.loads(ds.attrs["amb_fast"])
        arrays = {n: np.asarray(ds[n].values) for n in _REAL}
        for n in ("H", "force", "displacement"):
            arrays[n] = np.asarray(ds[f"{n}_real"].values) + 1j * np.asarray(ds[f"{n}_imag"].values)
        arrays["freq"] = np.asarray(ds.freq.values)
        arrays["weak"] = np.asarray(ds.weak.values).astype(bool)
        unexcited = UnexcitedLines(np.asarray(ds.unexcited_freq.values), np.asarray(ds.unexcited_force.values),
                                   np.asarray(ds.unexcited_displacement.values))  # fmt: skip
    scalars = {k: meta.pop(k) for k in ("periods", "blocks", "saturated_samples")}
    meta.pop("amb_fast_version", None)
    return Estimate(receptance=1.0 / arrays["H"], unexcited=unexcited, meta=meta, **arrays, **scalars)


def _csv_rows(text: str) -> np.ndarray:
    rows = [line for line in text.splitlines() if line and not line.startswith("#")]
    require(rows[0] == ",".join(_COLUMNS), "header", rows[0][:60], "the columns of an amb_fast estimate")
    return np.array([[float(v) for v in line.split(",")] for line in rows[1:]], dtype=float).reshape(-1, len(_COLUMNS))


# -- NetCDF with checksums ------------------------------------------------------------------------------------------


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


def trailer(meta: dict[str, Any]) -> str:
    """Metadata as trailing ``#`` lines of a CSV (readers that skip comments keep working)."""
    return f"# amb_fast {version()}\n# meta: {json.dumps(_jsonable(meta))}\n"


def figure_metadata(meta: dict[str, Any]) -> dict[str, str]:
    """PNG text chunks that record what drew a figure."""
    return {"Software": f"amb_fast {version()}", "Description": json.dumps(_jsonable(meta))}


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
        with open(target, "ab") as handle:  # HDF5 ignores bytes past its end of file
            handle.write(FILE_TRAILER + _file_digest(target, target.stat().st_size).encode() + b"\n")
    return Path(path)


def write_sweep_netcdf(result: SweepResult, path: str | Path) -> Path:
    """A sweep's ``.nc`` file (:meth:`SweepResult.save`), written with h5netcdf alone, without building an
    xarray Dataset: the variables, dimensions, attributes, fill values, fletcher32 filters and checksums of the
    file xarray writes from :meth:`SweepResult.to_xarray` (a test compares them byte for byte), so
    :func:`amb_fast.load_sweep` and ``xarray.open_dataset`` read the same dataset.

    Building and writing the Dataset through xarray imports xarray (~0.4 s) and, where they are installed, dask,
    distributed and pint (~0.6 s: xarray probes for their array types). Grids other than ``"product"`` (or arrays
    of other kinds) go through xarray (``save_netcdf_with_xarray``).
    """
    from .._sweep_result import save_netcdf_with_xarray

    path = Path(path)
    if result.grid != "product":
        save_netcdf_with_xarray(result, path)
        return path
    try:
        import h5netcdf
        import h5py
    except ImportError as error:
        raise ImportError("writing .nc needs h5netcdf and h5py: pip install 'amb_fast[xarray]'") from error
    data, coord_vars, dataset_attrs = result._dataset_parts()
    # In the order xarray's file gets them: the data variables, the coordinates, then H split as
    # SweepResult.save splits it (status as strings).
    H_dims, H, H_attrs = data.pop("H")
    dims_, status, status_attrs = data["status"]
    data["status"] = (dims_, np.asarray(status).astype(str), status_attrs)
    variables: dict[str, tuple[tuple[str, ...], np.ndarray, dict]] = {
        name: (tuple(vdims), np.asarray(values), vattrs)
        for name, (vdims, values, vattrs) in {**data, **coord_vars}.items()
    }
    variables["H_real"] = (tuple(H_dims), H.real, H_attrs)
    variables["H_imag"] = (tuple(H_dims), H.imag, H_attrs)
    if any(values.dtype.kind not in "fiuU" for _, values, _ in variables.values()):
        save_netcdf_with_xarray(result, path)  # what xarray would encode (booleans, complex, dates ...)
        return path
    coords = set(coord_vars)
    attrs: dict[str, Any] = {**dataset_attrs, "amb_fast_version": version()}
    attrs["sha256"] = _variables_digest({name: values for name, (_, values, _) in variables.items()}, attrs)
    require_space(path, sum(values.nbytes for _, values, _ in variables.values()))
    with atomic_path(path) as target:
        with h5netcdf.File(target, "w") as f:  # xarray's order: attributes, dimensions, variables
            for key, value in attrs.items():
                f.attrs[key] = value
            for vdims, values, _ in variables.values():
                for dim, size in zip(vdims, values.shape):
                    if dim not in f.dimensions:
                        f.dimensions[dim] = size
            for name, (vdims, values, vattrs) in variables.items():
                kind = values.dtype.kind
                var = f.create_variable(
                    name,
                    vdims,
                    dtype=h5py.string_dtype() if kind == "U" else values.dtype,
                    fillvalue=np.array(np.nan, values.dtype) if kind == "f" else None,
                    chunks=None,
                    fletcher32=name not in coords and kind in "fiu" and values.ndim >= 1 and values.size > 0,
                )
                for key, value in vattrs.items():
                    var.attrs[key] = value
                var[...] = values.astype(object) if kind == "U" else values
        with open(target, "ab") as handle:  # as write_netcdf: the SHA-256 of the file's bytes after them
            handle.write(FILE_TRAILER + _file_digest(target, target.stat().st_size).encode() + b"\n")
    return path


#: Written after the HDF5 data: the SHA-256 of every byte before it, checked before HDF5 sees the file.
#: (HDF5 can loop forever on damaged metadata, and fletcher32 covers only the data.)
FILE_TRAILER = b"\n# amb_fast sha256 "
_TRAILER_SIZE = len(FILE_TRAILER) + 64 + 1


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
    try:
        import xarray as xr
    except ImportError as error:
        raise ImportError("reading .nc needs xarray and h5netcdf: pip install 'amb_fast[xarray]'") from error
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


def read_npz(path: Path):  # noqa: ANN201
    """``np.load`` that turns a failed CRC-32 (zip's checksum per member) or a damaged header into a clear
    error (a flipped flag bit reads as an encrypted or unsupported member: zipfile's RuntimeError and
    NotImplementedError)."""
    try:
        with open(path, "rb") as handle, np.load(handle, allow_pickle=False) as f:
            return {name: f[name] for name in f.files}
    except (zipfile.BadZipFile, zlib.error, ValueError, OSError, KeyError, EOFError, RuntimeError,
            NotImplementedError) as error:  # fmt: skip
        raise ValueError(f"{path.name} is damaged: {error}") from None
