"""Two axes are the N = 2 case of amb_fast.system (issue 26): one experiment, estimate, trace and sweep."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system
from amb_fast import two_axis as ta

PID = af.PID.paper()
SPHS = af.schroeder_multisine(f0=20.0, f_max=200.0)
QUIET = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)


def test_two_axis_results_are_the_n_axis_ones() -> None:
    """The two-axis functions give the N-axis results of a TwoAxisRig, to the bit; system.sweep takes it."""
    rig = replace(ta.TwoAxisRig.paper(), kxy=2e3, kyx=-2e3)
    est = ta.run_experiment(rig, PID, SPHS, periods=3, seed=4)
    assert isinstance(est, system.EstimateN) and est.axes == ("x", "y")
    assert est == system.run_experiment(rig, PID, SPHS, periods=3, seed=4)
    assert isinstance(ta.simulate(rig, PID, np.zeros((20, 2)), seed=1), system.TraceN)
    swept = ta.sweep(rig, PID, SPHS, kxy=[0.0, 3e3], periods=3, seed=2, progress=False)
    assert swept == system.sweep(rig, PID, SPHS, kxy=[0.0, 3e3], periods=3, seed=2, progress=False)
    assert isinstance(swept, system.SweepResultN) and swept.axes == ("x", "y")
    with pytest.raises(ValueError, match="TwoAxisRig"):
        ta.run_experiment(af.Rig.paper(), PID, SPHS)


def test_two_axis_functions_are_the_n_axis_ones_behind_one_check() -> None:
    """No second implementation (issue 26): each two-axis function is the N-axis one behind the TwoAxisRig check,
    and the recordings of two experiments are read by system.identify (its checks and warning category)."""
    for name in ("predict", "sensitivity", "closed_loop", "closed_loop_poles", "effective_coefficients", "loop_model",
                 "simulate", "run_experiment", "sweep"):  # fmt: skip
        assert getattr(ta, name).__wrapped__ is getattr(system, name)
    assert ta.point_model2.__wrapped__ is system.point_model
    axis = replace(QUIET, force_coupling_tau=None)  # DC-coupled transducers: settled within the skipped periods
    rig = ta.TwoAxisRig(x=axis, y=axis, kxy=1e3, kyx=-1e3)
    trace = [ta.simulate(rig, PID, np.tile(np.outer(SPHS.samples, s), (22, 1))) for s in ta.SIGNS]
    keep = 21 * SPHS.period_samples + 7  # 7 samples past the last whole period of each experiment
    forces, displacements = [t.force[:keep] for t in trace], [t.displacement[:keep] for t in trace]
    with pytest.warns(af.IdentificationWarning, match="dropped 14 samples"):
        read = ta.identify(forces, displacements, fs=SPHS.fs, f0=SPHS.f0, mass=rig.mass, settle_periods=19)
    assert read.freq.size == SPHS.freq.size and read.axes == ("x", "y")
    with pytest.raises(ValueError, match=r"force shape must be recordings of N experiments, \(N, samples, N\), for N "
                       r"in \[2, 4\], got \(3, 10, 3\)"):  # fmt: skip
        af.identify(np.zeros((3, 10, 3)), np.zeros((3, 10, 3)), fs=4000.0, f0=20.0, mass=1.0)


def test_paths_of_a_two_axis_sweep() -> None:
    """``x.<field>`` and ``x_<field>`` name the same axis field; a rig field (sensor_angle) is a path; a gain
    on a diagonal that is not a PID is refused, not silently left as it was."""
    rig = ta.TwoAxisRig.paper()
    dotted, _ = system.point_model(rig, PID, {"x.amp_bandwidth": 1500.0, "sensor_angle": 0.02})
    underscored, _ = ta.point_model2(rig, PID, {"x_amp_bandwidth": 1500.0, "sensor_angle": 0.02})
    assert dotted == underscored == replace(rig, x=replace(rig.x, amp_bandwidth=1500.0), sensor_angle=0.02)
    one = af.Rig.paper()  # one axis: the rig is its own chain
    assert system.point_model(one, PID, {"amp_bandwidth": 2000.0})[0] == replace(one, amp_bandwidth=2000.0)
    _, cross = ta.point_model2(rig, [[PID, PID], [None, PID]], {"cross_kd": 0.5, "kp": 2500.0})
    assert cross.entries[0][1].kd == 0.5 and cross.entries[0][0].kd == PID.kd and cross.entries[1][0] is None
    assert cross.entries[0][0].kp == cross.entries[1][1].kp == 2500.0 and cross.entries[0][1].kp == PID.kp
    lead = af.lead_lag(gain=1.0, zero=10.0, pole=100.0, fs=PID.fs)
    with pytest.raises(ValueError, match="sweep axis.*PID"):
        ta.point_model2(rig, (lead, lead), {"kp": 2500.0})
    with pytest.raises(ValueError, match="sweep axis"):
        ta.sweep(rig, PID, SPHS, x=[1.0])


def test_probes_frame_of_the_actual_coefficients() -> None:
    """With rotated probes the known mass is removed in the probes' frame, ``k = Re(H + m w^2 R)``, as the
    effective coefficients are given; identify (the angle unknown) removes ``m w^2 I``."""
    axis = replace(QUIET, force_coupling_tau=None)  # DC-coupled transducers: settled within 20 periods
    rig = ta.TwoAxisRig(x=axis, y=axis, kxy=1e3, kyx=-1e3, sensor_angle=0.1)
    est = ta.run_experiment(rig, PID, SPHS, periods=3, seed=0)
    w2 = (2 * np.pi * est.freq[:, None, None]) ** 2
    np.testing.assert_allclose(est.k, (est.H + rig.mass * w2 * rig.rotation).real, rtol=1e-12, atol=1e-9)
    trace = [ta.simulate(rig, PID, np.tile(np.outer(SPHS.samples, s), (22, 1))) for s in ta.SIGNS]
    read = ta.identify([t.force for t in trace], [t.displacement for t in trace], fs=SPHS.fs, f0=SPHS.f0,
                       mass=rig.mass, settle_periods=20)  # fmt: skip
    np.testing.assert_allclose(read.k, (read.H + rig.mass * w2 * np.eye(2)).real, rtol=1e-12, atol=1e-9)
    assert np.max(np.abs(read.H / est.H - 1)) < 1e-8


def test_estimate_of_one_bearing_goes_to_ross_as_one_element() -> None:
    """Two axes are one bearing: one element at node n; a rotor's two bearings take a node each."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pytest.importorskip("ross")
    rig = replace(ta.TwoAxisRig.paper(), kxy=1e4, kyx=-1e4)
    est = system.run_experiment(rig, PID, SPHS, periods=3, seed=1)
    element = est.to_ross(2)
    assert element.n == 2
    np.testing.assert_allclose(element.K(2 * np.pi * est.freq[3])[:2, :2], est.k[3], rtol=1e-12)
    rotor = system.run_experiment(af.RotorRig.example(), af.RotorRig.example_controller(), SPHS, periods=3, seed=1)
    with pytest.raises(ValueError, match="nodes"):
        rotor.to_ross(2)


def test_summary_of_any_number_of_axes() -> None:
    rotor = system.run_experiment(af.RotorRig.example(), af.RotorRig.example_controller(), SPHS, periods=3, seed=1)
    header, *rows = rotor.summary(at=(40.0, 100.0)).splitlines()
    assert len(rows) == 2 and "kA.xB.y (N/m)" in header and len(header.split("(N/m)")) == 17
    assert float(rows[0].split()[0]) == 40.0
