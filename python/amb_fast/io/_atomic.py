"""Atomic writes: a temporary file in the target's directory, flushed and fsynced, then ``os.replace``.

A write that fails part-way (a full disk, an exception in the writer, an interrupt) leaves the old file
as it was and no temporary file behind, and raises an ``OSError`` that names the path. The new file gets
the old one's permissions, or a new file's (0666 less the umask): not mkstemp's owner-only 0600.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path


def _permissions(path: Path) -> int:
    """The mode ``path`` has, or a file created there with open() would get (0666 less the umask)."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0o022)  # read it the only portable way: set and restore at once
        os.umask(umask)
        return 0o666 & ~umask


def _fsync_dir(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # pragma: no cover - some platforms cannot open a directory
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
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
    """Write text atomically."""
    return atomic_write(path, lambda p: p.write_text(text))
