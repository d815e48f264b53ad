"""Text recordings: CSV/TSV/``;`` dialects with quoted headers, a units row and decimal commas.

:func:`sniff` finds the dialect from the first lines; the data are then read in chunks keeping only the
chosen columns (pandas' C parser when installed, numpy's ``loadtxt`` otherwise).
"""

from __future__ import annotations

import codecs
import csv
import itertools
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import require
from ._channels import UNIT_NAMES, UNIT_WORDS, UNITS, _index, _scale, _time_index, fs_from_time, split_unit, symbol

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
    rate: tuple[tuple[float, ...], str] | None = None  # fs (Hz) stated above the header (two readings of
    # "10,000": a thousands separator or a decimal mark), and that line
    above: str = ""  # with no header: the non-numeric row just above the data, when it has too few names
    encoding: str = "utf-8-sig"
    drop: tuple[int, ...] = ()  # lines after `skip` that are not data: the headers of a LabVIEW file's later segments


# A sampling rate or interval stated in the metadata: "Sample rate: 4000 Hz", "Sampling Frequency = 4 kHz",
# "Sample Rate (Hz),4000", LabVIEW's "Delta_X<tab>0.000250" (the interval, s).
_RATE_KEY = (
    r"sample[ _-]?rate|sampling[ _-]?(?:rate|frequency)|sample[ _-]?frequency|scan[ _-]?rate|fs"
    r"|abtastrate|abtastfrequenz"
)
_STEP_KEY = (
    r"delta[ _]?x|delta[ _]?t|sample[ _-]?interval|sampling[ _-]?interval|sample[ _-]?period|dt"
    r"|time[ _-]?step|abtastintervall"
)
_RATE_LINE = re.compile(
    rf'^\s*"?(?P<key>{_RATE_KEY}|{_STEP_KEY})"?\s*(?:[\[(](?P<u1>[^\])]*)[\])])?\s*"?\s*[:=\t,;]\s*"?'
    r"(?P<value>[0-9]+(?:[.,][0-9]*)?(?:[eE][-+]?[0-9]+)?)"
    r"(?![0-9.,])(?![ \u00a0\u202f][0-9]{3}(?![0-9]))"  # the whole number: not 10 of '10,000.5' or '10 000'
    r"\s*(?P<u2>[a-zA-Zµμ/]+)?",
    re.IGNORECASE,
)
_RATE_UNITS = {"hz": 1.0, "khz": 1e3, "s/s": 1.0, "sa/s": 1.0, "samples/s": 1.0, "ks/s": 1e3, "/s": 1.0, "1/s": 1.0}
_STEP_UNITS = {unit: factor for unit, (quantity, factor) in UNITS.items() if quantity == "time"}


def stated_rate(lines: list[str], path: Path) -> tuple[tuple[float, ...], str] | None:
    """fs (Hz) that metadata lines state (a rate, or an interval such as LabVIEW's ``Delta_X``), with the line
    it came from; None if none does; two lines stating different rates are an error naming both. A rate in
    Hz such as ``10,000`` or ``4.000`` (one to three digits, a separator, three digits) has two readings, a
    thousands separator or a decimal mark: both are returned, for the time column or ``fs=`` to settle
    (``4.000 kHz`` is 4 kHz: a rate of MHz is not a DAQ's)."""
    found: list[tuple[tuple[float, ...], str]] = []
    for line in lines:
        match = _RATE_LINE.match(line)
        if not match:
            continue
        text = match.group("value")
        values = [float(text.replace(",", "."))]
        unit = (match.group("u1") or match.group("u2") or "").strip().lower()
        interval = re.fullmatch(_STEP_KEY, match.group("key"), re.IGNORECASE) is not None
        factor = (_STEP_UNITS if interval else _RATE_UNITS).get(unit or ("s" if interval else "hz"))
        if factor is None or values[0] <= 0:
            continue  # a unit that is not a rate or an interval (e.g. "fs: 16 bit"): not the clock
        if not interval and factor == 1.0 and re.fullmatch(r"[1-9][0-9]{0,2}[.,][0-9]{3}", text):
            values.append(float(text.replace(",", "").replace(".", "")))  # in Hz, "10,000" may be ten thousand
        found.append((tuple(1.0 / (v * factor) if interval else v * factor for v in values), line.strip()))
    for fs, line in found[1:]:
        if not any(abs(a - b) <= 1e-9 * a for a in fs for b in found[0][0]):
            raise ValueError(f"{path.name} states two sampling rates: {found[0][1]!r} ({_hz(found[0][0])}) and "
                             f"{line!r} ({_hz(fs)}); pass fs= (Hz; on the command line --fs)")  # fmt: skip
    return found[0] if found else None


