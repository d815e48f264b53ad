"""Exceptions of amb_fast beyond the built-in ones."""

from __future__ import annotations


class TouchdownError(RuntimeError):
    """The platform reached its mechanical clearance (``Rig.clearance``, by default the air gap of the
    non-linear force law): the run stops there.

    Attributes
    ----------
    time : float
        When, s from the start of the run.
    position : float
        The platform displacement y there, m.
    """

    def __init__(self, message: str, time: float, position: float) -> None:
        super().__init__(message)
        self.time = time
        self.position = position


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


class NoExcitationError(ValueError):
    """The force has no excitation at the chosen lines: zero, constant, or not clearly above the noise
    floor measured at the unexcited lines. An estimate from it would be ``k = m w^2`` or noise."""
