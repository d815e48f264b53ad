"""One API for one and two axes: a function given a ``TwoAxisRig`` runs its two-axis version.

The two-axis model lives in :mod:`amb_fast.two_axis` under the same names and signatures; the one-axis
functions hand a :class:`~amb_fast.TwoAxisRig` over to it, so users call ``af.predict(rig, ...)``
whatever the rig. ``two_axis`` is imported only when a two-axis rig is met (it imports the one-axis
modules itself).
"""

from __future__ import annotations

import functools
import textwrap
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

F = TypeVar("F", bound=Callable[..., Any])


def _is_two_axis(value: Any) -> bool:
    return type(value).__name__ == "TwoAxisRig" and type(value).__module__.startswith("amb_fast.two_axis")


def _note(doc: str | None, sentence: str) -> str | None:
    """The docstring with a sentence saying where two axes go, after the summary paragraph."""
    if not doc:
        return doc
    summary, _, rest = doc.partition("\n\n")
    indent = " " * (len(rest) - len(rest.lstrip(" "))) if rest else "    "
    text = textwrap.fill(sentence, width=100, initial_indent=indent, subsequent_indent=indent)
    return f"{summary}\n\n{text}\n\n{rest}" if rest else f"{summary}\n\n{text}\n"


def two_axis_aware(function: F) -> F:
    """Decorate a one-axis function whose first argument is the rig."""
    name = function.__name__

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        rig = args[0] if args else kwargs.get("rig")
        if _is_two_axis(rig):
            from . import two_axis

            return getattr(two_axis, name)(*args, **kwargs)
        return function(*args, **kwargs)

    wrapper.__doc__ = _note(
        function.__doc__,
        f"A :class:`~amb_fast.TwoAxisRig` in place of the rig runs :func:`amb_fast.two_axis.{name}` (same "
        "arguments; 2x2 results).",
    )
    return wrapper  # type: ignore[return-value]


def two_recordings_aware(function: F) -> F:
    """Decorate ``identify``: two experiments' two-channel recordings, shape (2, n, 2), go to two axes."""

    @functools.wraps(function)
    def wrapper(force: Any, displacement: Any, *args: Any, **kwargs: Any) -> Any:
        if np.ndim(force) == 3:
            from . import two_axis

            return two_axis.identify(force, displacement, *args, **kwargs)
        return function(force, displacement, *args, **kwargs)

    wrapper.__doc__ = _note(
        function.__doc__,
        "Two experiments of a two-axis rig, force and displacement of shape (2, samples, 2) (experiment, "
        "sample, axis), give an :class:`~amb_fast.Estimate2` (:func:`amb_fast.two_axis.identify`).",
    )
    return wrapper  # type: ignore[return-value]
