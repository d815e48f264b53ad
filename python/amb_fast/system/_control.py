"""The controller matrix of N axes: ``u_i = sum_j G_ij e_j`` with each entry any SISO digital controller.

Made in :mod:`amb_fast._linear_loop` (the one-axis analysis is its 1x1 case); importable from here."""

from __future__ import annotations

from .._linear import ControllerMatrix, ControllerSpec, controller_matrix, controller_state_space

__all__ = ["ControllerMatrix", "ControllerSpec", "controller_matrix", "controller_state_space"]
