"""Digital controllers beyond the PID: any causal SISO discrete LTI controller at the sample rate.

:class:`Controller` (a state space plus a whole-sample computation delay, from measured displacement in m
to current command in A), its constructors (``Controller.from_tf``, ``from_zpk``, ``from_ss``,
``from_sos``, ``from_continuous``, ``from_control``), the blocks of the field (:func:`notch`,
:func:`low_pass`, :func:`lead_lag`, :func:`second_order`, :func:`gain`, :func:`pure_delay`,
:func:`pid_controller`), their combination (:func:`series`, :func:`parallel`, ``*``, ``+``) and the
controller file format (:func:`load_controller`). See ``docs/controllers.md``.

Modules: ``_controller`` (the class: its constructors, contract, parameters and algebra; :func:`series`,
:func:`parallel`, :func:`gain`, :func:`pure_delay`), ``_statespace`` (realisations as state spaces and the
discretisation of continuous designs), ``_blocks`` (the blocks of the field), ``_file`` (controller files).
"""

from __future__ import annotations

from ._blocks import lead_lag, low_pass, notch, pid_controller, second_order
from ._controller import Controller, as_controller, gain, parallel, pure_delay, series
from ._file import controller_table, load_controller, recorded_controller, save_controller
from ._statespace import MAX_ORDER

__all__ = [
    "MAX_ORDER",
    "Controller",
    "as_controller",
    "controller_table",
    "gain",
    "lead_lag",
    "load_controller",
    "low_pass",
    "notch",
    "parallel",
    "pid_controller",
    "pure_delay",
    "recorded_controller",
    "save_controller",
    "second_order",
    "series",
]
