"""Results out: estimates as CSV (a metadata header) or NetCDF (written by ``_netcdf``), the estimate's dataset
(its one description, for the xarray view and the NetCDF writer), xarray and pandas views, checksummed files.

Every file written here is written atomically and carries a SHA-256 of its content (NetCDF: also HDF5's
fletcher32 per variable), so a file with flipped bytes is refused on load instead of read as other numbers.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import zipfile
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._equality import UNITS as FIELD_UNITS
from .._validate import require
from ._atomic import atomic_path, atomic_text

if TYPE_CHECKING:
    from .._experiment import Estimate
    from ..system import EstimateN

ESTIMATE_SUFFIXES = (".csv", ".nc")


@dataclasses.dataclass(frozen=True)
class EstimateKind:
    """How files hold one kind of estimate, registered by the layer that defines it (this lower layer imports
    none): its CSV's first line, its NetCDF ``amb_fast_kind`` and its readers."""

    csv_head: str
    kind: str
    from_csv: Callable[[str, str], Any]  # (checked text, file name) -> estimate
    from_dataset: Callable[[Any], Any]  # NetCDF dataset -> estimate
    from_npz: Callable[[Path], Any] | None  # path -> estimate


KINDS: list[EstimateKind] = []
ONE_AXIS = "Estimate"  # the one-axis files' kind: their NetCDF has an ``amb_fast`` attribute (metadata), no kind


def register_estimate_kind(csv_head: str, kind: str, from_csv: Any, from_dataset: Any, from_npz: Any) -> None:
    """Let :func:`load_estimate` read a kind of estimate's files (``amb_fast`` and ``amb_fast.system`` call it on
    import); ``from_npz`` None: that kind has no ``.npz`` files."""
    KINDS.append(EstimateKind(csv_head, kind, from_csv, from_dataset, from_npz))


_COLUMNS = (  # CSV column -> (Estimate field or expression, unit)
    "freq_Hz", "excited", "weak", "H_real_N_per_m", "H_imag_N_per_m", "k_N_per_m", "c_Ns_per_m", "k_smooth_N_per_m",
    "c_smooth_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m", "force_real_N", "force_imag_N", "displacement_real_m",
    "displacement_imag_m", "force_abs_N", "displacement_abs_m", "receptance_abs_m_per_N",
)  # fmt: skip
_REAL = ("k", "c", "k_smooth", "c_smooth", "k_std", "c_std")
#: The estimate's arrays over ``freq`` and their units (the records' own table), in the files' order.
UNITS = {name: FIELD_UNITS[name] for name in ("H", "receptance", *_REAL, "force", "displacement")}


def column(name: str, part: str = "") -> str:
    """A CSV or DataFrame column: the field, the part of a complex one, its unit (``k_N_per_m``, ``H_real_N_per_m``)."""
    unit = UNITS[name].replace(" s", "s").replace("/", "_per_")
    return "_".join(p for p in (name, part, unit) if p)


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


def estimate_dataset_parts(estimate: Estimate) -> tuple[dict[str, tuple], dict[str, tuple], dict[str, Any]]:
    """The estimate's dataset: data variables and coordinates as ``name: (dims, values, attrs)``, and its
    attributes. The one description of it, for :meth:`Estimate.to_xarray` and the direct NetCDF writer
    (``io._netcdf.write_estimate_netcdf``)."""
    data: dict[str, tuple] = {
        name: (("freq",), getattr(estimate, name), {"units": unit}) for name, unit in UNITS.items()
    }
    data["weak"] = (("freq",), _weak(estimate), {"description": "force or displacement under 10x the unexcited level"})
    data["unexcited_force"] = (("unexcited_freq",), estimate.unexcited.force, {"units": "N"})
    data["unexcited_displacement"] = (("unexcited_freq",), estimate.unexcited.displacement, {"units": "m"})
    coords = {"freq": (("freq",), estimate.freq, {"units": "Hz"}),
              "unexcited_freq": (("unexcited_freq",), estimate.unexcited.freq, {"units": "Hz"})}  # fmt: skip
    return data, coords, {"amb_fast": json.dumps(metadata(estimate))}


def estimate_to_xarray(estimate: Estimate):  # noqa: ANN201 - xarray is optional
    data, coords, attrs = estimate_dataset_parts(estimate)
    return xarray_module().Dataset(data, coords=coords, attrs=attrs)


def estimate_to_dataframe(estimate: Estimate):  # noqa: ANN201 - pandas is optional
    """One row per line (excited and unexcited), indexed by frequency (Hz), units in the column names."""
    pd = pandas_module()
    table = _table(estimate)
    frame = pd.DataFrame({name: table[:, j] for j, name in enumerate(_COLUMNS)})
    frame["excited"] = frame["excited"].astype(bool)
    return frame.set_index("freq_Hz")


