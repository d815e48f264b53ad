"""Self-checks of the independent rigid-rotor reference (tests/rotor_reference.py).

The reference has two independent paths (a sample-by-sample loop with piecewise integration, and a
discrete closed-loop matrix); these tests check them against each other, against the one-axis model in
a case where the rotor is two independent masses, and against closed-form gyroscopic frequencies.
"""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
from rotor_reference import (
    HADAMARD,
    RotorParams,
    actual_coefficients,
    bearing_matrices,
    closed_loop,
    continuous_plant,
    diagonal,
    experiment,
    loop_eigenvalues,
    loop_modes,
    receptance,
    rigid_body_map,
    simulate,
    whirl_direction,
)

FS = 4000.0


def chain(**overrides: float | None) -> af.Rig:
    """One axis' chain with every linear effect on: lags, a dead time with a fraction of a sample,
    mass loading and an AC-coupled transducer (short tau so that tests settle fast)."""
    fields: dict = dict(
        mass=1.0,  # not used by the rotor
        kyy=-53.3e3,
        kiy=100.0,
        amp_bandwidth=1500.0,
        eddy_bandwidth=3000.0,
        sensor_bandwidth=5000.0,
        dead_time=1.3 / FS,
        mass_loading=0.06,
        force_coupling_tau=0.002,
    )
    fields.update(overrides)
    return af.Rig(**fields)


def pid(delay: int = 1) -> af.PID:
    return af.PID(kp=4000.0, ki=2e5, kd=10.0, derivative_cutoff=1000.0, fs=FS, delay=delay)


def spinning() -> RotorParams:
    """Speed, non-collocated and asymmetric sensors, unequal bearings, a cross-coupled process."""
    return RotorParams(
        mass=10.0,
        It=0.35,
        Ip=0.1,
        bearings=(0.2, -0.18),
        sensors=(0.23, -0.21),
        speed=300.0,
        process=[(0.05, 2e4, -2e4, 5.0, -5.0)],
    )


def full_controller() -> list[list]:
    """A PID per axis (one with a different delay) and one cross path A.x -> B.x."""
    ctrl = diagonal(pid())
    ctrl[3][3] = pid(delay=2)
    ctrl[2][0] = af.lead_lag(gain=300.0, zero=50.0, pole=500.0, fs=FS)
    return ctrl


X_PLANE, Y_PLANE = [0, 2], [1, 3]  # A.x, B.x and A.y, B.y


def test_planes_decouple_at_rest_and_couple_when_spinning() -> None:
    freq = np.array([1.0, 13.0, 55.0, 210.0, 900.0])
    rotor = RotorParams(mass=10.0, It=0.35, Ip=0.1, bearings=(0.2, -0.18), sensors=(0.23, -0.21))
    axes = [chain()] * 4
    G = receptance(rotor, axes, diagonal(pid()), freq)
    scale = np.abs(G).max()
    cross = np.abs(G[:, X_PLANE][:, :, Y_PLANE]).max() + np.abs(G[:, Y_PLANE][:, :, X_PLANE]).max()
    assert cross < 1e-13 * scale
    # the same x-y block of a spinning rotor is far from 0: the check above is not vacuous
    rotor.speed = 300.0
    G = receptance(rotor, axes, diagonal(pid()), freq)
    assert np.abs(G[:, X_PLANE][:, :, Y_PLANE]).max() > 1e-3 * scale


def test_two_independent_half_masses_equal_the_one_axis_model() -> None:
    # With zA = -zB = a and It = m a^2, the kinetic energy in the bearing coordinates yA = x + a ty,
    # yB = x - a ty is (m/2)(yA'^2 + yB'^2)/2: two independent masses m/2 (speed 0: no gyroscopics).
    # Sensors at the bearings: each axis is the one-axis loop with mass m/2 (+ its mass loading).
    m, a = 10.0, 0.2
    rotor = RotorParams(mass=m, It=m * a**2, Ip=0.3, bearings=(a, -a), sensors=(a, -a))
    freq = np.array([1.0, 7.0, 40.0, 123.0, 400.0, 1500.0])
    axis = chain()
    G = receptance(rotor, [axis] * 4, diagonal(pid()), freq)
    one = af.predict(chain(mass=m / 2), pid(), freq)
    for j in range(4):
        np.testing.assert_allclose(G[:, j, j], one, rtol=1e-9, atol=0)
    off = G - np.einsum("fj,jk->fjk", np.einsum("fjj->fj", G), np.eye(4))
    assert np.abs(off).max() < 1e-12 * np.abs(one).max()


