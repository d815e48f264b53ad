"""Flexible rotors from ROSS (issue 27, part 5): the reduction against ROSS's own modal analysis, its rigid
body against the rigid rotor, the loop's functions on it, and bad input."""

from __future__ import annotations

import sys
import warnings
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

import amb_fast as af

with warnings.catch_warnings():  # ROSS's import warns about an unrelated optional library
    warnings.simplefilter("ignore")
    rs = pytest.importorskip("ross")

SPRING = 1e6  # N/m: the example's ROSS bearings (kxx = kyy, no damping)
BEARINGS, SENSORS = (4, 26), (3, 27)


@pytest.fixture(scope="module")
def ross_rotor():  # noqa: ANN201 - a ross.Rotor
    return af.FlexibleRotor.example_ross()


def ross_lateral_frequencies(rotor, speed: float) -> np.ndarray:  # noqa: ANN001
    """ROSS's run_modal frequencies (rad/s, ascending) of the modes that move the lateral dofs (not its axial
    or torsional ones): ``wd`` at speed, ``wn`` at standstill (undamped: the same)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        modal = rotor.run_modal(speed=speed, num_modes=2 * rotor.ndof, sparse=False)
    width = rotor.number_dof
    lateral = [width * n + o for n in range(len(rotor.nodes)) for o in (0, 1, 3, 4)]
    vectors = modal.evectors[: rotor.ndof]
    share = np.linalg.norm(vectors[lateral], axis=0) / np.linalg.norm(vectors, axis=0)
    wd = np.abs(modal.wd)
    return np.sort(wd[share[: wd.size] > 0.5])


def reduced_frequencies(flexible: af.FlexibleRotor, speed: float) -> np.ndarray:
    """The reduced model's undamped frequencies (rad/s, ascending) on springs SPRING at its bearing nodes."""
    mech = flexible.mechanics()
    A = mech.actuators
    K, M, G = flexible.modal_stiffness + SPRING * A.T @ A, flexible.modal_mass, speed * flexible.modal_gyroscopic
    n = K.shape[0]
    state = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, G)]])
    s = scipy.linalg.eigvals(state)
    return np.sort(np.abs(s.imag[s.imag > 0]))


@pytest.mark.parametrize("speed", [0.0, 1500.0])
def test_all_modes_kept_are_ross_run_modal(ross_rotor, speed: float) -> None:  # noqa: ANN001
    """With every bending mode kept the reduction is a change of coordinates: on the same springs the
    natural frequencies are ROSS's run_modal ones (standstill and spinning: the gyroscopic projection and its
    sign) to 1e-6 (measured 6e-11 at standstill)."""
    modes = 2 * len(ross_rotor.nodes) - 2
    flexible = af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=modes)
    mine, theirs = reduced_frequencies(flexible, speed)[:10], ross_lateral_frequencies(ross_rotor, speed)[:10]
    np.testing.assert_allclose(mine, theirs, rtol=1e-6)


def test_truncation_converges_from_above(ross_rotor) -> None:  # noqa: ANN001
    """Fewer modes: a Ritz projection, every frequency above ROSS's and closer with more modes kept. What the
    truncation loses is the static flexibility of the modes left out: on 1e6 N/m springs the lowest eight
    frequencies are within 7.1e-4 with 4 modes, 7.7e-5 with 8, 3.4e-6 with 30 (of 60)."""
    theirs = ross_lateral_frequencies(ross_rotor, 0.0)[:8]
    previous = np.inf
    for modes, bound in ((4, 7.1e-4), (8, 7.7e-5), (30, 3.4e-6)):
        flexible = af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=modes)
        error = reduced_frequencies(flexible, 0.0)[:8] / theirs - 1
        assert np.all(error > -1e-9) and error.max() < bound and error.max() < previous
        previous = error.max()


def test_rigid_body_is_ross_mass_and_the_rigid_rotor(ross_rotor) -> None:  # noqa: ANN001
    """The rigid-body block is ROSS's mass and transverse inertia, decoupled from the bending modes; with no
    bending mode kept the model is the RigidRotor of that mass, It, Ip and planes, to round-off."""
    flexible = af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=8)
    m, It = ross_rotor.m, ross_rotor.It
    M = flexible.modal_mass
    np.testing.assert_allclose(np.diag(M)[:4], [m, m, It, It], rtol=1e-12)
    assert np.abs(M[:4, 4:]).max() < 1e-12 * m and np.abs(M[4:, 4:] - np.eye(16)).max() < 1e-12
    assert np.abs(flexible.modal_stiffness[:4]).max() == 0.0
    rigid_only = af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=0)
    Ip = rigid_only.modal_gyroscopic[2, 3]
    disks = ross_rotor.disk_elements
    shaft = (m - sum(d.m for d in disks)) * 0.02**2 / 2  # the solid shaft, 40 mm across: m r^2 / 2
    np.testing.assert_allclose(Ip, sum(d.Ip for d in disks) + shaft, rtol=1e-12)
    z = rigid_only.positions
    rigid = af.RigidRotor(m, It, Ip, bearings=(z[4], z[26]), sensors=(z[3], z[27])).mechanics()
    mine = rigid_only.mechanics()
    for name in ("mass", "gyroscopic", "actuators", "probes", "readout"):
        np.testing.assert_allclose(getattr(mine, name), getattr(rigid, name), rtol=0, atol=1e-12, err_msg=name)
    rig, pid = af.RotorRig(rigid_only, af.Rig.paper()), af.RotorRig.example_controller()
    f = np.array([5.0, 50.0, 500.0])
    R, Rr = af.predict(rig, pid, f), af.predict(af.RotorRig(replace(rig.rotor), af.Rig.paper()), pid, f)
    np.testing.assert_array_equal(R, Rr)  # equal rotors, equal models (hash and == by value)
    expected = af.predict(af.RotorRig(af.RigidRotor(m, It, Ip, (z[4], z[26]), (z[3], z[27])), af.Rig.paper()), pid, f)
    np.testing.assert_allclose(R, expected, rtol=1e-9)