def _hz(readings: tuple[float, ...]) -> str:
    return " or ".join(f"{fs:.10g} Hz" for fs in readings)


# A metadata line giving the channels' units: LabVIEW's "Y_Unit_Label<tab>Newtons<tab>Meters" (one per channel,
# the X_Value columns left out), a DAQ's "Units;s;N;mm" (one per column).
_UNIT_LINE = re.compile(r'^\s*"?(?P<key>y_unit_label|units?|einheit(?:en)?)"?\s*(?:[:=]\s*)?$', re.IGNORECASE)


def _labelled(names: list[str], above: list[str], delimiter: str | None, path: Path) -> list[str]:
    """The column names with the units that a metadata line above the header gives (the last such line),
    added as ``name [unit]`` where the name has none. A line whose units cannot be matched to the columns
    one to one is refused: a channel's scale is never guessed."""
    for line in reversed(above):
        fields = _fields(line, delimiter)
        match = _UNIT_LINE.match(fields[0]) if len(fields) > 1 else None
        if not match:
            continue
        units = [u.strip() for u in fields[1:]]
        while units and not units[-1]:
            units.pop()
        if match.group("key").lower() == "y_unit_label":
            columns = [c for c, n in enumerate(names) if n.casefold() != "x_value"]
        elif all(u.casefold() in UNIT_WORDS or u.casefold() in UNIT_NAMES for u in units if u):
            columns = list(range(len(names)))
        else:
            continue  # "Unit: B2" (a rig's unit), not units
        if len(units) != len(columns):
            raise ValueError(f"{path.name}: its metadata line {line.strip()!r} gives {len(units)} units for the "
                             f"{len(columns)} columns {[names[c] for c in columns]}: which unit is whose is not "
                             "known; write each unit in its column's name (force [N]) and delete the line, or "
                             "rescale the columns to N and m and delete the line")  # fmt: skip
        named = list(names)
        for c, unit in zip(columns, units):
            unit = symbol(unit)
            if unit and split_unit(names[c])[1] is None:
                named[c] = f"{names[c]} [{unit}]"
        return named
    return names


def _numeric(field: str, decimal_comma: bool) -> bool:
    text = field.strip().strip('"')
    if decimal_comma:
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return False
    return True


def _fields(line: str, delimiter: str | None) -> list[str]:
    """A line's fields; a delimiter ending every line (some DAQs write one) leaves no empty last field."""
    if delimiter is None:
        return line.split()
    fields = next(csv.reader([line], delimiter=delimiter, quotechar='"', skipinitialspace=True))
    return fields[:-1] if len(fields) > 1 and not fields[-1].strip() else fields


def _data_start(rows: list[list[str]], decimal_comma: bool) -> int | None:
    """Index of the first row from which every row (to the end of the sample) is numeric with one field count
    of at least 2 (a last row cut short by the sample's end is allowed); None if there is no such block."""
    numeric = [len(r) >= 2 and all(_numeric(f, decimal_comma) for f in r) for r in rows]
    for start in range(len(rows)):
        if not numeric[start]:
            continue
        width = len(rows[start])
        body = rows[start:]
        whole = [numeric[start + j] and len(r) == width for j, r in enumerate(body)]
        if all(whole[:-1]) and (whole[-1] or len(body) > 2):
            return start
    return None


def text_encoding(path: Path) -> str:
    """The encoding of a text recording: UTF-16 or UTF-8 by their byte-order mark; else UTF-8 if its first
    CHUNK_BYTES decode as UTF-8; else Windows-1252 (European DAQ software writes ``µm`` as the one byte 0xB5,
    as Latin-1 does), or Latin-1 for the bytes Windows-1252 leaves undefined."""
    with open(path, "rb") as handle:
        head = handle.read(CHUNK_BYTES)
    if head.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return "utf-16"
    try:
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)  # a character cut at the end is fine
    except UnicodeDecodeError:
        try:
            head.decode("cp1252")
        except UnicodeDecodeError:
            return "latin-1"
        return "cp1252"
    return "utf-8-sig"


