"""Recordings of a rig: CSV/TSV dialects, MATLAB v4-v7 and v7.3 (HDF5), dSPACE exports, NI TDMS.

Every reader returns *recordings*: a name (``""`` for a file's top level) mapped to its channels. A
channel is found by name (exact, then without its unit, then the last part of a dSPACE path) or by
index; a unit in the name (``force [kN]``, ``x (mm)``, ``disp_um``) or in a units row is scaled to SI,
and a unit that is not a force (for the force) or a length (for the displacement) is refused.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._validate import real, require, series
from ._atomic import atomic_write

SUFFIXES = (".csv", ".tsv", ".txt", ".mat", ".tdms")
# Unit -> (quantity, factor to SI).
UNITS = {
    "n": ("force", 1.0), "kn": ("force", 1e3), "mn": ("force", 1e-3),
    "m": ("length", 1.0), "mm": ("length", 1e-3), "um": ("length", 1e-6), "µm": ("length", 1e-6),
    "μm": ("length", 1e-6), "micron": ("length", 1e-6), "nm": ("length", 1e-9),
    "s": ("time", 1.0), "ms": ("time", 1e-3), "us": ("time", 1e-6),
}  # fmt: skip
_UNIT_IN_NAME = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<b>[^\]]*)\]|\((?P<p>[^)]*)\))\s*$")
_UNIT_SUFFIX = re.compile(r"^(?P<name>.+?)_(?P<u>kN|mN|N|mm|um|µm|μm|nm|m|ms|us|s)$")
CHUNK_LINES = 1 << 16  # rows per chunk when writing
CHUNK_BYTES = 1 << 16  # text per chunk when reading: bounds the memory beyond the two channels
WIDE = 16  # columns beyond which text is parsed by numpy (smaller buffers) even with pandas installed


@dataclass(frozen=True)
class Recording:
    """Force (N) and displacement (m) sampled at ``fs`` (Hz).

    Attributes
    ----------
    force, displacement : ndarray
        The two channels in SI units.
    fs : float
        Sampling frequency, Hz.
    source : str
        Where they came from: file, recording and channel names with the units they were scaled from.
    """

    force: np.ndarray
    displacement: np.ndarray
    fs: float
    source: str = ""


def save_recording(
    path: str | Path, *, force: ArrayLike, displacement: ArrayLike, fs: float, meta: dict | None = None
) -> None:
    """Write a recording atomically: ``.csv`` (columns time, force, displacement; full precision) or ``.mat``.

    The old file, if any, is replaced only once the new one is complete. The amb_fast version and ``meta``
    (the rig, controller and seed of a simulation) go in trailing ``#`` lines of a CSV, or a text variable
    ``amb_fast`` of a ``.mat``; :func:`load_recording` skips both.
    """
    from ._results import _jsonable, trailer, version

    path = Path(path)
    force, displacement = series("force", force), series("displacement", displacement)
    fs = real("fs", fs, "Hz", positive=True)
    suffix = path.suffix.lower()
    require(suffix in (".csv", ".mat"), "path", str(path), "a file name ending in .csv or .mat")
    if suffix == ".csv":

        def write(target: Path) -> None:
            with open(target, "w") as handle:
                handle.write("time,force,displacement\n")
                for start in range(0, force.size, CHUNK_LINES):
                    stop = min(start + CHUNK_LINES, force.size)
                    table = np.column_stack([np.arange(start, stop) / fs, force[start:stop], displacement[start:stop]])
                    np.savetxt(handle, table, delimiter=",", fmt="%.17g")
                handle.write(trailer(meta or {}))

        atomic_write(path, write)
    else:
        import json

        from scipy.io import savemat

        stamp = json.dumps({"amb_fast_version": version(), **_jsonable(meta or {})})
        variables = {"force": force, "displacement": displacement, "fs": fs, "amb_fast": stamp}
        atomic_write(path, lambda target: savemat(target, variables))


def load_recording(
    path: str | Path,
    *,
    force: str | int = "force",
    displacement: str | int = "displacement",
    fs: float | None = None,
    recording: str | None = None,
    time: str | int | None = "time",
) -> Recording:
    """Read force and displacement channels from a rig's file.

    Formats: CSV/TSV/``.txt`` (``,``, ``;``, tab or blank separated; quoted headers; an optional units
    row; decimal commas; ``#`` comment lines), MATLAB ``.mat`` v4-v7 (scipy) and v7.3 (HDF5, needs h5py)
    with top-level variables or dSPACE ControlDesk/TRACE exports (a struct with ``X.Data`` for time
    and ``Y(k).Name`` / ``Y(k).Data`` per channel), and NI ``.tdms`` (needs ``amb_fast[tdms]``; each
    group is a recording). Text files are read in chunks, keeping only the chosen columns.

    Parameters
    ----------
    force, displacement : str or int
        Channel name (a unit in brackets or a ``_mm``-style suffix may be left out) or 0-based column
        index. Units are scaled to N and m (``kN``, ``mN``, ``mm``, ``um``, ``nm``); other units are refused.
    fs : float, optional
        Sampling frequency, Hz. If the file has a time column (or ``fs``), the two must agree within 0.1 %.
    recording : str, optional
        Which recording of a file that holds several (dSPACE exports, TDMS groups). Required then:
        channels of different recordings are never mixed.
    time : str or int or None
        The time column (s, or ``ms``/``us`` by its unit), used for fs and checked to be uniform.
    """
    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    require(suffix in SUFFIXES, "path", str(path), f"a recording ending in {', '.join(SUFFIXES)}")
    if fs is not None:
        fs = real("fs", fs, "Hz", positive=True)
    if suffix == ".mat":
        groups = _read_mat(path)
    elif suffix == ".tdms":
        groups = _read_tdms(path)
    else:
        return _load_text(path, force, displacement, fs, time)
    name, channels = _choose_recording(groups, path, recording, (force, displacement))
    f_name, f_values = _channel(channels, force, "force", path)
    y_name, y_values = _channel(channels, displacement, "displacement", path)
    f_values = f_values * _scale(f_name, "force", path)
    y_values = y_values * _scale(y_name, "displacement", path)
    found = _file_fs(channels, time, path)
    fs = _agree(fs, found, path)
    where = f"{path.name}" + (f" recording {name!r}" if name else "")
    return Recording(series("force", f_values), series("displacement", y_values), fs,
                     f"{where}: force {f_name!r}, displacement {y_name!r}")  # fmt: skip


# -- channel names and units ----------------------------------------------------------------------------------------


def split_unit(name: str) -> tuple[str, str | None]:
    """``'force [kN]'`` -> ``('force', 'kN')``; ``'x_mm'`` -> ``('x', 'mm')``; ``'force'`` -> ``('force', None)``."""
    name = name.strip().strip('"').strip()
    match = _UNIT_IN_NAME.match(name)
    if match and match.group("name"):
        return match.group("name").strip(), next(u for u in match.group("b", "p") if u is not None).strip()
    match = _UNIT_SUFFIX.match(name)
    if match:
        return match.group("name"), match.group("u")
    return name, None


def _scale(name: str, quantity: str, path: Path) -> float:
    unit = split_unit(name)[1]
    if unit is None or unit == "":
        return 1.0
    want = {"force": "force", "displacement": "length", "time": "time"}[quantity]
    kind, factor = UNITS.get(unit.lower(), (None, 1.0))
    if kind != want:
        units = {"force": "N, kN, mN", "length": "m, mm, um, nm", "time": "s, ms, us"}[want]
        raise ValueError(f"{path.name}: the {quantity} channel {name!r} has unit {unit!r}; amb_fast needs "
                         f"one of {units} (scaled to SI), or rescale the column")  # fmt: skip
    return factor


def _index(names: list[str], key: str | int, role: str, path: Path) -> int:
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        require(0 <= key < len(names), role, key, f"a channel index 0..{len(names) - 1} of {path.name}")
        return int(key)
    return _find(names, str(key), role, path)


def _channel(channels: dict[str, np.ndarray], key: str | int, role: str, path: Path) -> tuple[str, np.ndarray]:
    names = list(channels)
    index = _index(names, key, role, path)
    return names[index], channels[names[index]]


def _find(names: list[str], key: str, role: str, path: Path) -> int:
    """The one column that ``key`` names: exactly, else without its unit, else by the last part of a path."""
    tests = (
        lambda n: n.strip().strip('"') == key,
        lambda n: split_unit(n)[0] == split_unit(key)[0],
        lambda n: split_unit(n.replace("\\", "/").split("/")[-1].strip('"'))[0] == split_unit(key)[0],
    )
    for test in tests:
        hits = [i for i, n in enumerate(names) if test(n)]
        if len(hits) > 1:
            raise ValueError(f"{path.name}: the {role} channel {key!r} is ambiguous: columns "
                             f"{[f'{i}: {names[i]}' for i in hits]} match; choose one by index")  # fmt: skip
        if hits:
            return hits[0]
    raise ValueError(f"{path.name} has no channel {key!r} for the {role}; it has {names}")


def _agree(given: float | None, found: float | None, path: Path) -> float:
    if given is None and found is None:
        raise ValueError(f"{path.name} has neither 'fs' nor a time column: pass fs= (Hz)")
    if given is not None and found is not None and abs(given - found) > 1e-3 * found:
        raise ValueError(f"fs must agree with the file's time column ({found:.10g} Hz from {path.name}) within "
                         f"0.1 %, got {given:g}")  # fmt: skip
    return float(given if given is not None else found)  # type: ignore[arg-type]


def _fs_from_time(first: float, last: float, count: int, steps: tuple[float, float], path: Path, scale: float) -> float:
    require(count >= 2 and last > first, "time", f"column of {path.name}", "increasing to give fs")
    mean = (last - first) / (count - 1)
    require(steps[0] > 0.5 * mean and steps[1] < 1.5 * mean, "time", f"column of {path.name} (steps {steps[0]:.6g} "
            f"to {steps[1]:.6g})", "uniformly spaced to give fs (no gaps or repeats)")  # fmt: skip
    return 1.0 / (mean * scale)


def _file_fs(channels: dict[str, np.ndarray], time: str | int | None, path: Path) -> float | None:
    names = list(channels)
    if "fs" in channels:
        return float(np.ravel(channels["fs"])[0])
    if time is None:
        return None
    try:
        index = _find(names, str(time), "time", path) if not isinstance(time, int) else time
    except ValueError:
        return None
    values = np.ravel(channels[names[index]]).astype(float)
    if values.size < 2:
        return None
    steps = np.diff(values)
    return _fs_from_time(values[0], values[-1], values.size, (steps.min(), steps.max()), path,
                         _scale(names[index], "time", path))  # fmt: skip


def _choose_recording(
    groups: dict[str, dict[str, np.ndarray]], path: Path, recording: str | None, keys: tuple[str | int, str | int]
) -> tuple[str, dict[str, np.ndarray]]:
    groups = {name: channels for name, channels in groups.items() if channels}
    if recording is not None:
        require(recording in groups, "recording", recording, f"one of {sorted(groups)} in {path.name}")
        return recording, groups[recording]

    def has(channels: dict[str, np.ndarray]) -> bool:
        try:
            for role, key in zip(("force", "displacement"), keys):
                _channel(channels, key, role, path)
        except ValueError:
            return False
        return True

    fitting = [name for name, channels in groups.items() if has(channels)]
    if len(groups) == 1:
        return next(iter(groups.items()))
    if len(fitting) == 1 and not any(name for name in groups if name and name not in fitting):
        return fitting[0], groups[fitting[0]]
    names = sorted(name for name in groups if name)
    raise ValueError(f"{path.name} holds several recordings {names}: choose one with recording=NAME "
                     "(channels of different recordings are never mixed)")  # fmt: skip


# -- text -----------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Dialect:
    delimiter: str | None  # None: runs of blanks
    decimal_comma: bool
    names: list[str]
    skip: int  # lines before the first data line (comments, header, units row)
    comment_percent: bool = False  # '%' comment lines among the data
    line_bytes: int = 64  # typical length of a data line


def _numeric(field: str, decimal_comma: bool) -> bool:
    text = field.strip().strip('"')
    if decimal_comma:
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return False
    return True


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return next(csv.reader([line], delimiter=delimiter, quotechar='"', skipinitialspace=True))


def sniff(path: Path) -> _Dialect:
    """Delimiter, decimal comma, column names and the lines before the data of a text recording."""
    with open(path, encoding="utf-8-sig", errors="replace", newline="") as handle:
        lines = []
        for line in handle:
            lines.append(line.rstrip("\r\n"))
            if len(lines) >= 64:
                break
    skip = 0
    while skip < len(lines) and (not lines[skip].strip() or lines[skip].lstrip().startswith(("#", "%"))):
        skip += 1
    if skip >= len(lines):
        raise ValueError(f"{path.name} has no header row naming the columns")
    header = lines[skip]
    body = [line for line in lines[skip + 1 :] if line.strip() and not line.lstrip().startswith(("#", "%"))]
    candidates: list[str | None] = ["\t", ";", ","] if "\t" in header or ";" in header or "," in header else []
    candidates.append(None)
    for delimiter in candidates:
        names = [n.strip() for n in _split(header, delimiter)]
        if len(names) < 2:
            continue
        for decimal_comma in (False, True):
            if decimal_comma and delimiter == ",":
                continue
            rows = [_split(line, delimiter) for line in body]
            numeric = [r for r in rows if len(r) == len(names) and all(_numeric(f, decimal_comma) for f in r)]
            if len(numeric) >= max(1, len(rows) - 1):
                units_row = bool(rows) and not all(_numeric(f, decimal_comma) for f in rows[0])
                if units_row:
                    units = [u.strip().strip("[]()") for u in rows[0]]
                    require(len(units) == len(names), "units row", rows[0], f"{len(names)} fields like the header")
                    names = [f"{n} [{u}]" if u and split_unit(n)[1] is None else n for n, u in zip(names, units)]
                percent = any(line.lstrip().startswith("%") for line in lines[skip + 1 :])
                width = max(16, int(np.mean([len(line) + 1 for line in body]))) if body else 64
                return _Dialect(delimiter, decimal_comma, names, skip + 1 + int(units_row), percent, width)
    raise ValueError(f"{path.name}: could not read it as a table (a header row naming the columns, then rows of "
                     "numbers separated by ',', ';', tabs or blanks)")  # fmt: skip


def _load_text(
    path: Path, force: str | int, displacement: str | int, fs: float | None, time: str | int | None
) -> Recording:
    dialect = sniff(path)
    names = dialect.names
    columns = [_index(names, force, "force", path), _index(names, displacement, "displacement", path)]
    f_name, y_name = names[columns[0]], names[columns[1]]
    t_index: int | None = None
    if time is not None:
        try:
            t_index = _find(names, str(time), "time", path) if not isinstance(time, int) else time
        except ValueError:
            t_index = None
    use = columns + ([t_index] if t_index is not None else [])
    count = _count_rows(path, dialect.skip)
    out = np.empty((2, count))
    first = last = math.nan
    steps = (math.inf, -math.inf)
    previous = math.nan
    row = 0
    for chunk in _chunks(path, dialect, use):  # the chosen columns, in the order of `use`
        n = chunk.shape[0]
        require(row + n <= count, "rows", f"of {path.name}", "countable (the file changed while being read)")
        out[:, row : row + n] = chunk[:, :2].T
        if t_index is not None and n:
            t = chunk[:, 2]
            if row == 0:
                first = float(t[0])
            else:
                gap = float(t[0] - previous)
                steps = (min(steps[0], gap), max(steps[1], gap))
            if n > 1:
                d = np.diff(t)
                steps = (min(steps[0], float(d.min())), max(steps[1], float(d.max())))
            previous = last = float(t[-1])
        row += n
    out = out[:, :row]
    found = None
    if t_index is not None and row >= 2:
        found = _fs_from_time(first, last, row, steps, path, _scale(names[t_index], "time", path))
    fs = _agree(fs, found, path)
    force_values = out[0]
    displacement_values = out[1]
    scale_f, scale_y = _scale(f_name, "force", path), _scale(y_name, "displacement", path)
    if scale_f != 1.0:
        force_values *= scale_f
    if scale_y != 1.0:
        displacement_values *= scale_y
    return Recording(force_values, displacement_values, fs,
                     f"{path.name}: force {f_name!r}, displacement {y_name!r}")  # fmt: skip


def _chunks(path: Path, dialect: _Dialect, use: list[int]) -> Iterator[np.ndarray]:
    """The data rows in chunks, only the columns ``use`` (in that order), as float64 arrays (rows, len(use)).

    pandas' C parser when pandas is installed and the file has at most WIDE columns (2-15x faster), else
    numpy's ``loadtxt`` on blocks of CHUNK_BYTES of lines, whose memory beyond the result stays near one
    block however many columns the file has (pandas' tokenizer holds about a megabyte more on wide files).
    """
    try:
        import pandas as pd
    except ImportError:
        pd = None
    if pd is not None and not dialect.comment_percent and len(dialect.names) <= WIDE:
        rows_per_chunk = max(256, CHUNK_BYTES // dialect.line_bytes)
        reader = pd.read_csv(
            path, sep=dialect.delimiter or r"\s+", header=None, skiprows=dialect.skip, usecols=sorted(set(use)),
            chunksize=rows_per_chunk, dtype=np.float64, decimal="," if dialect.decimal_comma else ".",
            comment="#", quotechar='"', skipinitialspace=True, encoding="utf-8-sig", engine="c",
        )  # fmt: skip
        rows = 0
        try:
            with reader:
                for frame in reader:
                    yield frame[use].to_numpy(dtype=np.float64)
                    rows += len(frame)
        except (ValueError, TypeError) as error:
            raise ValueError(f"{path.name}: a row after line {dialect.skip + rows} is not numeric ({error})") from None
        return
    rows = 0
    with open(path, encoding="utf-8-sig", errors="replace", newline="") as handle:
        for _ in range(dialect.skip):
            handle.readline()
        while True:
            block = handle.readlines(CHUNK_BYTES)
            if not block:
                return
            if dialect.decimal_comma:
                block = [line.replace(",", ".") for line in block]
            if any('"' in line for line in block[:1]) or '"' in block[-1]:
                block = [line.replace('"', "") for line in block]
            try:
                chunk = np.loadtxt(block, delimiter=dialect.delimiter, usecols=use, ndmin=2, comments=("#", "%"),
                                   dtype=np.float64)  # fmt: skip
            except ValueError as error:
                raise ValueError(f"{path.name}: a row after line {dialect.skip + rows} is not numeric ({error})") \
                    from None  # fmt: skip
            rows += chunk.shape[0]
            yield chunk


def _count_rows(path: Path, skip: int) -> int:
    """Data rows after ``skip`` lines (blank and comment lines excluded), without holding the file."""
    count = 0
    with open(path, "rb") as handle:
        for index, line in enumerate(handle):
            if index < skip:
                continue
            stripped = line.strip()
            if stripped and not stripped.startswith((b"#", b"%")):
                count += 1
    return count


# -- MATLAB ---------------------------------------------------------------------------------------------------------


def _is_hdf5(path: Path) -> bool:
    with open(path, "rb") as handle:
        head = handle.read(520)
    return head[512:520] == b"\x89HDF\r\n\x1a\n" or head[:8] == b"\x89HDF\r\n\x1a\n"


def _read_mat(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """Recordings of a ``.mat`` file: ``""`` for numeric top-level variables, one per dSPACE export struct."""
    if _is_hdf5(path):
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
    out = {"time": np.asarray(time, dtype=float).ravel()}
    for name, data in channels:
        out[name] = np.asarray(data, dtype=float).ravel()
    return out


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

        def char(ds: h5py.Dataset) -> str:
            return "".join(chr(c) for c in np.ravel(ds[()]))

        def deref(ref: h5py.Reference) -> h5py.Dataset:
            return f[ref]

        for key, item in f.items():
            if key.startswith("#"):
                continue
            cls = item.attrs.get("MATLAB_class", b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            if isinstance(item, h5py.Group) and cls == "struct" and "X" in item and "Y" in item:
                x, y = item["X"], item["Y"]
                time = _h5_field(f, x, "Data", 0)
                names_ds, data_ds = y["Name"], y["Data"]
                refs_n, refs_d = np.ravel(names_ds[()]), np.ravel(data_ds[()])
                chans = [(char(deref(rn)), np.ravel(deref(rd)[()])) for rn, rd in zip(refs_n, refs_d)]
                groups[key] = _dspace(time, chans)
            elif isinstance(item, h5py.Dataset) and item.dtype.kind in "iuf" and cls not in ("char", "cell"):
                value = np.asarray(item[()], dtype=float).T  # MATLAB is column-major
                groups[""][key] = np.ravel(value) if min(value.shape, default=1) <= 1 else value
    return groups


def _h5_field(f, group, field: str, index: int) -> np.ndarray:  # noqa: ANN001
    node = group[field]
    if node.dtype.kind == "O":  # a struct array: references per element
        return np.ravel(f[np.ravel(node[()])[index]][()]).astype(float)
    return np.ravel(node[()]).astype(float)


# -- TDMS -----------------------------------------------------------------------------------------------------------


def _read_tdms(path: Path) -> dict[str, dict[str, np.ndarray]]:
    try:
        from nptdms import TdmsFile
    except ImportError as error:
        raise ImportError(f"{path.name} is an NI TDMS file: reading it needs npTDMS: pip install 'amb_fast[tdms]'") \
            from error  # fmt: skip
    groups: dict[str, dict[str, np.ndarray]] = {}
    with TdmsFile.open(path) as tdms:
        for group in tdms.groups():
            channels: dict[str, np.ndarray] = {}
            for channel in group.channels():
                unit = channel.properties.get("unit_string")
                name = channel.name if not unit or split_unit(channel.name)[1] else f"{channel.name} [{unit}]"
                channels[name] = np.asarray(channel[:], dtype=float)
                increment = channel.properties.get("wf_increment")
                if increment and "fs" not in channels:
                    channels["fs"] = np.asarray(1.0 / float(increment))
            groups[group.name] = channels
    return groups
