"""MATLAB recordings: ``.mat`` v4-v7 (scipy) and v7.3 (HDF5, h5py), with top-level variables or dSPACE
ControlDesk/TRACE exports (one recording per export struct)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np


def _read_mat(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """Recordings of a ``.mat`` file: ``""`` for numeric top-level variables, one per dSPACE export struct."""
    with open(path, "rb") as handle:
        head = handle.read(520)
    if b"\x89HDF\r\n\x1a\n" in (head[512:520], head[:8]):  # v7.3: HDF5 behind a 512-byte header
        return _read_mat73(path)
    from scipy.io import loadmat

    try:
        content = loadmat(path, squeeze_me=True, struct_as_record=False)
    except Exception as error:  # scipy reports damage as ValueError, TypeError, IndexError, MatReadError ...
        raise ValueError(f"{path.name} is not a readable MATLAB file: {error}") from None
    groups: dict[str, dict[str, np.ndarray]] = {"": {}}
    for key, value in content.items():
        if key.startswith("__"):
            continue
        if hasattr(value, "Y") and hasattr(value, "X"):  # dSPACE export
            groups[key] = _dspace(np.ravel(value.X.Data if not isinstance(value.X, np.ndarray) else value.X[0].Data),
                                  [(str(c.Name), c.Data) for c in np.atleast_1d(value.Y)])  # fmt: skip
        elif isinstance(value, np.ndarray) and value.dtype.kind in "iufb":
            groups[""][key] = np.asarray(value, dtype=float)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            groups[""][key] = np.asarray(float(value))
        # text, cells and other structs are not channels: skipped
    return groups


def _dspace(time: np.ndarray, channels: Sequence[tuple[str, object]]) -> dict[str, np.ndarray]:
    """A dSPACE export's channels: ``time`` (its X.Data), then each Y(k) by name."""
    return {"time": np.ravel(np.asarray(time, dtype=float)), **{n: np.ravel(np.asarray(d, float)) for n, d in channels}}


def _read_mat73(path: Path) -> dict[str, dict[str, np.ndarray]]:
    try:
        import h5py
    except ImportError as error:
        raise ImportError(f"{path.name} is a MATLAB v7.3 (HDF5) file: reading it needs h5py: "
                          "pip install 'amb_fast[xarray]'") from error  # fmt: skip
    groups: dict[str, dict[str, np.ndarray]] = {"": {}}
    try:
        f = h5py.File(path, "r")
    except OSError as error:
        raise ValueError(f"{path.name} is not a readable MATLAB v7.3 (HDF5) file: {error}") from None
    with f:
        for key, item in f.items():
            if key.startswith("#"):
                continue
            cls = item.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            if isinstance(item, h5py.Group) and cls == "struct" and "X" in item and "Y" in item:
                time = item["X"]["Data"]
                if time.dtype.kind == "O":  # a struct array: a reference per element
                    time = f[np.ravel(time[()])[0]]
                names, data = (np.ravel(item["Y"][field][()]) for field in ("Name", "Data"))
                channels = [("".join(chr(c) for c in np.ravel(f[n][()])), f[d][()]) for n, d in zip(names, data)]
                groups[key] = _dspace(time[()], channels)
            elif isinstance(item, h5py.Dataset) and item.dtype.kind in "iuf" and cls not in ("char", "cell"):
                value = np.asarray(item[()], dtype=float).T  # MATLAB is column-major
                groups[""][key] = np.ravel(value) if min(value.shape, default=1) <= 1 else value
    return groups
