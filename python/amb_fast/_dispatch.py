"""One API for any number of axes: a function given a rig of N axes runs that rig's implementation.

The one-axis functions are decorated here; each structure's package registers its rig type and the
namespace that holds its N-axis functions under the same names (:func:`register`), so
``af.predict(rig, ...)`` works whatever the rig, and this lower layer never imports a higher one: a rig
of a registered type exists only once its package has been imported.
"""

from __future__ import annotations

import functools
import textwrap
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

from ._validate import require

F = TypeVar("F", bound=Callable[..., Any])

_SYSTEMS: dict[type, Any] = {}
_RECORDINGS: dict[int, Any] = {}  # namespaces by the number of axes


def register(rig_type: type, namespace: Any, axes: int) -> None:
    """Route the decorated functions given a ``rig_type`` to ``namespace``'s functions of the same names, and
    :func:`identify` given the recordings of ``axes`` experiments, shape (axes, samples, axes), to its ``identify``."""
    _SYSTEMS[rig_type] = namespace
    _RECORDINGS[axes] = namespace


def _note(doc: str | None, sentence: str) -> str | None:
    """The docstring with a sentence saying where more axes go, after the summary paragraph."""
    if not doc:
        return doc
    summary, _, rest = doc.partition("\n\n")
    indent = " " * (len(rest) - len(rest.lstrip(" "))) if rest else "    "
    text = textwrap.fill(sentence, width=100, initial_indent=indent, subsequent_indent=indent)
    return f"{summary}\n\n{text}\n\n{rest}" if rest else f"{summary}\n\n{text}\n"


def axes_aware(function: F) -> F:
    """Decorate a one-axis function whose first argument is the rig."""
    name = function.__name__

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        rig = args[0] if args else kwargs.get("rig")
        namespace = _SYSTEMS.get(type(rig))
        if namespace is not None:
            implementation = getattr(namespace, name, None)
            if implementation is None:
                raise TypeError(f"{name} does not take a {type(rig).__name__} yet")
            return implementation(*args, **kwargs)
        return function(*args, **kwargs)

    wrapper.__doc__ = _note(
        function.__doc__,
        f"A :class:`~amb_fast.TwoAxisRig` or a :class:`~amb_fast.RotorRig` in place of the rig runs its N-axis "
        f"``{name}`` (same arguments; N x N results).",
    )
    return wrapper  # type: ignore[return-value]


def recordings_aware(function: F) -> F:
    """Decorate ``identify``: N experiments' N-channel recordings, shape (N, n, N), go to N axes."""

    @functools.wraps(function)
    def wrapper(force: Any, displacement: Any, *args: Any, **kwargs: Any) -> Any:
        shape = np.shape(force)
        if len(shape) == 3:
            require(shape[0] in _RECORDINGS, "force shape", shape,
                    f"recordings of N experiments, (N, samples, N), for N in {sorted(_RECORDINGS)}")  # fmt: skip
            return _RECORDINGS[shape[0]].identify(force, displacement, *args, **kwargs)
        return function(force, displacement, *args, **kwargs)

    wrapper.__doc__ = _note(
        function.__doc__,
        "Two experiments of a two-axis rig, force and displacement of shape (2, samples, 2) (experiment, "
        "sample, axis), give an :class:`~amb_fast.Estimate2` (:func:`amb_fast.two_axis.identify`).",
    )
    return wrapper  # type: ignore[return-value]
