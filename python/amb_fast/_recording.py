"""Recordings of a rig: CSV with named columns, MATLAB .mat with named variables (or a dSPACE export)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ._validate import real, require, series


@dataclass(frozen=True)
class Recording:
    """Force (N) and displacement (m) sampled at ``fs`` (Hz)."""

    force: np.ndarray
    displacement: np.ndarray
    fs: float


def save_recording(path: str | Path, *, force: ArrayLike, displacement: ArrayLike, fs: float) -> None:
    """Write a recording: ``.csv`` (columns time, force, displacement; full precision) or ``.mat``."""
    path = Path(path)
    force, displacement = series("force", force), series("displacement", displacement)
    fs = real("fs", fs, "Hz", positive=True)
    if path.suffix.lower() == ".csv":
        table = np.column_stack([np.arange(force.size) / fs, force, displacement])
        np.savetxt(path, table, delimiter=",", header="time,force,displacement", comments="", fmt="%.17g")
    elif path.suffix.lower() == ".mat":
        from scipy.io import savemat

        savemat(path, {"force": force, "displacement": displacement, "fs": fs})
    else:
        raise ValueError(f"path must end in .csv or .mat, got {str(path)!r}")


def load_recording(
    path: str | Path, *, force: str = "force", displacement: str = "displacement", fs: float | None = None
) -> Recording:
    """Read force and displacement channels by name from a CSV or MATLAB ``.mat`` file.

    CSV: a header row names the columns. ``.mat``: top-level variables, or a dSPACE ControlDesk export
    (a struct with ``X.Data`` for time and ``Y(k).Name`` / ``Y(k).Data`` per channel), where a
    channel matches by its full name or the last part of its path. The sampling frequency is ``fs``
    if given, else a variable or column ``fs``, else the spacing of a ``time`` column, which must be
    uniform.
    """
    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        channels = _read_csv(path)
    elif suffix == ".mat":
        channels = _read_mat(path)
    else:
        raise ValueError(f"path must end in .csv or .mat, got {str(path)!r}")
    for name in (force, displacement):
        if name not in channels:
            raise ValueError(f"{path.name} has no channel {name!r}; it has {sorted(channels)}")
    if fs is None:
        fs = _sampling_frequency(channels, path)
    return Recording(series(force, channels[force]), series(displacement, channels[displacement]),
                     real("fs", fs, "Hz", positive=True))  # fmt: skip


def _sampling_frequency(channels: dict[str, np.ndarray], path: Path) -> float:
    if "fs" in channels:
        return float(np.ravel(channels["fs"])[0])
    if "time" in channels:
        steps = np.diff(np.ravel(channels["time"]))
        require(steps.size > 0 and np.ptp(steps) <= 1e-6 * abs(steps.mean()), "time", f"column of {path.name}",
                "uniformly spaced to give fs")  # fmt: skip
        return 1.0 / float(steps.mean())
    raise ValueError(f"{path.name} has neither 'fs' nor 'time': pass fs= (Hz)")


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    with path.open() as handle:
        names = [name.strip() for name in handle.readline().strip().split(",")]
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    require(data.shape[1] == len(names), "columns", data.shape[1], f"{len(names)} as named in the header")
    return {name: data[:, j] for j, name in enumerate(names)}


def _read_mat(path: Path) -> dict[str, np.ndarray]:
    from scipy.io import loadmat

    content = {
        k: v for k, v in loadmat(path, squeeze_me=True, struct_as_record=False).items() if not k.startswith("__")
    }
    channels: dict[str, np.ndarray] = {}
    for key, value in content.items():
        if hasattr(value, "Y") and hasattr(value, "X"):  # dSPACE export
            channels["time"] = np.ravel(value.X.Data)
            for channel in np.atleast_1d(value.Y):
                name = str(channel.Name)
                channels[name] = np.ravel(channel.Data)
                channels.setdefault(name.replace("\\", "/").split("/")[-1].strip('"'), channels[name])
        else:
            channels[key] = np.asarray(value, dtype=float)
    return channels
