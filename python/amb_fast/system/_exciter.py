"""The bearings as exciters: a multisine on each axis' current command, the force estimated from the coil
current and the probe by the actuator model, and the process at the bearings corrected for the hold.

With ``exciter="amb"`` experiment ``e`` adds ``signs[e, j] s`` (A) to axis ``j``'s current command after the
controller (before its dead time and amplifier); no shaker acts. The force on the rotor is not measured:
per line it is estimated as ``F = -kyy d - kiy i`` (``i``: the coil current at the sample instants, the
amplifier's output before the eddy-current lag; ``d = E^-1 Y``: the bearing planes' displacements from
the probes through the structure's readout), so ``H = F Y^-1 = -w^2 Mb + j w W Gb + P`` plus what the
samples hide: the current held between them, the amplifier's, the probes' and the eddy-current lags (the
force follows the current through the eddy-current lag, which the estimate from the current cannot see).

:func:`corrected_process` removes what the model knows. The command ``u`` drives the sampled current and
probes through the exact sampled plant and the continuous ones through the hold ``(1 - e^{-jwT})/(jwT)``,
each axis' dead time and the continuous plant; their ratio is the estimator's own ``rho`` (not the
approximate ``e^{jwT/2}/sinc``). The process enters only as a correction of the known structure's
(its process removed) sampled response, whose aliases (above Nyquist) are taken as the known
structure's: what is left is the process's effect on those aliases (about 5e-9 of ``|Z|`` on the example
rotor at 200 Hz with a 20 kN/m seal; 6e-7 of ``|Z|`` at 680 Hz with every lag on).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._linear import split_dead_time, state_response
from .._mechanics import Mechanics
from .._params import Rig
from ._model import LoopModel, System, discrete_plant, plant, sensor_rows


@dataclass(frozen=True)
class _Known:
    """What the estimate's correction knows of ``system``: all of it but its process (the structure's
    stiffness and damping, what is identified)."""

    system: Any

    @property
    def axes(self) -> tuple[Rig, ...]:
        return tuple(self.system.axes)

    def mechanics(self) -> Mechanics:
        mech = self.system.mechanics()
        zero = np.zeros_like(mech.stiffness)
        return replace(mech, stiffness=zero, damping=zero)


def current_rows(system: System, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(N, discrete plant states): each axis' recorded coil current (the amplifier's state, or with an ideal
    amplifier the command after the dead time's whole samples), and (N,) whether it is the command itself
    (no amplifier lag, no whole sample of dead time: the current follows the injection directly)."""
    Phi, _, states = discrete_plant(system, fs)
    _, _, lay = plant(system)
    names = system.mechanics().names
    rows, direct = np.zeros((len(names), Phi.shape[0])), np.zeros(len(names))
    for a, axis in enumerate(system.axes):
        whole = split_dead_time(axis.dead_time, fs)[0]
        if lay.coil[a] >= 0:
            rows[a, lay.coil[a]] = 1.0
        elif whole > 0:
            rows[a, states.index(f"{names[a]}.dead{whole}")] = 1.0
        else:
            direct[a] = 1.0
    return rows, direct


def amb_args(model: LoopModel, system: System) -> dict[str, np.ndarray]:
    """The core's model of the AMB experiment: the inputs are the N current commands' injections (they enter
    the plant where the commands do, ``Gu``, and not the controller), the outputs the N probes and the N
    coil currents; no transducer, no force noise (the core's recorded "force" is the injection itself). The
    core reports as many outputs as noise inputs: the currents come with N silent ones."""
    N = model.Bf.shape[1]
    Gu = discrete_plant(system, model.fs)[1][:, N:]
    Bf = np.vstack([Gu, np.zeros((model.M.shape[0] - Gu.shape[0], N))])
    silent = np.zeros((model.M.shape[0], N))
    noise = np.r_[[a.sensor_noise for a in system.axes], np.zeros(N)]
    return dict(M=model.M, Bf=Bf, Bn=np.hstack([model.Bn, silent]), C=model.C,
                Dn=np.hstack([model.Dn, silent[: 2 * N]]), transducer_pole=np.zeros(N), sensor_noise=noise,
                force_noise=np.zeros(N))  # fmt: skip


