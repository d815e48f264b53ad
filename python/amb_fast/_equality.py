"""Equality of the frozen records that hold numpy arrays (estimates, traces, sweep results, excitations).

A dataclass's own ``==`` compares its fields as a tuple, which raises for array fields ("the truth value
of an array ... is ambiguous"). Records that mix in :class:`ArrayRecord` (and pass ``eq=False`` to
``@dataclass``) compare field by field instead (the fields a dataclass would compare: not those declared
``field(compare=False)``): arrays by shape and value, NaN equal to NaN (a sweep's unstable rows, an
unexcited line), dicts and sequences entry by entry. They hold arrays, so they are not hashable.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import numpy as np


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


class ArrayRecord:
    """``==`` field by field for a dataclass with array fields (declare it with ``eq=False``)."""

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(equal_values(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)  # type: ignore[arg-type]  # fmt: skip

    __hash__ = None  # type: ignore[assignment]  # arrays are not hashable