def sweep_to_dataframe(result: Any):  # noqa: ANN201, ANN401
    """One row per point and line: the swept gains, status, freq_Hz and the estimates."""
    return pandas_module().DataFrame(sweep_columns(result))


def sweep_columns(result: Any) -> dict[str, np.ndarray]:  # noqa: ANN401 - a SweepResult
    """A one-axis sweep as columns of one row per point and line: the swept parameters, ``status``, ``freq_Hz``,
    the estimates (their units in the names) and ``H`` as parts; what its DataFrame and its CSV hold."""
    n, lines = result.k.shape
    columns = {name: np.repeat(values, lines) for name, values in result.points.items()}
    columns["status"] = np.repeat(result.status, lines)
    columns["freq_Hz"] = np.tile(result.freq, n)
    columns |= {column(name): getattr(result, name).ravel() for name in _REAL}
    columns[column("H", "real")], columns[column("H", "imag")] = result.H.real.ravel(), result.H.imag.ravel()
    return columns


def optional_module(name: str, needs: str, extra: str) -> Any:  # noqa: ANN401 - a module
    """Import an optional dependency, or raise ImportError saying what ``needs`` it and the amb_fast ``extra``
    that installs it."""
    try:
        return importlib.import_module(name)
    except ImportError as error:
        raise ImportError(f"{needs}: pip install 'amb_fast[{extra}]'") from error


def pandas_module():  # noqa: ANN202
    return optional_module("pandas", "to_dataframe needs pandas", "dataframe")


def xarray_module(needs: str = "to_xarray needs xarray"):  # noqa: ANN202
    """xarray, or an ImportError that says what ``needs`` it and how to install it."""
    return optional_module("xarray", needs, "xarray")


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
        return write_csv(path, "# amb_fast estimate", metadata(estimate), _COLUMNS, _table(estimate))
    from ._netcdf import write_estimate_netcdf

    return write_estimate_netcdf(estimate, path)  # with h5netcdf alone: xarray's file, without importing xarray


def write_csv(path: Path, head: str, meta: dict[str, Any], names: Sequence[str], table: np.ndarray) -> Path:
    """A table written atomically as CSV: ``head`` and the version, ``# meta:`` and ``meta`` as JSON, the column
    names, every value to 17 digits; a SHA-256 of all that in its first line (:func:`load_estimate` checks it)."""
    lines = [f"{head}, version {version()}", "# meta: " + json.dumps(meta), ",".join(names)]
    lines += [",".join(f"{v:.17g}" for v in row) for row in table]
    body = "\n".join(lines) + "\n"
    atomic_text(path, f"# sha256: {digest([body.encode()])}\n" + body)
    return path


def read_csv(text: str, columns: Sequence[str] | None = None) -> tuple[dict[str, Any], list[str], np.ndarray]:
    """The metadata, the column names (these ``columns``, if given) and the table of a :func:`write_csv` file's
    checked text."""
    meta = json.loads(next(line for line in text.splitlines() if line.startswith("# meta: "))[8:])
    rows = [line for line in text.splitlines() if line and not line.startswith("#")]
    header = rows[0].split(",")
    require(columns is None or header == list(columns), "header", rows[0][:60], "the columns of an amb_fast estimate")
    table = np.array([[float(v) for v in line.split(",")] for line in rows[1:]], dtype=float)
    return meta, header, table.reshape(-1, len(header))


def write_npz(path: Path, header: dict[str, Any], arrays: dict[str, Any]) -> None:
    """Arrays and a JSON ``header`` (with the amb_fast version) in a compressed ``.npz``, written atomically."""
    with atomic_path(path) as target, open(target, "wb") as handle:
        np.savez_compressed(handle, header=json.dumps(header | {"version": version()}), **arrays)


def complex_array(real: np.ndarray, imag: np.ndarray) -> np.ndarray:
    """``real + j imag`` bit for bit (``real + 1j * imag`` turns -0.0 into 0.0 and an infinite part into NaN)."""
    out = np.empty(np.shape(real), dtype=complex)
    out.real, out.imag = real, imag
    return out


def complex_variable(ds: Any, name: str) -> np.ndarray:  # noqa: ANN401 - an xarray Dataset
    """The complex variable ``name`` of a Dataset read from a ``.nc`` file, from its ``name_real`` and ``name_imag``
    (``_netcdf.split_complex``), bit for bit."""
    return complex_array(np.asarray(ds[f"{name}_real"].values), np.asarray(ds[f"{name}_imag"].values))


