"""One model of N controlled axes: a structure that moves, each axis' chain, a controller matrix.

A structure (:class:`Mechanics`: the platform, the planar mass of :class:`~amb_fast.TwoAxisRig`, the
:class:`RigidRotor`, the :class:`FlexibleRotor` from ROSS) with one :class:`~amb_fast.Rig` chain per axis
(actuator, probe, transducer) is assembled into one linear sampled-data loop (:mod:`._model`); predictions,
poles, sensitivity and effective coefficients are N x N; the rotor's experiments and its Campbell diagram
run on it.
"""

from __future__ import annotations

import sys

from .._dispatch import register
from .._mechanics import Mechanics
from ._campbell import Campbell, campbell
from ._control import ControllerMatrix, ControllerSpec, controller_matrix
from ._experiment import EstimateN, TraceN, estimate, experiment_forces, hadamard_signs, run_experiment, simulate
from ._file import load_rotor
from ._flexible import FlexibleRotor
from ._identify import identify
from ._model import (
    LoopModel,
    StabilityMarginN,
    closed_loop,
    closed_loop_poles,
    discrete_plant,
    effective_coefficients,
    loop_model,
    plant,
    predict,
    require_stable,
    sensitivity,
    stability_margin,
)
from ._rotor import RigidRotor, RotorRig, linear_chains
from ._sensitivity import SensitivityMeasurement, identify_sensitivity, measure_sensitivity
from ._sweep import SweepResultN, point_model, sweep
from ._unbalance import UnbalanceResponse, unbalance_response

__all__ = [
    "estimate",
    "experiment_forces",
    "load_rotor",
    "require_stable",
    "Campbell",
    "EstimateN",
    "FlexibleRotor",
    "TraceN",
    "UnbalanceResponse",
    "campbell",
    "hadamard_signs",
    "linear_chains",
    "identify",
    "identify_sensitivity",
    "measure_sensitivity",
    "run_experiment",
    "simulate",
    "ControllerMatrix",
    "ControllerSpec",
    "LoopModel",
    "Mechanics",
    "RigidRotor",
    "RotorRig",
    "SensitivityMeasurement",
    "StabilityMarginN",
    "SweepResultN",
    "closed_loop",
    "closed_loop_poles",
    "controller_matrix",
    "discrete_plant",
    "effective_coefficients",
    "loop_model",
    "plant",
    "point_model",
    "predict",
    "sensitivity",
    "stability_margin",
    "sweep",
    "unbalance_response",
]

# af.predict(rotor_rig, ...) and its siblings, af.identify of a rotor's four experiments' recordings
# (4, samples, 4; rig=...), run the N-axis functions of this namespace.
register(RotorRig, sys.modules[__name__], 4)
