"""Exceptions of amb_fast beyond the built-in ones."""

from __future__ import annotations


class UnstableLoopError(ValueError):
    """The linearised closed loop has a pole on or outside the unit circle.

    Attributes
    ----------
    poles : ndarray
        The offending z-plane poles (|z| >= 1).
    """

    def __init__(self, message: str, poles) -> None:  # noqa: ANN001
        super().__init__(message)
        self.poles = poles
