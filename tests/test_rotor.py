"""The rigid rotor on two bearings (N = 4) against independent answers: the one-axis model where the rotor
splits into two independent masses, the equations of motion written out here, exact experiments."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast.system import _model

PID = af.RotorRig.example_controller()
SPHS = af.schroeder_multisine(f0=20.0, f_max=400.0)  # 200-sample periods: quick
CHAIN = af.Rig(amp_bandwidth=3000.0, eddy_bandwidth=2000.0, sensor_bandwidth=10_000.0, mass_loading=0.06,
               force_coupling_tau=1.0, dead_time=0.3e-3)  # fmt: skip


def split_rotor(speed: float = 0.0, Ip: float = 0.0) -> af.RigidRotor:
    """Bearings at +-a with It = m a^2: in bearing coordinates the rotor is two masses m/2, uncoupled."""
    m, a = 10.0, 0.2
    return af.RigidRotor(m, m * a**2, Ip, bearings=(-a, a), sensors=(-a, a), speed=speed)


def test_a_rotor_that_splits_into_two_masses_is_four_one_axis_rigs() -> None:
    """Sensors at the bearings, It = m a^2, no spin: each axis is the one-axis rig of mass m/2 (the one-axis
    model, a separate code path through the C++ core), and nothing couples the axes."""
    rig = af.RotorRig(split_rotor(), CHAIN)
    freq = SPHS.harmonics * SPHS.f0
    R = af.predict(rig, PID, freq)
    one = af.predict(replace(CHAIN, mass=5.0), PID, freq)
    for j in range(4):
        np.testing.assert_allclose(R[:, j, j], one, rtol=1e-9)
    off = R[:, ~np.eye(4, dtype=bool)]
    assert np.max(np.abs(off)) < 1e-12 * np.max(np.abs(one))
    # Its actual coefficients remove the rotor's mass at the bearings (m/2 each): the one-axis estimate's.
    est = af.run_experiment(rig, PID, SPHS, periods=3)
    one_est = af.run_experiment(replace(CHAIN, mass=5.0), PID, SPHS, periods=3)
    for j in range(4):
        np.testing.assert_allclose(est.k[:, j, j], one_est.k, rtol=1e-8)
        np.testing.assert_allclose(est.c[:, j, j], one_est.c, rtol=1e-8)


def test_plant_is_the_equations_of_motion() -> None:
    """The continuous plant's rotor rows equal M^-1 of the equations written out here (no chain stages)."""
    rotor = af.RigidRotor(8.0, 0.3, 0.05, bearings=(-0.15, 0.25), sensors=(-0.2, 0.3), speed=700.0,
                          process=[(0.05, 2e3, -2e3, 10.0, -10.0)])  # fmt: skip
    kyy, kiy = -4e4, 40.0
    rig = af.RotorRig(rotor, af.Rig(kyy=kyy, kiy=kiy))
    A, B, layout = _model.plant(rig)
    pos, vel = list(layout.position), list(layout.velocity)
    m, It, Ip, W = 8.0, 0.3, 0.05, 700.0
    M = np.diag([m, m, It, It])

    # Forces (Fx, Fy) at z act as Qx = Fx, Qy = Fy, Qtx = -z Fy, Qty = z Fx; d(z) = (x + z ty, y - z tx).
    def Q(z: float) -> np.ndarray:  # (4, 2): generalized forces of (Fx, Fy) at z
        return np.array([[1, 0], [0, 1], [0, -z], [z, 0]], dtype=float)

    Kq = np.zeros((4, 4))
    for z in (-0.15, 0.25):
        Kq += Q(z) @ (kyy * np.eye(2)) @ Q(z).T  # -kyy d at the bearing, d = Q(z)^T q
    Kq += Q(0.05) @ np.array([[0, 2e3], [-2e3, 0]]) @ Q(0.05).T
    Cq = Q(0.05) @ np.array([[0, 10.0], [-10.0, 0]]) @ Q(0.05).T
    Cq[2, 3] += Ip * W  # It tx'' + Ip W ty'
    Cq[3, 2] -= Ip * W  # It ty'' - Ip W tx'
    np.testing.assert_allclose(A[np.ix_(vel, pos)], -np.linalg.solve(M, Kq), rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(A[np.ix_(vel, vel)], -np.linalg.solve(M, Cq), rtol=1e-12, atol=1e-12)
    forces = np.hstack([Q(-0.15), Q(0.25)])  # shaker columns A.x, A.y, B.x, B.y
    np.testing.assert_allclose(B[vel, :4], np.linalg.solve(M, forces), rtol=1e-12)
    np.testing.assert_allclose(B[vel, 4:], -kiy * np.linalg.solve(M, forces), rtol=1e-12)


@pytest.mark.parametrize("start", ["steady", "rest"])
def test_noise_free_experiment_equals_predict_with_speed_lags_and_non_collocated_probes(start: str) -> None:
    rotor = replace(af.RotorRig.example().rotor, speed=900.0, process=((0.1, 3e3, -3e3, 0.0, 0.0),))
    axes = [CHAIN, replace(CHAIN, amp_bandwidth=2500.0), replace(CHAIN, dead_time=0.1e-3), CHAIN]
    rig = af.RotorRig(rotor, axes)
    est = af.run_experiment(rig, PID, SPHS, periods=3, start=start)
    R = af.predict(rig, PID, est.freq)
    np.testing.assert_allclose(est.receptance, R, rtol=0, atol=1e-9 * np.max(np.abs(R)))
    np.testing.assert_allclose(est.H, np.linalg.inv(R), rtol=0, atol=1e-9 * np.max(np.abs(est.H)))


def test_standstill_symmetric_rotor_decouples_x_and_y() -> None:
    rig = af.RotorRig.example()
    R = af.predict(rig, PID, SPHS.harmonics * SPHS.f0)
    x, y = [0, 2], [1, 3]
    assert np.max(np.abs(R[:, x][:, :, y])) < 1e-13 * np.max(np.abs(R))
    assert np.max(np.abs(R[:, y][:, :, x])) < 1e-13 * np.max(np.abs(R))
    spinning = af.predict(rig.at_speed(2000.0), PID, SPHS.harmonics * SPHS.f0)
    assert np.max(np.abs(spinning[:, x][:, :, y])) > 1e-3 * np.max(np.abs(spinning))  # gyroscopics couple them


def test_actual_coefficients_remove_the_known_rotor() -> None:
    """k + j w c = H + w^2 Mb - j w W Gb: with the exact H of predict, Mb and Gb written out here."""
    rig = af.RotorRig(af.RotorRig.example(speed=1500.0).rotor, CHAIN)
    est = af.run_experiment(rig, PID, SPHS, periods=3)
    rotor = rig.rotor
    zA, zB = rotor.bearings
    # Bearing-plane displacements d = T q; T rows: A.x = x + zA ty, A.y = y - zA tx, ...
    T = np.array([[1, 0, 0, zA], [0, 1, -zA, 0], [1, 0, 0, zB], [0, 1, -zB, 0]], dtype=float)
    Ti = np.linalg.inv(T)
    Mb = Ti.T @ np.diag([rotor.mass, rotor.mass, rotor.transverse_inertia, rotor.transverse_inertia]) @ Ti
    G = np.zeros((4, 4))
    G[2, 3], G[3, 2] = rotor.polar_inertia, -rotor.polar_inertia
    Gb = Ti.T @ G @ Ti
    w = 2 * np.pi * est.freq[:, None, None]
    H = np.linalg.inv(af.predict(rig, PID, est.freq))
    expected = H + w**2 * Mb - 1j * w * rotor.speed * Gb
    np.testing.assert_allclose(est.k, expected.real, rtol=0, atol=1e-8 * np.max(np.abs(expected)))
    np.testing.assert_allclose(est.c * w, expected.imag, rtol=0, atol=1e-8 * np.max(np.abs(expected)))


def test_campbell_poles_whirl_and_onset() -> None:
    rig = af.RotorRig.example()
    speeds = np.array([0.0, 1000.0, 3000.0])
    c = af.campbell(rig, PID, speeds)
    for i, W in enumerate(speeds):
        M = _model.loop_model(rig.at_speed(W), PID).M
        expected = np.linalg.eigvals(M)
        assert np.max(np.min(np.abs(c.z[i][:, None] - expected[None, :]), axis=1)) < 1e-9
    np.testing.assert_allclose(c.frequency, np.abs(np.log(c.z).imag) * 4000.0 / (2 * np.pi), rtol=1e-12)
    assert c.onset_speed is None
    # The conical mode splits with speed: backward whirl falls, forward whirl rises (gyroscopic stiffening).
    conical = (c.whirl != 0) & (c.damping < 0.9) & (c.frequency > 25.0) & (c.frequency < 80.0)
    forward = [c.frequency[i][conical[i] & (c.whirl[i] > 0)] for i in range(3)]
    backward = [c.frequency[i][conical[i] & (c.whirl[i] < 0)] for i in range(3)]
    assert forward[0].min() == pytest.approx(backward[0].min(), rel=1e-9)  # standstill: one and the other
    assert forward[2].min() > forward[1].min() > forward[0].min()
    assert backward[2].size == 0 or backward[2].max() < backward[0].max()


def test_campbell_reports_instability_and_runs_name_the_speed() -> None:
    """A destabilising cross-coupled process (kxy = -kyx beyond what the bearings' damping holds, about
    2 c w = 2 (47.19 * 10) (2 pi 20) = 120 kN/m at the centre): unstable at every speed; the diagram says
    from which speed given, and an experiment refuses it naming the speed."""
    rotor = replace(af.RotorRig.example().rotor, process=((0.0, 3e5, -3e5, 0.0, 0.0),))
    rig = af.RotorRig(rotor, af.Rig.paper())
    c = af.campbell(rig, PID, [100.0, 200.0])
    assert c.onset_speed == 100.0 and np.all(np.abs(c.z).max(axis=1) > 1.0)
    with pytest.raises(af.UnstableLoopError, match="at speed 200 rad/s"):
        af.run_experiment(rig.at_speed(200.0), PID, SPHS)
    stable = af.campbell(af.RotorRig.example(), PID, [100.0, 200.0])
    assert stable.onset_speed is None


def test_bad_rotors_are_refused_naming_the_value() -> None:
    with pytest.raises(ValueError, match="bearings"):
        af.RigidRotor(10.0, 0.2, 0.01, bearings=(0.1, 0.1))
    with pytest.raises(ValueError, match="sensors"):
        af.RigidRotor(10.0, 0.2, 0.01, sensors=(0.0, 0.0))
    with pytest.raises(ValueError, match="polar_inertia"):
        af.RigidRotor(10.0, 0.2, 0.5)
    with pytest.raises(ValueError, match="transverse_inertia"):
        af.RigidRotor(10.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="mass"):
        af.RigidRotor(-1.0, 0.2, 0.0)
    with pytest.raises(ValueError, match="axes"):
        af.RotorRig(split_rotor(), [af.Rig()] * 3)
    with pytest.raises(ValueError, match="controller"):
        af.predict(af.RotorRig(split_rotor()), [PID, PID], [10.0])
    with pytest.raises(ValueError, match="controller"):
        af.predict(af.RotorRig(split_rotor()), [[PID] * 4] * 3, [10.0])
    with pytest.raises(ValueError, match="speeds"):
        af.campbell(af.RotorRig.example(), PID, [0.0, np.nan])


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_nxn_estimator_is_the_formula(n: int) -> None:
    """The core's N x N estimate against the formula in numpy: H = F Y^-1 of the period means, variances of
    the linearised dH = (dF - H dY) Y^-1 summed over periods / (P (P - 1)); for N = 2 also the 2x2 core's."""
    rng = np.random.default_rng(n)
    shape = (6, 5, n, n)
    Fp = rng.standard_normal(shape) + 1j * rng.standard_normal(shape) + 3 * np.eye(n)
    Yp = rng.standard_normal(shape) + 1j * rng.standard_normal(shape) + 3 * np.eye(n)
    H, R, F, Y, var_re, var_im = af._core.estimate_nxn(Fp, Yp)
    Fm, Ym = Fp.mean(axis=0), Yp.mean(axis=0)
    Hm = Fm @ np.linalg.inv(Ym)
    dH = ((Fp - Fm) - Hm @ (Yp - Ym)) @ np.linalg.inv(Ym)
    np.testing.assert_allclose(H, Hm, rtol=1e-12)
    np.testing.assert_allclose(R, np.linalg.inv(Hm), rtol=1e-12)
    np.testing.assert_allclose(F, Fm, rtol=1e-14)
    np.testing.assert_allclose(var_re, (dH.real**2).sum(axis=0) / 30, rtol=1e-12)
    np.testing.assert_allclose(var_im, (dH.imag**2).sum(axis=0) / 30, rtol=1e-12)
    if n == 2:
        for got, expected in zip(af._core.estimate_2x2(Fp, Yp), (H, R, F, Y, var_re, var_im)):
            np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_bearing_views_and_ross_elements() -> None:
    """est.bearing("A") is the A.x, A.y block of every matrix; to_ross gives one element per bearing holding
    it, and warns that the cross-bearing entries (non-collocated probes) cannot go into ROSS's element."""
    rig = af.RotorRig.example(speed=500.0)
    est = af.run_experiment(rig, PID, SPHS, periods=3, seed=4)
    for name, rows in (("A", [0, 1]), ("B", [2, 3])):
        view = est.bearing(name)
        np.testing.assert_array_equal(view.k, est.k[:, rows][:, :, rows])
        np.testing.assert_array_equal(view.c_std, est.c_std[:, rows][:, :, rows])
    with pytest.raises(ValueError, match="bearing"):
        est.bearing("C")
    with warnings.catch_warnings():  # ROSS's import warns about an unrelated optional library
        warnings.simplefilter("ignore")
        pytest.importorskip("ross")
    with pytest.warns(UserWarning, match="cross-bearing"):
        elements = est.to_ross((0, 4))
    omega = 2 * np.pi * est.freq
    for element, rows in zip(elements, ([0, 1], [2, 3])):
        for j in (0, 5, 9):
            np.testing.assert_allclose(element.K(omega[j])[:2, :2], est.k[j][np.ix_(rows, rows)], rtol=1e-12)
            np.testing.assert_allclose(element.C(omega[j])[:2, :2], est.c[j][np.ix_(rows, rows)], rtol=1e-12)
    assert [e.n for e in elements] == [0, 4]


def test_sweep_over_speed_gains_and_an_axis_field() -> None:
    """af.sweep takes a RotorRig: parameter paths (speed, a PID gain, one axis' field); every point equals
    run_experiment of that point bit for bit; unstable points are NaN and flagged."""
    rig = af.RotorRig.example()
    result = af.sweep(rig, PID, SPHS, speed=[0.0, 2000.0], kd=[10.0, 0.5], periods=3, seed=3, progress=False)
    assert result.k.shape == (4, SPHS.freq.size, 4, 4) and result.axes == ("A.x", "A.y", "B.x", "B.y")
    np.testing.assert_array_equal(result.stable, [True, False, True, False])  # kd = 0.5 A s/m: too little damping
    assert np.isnan(result.k[1]).all()
    for i in (0, 2):
        point = {name: float(values[i]) for name, values in result.params.items()}
        est = af.run_experiment(*af.system.point_model(rig, PID, point), SPHS, periods=3, seed=int(result.seeds[i]))
        np.testing.assert_array_equal(est.k, result.k[i])
    one = af.sweep(rig, PID, SPHS, periods=3, seed=1, progress=False, **{"B.y.amp_bandwidth": [1500.0]})
    changed = af.system.point_model(rig, PID, {"B.y.amp_bandwidth": 1500.0})[0]
    assert changed.axes[3].amp_bandwidth == 1500.0 and changed.axes[0].amp_bandwidth == rig.axes[0].amp_bandwidth
    assert one.stable.all()
    with pytest.raises(ValueError, match="sweep axis"):
        af.sweep(rig, PID, SPHS, C_x_kp=[1.0])


def test_unbalance_response_is_an_orbit_of_the_continuous_loop() -> None:
    """The synchronous response is exact at the sample instants: started on it, the continuous plant
    integrated with fine RK4 steps under the rotating force (continuous, not held) and the digital
    controller acting at the samples stays on it (to the integrator's error), for 200 samples."""
    rotor = replace(af.RotorRig.example().rotor, speed=0.0)
    rig = af.RotorRig(rotor, af.Rig(amp_bandwidth=3000.0))
    W, me, z = 700.0, 2e-4, 0.12
    result = af.unbalance_response(rig, PID, [W], [(me, z, 0.3)])
    system = rig.at_speed(W)
    A, B, layout = _model.plant(system)
    loop = _model.loop_model(system, PID)
    n = A.shape[0]
    # The digital side read back from the closed loop [[Phi + Gu Dc S, Gu Cc], [Bc S, Ac]]: the controller's
    # update x_c' = Mcp x_p + Mcc x_c, and its commands u = U [x_p; x_c] (Gu has full column rank).
    Mcp, Mcc = loop.M[n:, :n], loop.M[n:, n:]
    Phi, Gamma, _ = _model.discrete_plant(system, 4000.0)
    U = np.linalg.lstsq(Gamma[:, 4:], loop.M[:n, :] - np.hstack([Phi, np.zeros((n, Mcc.shape[0]))]), rcond=None)[0]
    m = np.diag([rotor.mass] * 2 + [rotor.transverse_inertia] * 2)
    P = np.array([[1, 0, 0, z], [0, 1, -z, 0]], dtype=float)
    phase = np.exp(0.3j)

    def rhs(t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        force = me * W**2 * np.real(np.array([1.0, -1j]) * phase * np.exp(1j * W * t))
        extra = np.zeros(n)
        extra[list(layout.velocity)] = np.linalg.solve(m, P.T @ force)
        return A @ x + B[:, 4:] @ u + extra

    X = result.states[0]
    state = np.real(X)
    T, steps = 1 / 4000.0, 100
    h = T / steps
    worst = 0.0
    for k in range(200):
        u = U @ state
        x, xc = state[:n].copy(), state[n:]
        t = k * T
        for _ in range(steps):
            k1 = rhs(t, x, u)
            k2 = rhs(t + h / 2, x + h / 2 * k1, u)
            k3 = rhs(t + h / 2, x + h / 2 * k2, u)
            k4 = rhs(t + h, x + h * k3, u)
            x, t = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + h
        state = np.concatenate([x, Mcp @ state[:n] + Mcc @ xc])
        expected = np.real(X * np.exp(1j * W * T * (k + 1)))
        worst = max(worst, float(np.max(np.abs(loop.C[:4] @ (state - expected)))))
    assert worst < 1e-6 * np.max(np.abs(result.probes))
    # A held force in place of the rotating one would leave the orbit at once: the test can tell.
    assert np.max(np.abs(result.probes)) > 1e-7


def test_unbalance_bad_input_names_the_value() -> None:
    rig = af.RotorRig.example()
    with pytest.raises(ValueError, match="unbalance\\[0\\] plane"):
        af.unbalance_response(rig, PID, [100.0], [(1e-4, 5.0, 0.0)])
    with pytest.raises(ValueError, match="speeds"):
        af.unbalance_response(rig, PID, [100.0, np.inf], [(1e-4, 0.0, 0.0)])
    with pytest.raises(ValueError, match="unbalance"):
        af.unbalance_response(rig, PID, [100.0], [])
    unstable = af.RotorRig(replace(rig.rotor, process=((0.0, 3e5, -3e5, 0.0, 0.0),)), rig.axes)
    with pytest.raises(af.UnstableLoopError, match="at speed 100 rad/s"):
        af.unbalance_response(unstable, PID, [100.0], [(1e-4, 0.0, 0.0)])


def test_campbell_batched_loops_are_the_loop_models() -> None:
    """Without dead time the Campbell diagram discretises all speeds in one batched exponential; each speed's
    loop equals loop_model's to rounding, and with a dead time it is loop_model's."""
    from amb_fast.system import _campbell, _control

    spec = _control.controller_matrix(PID, 4)
    for rig in (af.RotorRig.example(), af.RotorRig(af.RotorRig.example().rotor, CHAIN)):
        speeds = np.array([0.0, 1234.5, 6000.0])
        stack = _campbell.speed_loops(rig, spec, speeds, loops=True)[3]
        for M, W in zip(stack, speeds):
            expected = _model.loop_model(rig.at_speed(W), spec).M
            np.testing.assert_allclose(M, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def test_a_rotor_file_reads_as_toml_or_json(tmp_path) -> None:  # noqa: ANN001
    """load_rotor reads a file as the package's other files (read_table): the same tables in JSON give the same
    rig, and every error names the file (issue 26: the rotor file's own reader is gone)."""
    toml, json = tmp_path / "rotor.toml", tmp_path / "rotor.json"
    toml.write_text("[rotor]\nmass = 12.0\nprocess = [[0.1, 3e3, -3e3, 0.0, 0.0]]\n[controller]\nkd = 12.0\n")
    json.write_text('{"rotor": {"mass": 12.0, "process": [[0.1, 3e3, -3e3, 0.0, 0.0]]}, "controller": {"kd": 12.0}}')
    rig, pid = af.system.load_rotor(toml)
    assert (rig, pid) == af.system.load_rotor(json)
    assert rig.rotor.process == ((0.1, 3e3, -3e3, 0.0, 0.0),) and rig.rotor.mass == 12.0 and pid.kd == 12.0
    assert rig.rotor.transverse_inertia == af.RotorRig.example().rotor.transverse_inertia
    with pytest.raises(ValueError, match=r"rotor file '.*rotor\.txt': path must end in \.toml or \.json"):
        af.system.load_rotor(tmp_path / "rotor.txt")
