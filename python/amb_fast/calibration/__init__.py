"""Calibration and design on a calibrated virtual rig.

:func:`fit_rig` fits the exact sampled-data model (:func:`amb_fast.predict`) to measured estimates and
returns a :class:`RigFit`: the fitted :class:`~amb_fast.Rig`, its parameters' covariance, a goodness of
fit that accounts for standard errors estimated from few periods, and predictions with error bars for
controllers never tried on the rig. :func:`design_controller` chooses controller parameters so that the
*actual* stiffness and damping (lags included) meet targets, with a stability and sensitivity limit.
``docs/calibration.md`` is the user's guide.

Modules: ``_fit`` (:func:`fit_rig`: the least squares, covariance and goodness of fit), ``_problem`` (what
is fitted: the fittable rig fields and their scales, start values and bounds, the estimates as weighted
data, the loop model evaluated for a rig), ``_result`` (:class:`RigFit`: propagated predictions and the
report), ``_design`` (:func:`design_controller` and :class:`Design`), ``_estimates`` (estimate files as
``amb-fast fit`` reads them; the ``fit`` and ``design`` commands live in :mod:`amb_fast.cli`).
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ._design import Design, design_controller
    from ._estimates import PLAIN_PERIODS as PLAIN_PERIODS
    from ._estimates import read_estimate as read_estimate
    from ._estimates import records as records
    from ._fit import RigFit, fit_rig
    from ._problem import FITTABLE as FITTABLE
    from ._problem import same_controller as same_controller

__all__ = ["Design", "RigFit", "design_controller", "fit_rig"]
# Also read by the command line (`amb-fast fit`, `design`), not part of the Python API.
_FOR_THE_CLI = {"FITTABLE": "_problem", "same_controller": "_problem", "PLAIN_PERIODS": "_estimates",
                "read_estimate": "_estimates", "records": "_estimates"}  # fmt: skip


def __getattr__(name: str):  # noqa: ANN202 - scipy.optimize and scipy.stats load on first use (half a second)
    module = {"Design": "_design", "design_controller": "_design", "RigFit": "_fit", "fit_rig": "_fit",
              **_FOR_THE_CLI}.get(name)  # fmt: skip
    if module is not None:
        return getattr(import_module(f".{module}", __name__), name)
    raise AttributeError(f"module 'amb_fast.calibration' has no attribute {name!r}")
