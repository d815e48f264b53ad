"""MATLAB recordings: ``.mat`` v4-v7 (scipy) and v7.3 (HDF5, h5py), with top-level variables, structs of
channels, dSPACE ControlDesk/TRACE exports and Simulink "Structure with time" (one recording per struct).

A variable in no layout amb_fast reads (text, a cell, a MATLAB object such as a timeseries) is skipped; a file
with no channel at all is refused naming each variable's layout."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: The layouts amb_fast reads, for the message naming a file's variables when none is one of them.
LAYOUTS = ("numeric variables (one per channel, an optional 'fs' in Hz), a struct of numeric fields, a dSPACE "
           "export (X.Data and Y(k).Name/.Data), a Simulink 'Structure with time' (time and "
           "signals(k).values/.label); a timeseries or Simulink Dataset is a MATLAB object: save its Time and "
           "Data as variables")  # fmt: skip


def _read_mat(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """Recordings of a ``.mat`` file: ``""`` for numeric top-level variables, one per struct of channels."""
    with open(path, "rb") as handle:
        head = handle.read(520)
    if b"\x89HDF\r\n\x1a\n" in (head[512:520], head[:8]):  # v7.3: HDF5 behind a 512-byte header
        return _read_mat73(path)
    from scipy.io import loadmat
    from scipy.io.matlab import MatlabFunction, MatlabOpaque, mat_struct

    try:
        content = loadmat(path, squeeze_me=True, struct_as_record=False)
    except Exception as error:  # scipy reports damage as ValueError, TypeError, IndexError, MatReadError ...
        raise ValueError(f"{path.name} is not a readable MATLAB file: {error}") from None
    groups: dict[str, dict[str, np.ndarray]] = {"": {}}
    skipped: list[str] = []
    for key, value in content.items():
        if key.startswith("__"):
            continue
        if isinstance(value, mat_struct) and {"X", "Y"} <= set(value._fieldnames):  # dSPACE export
            groups[key] = _dspace(np.ravel(value.X.Data if not isinstance(value.X, np.ndarray) else value.X[0].Data),
                                  [(str(c.Name), c.Data) for c in np.atleast_1d(value.Y)])  # fmt: skip
        elif isinstance(value, mat_struct) and {"time", "signals"} <= set(value._fieldnames):  # Simulink
            signals = np.atleast_1d(value.signals)
            groups[key] = _simulink(value.time, [(_label(s), s.values) for s in signals])
        elif isinstance(value, mat_struct):
            fields = {name: getattr(value, name) for name in value._fieldnames}
            numeric = {name: v for name, v in fields.items() if _numeric(v)}
            if numeric:
                groups[key] = {name: _channel_values(v) for name, v in numeric.items()}
            else:
                skipped.append(f"{key!r} (a struct without numeric fields)")
        elif _numeric(value):
            groups[""].update(_columns(key, value))
        elif isinstance(value, str):
            skipped.append(f"{key!r} (text)")
        elif isinstance(value, (MatlabOpaque, MatlabFunction)):
            skipped.append(f"{key!r} (a MATLAB object or function)")
        elif isinstance(value, np.ndarray) and value.dtype == object and any(isinstance(v, mat_struct) for v in
                                                                             value.flat):  # fmt: skip
            skipped.append(f"{key!r} (a struct array)")
        else:
            skipped.append(f"{key!r} (a cell array or other non-numeric value)")
    _refuse_if_empty(groups, skipped, path)
    return groups


def _numeric(value: Any) -> bool:  # noqa: ANN401 - any value loadmat returns
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iufb"
    return isinstance(value, (int, float, np.number)) and not isinstance(value, (bool, np.bool_))


def _channel_values(value: Any) -> np.ndarray:  # noqa: ANN401 - a numeric value
    array = np.asarray(value, dtype=float)
    return np.ravel(array) if min(array.shape, default=1) <= 1 else array


def _columns(name: str, value: Any) -> dict[str, np.ndarray]:  # noqa: ANN401 - a numeric value
    """A numeric variable as channels: a vector or scalar as itself; a matrix longer than wide (Simulink's
    'Array' format, [t, y1, y2]) as its columns ``name column 1``, ... (1-based, as MATLAB counts), a wider
    one as its rows ``name row 1``, ...; a square matrix as itself (no axis is the samples')."""
    array = _channel_values(value)
    if array.ndim != 2 or array.shape[0] == array.shape[1]:
        return {name: array}
    if array.shape[0] > array.shape[1]:
        return {f"{name} column {j + 1}": array[:, j] for j in range(array.shape[1])}
    return {f"{name} row {j + 1}": array[j] for j in range(array.shape[0])}


def _label(signal: Any) -> str:  # noqa: ANN401 - a scipy mat_struct
    label = getattr(signal, "label", "")
    return str(label) if isinstance(label, str) and label else str(getattr(signal, "blockName", "") or "signal")


def _refuse_if_empty(groups: dict[str, dict[str, np.ndarray]], skipped: list[str], path: Path) -> None:
    if skipped and not any(groups.values()):
        raise ValueError(f"{path.name} holds no channel amb_fast reads: its variables are {', '.join(skipped)}. "
                         f"amb_fast reads {LAYOUTS}")  # fmt: skip


def _dspace(time: np.ndarray, channels: Sequence[tuple[str, object]]) -> dict[str, np.ndarray]:
    """A dSPACE export's channels: ``time`` (its X.Data), then each Y(k) by name."""
    return {"time": np.ravel(np.asarray(time, dtype=float)), **{n: np.ravel(np.asarray(d, float)) for n, d in channels}}


def _simulink(time: Any, signals: Sequence[tuple[str, Any]]) -> dict[str, np.ndarray]:  # noqa: ANN401
    """A Simulink 'Structure with time': ``time`` (none if empty: a 'Structure' without it), then each signal
    by its label (or block), a signal of several columns as ``label column 1``, ... (rows are samples)."""
    out: dict[str, np.ndarray] = {}
    time = np.ravel(np.asarray(time, dtype=float))
    if time.size:
        out["time"] = time
    for name, values in signals:
        array = np.asarray(values, dtype=float)
        if array.ndim > 2:  # a matrix per sample: which element is which channel is not amb_fast's to guess
            raise ValueError(f"the Simulink signal {name!r} holds a {array.shape[:-1]} matrix per sample: log the "
                             "force and the displacement as scalar signals")  # fmt: skip
        if array.ndim == 2 and min(array.shape) > 1:
            rows = array if time.size != array.shape[1] else array.T  # MATLAB: samples x columns
            out |= {f"{name} column {j + 1}": rows[:, j] for j in range(rows.shape[1])}
        else:
            out[name] = np.ravel(array)
    return out


def _read_mat73(path: Path) -> dict[str, dict[str, np.ndarray]]:
    try:
        import h5py
    except ImportError as error:
        raise ImportError(f"{path.name} is a MATLAB v7.3 (HDF5) file: reading it needs h5py: "
                          "pip install 'amb_fast[xarray]'") from error  # fmt: skip
    groups: dict[str, dict[str, np.ndarray]] = {"": {}}
    skipped: list[str] = []
    try:
        f = h5py.File(path, "r")
    except OSError as error:
        raise ValueError(f"{path.name} is not a readable MATLAB v7.3 (HDF5) file: {error}") from None

    def text(reference: Any) -> str:  # noqa: ANN401 - an HDF5 object reference
        return "".join(chr(c) for c in np.ravel(f[reference][()]))

    def numbers(item: Any) -> np.ndarray:  # noqa: ANN401 - an HDF5 dataset, or a reference to one
        if item.dtype.kind == "O":  # a struct array: a reference per element
            item = f[np.ravel(item[()])[0]]
        return np.asarray(item[()], dtype=float).T  # MATLAB is column-major

    def field(group: Any, name: str) -> list[Any]:  # noqa: ANN401 - the values of a struct (array) field
        item = group[name]
        if item.dtype.kind == "O":
            return [f[r] for r in np.ravel(item[()])]
        return [item]

    with f:
        for key, item in f.items():
            if key.startswith("#"):
                continue
            cls = item.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            if isinstance(item, h5py.Group) and cls == "struct" and "X" in item and "Y" in item:
                names, data = (np.ravel(item["Y"][name][()]) for name in ("Name", "Data"))
                groups[key] = _dspace(numbers(item["X"]["Data"]), [(text(n), f[d][()]) for n, d in zip(names, data)])
            elif isinstance(item, h5py.Group) and cls == "struct" and "time" in item and "signals" in item:
                signals = item["signals"]
                labels = [("".join(chr(c) for c in np.ravel(v[()])) or "signal") for v in field(signals, "label")]
                values = [np.asarray(v[()], float).T for v in field(signals, "values")]
                empty = "MATLAB_empty" in item["time"].attrs  # a 'Structure' without time
                groups[key] = _simulink(np.zeros(0) if empty else numbers(item["time"]), list(zip(labels, values)))
            elif isinstance(item, h5py.Group) and cls == "struct":
                numeric = {name: v for name, v in item.items() if isinstance(v, h5py.Dataset) and v.dtype.kind in "iuf"
                           and v.attrs.get("MATLAB_class", b"") not in (b"char", "char")}  # fmt: skip
                if numeric:
                    groups[key] = {name: _channel_values(np.asarray(v[()], float).T) for name, v in numeric.items()}
                else:
                    skipped.append(f"{key!r} (a struct without numeric fields)")
            elif isinstance(item, h5py.Dataset) and item.dtype.kind in "iuf" and cls not in ("char", "cell"):
                groups[""].update(_columns(key, np.asarray(item[()], dtype=float).T))
            else:
                kind = {"char": "text", "cell": "a cell array", "struct": "a struct array"}.get(cls, f"a MATLAB {cls}")
                skipped.append(f"{key!r} ({kind if cls else 'not a MATLAB variable'})")
    _refuse_if_empty(groups, skipped, path)
    return groups
