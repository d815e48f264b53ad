"""The core's assembler of the N-axis loop (``_core.nd_loop``, issue 26) against an independent numpy one.

The reference orders its states its own way (positions, velocities, then each axis' lags), takes a dead
time's fraction as ``Gamma(T) - Gamma(T - delta)`` (not the core's ``Phi(T - delta) Gamma(delta)``) and
builds the closed loop column by column from one sample of its equations; the core's matrices are
compared after reordering them by state name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from scipy.linalg import expm

import amb_fast as af
from amb_fast import _core, _linear_loop
from amb_fast._mechanics import Mechanics
from amb_fast.system import _model
from amb_fast.system._control import controller_matrix, controller_state_space

FS = 4000.0
T = 1.0 / FS


@dataclass(frozen=True, eq=False)
class Structure:
    """A System of any structure (hashed by identity)."""

    mech: Mechanics
    axes: tuple[af.Rig, ...]

    def mechanics(self) -> Mechanics:
        return self.mech


def structure(N: int, n: int, speed: float) -> Mechanics:
    """A made-up structure: n coordinates, N axes, coupled mass, process, gyroscopic term, probes off the
    bearing planes."""
    rng = np.random.default_rng(N * 10 + n)
    mass = np.diag(rng.uniform(0.5, 2.0, n)) + 0.05 * np.ones((n, n))
    gyro = rng.normal(0, 0.01, (n, n))
    actuators = np.eye(N, n) + 0.1 * rng.normal(size=(N, n))
    probes = actuators + 0.05 * rng.normal(size=(N, n))
    names = tuple(f"a{j}" for j in range(N))
    return Mechanics(mass, gyro - gyro.T, rng.normal(0, 1e3, (n, n)), rng.normal(0, 2.0, (n, n)), actuators, probes,
                     np.eye(N), speed, names, tuple(f"q{k}" for k in range(n)))  # fmt: skip


# Per axis (cycled): which lags, dead time (whole samples + a fraction), mass loading, transducer.
CHAINS = [
    dict(amp_bandwidth=3000.0, eddy_bandwidth=2000.0, sensor_bandwidth=10000.0, dead_time=1.3 * T, mass_loading=0.06,
         force_coupling_tau=1.0),
    dict(amp_bandwidth=None, eddy_bandwidth=None, sensor_bandwidth=None, dead_time=0.0, mass_loading=0.0),
    dict(amp_bandwidth=None, eddy_bandwidth=1500.0, sensor_bandwidth=8000.0, dead_time=2.0 * T, mass_loading=0.02),
    dict(amp_bandwidth=2500.0, eddy_bandwidth=None, sensor_bandwidth=None, dead_time=0.4 * T, mass_loading=0.1,
         force_coupling_tau=0.5),
]  # fmt: skip


def system(N: int, n: int, speed: float = 0.0) -> Structure:
    axes = tuple(af.Rig(kyy=-5e4 + 1e3 * j, kiy=47.0 + j, **CHAINS[j % 4]) for j in range(N))  # type: ignore[arg-type]
    return Structure(structure(N, n, speed), axes)


def controller(N: int) -> list[list[Any]]:
    """Diagonal PIDs with a computation delay, and a cross path."""
    pid = af.PID(kp=2400.0, ki=2e4, kd=3.0, derivative_cutoff=1000.0, fs=FS, delay=1)
    cross = af.PID(kp=300.0, ki=0.0, kd=0.5, derivative_cutoff=800.0, fs=FS, delay=0)
    return [[pid if i == j else cross if j == (i + 1) % N else None for j in range(N)] for i in range(N)]


def hold(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = B.shape
    E = expm(np.block([[A, B], [np.zeros((m, n + m))]]) * h)
    return E[:n, :n], E[:n, n:]


def reference(sys: Structure, fs: float, ss: tuple[np.ndarray, ...]) -> dict[str, Any]:
    """The loop from the equations, in the reference's own state order."""
    mech, axes = sys.mech, sys.axes
    n, N = mech.coordinates, mech.axes
    names = list(mech.coordinate_names) + [f"{q}'" for q in mech.coordinate_names]
    for label, a in zip(mech.names, axes):
        names += [f"{label}.{s}" for s, bw in (("i", a.amp_bandwidth), ("i_f", a.eddy_bandwidth),
                                                ("ys", a.sensor_bandwidth)) if bw is not None]  # fmt: skip
    at = {name: k for k, name in enumerate(names)}
    p = len(names)
    Mt, K = mech.mass.copy(), mech.stiffness.copy()
    for j, a in enumerate(axes):
        Mt += a.mass_loading * np.outer(mech.actuators[j], mech.actuators[j])
        K += a.kyy * np.outer(mech.actuators[j], mech.actuators[j])
    Minv = np.linalg.inv(Mt)
    A, B = np.zeros((p, p)), np.zeros((p, 2 * N))
    A[:n, n : 2 * n] = np.eye(n)
    A[n : 2 * n, :n] = -Minv @ K
    A[n : 2 * n, n : 2 * n] = -Minv @ (mech.damping + mech.speed * mech.gyroscopic)
    S = np.zeros((N, p))
    for j, (label, a) in enumerate(zip(mech.names, axes)):
        push = Minv @ mech.actuators[j]
        B[n : 2 * n, j] = push
        coil, eddy, ys = (at.get(f"{label}.{s}") for s in ("i", "i_f", "ys"))
        drive = eddy if eddy is not None else coil
        if drive is None:
            B[n : 2 * n, N + j] -= a.kiy * push
        else:
            A[n : 2 * n, drive] -= a.kiy * push
        for stage, bw, source in ((coil, a.amp_bandwidth, None), (eddy, a.eddy_bandwidth, coil)):
            if stage is not None:
                A[stage, stage] = -2 * np.pi * bw
                if source is None:
                    B[stage, N + j] = 2 * np.pi * bw
                else:
                    A[stage, source] = 2 * np.pi * bw
        if ys is None:
            S[j, :n] = mech.probes[j]
        else:
            A[ys, ys] = -2 * np.pi * a.sensor_bandwidth
            A[ys, :n] = 2 * np.pi * a.sensor_bandwidth * mech.probes[j]
            S[j, ys] = 1.0
    h = 1.0 / fs
    Phi, Gamma = hold(A, B, h)
    whole = [int(np.floor(a.dead_time / h)) for a in axes]
    frac = [max(0.0, a.dead_time - w * h) for a, w in zip(axes, whole)]
    # The command felt over the sample's last T - delta (now) and its first delta (the previous one).
    G0, G1 = Gamma[:, N:].copy(), np.zeros((p, N))
    for j, d in enumerate(frac):
        if d > 0:
            G0[:, j] = hold(A, B, h - d)[1][:, N + j]
            G1[:, j] = Gamma[:, N + j] - G0[:, j]
    lines = [w + (d > 0) for w, d in zip(whole, frac)]
    for label, line in zip(mech.names, lines):
        names += [f"{label}.dead{k + 1}" for k in range(line)]
    Ac, Bc, Cc, Dc = ss
    names += [f"controller{k}" for k in range(Ac.shape[0])]
    size, q = len(names), p + sum(lines)

    def step(z: np.ndarray, f: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, xc = z[:p], z[q:]
        queue = np.split(z[p:q], np.cumsum(lines)[:-1])
        e = S @ x + noise
        u = Cc @ xc + Dc @ e
        now = [u[j] if whole[j] == 0 else queue[j][whole[j] - 1] for j in range(N)]
        before = [queue[j][whole[j]] if frac[j] > 0 else 0.0 for j in range(N)]
        x_next = Phi @ x + Gamma[:, :N] @ f + G0 @ np.array(now) + G1 @ np.array(before)
        queue_next = [np.concatenate([[u[j]], queue[j]])[: lines[j]] for j in range(N)]
        coil = [x[at[f"{label}.i"]] if f"{label}.i" in at else now[j] for j, label in enumerate(mech.names)]
        return np.concatenate([x_next, *queue_next, Ac @ xc + Bc @ e]), np.concatenate([e, coil])

    zero_z, zero_N, unit = np.zeros(size), np.zeros(N), np.eye(size)
    columns = [step(unit[k], zero_N, zero_N) for k in range(size)]
    forces = [step(zero_z, np.eye(N)[j], zero_N) for j in range(N)]
    noises = [step(zero_z, zero_N, np.eye(N)[j]) for j in range(N)]
    poles = [0.0 if a.force_coupling_tau is None else np.exp(-1 / (fs * a.force_coupling_tau)) for a in axes]
    return dict(names=names, plant=names[:p], A=A, B=B, S=S, Phi=Phi, Gamma=Gamma,
                M=np.stack([c[0] for c in columns], 1), C=np.stack([c[1] for c in columns], 1),
                Bf=np.stack([c[0] for c in forces], 1), Bn=np.stack([c[0] for c in noises], 1),
                Dn=np.stack([c[1] for c in noises], 1), poles=np.array(poles))  # fmt: skip


def close(actual: np.ndarray, expected: np.ndarray, what: str) -> None:
    """Equal to 1e-12 of the largest entry in each entry's row or column (states and inputs differ in scale:
    m, m/s, A, N; an exact zero comes out as rounding of its row's entries)."""
    size = np.abs(expected)
    scale = np.maximum(size.max(axis=1, keepdims=True), size.max(axis=0, keepdims=True))
    np.testing.assert_array_less(np.abs(actual - expected), 1e-12 * scale + 1e-300, err_msg=what)


@pytest.mark.parametrize(("N", "n", "speed"), [(1, 1, 0.0), (2, 2, 0.0), (2, 3, 50.0), (4, 4, 300.0)])
def test_core_assembly_equals_an_independent_numpy_one(N: int, n: int, speed: float) -> None:
    sys = system(N, n, speed)
    spec = controller_matrix(controller(N), N)
    ref = reference(sys, FS, controller_state_space(spec))
    A, B, layout = _model.plant(sys)
    plant_order = [layout.names.index(name) for name in ref["plant"]]
    assert sorted(layout.names) == sorted(ref["plant"])
    close(A[np.ix_(plant_order, plant_order)], ref["A"], "A")
    close(B[plant_order], ref["B"], "B")
    close(_model.sensor_rows(sys)[:, plant_order], ref["S"], "S")
    Phi, Gamma, states = _model.discrete_plant(sys, FS)
    close(Phi[np.ix_(plant_order, plant_order)], ref["Phi"], "Phi")
    close(Gamma[plant_order, :N], ref["Gamma"][:, :N], "Gamma (forces)")
    model = _model.loop_model(sys, spec)
    assert sorted(model.states) == sorted(ref["names"])
    order = [model.states.index(name) for name in ref["names"]]
    close(model.M[np.ix_(order, order)], ref["M"], "M")
    close(model.Bf[order], ref["Bf"], "Bf")
    close(model.Bn[order], ref["Bn"], "Bn")
    close(model.C[:, order], ref["C"], "C")
    close(model.Dn, ref["Dn"], "Dn")
    np.testing.assert_allclose(model.poles, ref["poles"], rtol=1e-15)


def test_states_keep_the_documented_order() -> None:
    """Per coordinate its position and velocity, then that axis' chain; then the command lines."""
    sys = system(2, 3)
    assert _model.discrete_plant(sys, FS)[2] == ("q0", "q0'", "a0.i", "a0.i_f", "a0.ys", "q1", "q1'", "q2", "q2'",
                                                 "a0.dead1", "a0.dead2")  # fmt: skip


def test_batched_loops_equal_single_ones_to_the_bit() -> None:
    """loop_models on two threads: each point's loop is loop_model's, digit for digit."""
    points = [(system(N, N, speed), controller(N)) for N in (1, 2, 4) for speed in (0.0, 200.0)]
    for batched, (sys, c) in zip(_model.loop_models(points, workers=2), points):
        single = _model.loop_model(sys, c)
        assert batched.states == single.states
        for name in ("M", "Bf", "Bn", "C", "Dn", "poles"):
            np.testing.assert_array_equal(getattr(batched, name), getattr(single, name), err_msg=name)


def core_args(**changes: Any) -> dict[str, Any]:
    sys = system(2, 2)
    args = _linear_loop._core_args(sys)[1]
    return {**args, **changes}


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (dict(mass=np.zeros((2, 2))), "mass (with the axes' mass loading) must be invertible"),
        (dict(probes=np.zeros((3, 2))), "probes must be 2x2, got 3x2"),
        (dict(kyy=np.array([1.0, np.nan])), "kyy must be finite (N/m), got nan"),
        (dict(amp_bandwidth=np.array([-1.0, np.nan])), "amp_bandwidth must be a finite number > 0 (Hz; NaN: an ideal"),
        (dict(dead_time=np.array([0.0])), "dead_time must be one entry per axis, got 1 entries"),
        (dict(fs=-4000.0, Ac=np.zeros((0, 0)), Bc=np.zeros((0, 2)), Cc=np.zeros((2, 0)), Dc=np.eye(2)),
         "fs must be a finite number > 0 (Hz), got -4000"),
        (dict(fs=4000.0, Ac=np.zeros((1, 1)), Bc=np.zeros((1, 2)), Cc=np.zeros((2, 1)), Dc=np.eye(3)),
         "controller D must be 2x2, got 3x3"),
    ],
)  # fmt: skip
def test_bad_input_names_the_parameter(changes: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        _core.nd_loop(**core_args(**changes))
