"""The core's Campbell linear algebra against numpy/scipy: the sampled loops of a plant affine in the speed
(``_core.speed_loops``) and each loop's poles with their shapes at chosen rows (``_core.loop_modes``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

import amb_fast as af
from amb_fast import _core
from amb_fast.system import _campbell, _control, _model


def random_parts(rng: np.random.Generator, n: int = 7, k: int = 2, m: int = 11) -> tuple[np.ndarray, ...]:
    """A plant affine in the speed with two holds, and random P, L (L zero in the plant's rows)."""
    A0, A1 = rng.standard_normal((n, n)) * 300.0, rng.standard_normal((n, n))
    B = rng.standard_normal((n, k))
    P, L = rng.standard_normal((n + 2 * k, m)) * 0.3, rng.standard_normal((m, m)) * 0.3
    L[:n] = 0.0
    return A0, A1, B, np.array([2.5e-4, 1.7e-4]), P, L


def reference_loop(A0, A1, B, holds, P, L, W: float) -> np.ndarray:  # noqa: ANN001
    """The loop at speed W from scipy's expm: L + [Phi | Gamma(h) for each hold] P (Phi from the first hold)."""
    n, k = B.shape
    blocks = []
    for j, h in enumerate(holds):
        aug = np.zeros((n + k, n + k))
        aug[:n, :n], aug[:n, n:] = (A0 + W * A1) * h, B * h
        E = scipy.linalg.expm(aug)
        blocks += [E[:n, :n]] * (j == 0) + [E[:n, n:]]
    expected = L.copy()
    expected[:n] += np.hstack(blocks) @ P
    return expected


@pytest.mark.parametrize("workers", [1, 2])
def test_speed_loops_are_scipys_expm_eigvals_and_solve(workers: int) -> None:
    """Each speed's loop is L + [Phi | Gamma(T) | Gamma(h)] P from scipy's expm; its poles are numpy's
    eigenvalues; the steady state under the rotating force ``Re(p^2 b e^{jpt})`` solves the loop at
    ``z = e^{jpT}`` with the force's sample integral from scipy's complex expm."""
    rng = np.random.default_rng(1)
    A0, A1, B, holds, P, L = random_parts(rng)
    n, m = B.shape[0], L.shape[0]
    b = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    speeds = np.linspace(-500.0, 2000.0, 37)
    values, shapes, states, loops = _core.speed_loops(A0, A1, B, holds, P, L, speeds, drive=b, loops=True,
                                                      workers=workers)  # fmt: skip
    assert shapes is None and loops.shape == (speeds.size, m, m) and states.shape == (speeds.size, m)
    for W, M, z, x in zip(speeds, loops, values, states):
        expected = reference_loop(A0, A1, B, holds, P, L, W)
        np.testing.assert_allclose(M, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
        assert matched(z, np.linalg.eigvals(expected)) < 1e-10 * np.abs(z).max()
        aug = np.zeros((n + 1, n + 1), dtype=complex)
        aug[:n, :n], aug[:n, n], aug[n, n] = A0 + W * A1, W**2 * b, 1j * W
        G = scipy.linalg.expm(aug * holds[0])[:n, n]
        rhs = np.r_[G, np.zeros(m - n)]
        steady = np.linalg.solve(np.exp(1j * W * holds[0]) * np.eye(m) - expected, rhs)
        np.testing.assert_allclose(x, steady, rtol=0, atol=1e-9 * np.abs(steady).max())


@pytest.mark.parametrize("norm", [1e-3, 0.1, 0.5, 1.5, 4.0, 40.0])
def test_speed_loops_exponential_at_every_pade_degree(norm: float) -> None:
    """The core's exponential picks its Pade degree (3, 5, 7, 9, 13 and 13 with squarings) from the
    augmented matrix's norm: at each, the loop is L + [Phi | Gamma(T) | Gamma(h)] P from scipy's expm."""
    rng = np.random.default_rng(7)
    A0, A1, B, holds, P, L = random_parts(rng)
    # The augmented matrix [[A0 T, B T], [0, 0]]'s 1-norm about ``norm`` (the balanced one is no larger).
    size = max(np.abs(A0 * holds[0]).sum(axis=0).max(), np.abs(B * holds[0]).sum(axis=0).max())
    A0, A1, B = A0 * norm / size, A1 * norm / size, B * norm / size
    speeds = np.array([0.0, 0.5])
    _, _, _, loops = _core.speed_loops(A0, A1, B, holds, P, L, speeds, loops=True)
    for W, M in zip(speeds, loops):
        expected = reference_loop(A0, A1, B, holds, P, L, W)
        np.testing.assert_allclose(M, expected, rtol=0, atol=1e-13 * np.abs(expected).max())


def test_speed_loops_shapes_are_loop_modes() -> None:
    """With rows R the poles and shapes are those :func:`_core.loop_modes` gives for the same loops."""
    A0, A1, B, holds, P, L = random_parts(np.random.default_rng(4))
    R = np.random.default_rng(5).standard_normal((3, L.shape[0]))
    speeds = np.array([0.0, 300.0, 1200.0])
    values, shapes, states, loops = _core.speed_loops(A0, A1, B, holds, P, L, speeds, R=R, loops=True)
    assert states is None
    expected_values, expected_shapes = _core.loop_modes(loops, R)
    np.testing.assert_array_equal(values, expected_values)
    np.testing.assert_array_equal(shapes, expected_shapes)


def test_warm_started_poles_are_each_speeds_own_and_do_not_depend_on_the_threads() -> None:
    """Each speed's QR starts from the previous speed's poles (within a block of speeds): the poles and the
    bearing shapes' size (of the oscillating poles) are those of the speed alone (cold) to rounding, and the
    same digits on one thread or two (the blocks, not the threads, fix which speed warms which)."""
    rig, pid = af.RotorRig.example(), af.RotorRig.example_controller()
    parts = _campbell._loop_parts(rig, _control.controller_matrix(pid, 4))
    R, _ = _campbell._bearing_form(rig, parts[-1].shape[0])
    speeds = np.linspace(0.0, 6000.0, 41)
    one = _core.speed_loops(*parts, speeds, R=R, workers=1)
    two = _core.speed_loops(*parts, speeds, R=R, workers=2)
    np.testing.assert_array_equal(one[0], two[0])
    np.testing.assert_array_equal(one[1], two[1])
    for speed, values, shapes in zip(speeds, one[0], one[1]):
        cold_values, cold_shapes, _, _ = _core.speed_loops(*parts, np.array([speed]), R=R, workers=1)
        assert matched(values, cold_values[0]) < 1e-12
        size, cold_size = np.linalg.norm(shapes, axis=0), np.linalg.norm(cold_shapes[0], axis=0)
        for pole, s in zip(values, size):  # a repeated pole's copies: the same sizes as a set
            if min(abs(np.angle(pole)), np.pi - abs(np.angle(pole))) <= 1e-9:  # on the real axis to rounding:
                # no whirl, and its shape may be none
                continue
            near = np.abs(cold_values[0] - pole) < 1e-9
            assert np.min(np.abs(cold_size[near] - s)) < 1e-9 * max(size.max(), 1e-300)


def test_speed_loops_refuse_mismatched_shapes_and_holds() -> None:
    A0, A1, B, holds, P, L = random_parts(np.random.default_rng(6))
    with pytest.raises(ValueError, match="A0, A1, B"):
        _core.speed_loops(A0, A1[:3], B, holds, P, L, [0.0])
    with pytest.raises(ValueError, match="hold"):
        _core.speed_loops(A0, A1, B, [0.0, 1e-4], P, L, [0.0])
    with pytest.raises(ValueError, match="P, L"):
        _core.speed_loops(A0, A1, B, holds[:1], P, L, [0.0])
    with pytest.raises(ValueError, match="drive"):
        _core.speed_loops(A0, A1, B, holds, P, L, [0.0], drive=np.ones(3))


def test_speed_loops_are_loop_model_with_any_dead_times() -> None:
    """Every speed's loop as loop_model makes it: axes without dead time, with a fraction of a sample only,
    whole samples only and both (4 kHz: T = 0.25 ms), so the core's holds over T - delta are checked."""
    axes = [replace(af.Rig.paper(), dead_time=d) for d in (0.0, 1e-4, 5e-4, 6e-4)]
    rig = af.RotorRig(af.RotorRig.example().rotor, axes)
    spec = _control.controller_matrix(af.RotorRig.example_controller(), 4)
    speeds = np.array([0.0, 2500.0])
    stack = _campbell.speed_loops(rig, spec, speeds, loops=True)[3]
    for M, W in zip(stack, speeds):
        expected = _model.loop_model(rig.at_speed(W), spec).M
        np.testing.assert_allclose(M, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def matched(values: np.ndarray, expected: np.ndarray) -> float:
    """The largest distance from one of ``values`` to the nearest of ``expected``."""
    return float(np.max(np.min(np.abs(values[:, None] - expected[None, :]), axis=1)))


def test_loop_modes_poles_and_shapes_are_numpys() -> None:
    """Every pole is numpy's; for a simple pole off the real axis the shape R v is numpy's eigenvector's up to a
    unit phase; on the real axis no shape (zero)."""
    rig, pid = af.RotorRig.example(), af.RotorRig.example_controller()
    spec = _control.controller_matrix(pid, 4)
    stack = _campbell.speed_loops(rig, spec, np.array([0.0, 700.0, 4000.0]), loops=True)[3]
    rng = np.random.default_rng(2)
    stack = np.concatenate([stack, rng.standard_normal((4, stack.shape[1], stack.shape[1]))])
    R = rng.standard_normal((3, stack.shape[1]))
    values, shapes = _core.loop_modes(stack, R, 2)
    for M, z, P in zip(stack, values, shapes):
        expected, vectors = np.linalg.eig(M)
        assert matched(z, expected) < 1e-11 * max(1.0, np.abs(expected).max())
        for i, pole in enumerate(z):
            if pole.imag == 0:
                assert np.all(P[:, i] == 0)
                continue
            gaps = np.abs(expected - pole)
            j = int(np.argmin(gaps))
            if np.sort(gaps)[1] < 1e-6:  # repeated: a plane of vectors
                continue
            reference = R @ vectors[:, j]
            phase = np.vdot(reference, P[:, i]) / np.vdot(reference, reference)
            assert abs(abs(phase) - 1.0) < 1e-8
            np.testing.assert_allclose(P[:, i], phase * reference, rtol=0, atol=1e-8 * np.abs(reference).max())


def test_a_repeated_poles_copies_span_its_plane() -> None:
    """A block-diagonal (A, A): each pole twice; the two copies' vectors (R = I: the vectors themselves) are
    eigenvectors and independent, so whirl can be read in the plane they span."""
    rng = np.random.default_rng(3)
    A = rng.standard_normal((4, 4))
    M = scipy.linalg.block_diag(A, A)
    values, shapes = _core.loop_modes(M[None], np.eye(8))
    z, V = values[0], shapes[0]
    for pole in np.linalg.eigvals(A):
        if pole.imag == 0:
            continue
        copies = np.nonzero(np.abs(z - pole) < 1e-9)[0]
        assert copies.size == 2
        pair = V[:, copies]
        np.testing.assert_allclose(M @ pair, pair * z[copies], rtol=0, atol=1e-9)
        assert np.linalg.svd(pair, compute_uv=False)[1] > 1e-3  # independent: a plane, not one line


def test_loop_modes_refuse_rows_of_another_size() -> None:
    with pytest.raises(ValueError, match="R"):
        _core.loop_modes(np.eye(3)[None], np.ones((2, 4)))


def test_whirl_of_a_repeated_negative_real_pole_is_none() -> None:
    """A repeated pole on the negative real axis (x and y alike, at the Nyquist frequency) has whirl 0, as a
    simple one has: its samples alternate along a line, and its plane holds a forward and a backward shape
    that sample alike. A repeated complex pole at the same bearing shapes reads one forward, one backward."""
    R, F = np.eye(2), np.array([[0.0, 2j], [-2j, 0.0]])  # one bearing plane: x, y
    shapes = np.array([[[1.0, 0.0], [0.0, 1.0]]] * 2, dtype=complex)  # (speeds, N, poles): the x and y lines
    values = np.array([[-0.3, -0.3], [0.3 + 0.4j, 0.3 + 0.4j]])
    whirl = _campbell._whirl(values, R @ shapes, F)
    np.testing.assert_array_equal(whirl, [[0, 0], [1, -1]])


def test_campbell_orders_poles_by_frequency_then_half_plane_then_modulus() -> None:
    """Per speed: |angle| (frequency) rising; equal frequencies (a conjugate pair, poles on the real axis):
    the pole above the axis first, then rising modulus, whatever order the core found them in."""
    c = af.campbell(af.RotorRig.example(), af.RotorRig.example_controller(), np.linspace(0.0, 6000.0, 25))
    angle = np.angle(c.z)
    keys = np.stack([np.abs(angle), -angle, np.abs(c.z)], axis=-1)  # (speeds, poles, 3)
    for row in keys:
        for earlier, later in zip(row[:-1], row[1:]):
            assert tuple(earlier) <= tuple(later)
    assert np.any((c.z.imag == 0) & (np.abs(angle[:, :1]) == 0))  # real poles tie on frequency: the check bites


def test_poles_of_a_flexible_rotor_at_standstill_whatever_its_rounding() -> None:
    """At standstill a flexible rotor's loop has every pole twice (x and y alike), on which the Francis steps
    can stall (about 1 in 20 of the model's last-digit perturbations did: "eigenvalues did not converge"); the
    core then takes Eigen's solver: every perturbation gives numpy's poles."""
    pytest.importorskip("ross")
    rig = af.RotorRig(af.FlexibleRotor.example(modes=3, speed=500.0),
                      af.Rig(amp_bandwidth=3000.0, sensor_bandwidth=10_000.0))  # fmt: skip
    parts = _campbell._loop_parts(rig, _control.controller_matrix(af.RotorRig.example_controller(), 4))
    R, _ = _campbell._bearing_form(rig, parts[-1].shape[0])
    rng = np.random.default_rng(0)
    for _ in range(100):
        perturbed = [x * (1.0 + 1e-15 * rng.standard_normal(x.shape)) if x.ndim == 2 else x for x in parts]
        values, _, _, loops = _core.speed_loops(*perturbed, np.array([0.0]), R=R, loops=True)
        expected = np.linalg.eigvals(loops[0])
        assert matched(values[0], expected) < 1e-10 * np.abs(expected).max()
