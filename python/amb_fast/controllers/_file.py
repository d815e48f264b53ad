"""Controller files (TOML or JSON): a list of blocks in series.

The format (``docs/controllers.md`` has the examples)::

    fs = 4000.0          # sampling frequency, Hz (default 4000.0)
    delay = 0            # whole-sample computation delay of the whole controller (default 0)

    [[block]]            # blocks in series, in order
    type = "pid"         # kp (A/m), ki (A/(m s)), kd (A s/m), derivative_cutoff (Hz, optional)
    kp = 2400.0
    ki = 20000.0
    kd = 3.0
    derivative_cutoff = 1000.0

    [[block]]
    type = "notch"       # freq, width, depth as amb_fast.notch
    freq = 700.0

Block types and their keys (optional ones take the function's defaults):

- ``pid``: ``kp``, ``ki``, ``kd``, ``derivative_cutoff`` (optional);
- ``notch``: ``freq``, ``width``, ``depth``; ``low_pass``: ``freq``, ``order``, ``damping``;
  ``lead_lag``: ``gain``, ``zero``, ``pole``; ``second_order``: ``num_freq``, ``den_freq``,
  ``num_damping``, ``den_damping``, ``gain``; ``gain``: ``value``;
- ``tf``: ``num``, ``den`` (z, highest power first); ``sos``: ``sos`` (rows of 6);
  ``continuous``: ``num``, ``den`` (s), ``method`` ("tustin", "zoh", "matched"), ``prewarp`` (Hz).

JSON has the same keys: ``{"fs": 4000.0, "delay": 0, "block": [{"type": "pid", ...}, ...]}``.
Errors name the file, the block (counted from 1) and the key.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .._validate import integer, real
from ._blocks import lead_lag, low_pass, notch, pid_controller, second_order
from ._controller import Controller, gain, pure_delay, series


def _pid(fs: float, **keys: Any) -> Controller:
    from .._params import PID

    return pid_controller(PID(**keys, fs=fs, delay=0))


# type -> (builder(fs, **keys), required keys, optional keys)
_TYPES: dict[str, tuple[Callable[..., Controller], tuple[str, ...], tuple[str, ...]]] = {
    "pid": (_pid, ("kp", "ki", "kd"), ("derivative_cutoff",)),
    "notch": (lambda fs, **k: notch(fs=fs, **k), ("freq",), ("width", "depth")),
    "low_pass": (lambda fs, **k: low_pass(fs=fs, **k), ("freq",), ("order", "damping")),
    "lead_lag": (lambda fs, **k: lead_lag(fs=fs, **k), (), ("gain", "zero", "pole")),
    "second_order": (
        lambda fs, **k: second_order(fs=fs, **k),
        ("num_freq", "den_freq"),
        ("num_damping", "den_damping", "gain"),
    ),
    "gain": (lambda fs, **k: gain(fs=fs, **k), ("value",), ()),
    "tf": (lambda fs, **k: Controller.from_tf(fs=fs, **k), ("num", "den"), ()),
    "sos": (lambda fs, **k: Controller.from_sos(fs=fs, **k), ("sos",), ()),
    "continuous": (lambda fs, **k: Controller.from_continuous(fs=fs, **k), ("num", "den"), ("method", "prewarp")),
}


def _read(path: Path) -> dict[str, Any]:
    suffix = path.suffix.lower()
    if suffix == ".json":
        with open(path, encoding="utf-8") as file:
            data = json.load(file)
    elif suffix == ".toml":
        try:
            import tomllib  # type: ignore[import-not-found,unused-ignore]
        except ImportError:  # pragma: no cover - Python < 3.11
            try:
                import tomli as tomllib  # type: ignore[no-redef,import-not-found,unused-ignore]
            except ImportError:
                raise ImportError(
                    f"reading the TOML controller file {path} needs Python >= 3.11 or the tomli package "
                    "(pip install tomli); or write it as JSON"
                ) from None
        with open(path, "rb") as file:
            data = tomllib.load(file)
    else:
        raise ValueError(f"path must end in .toml or .json (a controller file), got {str(path)!r}")
    if not isinstance(data, dict):
        raise ValueError(f"controller file {path}: the top level must be a table/object, got {type(data).__name__}")
    return data


def load_controller(path: str | os.PathLike[str]) -> Controller:
    """Read a controller file (TOML or JSON, by its suffix): blocks in series at one ``fs``.

    See the module docstring (``amb_fast.controllers._file``) or ``docs/controllers.md`` for the
    format. Raises ValueError naming the file, the block (counted from 1) and the key.
    """
    file = Path(path)
    data = _read(file)
    where = f"controller file {file}"
    unknown = sorted(set(data) - {"fs", "delay", "block"})
    if unknown:
        raise ValueError(f"{where}: unknown top-level key(s) {', '.join(unknown)}; known: fs, delay, block")
    try:
        fs = real("fs", data.get("fs", 4000.0), "Hz", positive=True)
        delay = integer("delay", data.get("delay", 0), 0)
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None
    blocks = data.get("block")
    if not isinstance(blocks, list) or not blocks or not all(isinstance(b, dict) for b in blocks):
        raise ValueError(f"{where}: block must be a non-empty list of tables ([[block]] in TOML), got {blocks!r}")
    built = []
    for index, block in enumerate(blocks, start=1):
        kind = block.get("type")
        here = f"{where}, block {index}"
        if kind not in _TYPES:
            raise ValueError(f"{here}: key 'type' must be one of {', '.join(_TYPES)}, got {kind!r}")
        builder, required, optional = _TYPES[kind]
        here += f" (type {kind!r})"
        keys = {k: v for k, v in block.items() if k != "type"}
        extra = sorted(set(keys) - set(required) - set(optional))
        if extra:
            raise ValueError(f"{here}: unknown key(s) {', '.join(extra)}; known: {', '.join(required + optional)}")
        missing = [k for k in required if k not in keys]
        if missing:
            raise ValueError(f"{here}: missing key(s) {', '.join(missing)}")
        try:
            built.append(builder(fs, **keys))
        except (ValueError, TypeError) as error:
            raise ValueError(f"{here}: {_key_of(error, keys)}{error}") from None
    if delay:
        built.append(pure_delay(delay, fs))
    return series(*built)


def _key_of(error: Exception, keys: dict[str, Any]) -> str:
    """``"key 'freq': "`` for the key an error is about (validators start with the parameter's name)."""
    text = str(error)
    for key in sorted(keys, key=len, reverse=True):
        if text.startswith(key + " "):
            return f"key {key!r}: "
    return ""
