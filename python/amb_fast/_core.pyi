"""Type stubs for the compiled core (cpp/bindings). Units as in the Python layer: SI, Hz."""

from collections.abc import Sequence
from enum import Enum
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

class ForceLaw(Enum):
    linear = ...
    nonlinear = ...

class PointStatus(Enum):
    ok = ...
    unstable = ...
    touchdown = ...
    saturated = ...

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
        sensor_noise: float = 0.0,
        force_noise: float = 0.0,
        mass_loading: float = 0.0,
        force_coupling_tau: float | None = None,
        clearance: float | None = None,
        current_limit: float | None = None,
        dead_time: float = 0.0,
    ) -> None: ...
    def magnet_force(self, y: float, i: float) -> float: ...
    @property
    def gap(self) -> float: ...

class Controller:
    def __init__(self, *, A: ArrayLike, B: ArrayLike, C: ArrayLike, D: float, fs: float, delay: int) -> None: ...
    @property
    def order(self) -> int: ...
    @property
    def A(self) -> np.ndarray: ...
    @property
    def B(self) -> np.ndarray: ...
    @property
    def C(self) -> np.ndarray: ...
    @property
    def D(self) -> float: ...
    @property
    def fs(self) -> float: ...
    @property
    def delay(self) -> int: ...

def pid_controllers(
    integral_in: ArrayLike,
    derivative_out: ArrayLike,
    direct: ArrayLike,
    *,
    ki: ArrayLike,
    kd: ArrayLike,
    pole: float,
    fs: float,
    delay: int,
) -> list[Controller]: ...

class LinePlan:
    def __init__(self, *, period: int, excited: ArrayLike, unexcited: ArrayLike) -> None: ...

class LineEstimate:
    force: np.ndarray
    displacement: np.ndarray
    H: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    unexcited_force: np.ndarray
    unexcited_displacement: np.ndarray
    periods: int
    blocks: int
    saturated_samples: int

class SweepEstimates:
    H: np.ndarray
    k: np.ndarray
    c: np.ndarray
    k_std: np.ndarray
    c_std: np.ndarray
    k_smooth: np.ndarray
    c_smooth: np.ndarray
    unexcited_displacement: np.ndarray
    status: np.ndarray
    radius: np.ndarray
    periods: int
    blocks: int
    def take(self) -> dict[str, np.ndarray]: ...

def simulate(
    rig: Rig, controller: Controller, force: ArrayLike, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...
def loop_model(rig: Rig, controller: Controller) -> dict[str, np.ndarray]: ...
def normal_noise(seed: int, chunks: Sequence[int], sigma: float = 1.0) -> np.ndarray: ...
def xoshiro256pp(seed: int, n: int) -> np.ndarray: ...
def median_filter(x: ArrayLike, window: int) -> np.ndarray: ...
def line_spectrum(x: ArrayLike, bins: Sequence[int], method: str = "auto") -> tuple[np.ndarray, str]: ...
def run_experiment(
    rig: Rig,
    controller: Controller,
    period_force: ArrayLike,
    settle_periods: int,
    periods: int,
    plan: LinePlan,
    seed: int,
    median_window: int,
    steady_start: bool = False,
) -> LineEstimate: ...
def identify(
    force: ArrayLike,
    displacement: ArrayLike,
    settle_periods: int,
    plan: LinePlan,
    mass: float,
    fs: float,
    median_window: int,
) -> LineEstimate: ...
def run_sweep(
    period_force: ArrayLike,
    rigs: list[Rig],
    controllers: list[Controller],
    settle_periods: ArrayLike,
    seeds: ArrayLike,
    periods: int,
    plan: LinePlan,
    median_window: int,
    workers: int,
    steady_start: bool = False,
    loop_matrices: ArrayLike | None = None,
) -> SweepEstimates: ...
def eigenvalues(stack: ArrayLike, workers: int = 1) -> np.ndarray: ...

# Campbell diagrams: the sampled loop at many speeds, its poles and their shapes at a few rows.
def speed_loops(
    A0: ArrayLike,
    A1: ArrayLike,
    B: ArrayLike,
    holds: ArrayLike,
    P: ArrayLike,
    L: ArrayLike,
    speeds: ArrayLike,
    R: ArrayLike | None = None,
    drive: ArrayLike | None = None,
    loops: bool = False,
    workers: int = 1,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]: ...
def loop_modes(stack: ArrayLike, R: ArrayLike, workers: int = 1) -> tuple[np.ndarray, np.ndarray]: ...

# Two axes (amb_fast.two_axis): the generic dense MIMO loop.
def mimo_simulate(
    M: ArrayLike,
    Bf: ArrayLike,
    Bn: ArrayLike,
    C: ArrayLike,
    Dn: ArrayLike,
    transducer_pole: ArrayLike,
    sensor_noise: ArrayLike,
    force_noise: ArrayLike,
    force: ArrayLike,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]: ...
def mimo_experiments(
    M: ArrayLike,
    Bf: ArrayLike,
    Bn: ArrayLike,
    C: ArrayLike,
    Dn: ArrayLike,
    transducer_pole: ArrayLike,
    sensor_noise: ArrayLike,
    force_noise: ArrayLike,
    period_forces: ArrayLike,
    settle_periods: int,
    periods: int,
    seeds: list[int],
    steady_start: bool = True,
    all_forces: bool = True,
) -> tuple[np.ndarray, np.ndarray]: ...
def mimo_line_experiments(
    M: ArrayLike,
    Bf: ArrayLike,
    Bn: ArrayLike,
    C: ArrayLike,
    Dn: ArrayLike,
    transducer_pole: ArrayLike,
    sensor_noise: ArrayLike,
    force_noise: ArrayLike,
    period_forces: ArrayLike,
    settle_periods: int,
    periods: int,
    seeds: list[int],
    steady_start: bool,
    bins: ArrayLike,
) -> tuple[np.ndarray, np.ndarray]: ...
def mimo_line_sweep(
    M: list[ArrayLike],
    Bf: list[ArrayLike],
    Bn: list[ArrayLike],
    C: list[ArrayLike],
    Dn: list[ArrayLike],
    transducer_pole: list[ArrayLike],
    sensor_noise: list[ArrayLike],
    force_noise: list[ArrayLike],
    period_forces: ArrayLike,
    settle_periods: list[int],
    periods: int,
    seeds: ArrayLike,
    steady_start: bool,
    bins: ArrayLike,
    workers: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...
def estimate_2x2(
    force_lines: ArrayLike, displacement_lines: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...
def estimate_nxn(
    force_lines: ArrayLike, displacement_lines: ArrayLike, readout: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...

# N axes (amb_fast.system._model): the one assembler of the linear loop. Keywords: the structure's mass,
# gyroscopic, stiffness, damping (n x n), actuators, probes (N x n), speed (rad/s); per axis kyy, kiy,
# amp_bandwidth, eddy_bandwidth, sensor_bandwidth (Hz, NaN: ideal), mass_loading (kg), dead_time (s),
# force_coupling_tau (s, NaN: DC); optional fs (Hz) and Ac, Bc, Cc, Dc (the controller matrix). Returns the
# layout (position, velocity, coil, eddy, sensor, lines: tuples of indices) and arrays A, B, S; with fs Phi,
# Gamma; with the controller M, Bf, Bn, C, Dn, poles.
def nd_loop(**arguments: ArrayLike | float) -> dict[str, Any]: ...
def nd_loops(points: list[dict[str, Any]], workers: int = 1) -> list[dict[str, Any]]: ...