def test_the_loop_runs_on_a_flexible_rotor() -> None:
    """Every rotor function takes a RotorRig of a FlexibleRotor: the noise-free experiment is predict and its
    k, c remove the flexible rotor's own dynamic stiffness; Campbell, the ISO sensitivity and the unbalance
    response run (the example holds under the example controller, spinning too)."""
    flexible = af.FlexibleRotor.example(modes=3, speed=500.0)
    rig = af.RotorRig(flexible, af.Rig(amp_bandwidth=3000.0, sensor_bandwidth=10_000.0))
    pid = af.RotorRig.example_controller()
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    est = af.run_experiment(rig, pid, sphs, periods=3)
    R = af.predict(rig, pid, est.freq)
    np.testing.assert_allclose(est.receptance, R, rtol=0, atol=1e-9 * np.max(np.abs(R)))
    mech = flexible.mechanics()
    A, w = mech.actuators, 2 * np.pi * est.freq[:, None, None]
    D = mech.elastic - w**2 * mech.mass + 1j * w * (mech.elastic_damping + flexible.speed * mech.gyroscopic)
    own = np.linalg.inv(A @ np.linalg.solve(D, A.T)) @ np.linalg.inv(mech.readout @ mech.reads)
    np.testing.assert_allclose(est.k + 1j * w * est.c, est.H - own, rtol=0, atol=1e-9 * np.max(np.abs(est.H)))
    campbell = af.campbell(rig, pid, [0.0, 1000.0, 2000.0])
    assert campbell.onset_speed is None and np.any(campbell.whirl == 1) and np.any(campbell.whirl == -1)
    sensitivity = af.measure_sensitivity(rig, pid, af.schroeder_multisine(f0=4.0, f_max=1000.0, rms=1e-6))
    assert np.all(np.isfinite(sensitivity.peak)) and set(sensitivity.zone) <= {"A", "B"}
    disk = flexible.positions[8]
    response = af.unbalance_response(rig, pid, np.linspace(50.0, 1000.0, 20), [(1e-4, disk, 0.0)])
    assert response.probes.shape == (20, 4) and np.all(np.abs(response.probes) > 0)
    result = af.sweep(rig, pid, sphs, speed=[0.0, 800.0], periods=2, workers=1)
    assert result.stable.all()


def test_bad_input_names_the_value(ross_rotor) -> None:  # noqa: ANN001
    with pytest.raises(ValueError, match=r"bearings\[1\] must be a node of the rotor \(0 .. 30\), got 31"):
        af.FlexibleRotor.from_ross(ross_rotor, (4, 31), SENSORS, modes=2)
    with pytest.raises(ValueError, match=r"sensors must be two different nodes .*got \(3, 3\)"):
        af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, (3, 3), modes=2)
    with pytest.raises(ValueError, match=r"modes must be at most 60 .*got 61"):
        af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=61)
    with pytest.raises(ValueError, match=r"rotor must be a ross.Rotor, got 'RigidRotor'"):
        af.FlexibleRotor.from_ross(af.RotorRig.example().rotor, BEARINGS, SENSORS, modes=2)
    with pytest.raises(ValueError, match=r"rotor must be a rotor .*got 'Rig'"):
        af.RotorRig(af.Rig.paper())
    flexible = af.FlexibleRotor.from_ross(ross_rotor, BEARINGS, SENSORS, modes=2)
    rig = af.RotorRig(flexible, af.Rig.paper())
    with pytest.raises(ValueError, match=r"unbalance\[0\] plane must be a node's axial position .*got 0.01"):
        af.unbalance_response(rig, af.RotorRig.example_controller(), [100.0], [(1e-4, 0.01, 0.0)])
    with pytest.raises(ValueError, match=r"sweep axis must be a number of the rig .*got 'rotor.mass'"):
        af.sweep(rig, af.RotorRig.example_controller(), af.schroeder_multisine(f0=20.0, f_max=400.0),
                 **{"rotor.mass": [9.0, 10.0]})  # fmt: skip


def test_without_ross_from_ross_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ross", None)  # import ross raises ImportError
    with pytest.raises(ImportError, match=r"FlexibleRotor.from_ross needs ROSS: pip install 'amb_fast\[ross\]'"):
        af.FlexibleRotor.from_ross(object(), BEARINGS, SENSORS, modes=2)


def test_the_bearings_excite_a_flexible_rotor() -> None:
    """exciter="amb" on a flexible rotor failed (inv of the 4 x 20 actuator matrix). Noise-free, with no process,
    the process estimate is 0 to rounding (measured 3e-12 of |Z|)."""
    pytest.importorskip("ross")
    rig = af.RotorRig(af.FlexibleRotor.example(), replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0))
    sphs = af.schroeder_multisine(f0=5.0, f_max=200.0, rms=1.0)
    est = af.run_experiment(rig, af.RotorRig.example_controller(), sphs, exciter="amb", periods=2)
    Z = np.abs(est.H).max(axis=(1, 2))
    assert np.all(np.abs(est.process).max(axis=(1, 2)) < 1e-9 * Z)
    assert np.all(np.isfinite(est.k)) and np.all(np.isfinite(est.c))
