"""What every reader of a recording shares: a channel by name (exact, then without case, unit or dSPACE path)
or index, its unit (in the name or a units row) scaled to SI or refused, fs from ``fs`` or a time column, and
the choice among a file's recordings."""

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
    "s": ("time", 1.0), "ms": ("time", 1e-3), "us": ("time", 1e-6), "µs": ("time", 1e-6), "μs": ("time", 1e-6),
    "sec": ("time", 1.0), "msec": ("time", 1e-3), "usec": ("time", 1e-6),
}  # fmt: skip
# Units a DAQ writes that amb_fast does not scale: recognised (in a units row, after a slash) so a channel in
# one of them is refused naming its unit.
OTHER_UNITS = frozenset({"v", "mv", "a", "ma", "g", "lbf", "in", "mil", "mils", "hz", "rpm", "pa", "bar", "%", "-",
                         "°c", "degc", "k", "w", "rad", "deg", "m/s", "m/s^2", "m/s2"})  # fmt: skip
UNIT_WORDS = OTHER_UNITS | set(UNITS)
# Unit names LabVIEW, DAQmx and TDMS files write -> the symbols amb_fast scales (or refuses: V, lbf, ...).
UNIT_NAMES = {"newtons": "N", "newton": "N", "kilonewtons": "kN", "meters": "m", "metres": "m", "meter": "m",
              "metre": "m", "millimeters": "mm", "millimetres": "mm", "micrometers": "um", "micrometres": "um",
              "microns": "um", "seconds": "s", "volts": "V", "pounds": "lbf", "inches": "in"}  # fmt: skip


def symbol(unit: str) -> str:
    """``'Newtons'`` -> ``'N'``, ``'Millimeters'`` -> ``'mm'``; a symbol or an unknown name unchanged."""
    return UNIT_NAMES.get(unit.strip().casefold(), unit.strip())


_UNIT_IN_NAME = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<b>[^\]]*)\]|\((?P<p>[^)]*)\))\s*$")
_UNIT_WORD = re.compile(r"^(?P<name>\S.*?)(?:\s+in)?\s+(?P<u>\S+)$", re.IGNORECASE)
_UNIT_SUFFIX = re.compile(r"^(?P<name>.+?)_(?P<u>kN|mN|N|mm|um|µm|μm|nm|m|ms|us|s)$")


def split_unit(name: str) -> tuple[str, str | None]:
    """``'force [kN]'`` -> ``('force', 'kN')``; ``'x_mm'`` -> ``('x', 'mm')``; ``'Displacement/µm'`` ->
    ``('Displacement', 'µm')`` (a known unit after a slash; ``'Platform/Force'`` is a model path, not a unit);
    ``'Weg in mm'``, ``'Gap mm'`` -> ``('Weg', 'mm')``, ``('Gap', 'mm')`` (a unit of force, length or time as
    the last word); ``'force'`` -> ``('force', None)``."""
    name = name.strip().strip('"').strip()
    match = _UNIT_IN_NAME.match(name)
    if match and match.group("name"):
        return match.group("name").strip(), next(u for u in match.group("b", "p") if u is not None).strip()
    for slash in [j for j, c in enumerate(name) if c == "/" and j > 0]:  # the longest unit: 'v/m/s' is 'v' in m/s
        if name[slash + 1 :].strip().casefold() in UNIT_WORDS:
            return name[:slash].strip(), name[slash + 1 :].strip()
    match = _UNIT_WORD.match(name)  # 'Weg in mm', 'Gap mm': a unit amb_fast scales, as the last word
    if match and match.group("u").casefold() in UNITS:
        return match.group("name"), match.group("u")
    match = _UNIT_SUFFIX.match(name)
    if match:
        return match.group("name"), match.group("u")
    return name, None


_QUANTITIES = {"force": ("force", "N, kN, mN, MN"), "displacement": ("length", "m, mm, um, nm"),
               "time": ("time", "s, ms, us")}  # fmt: skip


