"""What every reader of a recording shares: channel names and their units, a channel by name or index,
the sampling frequency from ``fs`` or a time column, and the choice among a file's recordings.

A channel is found by name (exact, then without its unit, then the last part of a dSPACE path) or by
index; a unit in the name (``force [kN]``, ``x (mm)``, ``disp_um``) or in a units row is scaled to SI,
and a unit that is not a force (for the force) or a length (for the displacement) is refused.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._validate import require

# Unit -> (quantity, factor to SI).
UNITS = {
    "n": ("force", 1.0), "kn": ("force", 1e3), "mn": ("force", 1e-3),
    "m": ("length", 1.0), "mm": ("length", 1e-3), "um": ("length", 1e-6), "µm": ("length", 1e-6),
    "μm": ("length", 1e-6), "micron": ("length", 1e-6), "nm": ("length", 1e-9),
    "s": ("time", 1.0), "ms": ("time", 1e-3), "us": ("time", 1e-6),
}  # fmt: skip
_UNIT_IN_NAME = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<b>[^\]]*)\]|\((?P<p>[^)]*)\))\s*$")
_UNIT_SUFFIX = re.compile(r"^(?P<name>.+?)_(?P<u>kN|mN|N|mm|um|µm|μm|nm|m|ms|us|s)$")


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
