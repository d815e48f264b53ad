"""Small TOML/JSON files: reading them with errors that name the file, writing TOML, rig files (:func:`load_rig`,
:func:`save_rig`), and the atomic writes every file of the package goes through: a temporary file beside the
target, fsynced, then ``os.replace``. A failed write (a full disk, an exception in the writer, an interrupt)
leaves the old file and no temporary file behind and raises an ``OSError`` naming the path; the new file gets
the old one's permissions, or a new file's (0666 less the umask), not mkstemp's owner-only 0600.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from ._params import UNITS, Rig


def read_table(path: str | os.PathLike[str], what: str) -> dict[str, Any]:
    """The top-level table of a TOML or JSON file (by its suffix). Every error names ``what`` and the file:
    a missing file, a syntax error (with its line), a top level that is not a table."""
    file = Path(path)
    where = f"{what} {str(file)!r}"
    suffix = file.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise ValueError(f"{where}: path must end in .toml or .json, got {file.suffix or 'no suffix'!r}")
    if not file.is_file():
        raise ValueError(f"{where} does not exist" if not file.exists() else f"{where} is not a file")
    try:
        if suffix == ".json":
            with open(file, encoding="utf-8") as handle:
                data = json.load(handle)
        else:
            tomllib = _tomllib(where)
            with open(file, "rb") as handle:
                data = tomllib.load(handle)
    except UnicodeDecodeError as error:
        raise ValueError(f"{where}: not a text file ({error.reason} at byte {error.start})") from None
    except ValueError as error:  # json.JSONDecodeError and tomllib.TOMLDecodeError are ValueErrors
        kind = "JSON" if suffix == ".json" else "TOML"
        raise ValueError(f"{where}: {kind} syntax error: {error}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{where}: the top level must be a table/object, got {type(data).__name__}")
    return data


def _tomllib(where: str) -> Any:
    try:
        import tomllib  # type: ignore[import-not-found,unused-ignore]
    except ImportError:  # pragma: no cover - Python < 3.11
        try:
            import tomli as tomllib  # type: ignore[no-redef,import-not-found,unused-ignore]
        except ImportError:
            raise ImportError(
                f"reading {where} needs Python >= 3.11 or the tomli package (pip install tomli); or write it as JSON"
            ) from None
    return tomllib


# ---------------------------------------------------------------------------------------------- writing
def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # shortest text that reads back to the same double
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string is a JSON string for these texts
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} {value!r} to TOML")


def to_toml(data: Mapping[str, Any], comments: Mapping[str, str] | None = None) -> str:
    """TOML text of ``data``: scalars and lists first, then tables (``dict``) and arrays of tables (a list
    of ``dict``) one level deep; ``comments`` a trailing ``# ...`` per top-level key."""
    comments = comments or {}
    out: list[str] = []
    plain = {k: v for k, v in data.items() if not isinstance(v, Mapping) and not _is_tables(v)}
    for key, value in plain.items():
        note = f"  # {comments[key]}" if key in comments else ""
        out.append(f"{key} = {_value(value)}{note}")
    for key, value in data.items():
        if isinstance(value, Mapping):
            out += ["", f"[{key}]"] + [f"{k} = {_value(v)}" for k, v in value.items()]
        elif _is_tables(value):
            for table in value:
                out += ["", f"[[{key}]]"] + [f"{k} = {_value(v)}" for k, v in table.items()]
    return "\n".join(out) + "\n"


def _is_tables(value: Any) -> bool:
    return isinstance(value, (list, tuple)) and bool(value) and all(isinstance(v, Mapping) for v in value)


def _permissions(path: Path) -> int:
    """The mode ``path`` has, or a file created there with open() would get (0666 less the umask)."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0o022)  # read it the only portable way: set and restore at once
        os.umask(umask)
        return 0o666 & ~umask


def _fsync_dir(directory: Path) -> None:
    with contextlib.suppress(OSError):  # some platforms cannot open or fsync a directory
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` to write to; on success it replaces ``path`` atomically.

    For writers that want a file name (h5py, xarray, matplotlib, ``scipy.io.savemat``).
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise OSError(f"cannot write {str(path)!r}: the directory {str(directory)!r} does not exist")
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix, dir=directory)
    os.close(fd)
    temporary = Path(name)
    try:
        yield temporary
        with open(temporary, "rb+") as handle:
            os.fsync(handle.fileno())
        os.chmod(temporary, _permissions(path))
        os.replace(temporary, path)
        _fsync_dir(directory)
    except BaseException as error:
        with contextlib.suppress(OSError):
            temporary.unlink()
        if isinstance(error, OSError):
            raise OSError(f"could not write {str(path)!r} (the old file, if any, is unchanged): {error}") from error
        raise


def atomic_write(path: str | Path, write: Callable[[Path], object]) -> Path:
    """Call ``write(temporary_path)`` and move the result onto ``path`` atomically; return ``path``."""
    with atomic_path(path) as temporary:
        write(temporary)
    return Path(path)


def atomic_text(path: str | Path, text: str) -> Path:
    """Write text (UTF-8) atomically."""
    return atomic_write(path, lambda p: p.write_text(text, encoding="utf-8"))


write_text = atomic_text  # rig and controller files


# ---------------------------------------------------------------------------------------------- rig files
_RIG_UNITS = {**{f.name: UNITS[f.name] for f in fields(Rig) if f.name in UNITS},
              "substeps": "integration substeps per sample"}  # fmt: skip


def save_rig(rig: Rig, path: str | os.PathLike[str], extra: Mapping[str, Mapping[str, Any]] | None = None) -> Path:
    """Write ``rig`` to a TOML rig file (read back by :func:`load_rig`); ``extra`` tables are appended."""
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be an amb_fast.Rig, got {type(rig).__name__}")
    file = Path(path)
    if file.suffix.lower() != ".toml":
        raise ValueError(f"path must end in .toml (a rig file), got {str(file)!r}")
    header = "# amb_fast rig file: Rig fields in SI units ('none': stage switched off); load with amb_fast.load_rig\n"
    table = {f.name: "none" if getattr(rig, f.name) is None else getattr(rig, f.name) for f in fields(Rig)}
    return write_text(file, header + to_toml({**table, **(extra or {})}, _RIG_UNITS))


def load_rig(path: str | os.PathLike[str]) -> Rig:
    """Read a rig file (TOML or JSON): :class:`~amb_fast.Rig` fields at the top level in SI units, ``"none"``
    for a stage switched off; a field left out takes ``Rig.paper()``'s value. Tables (``[fit]``) are a
    record and are not read. Errors name the file and the key."""
    data = read_table(path, "rig file")
    where = f"rig file {str(Path(path))!r}"
    known = {f.name for f in fields(Rig)}
    values = {k: v for k, v in data.items() if not isinstance(v, dict)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    changes: dict[str, Any] = {
        k: None if isinstance(v, str) and v.lower() == "none" and k != "force_law" else v for k, v in values.items()
    }
    try:
        return replace(Rig.paper(), **changes)
    except (ValueError, TypeError) as error:
        raise ValueError(f"{where}: {error}") from None
