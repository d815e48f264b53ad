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

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._toml import read_table, to_toml, write_text
from .._validate import integer, real
from ._blocks import lead_lag, low_pass, notch, pid_controller, second_order
from ._controller import Controller, as_controller, gain, pure_delay, series


def _pid(fs: float, **keys: Any) -> Controller:
    from .._params import PID

    return pid_controller(PID(**keys, fs=fs, delay=0))


# type -> (builder(fs=, **keys), required keys, optional keys)
_TYPES: dict[str, tuple[Callable[..., Controller], tuple[str, ...], tuple[str, ...]]] = {
    "pid": (_pid, ("kp", "ki", "kd"), ("derivative_cutoff",)),
    "notch": (notch, ("freq",), ("width", "depth")),
    "low_pass": (low_pass, ("freq",), ("order", "damping")),
    "lead_lag": (lead_lag, (), ("gain", "zero", "pole")),
    "second_order": (second_order, ("num_freq", "den_freq"), ("num_damping", "den_damping", "gain")),
    "gain": (gain, ("value",), ()),
    "tf": (Controller.from_tf, ("num", "den"), ()),
    "sos": (Controller.from_sos, ("sos",), ()),
    "continuous": (Controller.from_continuous, ("num", "den"), ("method", "prewarp")),
}


def load_controller(path: str | os.PathLike[str]) -> Controller:
    """Read a controller file (TOML or JSON, by its suffix): blocks in series at one ``fs``.

    See the module docstring (``amb_fast.controllers._file``) or ``docs/controllers.md`` for the
    format. Raises ValueError naming the file, the block (counted from 1) and the key.
    """
    file = Path(path)
    data = read_table(file, "controller file")
    where = f"controller file {str(file)!r}"
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
            built.append(builder(fs=fs, **keys))
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


# ------------------------------------------------------------------------------------------------- writing
def _block_table(leaf: Controller) -> dict[str, Any] | None:
    """The file block of one leaf (its parameters under their own names; a gain's is ``value``), or None for
    a leaf the format has no named block for (a raw representation, a delay)."""
    if leaf._kind not in ("pid", "notch", "low_pass", "lead_lag", "second_order", "gain"):
        return None
    table: dict[str, Any] = {"type": leaf._kind}
    for name, value in leaf._local:
        if name == "derivative_cutoff" and value == float("inf"):
            continue  # no derivative filter: the key left out
        table["value" if leaf._kind == "gain" else name] = value
    if leaf._kind == "low_pass":
        table["order"] = int(leaf._fixed[0])
    return table


def controller_table(controller: Any) -> dict[str, Any]:
    """The controller file's table of a PID or :class:`Controller` (what :func:`save_controller` writes).

    A series of the named blocks (pid, notch, low_pass, lead_lag, second_order, gain) is written block by
    block with their parameters; anything else (a parallel connection, a raw representation) as one
    ``tf`` block of its transfer function. The delays of the blocks are summed into the file's ``delay``.
    """
    c = as_controller(controller, "controller")
    leaves = list(c._parts) if c._kind == "series" else [c]
    blocks = [_block_table(leaf) for leaf in leaves]
    if any(b is None for b in blocks):
        num, den = Controller.from_ss(*c.to_ss(), fs=c.fs).to_tf()
        blocks = [{"type": "tf", "num": [float(v) for v in num], "den": [float(v) for v in den]}]
    return {"fs": c.fs, "delay": c.delay, "block": blocks}


def save_controller(controller: Any, path: str | os.PathLike[str]) -> Path:
    """Write a PID or :class:`Controller` to a TOML controller file that :func:`load_controller` reads
    back to the same response (the named blocks with their parameters; see :func:`controller_table`)."""
    file = Path(path)
    if file.suffix.lower() != ".toml":
        raise ValueError(f"path must end in .toml (a controller file), got {str(file)!r}")
    header = "# amb_fast controller file (docs/controllers.md); load with amb_fast.load_controller\n"
    return write_text(file, header + to_toml(controller_table(controller), {"fs": "Hz", "delay": "whole samples"}))


def recorded_controller(record: Any) -> Any:
    """The controller a saved estimate's metadata describes (``meta["controller"]``): a PID or Controller
    object as it is; a PID's fields (``{"class": "PID", ...}``) as that PID; a Controller's description as
    a Controller of the same state space, fs and delay (the same response; block names are not kept).
    None for a record that describes no controller."""
    if record is None:
        return None
    if isinstance(record, Controller) or callable(getattr(record, "to_controller", None)):
        return record
    if not isinstance(record, dict):
        return None
    kind = record.get("class")
    if kind == "PID":
        from .._params import PID

        return PID(**{k: v for k, v in record.items() if k != "class"})
    if kind == "Controller":
        n = len(record["_b"])  # the flat tuples of a Controller's fields; B and C 1-D
        A = np.reshape(np.asarray(record["_a"], dtype=float), (n, n))
        return Controller.from_ss(
            A, record["_b"], record["_c"], float(record["_d"]), fs=record["fs"], delay=record["delay"]
        )
    return None