def sniff(path: Path) -> _Dialect:
    """Delimiter, decimal comma, column names and the lines before the data of a text recording.

    The data are the block of numeric rows that runs to the end of the file's first lines; the header is
    the row just before it with as many fields (a units row may sit between them), and anything before is
    metadata (LabVIEW's ``***End_of_Header***`` blocks, a DAQ's ``key: value`` preamble) and skipped. A file
    without a header row has its columns named ``column 0``, ``column 1``, ... (choose them by index)."""
    encoding = text_encoding(path)
    with open(path, encoding=encoding, errors="replace", newline="") as handle:
        lines = [line.rstrip("\r\n") for line in itertools.islice(handle, 256)]
    drop = _lvm_segment_headers(path, encoding) if lines and lines[0].startswith("LabVIEW Measurement") else ()
    kept = [j for j, line in enumerate(lines) if line.strip() and not line.lstrip().startswith(("#", "%"))
            and j not in drop]  # fmt: skip
    if not kept:
        raise ValueError(f"{path.name} has no rows of numbers")
    sample = "\n".join(lines[j] for j in kept[-16:])
    for delimiter in [*(d for d in ("\t", ";", ",") if d in sample), None]:
        rows = [_fields(lines[j], delimiter) for j in kept]
        for decimal_comma in (False, True):
            start = _data_start(rows, decimal_comma)
            if start is None:
                continue
            width = len(rows[start])
            last = rows[start - 1] if start >= 1 else []
            filled = [f for f in last if f.strip()]
            if filled and all(_numeric(f, decimal_comma) for f in filled):  # numbers: not a header
                row = f"line {kept[start - 1] + 1} ({lines[kept[start - 1]].strip()!r})"
                raise ValueError(f"{path.name}: {row} is a row of numbers with a field empty or missing "
                                 f"({len(last)} fields, {len(last) - len(filled)} empty; the rows after it have "
                                 f"{width} numbers): a lost sample? amb_fast never guesses one: repair the row or "
                                 "cut the file there")  # fmt: skip
            # The header has the data's fields, or one more whose column is empty (LabVIEW's "Comment").
            before = [r[:width] for r in rows[max(0, start - 2) : start] if len(r) in (width, width + 1)]
            units_row = len(before) == 2 and all(
                u.strip().strip("[]()").lower() in UNIT_WORDS for u in before[1] if u.strip()
            )
            above = ""
            if units_row:  # a header, then a units row
                names = [n.strip() for n in before[0]]
                units = [u.strip().strip("[]()") for u in before[1]]
                names = [f"{n} [{u}]" if u and split_unit(n)[1] is None else n for n, u in zip(names, units)]
            elif start >= 1 and len(rows[start - 1]) in (width, width + 1):
                names = [n.strip() for n in rows[start - 1][:width]]
            else:  # no header row: columns by index
                names = [f"column {c}" for c in range(width)]
                above = lines[kept[start - 1]].strip() if start >= 1 and 2 <= len(rows[start - 1]) < width else ""
            skip = kept[start]
            header = kept[start - (2 if units_row else 1)] if start >= 1 and not names[0] == "column 0" else skip
            _no_data_above(rows, kept, lines, header, width, decimal_comma, path)
            names = _labelled(names, lines[:header], delimiter, path)
            rate = stated_rate(lines[:header], path)
            percent = any(line.lstrip().startswith("%") for line in lines[skip:])
            body = [lines[j] for j in kept[start:]]
            line_bytes = max(16, int(np.mean([len(line) + 1 for line in body])))
            return _Dialect(delimiter, decimal_comma, names, skip, percent, line_bytes, rate, above, encoding, drop)
    raise ValueError(f"{path.name}: could not read it as a table (rows of numbers separated by ',', ';', tabs or "
                     "blanks, after an optional header row naming the columns)")  # fmt: skip


_END = "***End_of_Header***"
_SAME = ("Channels", "Delta_X", "Y_Unit_Label", "X_Dimension")  # a segment changing one is another recording


