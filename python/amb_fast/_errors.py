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


class IdentificationWarning(UserWarning):
    """An identification (:func:`amb_fast.identify`, :func:`amb_fast.run_experiment`) whose recording or
    result looks wrong: a kept start transient, implausible magnitudes (a unit mistake), a force that is
    not periodic with the given period, most lines weak. A ``UserWarning``; turn it into an error with
    ``warnings.simplefilter("error", amb_fast.IdentificationWarning)``."""


class NonPeriodicExcitationWarning(IdentificationWarning):
    """The recorded force does not repeat with the period ``fs/f0`` samples: a large share of its power
    changes from period to period or falls between the excited lines. The usual cause is a wrong ``fs``
    or ``f0``; the estimate is then at the wrong frequencies and biased by leakage.

    Attributes
    ----------
    fraction : float
        The share of the force power (0-1) that does not repeat at the excited lines.
    """

    def __init__(self, message: str, fraction: float) -> None:
        super().__init__(message)
        self.fraction = fraction


class WeakLinesWarning(IdentificationWarning):
    """Most excited lines are weak: their force or displacement is under 10x the noise level, so the
    estimate there is mostly noise (``Estimate.weak`` flags each line).

    Attributes
    ----------
    weak, lines : int
        How many lines are weak, of how many.
    """

    def __init__(self, message: str, weak: int, lines: int) -> None:
        super().__init__(message)
        self.weak = weak
        self.lines = lines


class ShortPeriodWarning(IdentificationWarning):
    """Every harmonic the force excites is a multiple of some g >= 2: the force repeats every ``fs/f0/g``
    samples, a g-th of the period given. Either ``f0`` is really g times larger (harmless: the estimate is
    right, with unexcited lines in between) or ``fs`` is g times too large (the estimate's frequencies are
    g times too high). A period that is too long by a whole factor cannot be seen otherwise: the force is
    periodic with it.

    Attributes
    ----------
    factor : int
        g.
    """

    def __init__(self, message: str, factor: int) -> None:
        super().__init__(message)
        self.factor = factor
