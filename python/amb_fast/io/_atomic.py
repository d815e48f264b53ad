"""The atomic writes (:func:`atomic_path`, :func:`atomic_write`, :func:`atomic_text`), kept at this import path:
they live in :mod:`amb_fast._toml`, below ``io``, as rig and controller files are written with them too."""

from __future__ import annotations

from .._toml import atomic_path, atomic_text, atomic_write

__all__ = ["atomic_path", "atomic_text", "atomic_write"]
