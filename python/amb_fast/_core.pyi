"""Type stubs for the compiled core (cpp/bindings)."""

from enum import Enum

import numpy as np
from numpy.typing import ArrayLike

class ForceLaw(Enum):
    linear = ...
    nonlinear = ...

class Rig:
    def __init__(
        self,
        *,
        mass: float,
        kyy: float,
        kiy: float,
        bias_current: float,
        force_law: ForceLaw,
        amp_bandwidth: float | None,
        eddy_bandwidth: float | None,
        sensor_bandwidth: float | None,
        substeps: int,
    ) -> None: ...
    def magnet_force(self, y: float, i: float) -> float: ...
    @property
    def gap(self) -> float: ...

class Pid:
    def __init__(
        self, *, kp: float, ki: float, kd: float, derivative_cutoff: float | None, fs: float, delay: int
    ) -> None: ...

def simulate(rig: Rig, pid: Pid, force: ArrayLike) -> tuple[np.ndarray, np.ndarray]: ...