def _scale(name: str, quantity: str, path: Path) -> float:
    """The factor to SI of a channel's unit (1 without one), compared without case except for mega: ``MN`` is
    a meganewton, not mN, and refused in a name all in capitals (``FORCE [MN]``). Another quantity's unit is
    refused."""
    unit = split_unit(name)[1]
    if not unit:
        return 1.0
    if unit == "MN" and name.upper() == name:
        raise ValueError(f"{path.name}: the channel {name!r} has unit 'MN', written in capitals: meganewton or "
                         "millinewton? Write the unit as 'mN' or 'kN' (or rescale the column to N)")  # fmt: skip
    kind, factor = ("force", 1e6) if unit == "MN" else UNITS.get(symbol(unit).lower(), (None, 1.0))
    if kind != _QUANTITIES[quantity][0]:
        calibration = f"scale={{{quantity!r}: SI per unit}} (a DAQ in volts: N/V, m/V)"
        remedy = "rescale the column" if quantity == "time" else f"the channel's calibration as {calibration}"
        raise ValueError(f"{path.name}: the {quantity} channel {name!r} has unit {unit!r}; amb_fast needs "
                         f"one of {_QUANTITIES[quantity][1]} (scaled to SI), or {remedy}")  # fmt: skip
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


#: Names a time column goes by (compared without case and unit) when ``time`` is left at ``"time"``.
TIME_NAMES = ("time", "t", "zeit", "timestamp", "time stamp", "temps", "tiempo", "x_value", "seconds")


def _find(names: list[str], key: str, role: str, path: Path) -> int:
    """The one column that ``key`` names: exactly; else without case; else without its unit (and case); else
    by the last part of a dSPACE path. A test that several columns pass is ambiguous; the columns are named
    in every error."""
    bare = split_unit(key)[0]
    tests = (
        lambda n: n.strip().strip('"') == key,
        lambda n: n.strip().strip('"').casefold() == key.casefold(),
        lambda n: split_unit(n)[0] == bare,
        lambda n: split_unit(n)[0].casefold() == bare.casefold(),
        lambda n: split_unit(n.replace("\\", "/").split("/")[-1].strip('"'))[0].casefold() == bare.casefold(),
    )
    for test in tests:
        hits = [i for i, n in enumerate(names) if test(n)]
        if len(hits) > 1:
            raise ValueError(f"{path.name}: the {role} channel {key!r} is ambiguous: columns "
                             f"{[f'{i}: {names[i]}' for i in hits]} match; choose one by index")  # fmt: skip
        if hits:
            return hits[0]
    raise ValueError(f"{path.name} has no channel {key!r} for the {role}; its columns are {_listed(names)} "
                     "(choose one by name or 0-based index)")  # fmt: skip


def _time_index(names: list[str], time: str | int | None, path: Path) -> int | None:
    """The time column: ``time`` by name or index; the default ``"time"`` also finds the usual names of a
    time column (``Time [s]``, ``TIME``, ``t [ms]``, ``Zeit``, LabVIEW's ``X_Value``, ...). None if absent."""
    if time is None:
        return None
    try:
        return _index(names, time, "time", path)
    except ValueError:
        if not isinstance(time, str) or time != "time":
            raise
    hits = [i for i, n in enumerate(names) if split_unit(n)[0].strip().casefold() in TIME_NAMES]
    if len(hits) > 1:  # two columns that could be the clock: guessing one could give a wrong fs
        raise ValueError(f"{path.name}: columns {[f'{i}: {names[i]}' for i in hits]} could each be the time "
                         "column: choose one with time=NAME or its 0-based index, or ignore both with time=None "
                         "and pass fs= (Hz; on the command line --fs)")  # fmt: skip
    return hits[0] if hits else None


def _listed(names: list[str]) -> str:
    return ", ".join(f"{i}: {n!r}" for i, n in enumerate(names))


