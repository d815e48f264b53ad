"""Results of N axes out and in: :class:`EstimateN` as xarray and pandas views and as checksummed files
written atomically (:class:`SweepResultN` uses the same pieces).

An estimate's every array is (lines, N, N): the matrices over ``(freq, out, in)`` (``H[:, i, j] = dF_i /
dY_j``), the period-averaged amplitudes over ``(freq, channel, experiment)``. Files: ``.nc`` (NetCDF written
with h5netcdf alone: fletcher32 per variable, a SHA-256 of the variables and one of the bytes), ``.npz``
(zip's CRC-32 per array) and, for an estimate, ``.csv`` (one row per line and matrix entry, a SHA-256 in
its first line); :func:`amb_fast.load_estimate` reads an estimate back (it sees which kind a file holds),
:meth:`SweepResultN.load` a sweep. Floats are written exactly (``%.17g`` in CSV), so loaded equals saved.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validate import require
from ..io import RESULT_UNITS as UNITS
from ..io import (
    column,
    complex_array,
    complex_variable,
    pandas_module,
    read_csv,
    read_npz,
    register_estimate_kind,
    write_csv,
    write_dataset_netcdf,
    write_npz,
    xarray_module,
)

if TYPE_CHECKING:
    from ._experiment import EstimateN

KIND = "EstimateN"  # the ``amb_fast_kind`` attribute (NetCDF) or the CSV's second line: an estimate of N axes
CSV_HEAD = "# amb_fast estimate of N axes"
MATRICES = ("H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std")
AMPLITUDES = ("force", "displacement")  # (lines, channel, experiment)
SUFFIXES = (".nc", ".npz", ".csv")


def _fields(est: EstimateN) -> dict[str, np.ndarray]:
    return {name: getattr(est, name) for name in (*MATRICES, *AMPLITUDES)}


# -- views ----------------------------------------------------------------------------------------------------------


def estimate_parts(est: EstimateN) -> tuple[dict[str, tuple], dict[str, tuple], dict[str, Any]]:
    """The estimate's dataset as ``name: (dims, values, attrs)`` (data and coordinates) and its attributes:
    the one description of it, for :func:`estimate_to_xarray` and the NetCDF file."""
    data = {name: (("freq", "out", "in"), getattr(est, name), {"units": UNITS[name]}) for name in MATRICES}
    data |= {name: (("freq", "channel", "experiment"), getattr(est, name), {"units": UNITS[name]})
             for name in AMPLITUDES}  # fmt: skip
    names = np.array(est.axes)
    coords = {"freq": (("freq",), est.freq, {"units": "Hz"}), "out": (("out",), names, {}),
              "in": (("in",), names, {}), "channel": (("channel",), names, {}),
              "experiment": (("experiment",), np.arange(len(names)), {})}  # fmt: skip
    return data, coords, {"amb_fast_kind": KIND, "periods": est.periods, "axes": json.dumps(list(est.axes))}


def estimate_to_xarray(est: EstimateN):  # noqa: ANN201 - xarray is optional
    """An ``xarray.Dataset``: the matrices over ``(freq, out, in)``, ``force`` and ``displacement`` over
    ``(freq, channel, experiment)``, the axes' names as coordinates, units in every variable's ``attrs``."""
    data, coords, attrs = estimate_parts(est)
    return xarray_module().Dataset(data, coords=coords, attrs=attrs)


def _long(matrices: dict[str, np.ndarray], freq: np.ndarray, names: Any) -> dict[str, np.ndarray]:
    """Long-form columns of (..., lines, N, N) matrices: freq_Hz, i, j (``names[i]``, ``names[j]``), then each
    matrix's values (complex ones as ``_real``, ``_imag``), one row per leading index, line and entry."""
    shape = next(iter(matrices.values())).shape
    lead, N = int(np.prod(shape[:-3])), shape[-1]
    index = np.arange(N)
    columns = {"freq_Hz": np.tile(np.repeat(freq, N * N), lead), "i": np.tile(np.repeat(index, N), lead * freq.size),
               "j": np.tile(index, lead * freq.size * N)}  # fmt: skip
    columns["i"], columns["j"] = np.asarray(names)[columns["i"]], np.asarray(names)[columns["j"]]
    for name, values in matrices.items():
        if np.iscomplexobj(values):
            columns[column(name, "real")], columns[column(name, "imag")] = values.real.ravel(), values.imag.ravel()
        else:
            columns[column(name)] = values.ravel()
    return columns