def load_estimate(path: str | Path) -> Estimate | EstimateN:
    """Read an estimate written by :meth:`Estimate.save` (``.csv`` or ``.nc``) or :meth:`EstimateN.save`
    (``.csv``, ``.nc`` or ``.npz``: an :class:`EstimateN`); a damaged file is refused, naming it."""
    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    require(
        suffix in (*ESTIMATE_SUFFIXES, ".npz"), "path", str(path), "a file name ending in .csv or .nc, or .npz (N axes)"
    )
    if suffix == ".npz":
        return next(kind.from_npz for kind in KINDS if kind.from_npz)(path)
    if suffix == ".csv":
        raw = path.read_bytes()
        first, _, body = raw.partition(b"\n")
        text = body.decode(errors="replace")
        if not first.startswith(b"# sha256: "):
            raise ValueError(f"{path.name} is not an estimate written by amb_fast (no '# sha256:' first line)")
        if first[10:].strip().decode(errors="replace") != digest([body]):
            raise ValueError(f"{path.name} is damaged: its content does not match its SHA-256 checksum")
        kind = next((kind for kind in KINDS if text.startswith(f"{kind.csv_head}, version ")), None)
        require(kind is not None, "path", str(path), "a .csv file written by Estimate.save or EstimateN.save")
        return kind.from_csv(text, path.name)  # type: ignore[union-attr]
    from ._netcdf import read_netcdf

    ds = read_netcdf(path)
    name = ds.attrs.get("amb_fast_kind", ONE_AXIS if "amb_fast" in ds.attrs else None)
    kind = next((kind for kind in KINDS if kind.kind == name), None)
    require(kind is not None, "path", str(path), "a .nc file written by Estimate.save or EstimateN.save "
            "(this one holds another dataset: a sweep's loads with load_sweep or SweepResultN.load)")  # fmt: skip
    return kind.from_dataset(ds)  # type: ignore[union-attr]


def estimate_fields_from_csv(text: str) -> dict[str, Any]:
    """:class:`Estimate`'s fields (``unexcited``: its three arrays) from a ``.csv`` file's checked text."""
    meta, _, table = read_csv(text, _COLUMNS)
    col = {column: table[:, j] for j, column in enumerate(_COLUMNS)}
    excited = col["excited"] == 1.0
    pick = {column: values[excited] for column, values in col.items()}
    rest = {column: values[~excited] for column, values in col.items()}
    arrays = {
        "freq": pick["freq_Hz"], "H": complex_array(pick["H_real_N_per_m"], pick["H_imag_N_per_m"]),
        "force": complex_array(pick["force_real_N"], pick["force_imag_N"]),
        "displacement": complex_array(pick["displacement_real_m"], pick["displacement_imag_m"]),
        "weak": pick["weak"] == 1.0, **{n: pick[c] for n, c in zip(_REAL, _COLUMNS[5:11])},
    }  # fmt: skip
    return _fields(meta, arrays, (rest["freq_Hz"], rest["force_abs_N"], rest["displacement_abs_m"]))


def estimate_fields_from_dataset(ds: Any) -> dict[str, Any]:  # noqa: ANN401 - an xarray Dataset
    """:class:`Estimate`'s fields (``unexcited``: its three arrays) from its ``.nc`` file's Dataset."""
    arrays = {n: np.asarray(ds[n].values) for n in (*_REAL, "freq")}
    arrays |= {n: complex_variable(ds, n) for n in ("H", "force", "displacement")}
    arrays["weak"] = np.asarray(ds.weak.values).astype(bool)
    unexcited = (ds.unexcited_freq.values, ds.unexcited_force.values, ds.unexcited_displacement.values)
    return _fields(json.loads(ds.attrs["amb_fast"]), arrays, tuple(np.asarray(v) for v in unexcited))


def _fields(meta: dict[str, Any], arrays: dict[str, np.ndarray], unexcited: tuple) -> dict[str, Any]:
    scalars = {k: meta.pop(k) for k in ("periods", "blocks", "saturated_samples")}
    meta.pop("amb_fast_version", None)
    return {"receptance": 1.0 / arrays["H"], "unexcited": unexcited, "meta": meta, **arrays, **scalars}


# -- other writers' helpers -----------------------------------------------------------------------------------------


def trailer(meta: dict[str, Any]) -> str:
    """Metadata as trailing ``#`` lines of a CSV (readers that skip comments keep working)."""
    return f"# amb_fast {version()}\n# meta: {json.dumps(_jsonable(meta))}\n"


def figure_metadata(meta: dict[str, Any]) -> dict[str, str]:
    """PNG text chunks that record what drew a figure."""
    return {"Software": f"amb_fast {version()}", "Description": json.dumps(_jsonable(meta))}


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