def _agree(
    given: float | None, found: float | None, path: Path, where: str = "time column", names: list[str] | None = None
) -> float:
    if given is None and found is None:
        columns = f" (its columns are {_listed(names)})" if names else ""
        raise ValueError(f"{path.name} has neither 'fs' nor a time column{columns}: pass fs= (Hz; on the command "
                         "line --fs), or name the time column with time=NAME or its 0-based index")  # fmt: skip
    if given is not None and found is not None and abs(given - found) > 1e-3 * found:
        raise ValueError(f"fs must agree with {path.name}'s {where} ({found:.10g} Hz) within 0.1 %, got {given:g}")
    return float(given if given is not None else found)  # type: ignore[arg-type]


BLOCK = 1 << 13  # samples per block of the time column's checks: their temporaries stay small


def _quantum(t: np.ndarray) -> float:
    """The resolution the times were written with (``%.4f``: 1e-4), 0 if they look unrounded.

    Judged on the times from the first one, with the float spacing of the largest time allowed for (absolute
    clocks such as Unix timestamps carry it: 2.4e-7 s at 1.7e9 s)."""
    t0, spacing = float(t[0]), float(np.spacing(max(abs(float(t[0])), abs(float(t[-1])))))
    for digits in range(0, 10):
        tolerance = 1e-6 + 4.0 * spacing * 10.0**digits
        if tolerance > 1e-2:  # digits finer than the floats resolve
            return 0.0
        for a in range(0, t.size, BLOCK):
            x = (t[a : a + BLOCK] - t0) * 10.0**digits
            if float(np.max(np.abs(x))) >= 1e15 or float(np.max(np.abs(x - np.rint(x)))) >= tolerance:
                break
        else:
            return 10.0**-digits
    return 0.0


def fs_from_time(t: np.ndarray, path: Path, name: str, scale: float) -> float:
    """The sampling frequency of a time column (in its unit; ``scale`` to s): the clock fitted over the whole
    column by least squares.

    A clock written rounded (``%.4f`` at 4 kHz: steps of 0.2 and 0.3 ms) is uniform when every sample lies
    within half its last digit (or a quarter of a sample) of the fitted line; its fs is then the round value
    within the fit's uncertainty (4000 Hz, not 4000.00667). A column that breaks that (a gap, a repeat, a
    restart) is refused, naming the data row where it breaks. Computed in blocks (a long recording's column
    is never copied whole)."""
    t = np.asarray(t, dtype=float)
    n = t.size
    require(n >= 2 and bool(np.all(np.isfinite(t))), "time", f"column {name!r} of {path.name}",
            "at least two finite times to give fs")  # fmt: skip
    middle, t0 = (n - 1) / 2.0, float(t[0])
    mean = t0 + sum(float(np.sum(t[a : a + BLOCK] - t0)) for a in range(0, n, BLOCK)) / n

    def k(a: int) -> np.ndarray:
        return np.arange(a, min(a + BLOCK, n)) - middle

    # Least squares over k = 0..n-1 centred: step = sum k t / sum k^2 (sum k = 0), on t - t[0]: an absolute
    # clock's offset (Unix time, 1.7e9 s) would otherwise swamp the sum (fs 3999.998 Hz for 4000).
    step = sum(float(k(a) @ (t[a : a + BLOCK] - t0)) for a in range(0, n, BLOCK)) / (n * (n * n - 1.0) / 12.0)
    require(step > 0, "time", f"column {name!r} of {path.name}", "increasing to give fs")
    quantum = _quantum(t)
    row = -1
    for a in range(0, n - 1, BLOCK):  # the first step off the clock by more than its rounding allows
        d = np.diff(t[a : a + BLOCK + 1])
        bad = np.flatnonzero(np.abs(d - step) > max(quantum * (1 + 1e-6), 0.25 * step))
        if bad.size:
            row = a + int(bad[0]) + 1
            break
    if row < 0:  # steps within their rounding, but a drift: any time off the fitted clock
        worst = [float(np.max(np.abs(t[a : a + BLOCK] - mean - step * k(a)))) for a in range(0, n, BLOCK)]
        if max(worst) > max(0.5 * quantum * (1 + 1e-6), 0.25 * step):
            a = BLOCK * int(np.argmax(worst))
            row = max(1, a + int(np.argmax(np.abs(t[a : a + BLOCK] - mean - step * k(a)))))
    if row > 0:
        at = _worst_step(t, step)
        also = f"; the worst step, at data row {at}, is {t[at] - t[at - 1]:.6g}" if at != row else ""
        raise ValueError(f"{path.name}: the time column {name!r} is not a uniform clock: at data row {row} "
                         f"(t = {t[row]:.10g}) the step is {t[row] - t[row - 1]:.6g} against {step:.6g} fitted over "
                         f"all {n} rows (a gap, a repeat or a restart){also}; cut the record before that row, or "
                         "ignore the column with time=None and pass fs= (Hz; on the command line --fs)")  # fmt: skip
    fs = 1.0 / (step * scale)
    # The fit's uncertainty with the times rounded to `quantum` (uniform errors): about q / n^1.5 in the step.
    spacing = float(np.spacing(max(abs(float(t[0])), abs(float(t[-1])))))
    spread = 3.0 * max(quantum, 4.0 * spacing) / n**1.5 / step * fs
    for decimals in range(-int(np.floor(np.log10(fs))), 12):
        candidate = round(fs, decimals)
        if abs(candidate - fs) <= spread:
            return float(candidate)
    return fs


