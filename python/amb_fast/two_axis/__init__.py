"""Two axes of a radial magnetic bearing: 2x2 stiffness and damping matrices, identified, exported to ROSS.

Here lives :class:`TwoAxisRig` (two one-axis rigs on one rotor, a cross-coupling process, rotated probes),
a structure of the N-axis model (:mod:`amb_fast.system`), with that model's functions under the names
and signatures of the one-axis API, taking a :class:`TwoAxisRig` in place of a :class:`~amb_fast.Rig`:
the loop in closed form (:func:`predict`, :func:`closed_loop_poles`, :func:`stability_margin`,
:func:`effective_coefficients`), its simulation (:func:`simulate`), the two-experiment identification
(:func:`run_experiment`, :func:`identify` giving an :class:`Estimate2`, the N-axis
:class:`~amb_fast.system.EstimateN` of two axes), sweeps and the export to ``ross.BearingElement``
(:func:`to_ross`).
"""

from __future__ import annotations

import sys

from .._dispatch import register
from .._ross import coefficient_arrays, to_ross
from ..plots import plot_coefficients2
from ..system import ControllerMatrix
from ._command import add_two_axis_options, run_two_axis, save_estimate2, summary2, two_axis_model
from ._experiment import (
    SIGNS,
    Estimate2,
    SweepResult2,
    Trace2,
    excitation_pair,
    identify,
    point_model2,
    run_experiment,
    simulate,
    sweep,
)
from ._model import (
    StabilityMargin2,
    closed_loop,
    closed_loop_poles,
    controller_matrix,
    discrete_plant2,
    effective_coefficients,
    loop_model,
    plant_matrices2,
    predict,
    sensitivity,
    stability_margin,
)
from ._rig import TwoAxisRig

__all__ = [
    "SIGNS",
    "ControllerMatrix",
    "Estimate2",
    "StabilityMargin2",
    "SweepResult2",
    "Trace2",
    "TwoAxisRig",
    "add_two_axis_options",
    "closed_loop",
    "closed_loop_poles",
    "coefficient_arrays",
    "controller_matrix",
    "discrete_plant2",
    "effective_coefficients",
    "excitation_pair",
    "identify",
    "loop_model",
    "plot_coefficients2",
    "point_model2",
    "plant_matrices2",
    "predict",
    "run_experiment",
    "run_two_axis",
    "save_estimate2",
    "sensitivity",
    "simulate",
    "stability_margin",
    "summary2",
    "sweep",
    "to_ross",
    "two_axis_model",
]

# af.predict(two_axis_rig, ...) and its siblings, af.identify of two experiments' recordings, run these.
register(TwoAxisRig, sys.modules[__name__], 2)