def test_experiment_equals_inverse_receptance_with_everything_on() -> None:
    rotor, ctrl = spinning(), full_controller()
    axes = [chain(), chain(amp_bandwidth=1200.0), chain(dead_time=0.4 / FS), chain()]
    L = 100  # fs 4000 Hz, f0 40 Hz
    n, lines = np.arange(L), np.arange(1, 50)
    s = np.cos(2 * np.pi * np.outer(n, lines) / L - np.pi * lines * (lines - 1) / lines.size).sum(axis=1)
    # the slowest pole decays 5.2 Hz (|z| = 0.9918): 45 periods (1.1 s) take it below 1e-12
    freq, H = experiment(rotor, axes, ctrl, s, periods=2, settle=45)
    np.testing.assert_allclose(freq, lines * FS / L, rtol=1e-15)
    expected = np.linalg.inv(receptance(rotor, axes, ctrl, freq))
    assert np.abs(H - expected).max() < 1e-9 * np.abs(expected).max()
    np.testing.assert_allclose(H, expected, rtol=1e-9, atol=0)


def test_simulated_impulse_response_is_the_closed_loop_matrix() -> None:
    # The loop and the matrix are independent paths: equal Markov parameters mean the eigenvalues of
    # the matrix (loop_eigenvalues) are the poles of what simulate computes.
    rotor, axes, ctrl = spinning(), [chain(), chain(), chain(dead_time=2.6 / FS), chain()], full_controller()
    Ad, Bd, Cd, Dd, fs = closed_loop(rotor, axes, ctrl)
    assert fs == FS
    steps = 300
    for j in (0, 3):
        force = np.zeros((steps, 4))
        force[0, j] = 1.0
        recorded, probe = simulate(rotor, axes, ctrl, force)
        X = Bd[:, j].copy()
        expected = [Dd[:, j]]
        for _ in range(steps - 1):
            expected.append(Cd @ X)
            X = Ad @ X
        expected_arr = np.array(expected)
        np.testing.assert_allclose(probe, expected_arr[:, :4], rtol=0, atol=1e-12 * np.abs(probe).max())
        np.testing.assert_allclose(recorded, expected_arr[:, 4:], rtol=0, atol=1e-12)
    z = loop_eigenvalues(rotor, axes, ctrl)
    rho = np.abs(z).max()
    assert 0.9 < rho < 1.0
    # and the late impulse response decays at the slowest pole's rate (within 20 % over 2000 samples)
    force = np.zeros((6000, 4))
    force[0, 0] = 1.0
    _, probe = simulate(rotor, axes, ctrl, force)
    late = np.abs(probe[4000:4400]).max() / np.abs(probe[2000:2400]).max()
    assert abs(np.log(late) / (2000 * np.log(rho)) - 1) < 0.2


def test_free_rotor_whirl_splits_as_the_characteristic_equation() -> None:
    # Springs k at both bearings (kyy = k > 0, no current), zA = -zB = a: translation w_t = sqrt(2k/m);
    # tilt with k_theta = 2 k a^2: (It s^2 + k_theta)^2 + (Ip W s)^2 = 0, i.e. It s^2 + k_theta = +-j Ip W s;
    # s = j w gives It w^2 -+ Ip W w - k_theta = 0, so w = (+-Ip W + sqrt(Ip^2 W^2 + 4 It k_theta)) / (2 It):
    # forward whirl (same sense as the spin) with +, rising with W; backward with -, falling.
    m, It, Ip, a, k = 10.0, 0.35, 0.15, 0.2, 1e5
    spring = af.Rig(kyy=k)
    k_theta = 2 * k * a**2
    for W in (0.0, 500.0, 3000.0):
        rotor = RotorParams(mass=m, It=It, Ip=Ip, bearings=(a, -a), sensors=(0.25, -0.25), speed=W)
        A, _, names = continuous_plant(rotor, [spring] * 4)
        assert names == ["x", "y", "tx", "ty", "vx", "vy", "wx", "wy"]
        root = np.sqrt((Ip * W) ** 2 + 4 * It * k_theta)
        forward, backward = (Ip * W + root) / (2 * It), (-Ip * W + root) / (2 * It)
        expected = np.sort([np.sqrt(2 * k / m)] * 2 + [forward, backward])
        values, vectors = np.linalg.eig(A)
        assert np.abs(values.real).max() < 1e-9 * np.abs(values).max()
        upper = values.imag > 0
        np.testing.assert_allclose(np.sort(values.imag[upper]), expected, rtol=1e-12)
        if W == 0:
            continue
        for w, sense in ((forward, 1), (backward, -1)):
            v = vectors[:, np.argmin(np.abs(values - 1j * w))]
            X, Y = v[0] + a * v[3], v[1] - a * v[2]  # displacement at bearing A for e^{jwt}
            fwd, bwd = abs(X + 1j * Y), abs(X - 1j * Y)  # counter-clockwise (x -> y) and clockwise parts
            assert (bwd if sense > 0 else fwd) < 1e-9 * (fwd if sense > 0 else bwd)
            # the classifier the loop's modes use agrees, for the mode and its conjugate
            pair = np.column_stack([v[:4], v[:4].conj()])
            _, direction = whirl_direction(rotor, pair, np.array([w, -w]))
            np.testing.assert_array_equal(direction, [sense, sense])


