"""The linearised sampled-data loop in closed form: prediction, poles, margins, effective coefficients.

Matrix-level numpy (no per-sample loops) on the core's model, of which one axis is the 1x1 case: the plant
is discretised exactly (zero-order hold), so the frequency response here is what a noise-free, settled,
period-averaged experiment must reproduce.

The code is in three modules; import it from here, as the rest of the package does: ``_linear_loop``
(the plant, the controllers and the closed loop as state spaces, one axis or N), ``_linear_poles`` (the closed-loop
poles as runs and sweeps compute them, the stability check, settling), ``_linear_response`` (the
receptance, the sensitivity and its margin, the effective coefficients). ``__all__`` also names the
private helpers that the sweep, the calibration, the N-axis model and the tests import from here.
"""

from __future__ import annotations

from ._linear_loop import (
    AnyController,
    ControllerMatrix,
    ControllerSpec,
    DesignController,
    Layout,
    LoopModel,
    System,
    closed_loop,
    controller_matrices,
    controller_matrix,
    controller_state_space,
    core_controller,
    discrete_plant,
    is_controller,
    loop_model,
    loop_models,
    plant,
    plant_matrices,
    sampled_plant,
    sampled_sensor_rows,
    sensor_rows,
    split_dead_time,
    state_space,
)
from ._linear_poles import (
    _closed_loop_stacks,
    _gain_arrays,
    checked_poles,
    closed_loop_poles,
    eigenvalues,
    loop_poles,
    require_stable,
    settle_periods_for,
    settling_radius,
    spectral_radius,
)
from ._linear_response import (
    StabilityMargin,
    controller_frequency_response,
    controller_response,
    effective_coefficients,
    iso_zone,
    peak_margin,
    plant_responses,
    predict,
    sensitivity,
    stability_margin,
    state_response,
    transducer_response,
)

__all__ = [
    "checked_poles",
    "_closed_loop_stacks",
    "eigenvalues",
    "_gain_arrays",
    "plant_responses",
    "state_response",
    "AnyController",
    "ControllerMatrix",
    "ControllerSpec",
    "DesignController",
    "Layout",
    "LoopModel",
    "StabilityMargin",
    "System",
    "closed_loop",
    "closed_loop_poles",
    "controller_frequency_response",
    "controller_matrices",
    "controller_response",
    "core_controller",
    "discrete_plant",
    "effective_coefficients",
    "controller_matrix",
    "controller_state_space",
    "is_controller",
    "iso_zone",
    "loop_model",
    "loop_models",
    "loop_poles",
    "peak_margin",
    "plant",
    "plant_matrices",
    "predict",
    "require_stable",
    "sampled_plant",
    "sampled_sensor_rows",
    "sensitivity",
    "sensor_rows",
    "settle_periods_for",
    "settling_radius",
    "spectral_radius",
    "split_dead_time",
    "stability_margin",
    "state_space",
    "transducer_response",
]