def _worst_step(t: np.ndarray, step: float) -> int:
    """The data row whose step from the one before is farthest from ``step`` (in blocks)."""
    worst, row = -1.0, 1
    for a in range(0, t.size - 1, BLOCK):
        off = np.abs(np.diff(t[a : a + BLOCK + 1]) - step)
        if off.size and float(off.max()) > worst:
            worst, row = float(off.max()), a + int(np.argmax(off)) + 1
    return row


def _file_fs(
    channels: dict[str, np.ndarray], time: str | int | None, path: Path, chosen: tuple[str, ...] = ()
) -> tuple[float | None, str]:
    """fs (Hz) from a file's ``fs`` variable or its time column, and where it came from. A TDMS group whose
    channels have different rates has one per channel (NaN without one) in ``fs``: the ``chosen`` channels'
    must agree."""
    names = list(channels)
    if "fs" in channels:
        where = "channels' wf_increment" if path.suffix.lower() == ".tdms" else "'fs' variable"  # TDMS: the waveform's
        value = np.ravel(channels["fs"])
        if where != "'fs' variable" and value.size == len(names) - 1 and value.size > 1:  # TDMS: a rate per channel
            rates = {name: value[names.index(name)] for name in chosen}
            if len({float(r) for r in rates.values() if np.isfinite(r)}) > 1:
                listed = ", ".join(f"{name!r} {rate:.10g} Hz" for name, rate in rates.items())
                raise ValueError(f"{path.name}: the channels {listed} have different rates (their wf_increment): "
                                 "force and displacement must be sampled together")  # fmt: skip
            value = np.array([r for r in rates.values() if np.isfinite(r)][:1])
            if value.size == 0:
                return _file_fs({n: v for n, v in channels.items() if n != "fs"}, time, path)
        if value.size != 1 or not value[0] > 0 or not np.isfinite(value[0]):  # never a guess among several
            raise ValueError(f"{path.name}: its {where} must be one finite number > 0 (Hz), got {value.tolist()}")
        return float(value[0]), where
    index = _time_index(names, time, path)
    if index is None:
        return None, ""
    values = np.ravel(channels[names[index]]).astype(float)
    if values.size < 2:
        return None, ""
    return fs_from_time(values, path, names[index], _scale(names[index], "time", path)), f"time column {names[index]!r}"


def _choose_recording(
    groups: dict[str, dict[str, np.ndarray]], path: Path, recording: str | None, keys: tuple[str | int, str | int]
) -> tuple[str, dict[str, np.ndarray]]:
    groups = {name: channels for name, channels in groups.items() if channels}
    if not groups:
        raise ValueError(f"{path.name} holds no channels: the file is empty or damaged (cut short before its first "
                         "channel was written)")  # fmt: skip
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