def _chain(system: System) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each axis' kyy (N/m), kiy (N/A) and the estimate frame's inverse ``E^-1``."""
    mech = system.mechanics()
    kyy = np.array([a.kyy for a in system.axes])
    kiy = np.array([a.kiy for a in system.axes])
    return kyy, kiy, np.linalg.inv(mech.frame)


def amb_force(system: System, probes: np.ndarray, current: np.ndarray) -> np.ndarray:
    """The estimated forces' line spectra (N) from the probes' (m) and the coil currents' (A), each (periods,
    lines, N, experiments): ``F = -kyy E^-1 readout y - kiy i``."""
    kyy, kiy, inverse_frame = _chain(system)
    d = np.tensordot(probes, (inverse_frame @ system.mechanics().readout).T, axes=(2, 0)).swapaxes(2, 3)  # one product
    return np.ascontiguousarray(-kyy[:, None] * d - kiy[:, None] * current)


def amb_lines(system: System, fs: float, injection: np.ndarray, outputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The estimated forces' and the probes' line spectra (periods, lines, N, experiments) from the core's
    injection and output (probes, then coil currents) lines (:func:`amb_force`)."""
    N = injection.shape[2]
    probes = outputs[:, :, :N]
    current = outputs[:, :, N:] + current_rows(system, fs)[1][:, None] * injection
    return amb_force(system, probes, current), np.ascontiguousarray(probes)


def corrected_process(system: System, fs: float, freq: np.ndarray, H: np.ndarray) -> np.ndarray:
    """The process at the bearing planes (lines, N, N), complex ``K + j w C`` in N/m, in the estimate's frame
    (``K E^-1`` as ``H``), from the AMB-exciter estimate ``H`` with the hold, the amplifier's and the probes'
    lags, the dead time, the mass loading and the structure's mass and gyroscopics removed (the module's
    docstring), and the eddy-current lag, which ``H`` carries, removed with the model's ``eddy_bandwidth``."""
    mech, known = system.mechanics(), _Known(system)
    N = mech.axes
    kyy, kiy, inverse_frame = _chain(system)
    A, B, _ = plant(known)
    Phi, Gamma, _ = discrete_plant(known, fs)
    probes = mech.readout @ sensor_rows(known)  # (N, continuous plant states)
    rows, direct = current_rows(known, fs)
    w = 2 * np.pi * np.asarray(freq, dtype=float)
    T = 1.0 / fs
    # The sampled response of the known structure to the commands: probes (through the readout), currents.
    outputs = np.zeros((2 * N, Phi.shape[0]))
    outputs[:N, : A.shape[0]], outputs[N:] = probes, rows
    sampled = state_response(Phi, Gamma[:, N:], outputs, np.exp(1j * w * T), frequency_first=True)
    Py0, current = sampled[:, :N], sampled[:, N:] + np.diag(direct)
    # The continuous response at w to the commands' fundamental: held, then each axis' dead time.
    dead = np.array([a.dead_time for a in system.axes])
    held = ((1 - np.exp(-1j * w * T)) / (1j * w * T))[:, None] * np.exp(-1j * w[:, None] * dead)  # (lines, N)
    Ty0 = state_response(A, B[:, N:], probes, 1j * w, frequency_first=True) * held[:, None, :]
    # Measured: Y I^-1 from H = -kyy E^-1 - kiy I Y^-1; times the current per command it is the sampled
    # response of the probes to the commands; less the known one it is the process's.
    IY = -(H + kyy[:, None] * inverse_frame) / kiy[:, None]
    dT = np.linalg.solve(IY, current) - Py0
    # Ty = readout Lp S A^-1 Wb^-1 D (Wb = Zb + kyy, D = -kiy La held): Wb - Wb0 = -D Ty^-1 dT Ty0^-1 RL.
    lags = _lag(w, [a.amp_bandwidth for a in system.axes]) * _lag(w, [a.eddy_bandwidth for a in system.axes])
    D = -kiy * lags * held
    # What the probes read of the bearing planes (a flexible rotor: under its rigid-body motion only, so
    # there the correction is approximate).
    RL = mech.readout @ (_lag(w, [a.sensor_bandwidth for a in system.axes])[:, :, None] * mech.reads)
    P = -D[:, :, None] * np.linalg.solve(Ty0 + dT, dT) @ np.linalg.solve(Ty0, RL)
    return P @ inverse_frame


def _lag(w: np.ndarray, bandwidths: list[float | None]) -> np.ndarray:
    """(lines, N): each axis' first-order lag at ``w`` (rad/s); 1 where the stage is ideal (None)."""
    return np.stack([1 / (1 + 1j * w / (2 * np.pi * b)) if b else np.ones_like(w, dtype=complex)
                     for b in bandwidths], axis=-1)  # fmt: skip