def _lvm_segment_headers(path: Path, encoding: str) -> tuple[int, ...]:
    """The lines of a LabVIEW ``.lvm`` file's segment headers after its first data line (Write To Measurement
    File's "one header per segment": the recording continues under each), to be skipped. Each must repeat
    the first segment's column names, ``Channels``, ``Delta_X``, ``Y_Unit_Label`` and ``X_Dimension``: a
    segment that changes one is another recording, refused."""
    drop: list[int] = []
    ends, first, names = 0, -1, ""
    fixed: dict[str, str] = {}  # the first segment's lines that every segment must repeat
    block: list[int] = []  # the lines of the segment header being read
    closed = False  # its End_of_Header seen: next comes its column names line (or data)
    with open(path, encoding=encoding, errors="replace", newline="") as handle:
        for j, raw in enumerate(handle):
            line = raw.strip()
            data = line[:1] != "" and line[:1] in "0123456789+-."
            if first < 0:  # the file header and the first segment's header
                ends += line.startswith(_END)
                if line.startswith(_SAME):
                    fixed[line.split()[0]] = line
                names = line if ends >= 2 and not names and line and not (data or line.startswith(_END)) else names
                first = j if data and ends >= 2 else first
                continue
            if not line or line.startswith("#") or (data and not block):
                continue
            if closed:  # the segment's column names, or its data
                if not data and line != names:
                    raise ValueError(f"{path.name}: the LabVIEW segment at line {j + 1} has the columns {line!r}, "
                                     f"the first {names!r}: another recording; cut the file there")  # fmt: skip
                drop += block + ([] if data else [j])
                block, closed = [], False
            elif data:  # text among the data, not a segment header: left to the parser to refuse
                block = []
            else:
                before = fixed.get(line.split()[0], "") if line.startswith(_SAME) else line
                if line != before:
                    raise ValueError(f"{path.name}: the LabVIEW segment at line {j + 1} states {line!r}, the first "
                                     f"{before!r}: another recording; cut the file there")  # fmt: skip
                block.append(j)
                closed = line.startswith(_END)
    return tuple(drop)


def _no_data_above(
    rows: list[list[str]], kept: list[int], lines: list[str], header: int, width: int, decimal_comma: bool, path: Path
) -> None:
    """Refuse rows of numbers as wide as the data above the header: the table would start after them and
    they would be dropped without a word (two recordings joined in one file)."""
    numeric = [kept[j] for j, r in enumerate(rows) if kept[j] < header and len(r) in (width, width + 1)
               and all(_numeric(f, decimal_comma) for f in r[:width])]  # fmt: skip
    if numeric:
        raise ValueError(f"{path.name}: rows of numbers at lines {numeric[0] + 1}-{numeric[-1] + 1} come before "
                         f"line {header + 1} ({lines[header].strip()!r}), where the table read starts: the file holds "
                         "two tables (recordings joined?); amb_fast drops no rows: "
                         "cut it into one file per table")  # fmt: skip


