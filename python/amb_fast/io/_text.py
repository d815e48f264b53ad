"""Text recordings: CSV/TSV/``;`` dialects with quoted headers, a units row and decimal commas.

:func:`sniff` finds the dialect from the first lines; the data are then read in chunks keeping only the
chosen columns (pandas' C parser when installed, numpy's ``loadtxt`` otherwise).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import require
from ._channels import _agree, _find, _fs_from_time, _index, _scale, split_unit

CHUNK_BYTES = 1 << 16  # text per chunk when reading: bounds the memory beyond the two channels
WIDE = 16  # columns beyond which text is parsed by numpy (smaller buffers) even with pandas installed


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
) -> tuple[np.ndarray, np.ndarray, float, str]:
    """Force (N), displacement (m), fs (Hz) and the source of a text recording: the fields of its Recording."""
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
    return force_values, displacement_values, fs, f"{path.name}: force {f_name!r}, displacement {y_name!r}"


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