def estimate_to_dataframe(est: EstimateN):  # noqa: ANN201 - pandas is optional
    """One row per line and matrix entry: ``freq_Hz``, ``i`` (the force's axis), ``j`` (the displacement's),
    then ``H`` and ``receptance`` (real and imaginary parts), ``k``, ``c``, smoothed and standard errors,
    units in the column names."""
    return pandas_module().DataFrame(_long({n: getattr(est, n) for n in MATRICES}, est.freq, est.axes))


# -- an estimate's files --------------------------------------------------------------------------------------------


def save_estimate(est: EstimateN, path: str | Path) -> Path:
    """Write atomically (the old file stays whole if the write fails) to ``.nc`` (NetCDF through h5netcdf:
    fletcher32 per variable, SHA-256s of the variables and of the bytes), ``.npz`` (zip's CRC-32 per array) or
    ``.csv`` (one row per line and entry ``i, j`` (0-based), every value to 17 digits, ``force`` and
    ``displacement`` as ``[channel i, experiment j]``; a SHA-256 in its first line). Returns the path;
    :func:`amb_fast.load_estimate` reads any of them back equal to this estimate, and refuses a damaged one
    naming the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    require(suffix in SUFFIXES, "path", str(path), "a file name ending in .nc, .npz or .csv")
    meta = {"periods": est.periods, "axes": list(est.axes)}
    if suffix == ".nc":
        write_dataset_netcdf(path, *estimate_parts(est))
    elif suffix == ".npz":
        write_npz(path, {"kind": KIND, **meta}, {"freq": est.freq, **_fields(est)})
    else:
        columns = _long(_fields(est), est.freq, np.arange(len(est.axes)))
        write_csv(path, CSV_HEAD, meta, list(columns), np.column_stack(list(columns.values())))
    return path


def _build(freq: np.ndarray, arrays: dict[str, np.ndarray], periods: int, axes: list[str]) -> EstimateN:
    from ._experiment import EstimateN

    return EstimateN(freq=freq, **arrays, periods=int(periods), axes=tuple(str(a) for a in axes))


def estimate_from_dataset(ds: Any) -> EstimateN:  # noqa: ANN401 - an xarray Dataset
    """The estimate of a Dataset read by :func:`amb_fast.io.read_netcdf` from its ``.nc`` file."""
    arrays = {name: np.asarray(ds[name].values) if name in ds else complex_variable(ds, name)
              for name in MATRICES + AMPLITUDES}  # fmt: skip
    return _build(np.asarray(ds.freq.values), arrays, ds.attrs["periods"], json.loads(ds.attrs["axes"]))


def estimate_from_csv(text: str, name: str) -> EstimateN:
    """The estimate of a ``.csv`` file's checked text (after its ``# sha256:`` line); ``name``: the file's."""
    meta, header, table = read_csv(text)
    N = len(meta["axes"])
    require(table.shape[0] % (N * N) == 0, f"{name} rows", table.shape[0], f"a multiple of {N * N} (N x N per line)")
    col = {c: table[:, k].reshape(-1, N, N) for k, c in enumerate(header)}
    arrays = {n: col[column(n)] if column(n) in col else complex_array(col[column(n, "real")],
                                                                        col[column(n, "imag")])
              for n in MATRICES + AMPLITUDES}  # fmt: skip
    return _build(col["freq_Hz"][:, 0, 0], arrays, meta["periods"], meta["axes"])


def load_estimate(path: Path) -> EstimateN:
    """Read an ``.npz`` estimate of N axes (a member failing its CRC-32 is refused, naming the file)."""
    f = read_npz(path)
    header = json.loads(str(f["header"])) if "header" in f else {}  # a plain .npz: refused by kind below
    require(header.get("kind") == KIND, "path", str(path), f"an .npz file written by {KIND}.save")
    return _build(f["freq"], {name: f[name] for name in MATRICES + AMPLITUDES}, header["periods"], header["axes"])


# amb_fast.load_estimate (the io layer) reads these files through what this module registers.
register_estimate_kind(CSV_HEAD, KIND, estimate_from_csv, estimate_from_dataset, load_estimate)