def _load_text(
    path: Path, force: str | int, displacement: str | int, time: str | int | None, given: float | None = None
) -> tuple[list[str], str, np.ndarray, str, np.ndarray, float | None, str]:
    """A text recording's column names, the force's and the displacement's name and values (in their units),
    and fs (Hz) from its time column or metadata with where it came from (None, "" without either). ``given``
    (``fs=``) settles a metadata rate with two readings."""
    dialect = sniff(path)
    names = dialect.names
    headerless = names[0] == "column 0"
    try:
        columns = [_index(names, force, "force", path), _index(names, displacement, "displacement", path)]
    except ValueError as error:
        if headerless:
            short = (f" (the row above the data, {dialect.above!r}, has fewer names than the {len(names)} data "
                     "columns: which column each names is not known)") if dialect.above else ""  # fmt: skip
            raise ValueError(f"{path.name} has no header row naming its {len(names)} columns{short}: choose the force "
                             "and the displacement by 0-based index (force=1, displacement=2, and the time column, "
                             "if any, time=0; on the command line --force 1 --displacement 2 --time 0)") \
                from error  # fmt: skip
        raise
    t_index = None if headerless and not isinstance(time, int) else _time_index(names, time, path)
    use = columns + ([t_index] if t_index is not None else [])
    count = _count_rows(path, dialect.skip, dialect.encoding)
    out = np.empty((len(use), count))
    row = 0
    for chunk in _chunks(path, dialect, use):  # the chosen columns, in the order of `use`
        n = chunk.shape[0]
        require(row + n <= count, "rows", f"of {path.name}", "countable (the file changed while being read)")
        out[:, row : row + n] = chunk.T
        row += n
    out = out[:, :row]
    found, origin = None, ""
    if t_index is not None and row >= 2:
        found = fs_from_time(out[2], path, names[t_index], _scale(names[t_index], "time", path))
        origin = f"time column {names[t_index]!r}"
    if dialect.rate is not None:
        readings, line = dialect.rate
        if found is not None and not any(abs(stated - found) <= 1e-3 * found for stated in readings):
            raise ValueError(f"{path.name}: its {origin} gives fs {found:.10g} Hz but its metadata line {line!r} "
                             f"states {_hz(readings)}; pass fs= (Hz; on the command line --fs) and time=None to "
                             "choose")  # fmt: skip
        if found is None and len(readings) > 1 and not any(abs(r - (given or 0.0)) <= 1e-3 * r for r in readings):
            raise ValueError(f"{path.name}: its metadata line {line!r} states {_hz(readings)} (a thousands separator "
                             "or a decimal mark?): pass fs= (Hz; on the command line --fs), one of them"
                             + (f", not {given:g}" if given is not None else ""))  # fmt: skip
        if found is None and len(readings) == 1:
            found, origin = readings[0], f"metadata line {line!r}"
    return names, names[columns[0]], out[0], names[columns[1]], out[1], found, origin


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
    rows = 0
    try:
        if pd is not None and not dialect.comment_percent and len(dialect.names) <= WIDE:
            with pd.read_csv(
                path, sep=dialect.delimiter or r"\s+", header=None, usecols=sorted(set(use)),
                skiprows=[*range(dialect.skip), *dialect.drop] if dialect.drop else dialect.skip,
                chunksize=max(256, CHUNK_BYTES // dialect.line_bytes), dtype=np.float64,
                decimal="," if dialect.decimal_comma else ".", comment="#", quotechar='"', skipinitialspace=True,
                encoding=dialect.encoding, encoding_errors="replace", engine="c",
            ) as reader:  # fmt: skip
                for frame in reader:
                    yield frame[use].to_numpy(dtype=np.float64)
                    rows += len(frame)
            return
        with open(path, encoding=dialect.encoding, errors="replace", newline="") as handle:
            for _ in range(dialect.skip):
                handle.readline()
            read, drop = dialect.skip, set(dialect.drop)  # lines read; the segment headers to leave out
            while block := handle.readlines(CHUNK_BYTES):
                delimiter = dialect.delimiter
                read += len(block)
                if drop:
                    block = [text for j, text in enumerate(block, read - len(block)) if j not in drop]
                    if not block:
                        continue
                if dialect.decimal_comma and delimiter == ",":  # "1,5","2,5": the quotes keep the fields apart
                    block = [";".join(fields) + "\n" for fields in csv.reader(block, skipinitialspace=True)]
                    delimiter = ";"
                if dialect.decimal_comma:
                    block = [line.replace(",", ".") for line in block]
                if any('"' in line for line in block):  # quoted numbers, in any row (not only the first or last)
                    block = [line.replace('"', "") for line in block]
                chunk = np.loadtxt(block, delimiter=delimiter, usecols=use, ndmin=2, comments=("#", "%"),
                                   dtype=np.float64)  # fmt: skip
                yield chunk
                rows += chunk.shape[0]
    except (ValueError, TypeError) as error:
        raise ValueError(f"{path.name}: a row after line {dialect.skip + rows} is not numeric ({error})") from None


def _count_rows(path: Path, skip: int, encoding: str = "utf-8-sig") -> int:
    """Data rows after ``skip`` lines (blank and comment lines excluded), without holding the file."""
    if encoding == "utf-16":  # two bytes a character: counted as text
        with open(path, encoding=encoding, errors="replace") as text:
            lines = (line.strip() for line in itertools.islice(text, skip, None))
            return sum(1 for line in lines if line and not line.startswith(("#", "%")))
    with open(path, "rb") as handle:
        rows = (line.strip() for line in itertools.islice(handle, skip, None))
        return sum(1 for row in rows if row and not row.startswith((b"#", b"%")))