def test_hadamard_rows_and_rigid_body_map() -> None:
    np.testing.assert_array_equal(HADAMARD @ HADAMARD.T, 4 * np.eye(4))
    rotor = spinning()
    q = np.array([1e-5, -2e-5, 3e-4, -1e-4])
    probes = np.array([q[0] + 0.23 * q[3], q[1] - 0.23 * q[2], q[0] - 0.21 * q[3], q[1] + 0.21 * q[2]])
    bearings = np.array([q[0] + 0.2 * q[3], q[1] - 0.2 * q[2], q[0] - 0.18 * q[3], q[1] + 0.18 * q[2]])
    np.testing.assert_allclose(rigid_body_map(rotor) @ probes, bearings, rtol=1e-12, atol=0)


def test_bad_input_is_refused() -> None:
    rotor = spinning()
    rotor.sensors = (0.1, 0.1)
    with pytest.raises(ValueError, match="sensors"):
        rigid_body_map(rotor)
    with pytest.raises(ValueError, match="4x4"):
        receptance(spinning(), [chain()] * 4, [[pid()]], [10.0])
    with pytest.raises(ValueError, match="axes"):
        continuous_plant(spinning(), [chain()] * 3)


def test_bearing_matrices_give_the_springs_back_from_the_plant() -> None:
    # The free rotor on springs kyy at the bearings (no lags, no mass loading): the continuous dynamic
    # stiffness in bearing coordinates is -w^2 Mb + j w W Gb + diag(kyy), so the actual coefficients of
    # its inverse receptance are K = diag(kyy), C = 0.
    rotor = spinning()
    rotor.process = []
    springs = [af.Rig(kyy=k) for k in (1e5, 2e5, 3e5, 4e5)]
    A, B, _ = continuous_plant(rotor, springs)
    Bm = np.array([[1, 0, 0, 0.2], [0, 1, -0.2, 0], [1, 0, 0, -0.18], [0, 1, 0.18, 0]])
    freq = np.array([3.0, 30.0, 300.0])
    H = np.array([np.linalg.inv(Bm @ np.linalg.solve(2j * np.pi * f * np.eye(8) - A, B[:, :4])[:4]) for f in freq])
    K, C = actual_coefficients(rotor, freq, H)
    np.testing.assert_allclose(K, np.broadcast_to(np.diag([1e5, 2e5, 3e5, 4e5]), K.shape), rtol=0, atol=1e-6)
    np.testing.assert_allclose(C, 0, atol=1e-9)
    Mb, Gb = bearing_matrices(rotor)
    np.testing.assert_allclose(Mb, Mb.T, rtol=1e-14, atol=0)
    np.testing.assert_allclose(Gb, -Gb.T, rtol=1e-14, atol=0)


def test_loop_modes_of_an_isotropic_spinning_rotor_are_circular() -> None:
    # Identical axes, a diagonal controller and no process: the loop is isotropic, so every mode whirls
    # on a circle at each bearing (one of |X + jY|, |X - jY| is 0); conjugate modes have one direction.
    rotor = RotorParams(mass=10.0, It=0.35, Ip=0.3, bearings=(0.2, -0.18), sensors=(0.23, -0.21), speed=600.0)
    z, shapes, direction = loop_modes(rotor, [chain()] * 4, diagonal(pid()))
    np.testing.assert_allclose(z, loop_eigenvalues(rotor, [chain()] * 4, diagonal(pid())), rtol=0, atol=1e-12)
    moving = direction != 0
    assert moving.sum() > 20 and set(direction[moving]) == {-1, 1}
    X, Y = shapes[:, [0, 2]], shapes[:, [1, 3]]
    ccw, cw = np.linalg.norm(X + 1j * Y, axis=1), np.linalg.norm(X - 1j * Y, axis=1)
    assert (np.minimum(ccw, cw) / np.maximum(ccw, cw))[moving].max() < 1e-5
    for k in np.flatnonzero(moving):
        partner = np.argmin(np.abs(z - z[k].conj()))
        assert direction[partner] == direction[k]
