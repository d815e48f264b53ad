"""Equality of the frozen records that hold numpy arrays (estimates, traces, sweep results, excitations).

A dataclass's own ``==`` compares its fields as a tuple, which raises for array fields ("the truth value
of an array ... is ambiguous"). Records that mix in :class:`ArrayRecord` (and pass ``eq=False`` to
``@dataclass``) compare field by field instead (the fields a dataclass would compare: not those declared
``field(compare=False)``): arrays by shape and value, NaN equal to NaN (a sweep's unstable rows, an
unexcited line), dicts and sequences entry by entry. They hold arrays, so they are not hashable.

Their ``repr`` is a summary, not the arrays (a dataclass's own repr printed every number: 90,000 characters
for a 3-point sweep): a head (lines and band for a record with ``freq``; a record adds its own with
``_repr_head``), then every field: arrays as shape, dtype and unit, dicts as their keys, nested records as
their own summary, other values shortened.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any, ClassVar

import numpy as np

# Units of the field names the records share (a record adds or overrides its own in ``_units``).
UNITS = {"freq": "Hz", "fs": "Hz", "f0": "Hz", "H": "N/m", "receptance": "m/N", "force": "N", "displacement": "m",
         "current": "A", "mass": "kg"} | {
    f"{name}{tail}": unit for name, unit in (("k", "N/m"), ("c", "N s/m"))
    for tail in ("", "_smooth", "_std", "_effective", "_eff", "_target", "_miss")
}  # fmt: skip
REPR_WIDTH = 60  # characters of a value's repr shown before "..."
REPR_KEYS = 6  # keys of a dict shown before "..."


def equal_values(a: Any, b: Any) -> bool:
    """Whether two field values are equal: arrays exactly (NaN equal to NaN), containers entry by entry."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape:
            return False
        nan_aware = a.dtype.kind in "fc" and b.dtype.kind in "fc"
        return bool(np.array_equal(a, b, equal_nan=nan_aware))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(equal_values(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(equal_values(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a is b or a == b)


def _short(text: str) -> str:
    return text if len(text) <= REPR_WIDTH else text[: REPR_WIDTH - 3] + "..."


def summary(value: Any, unit: str = "") -> str:
    """A field value in a few characters: an array's shape, dtype and unit, a dict's keys, a record's summary."""
    if isinstance(value, np.ndarray):
        if value.size <= 3 and value.ndim <= 1 and value.dtype.kind in "biufc":
            text = np.array2string(value, precision=4, separator=", ")
        else:
            text = str(value.shape) if value.dtype == np.float64 else f"{value.shape} {value.dtype}"
        return f"{text} {unit}" if unit else text
    if isinstance(value, ArrayRecord):
        return repr(value)
    if isinstance(value, dict) and all(isinstance(v, (int, float)) for v in value.values()):
        pairs = [f"{k}: {summary(v)}" for k, v in value.items()]  # a few numbers (Design.params): values
        return "{" + ", ".join(pairs[:REPR_KEYS]) + (", ..." if len(pairs) > REPR_KEYS else "") + "}"
    if isinstance(value, dict):
        keys = [str(k) for k in value]
        return "{" + ", ".join(keys[:REPR_KEYS]) + (", ..." if len(keys) > REPR_KEYS else "") + "}"
    if isinstance(value, (list, tuple)) and any(isinstance(v, (np.ndarray, ArrayRecord)) for v in value):
        return f"[{len(value)} items]"
    if isinstance(value, float):
        return f"{value:.6g}" + (f" {unit}" if unit else "")
    return _short(repr(value))


class ArrayRecord:
    """``==`` field by field for a dataclass with array fields (declare it with ``eq=False``), and a short
    ``repr`` (see the module docstring)."""

    _units: ClassVar[dict[str, str]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        # @dataclass (applied after this) writes its own __repr__ only where the class has none
        if "__repr__" not in cls.__dict__:
            cls.__repr__ = ArrayRecord.__repr__  # type: ignore[method-assign]

    def _repr_head(self) -> list[str]:
        """The summary's first items: the number of lines and the band of a record with a ``freq`` array."""
        freq = getattr(self, "freq", None)
        if isinstance(freq, np.ndarray) and freq.ndim == 1 and freq.size:
            return [f"lines={freq.size}", f"{freq.min():.6g}-{freq.max():.6g} Hz"]
        return []

    def __repr__(self) -> str:
        units = {**UNITS, **self._units}
        units |= {f.name: "Hz" for f in fields(self) if f.name.endswith("_freq") and f.name not in units}  # type: ignore[arg-type]
        items = self._repr_head()
        for f in fields(self):  # type: ignore[arg-type]
            if not f.repr:
                continue
            value = getattr(self, f.name)
            if isinstance(value, (np.ndarray, dict, ArrayRecord)) or (isinstance(value, (list, tuple)) and value):
                items.append(f"{f.name}: {summary(value, units.get(f.name, ''))}")
            else:
                items.append(f"{f.name}={summary(value, units.get(f.name, ''))}")
        return f"{type(self).__name__}({', '.join(items)})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(equal_values(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)  # type: ignore[arg-type]  # fmt: skip

    __hash__ = None  # type: ignore[assignment]  # arrays are not hashable
