"""The model of N axes for N = 1: the platform as the 1x1 case gives the one-axis model's answers (a separate
path: the one-axis plant, controller and closed loop, and the C++ core's experiment); the ISO 14839-3
sensitivity measurement against the exact output sensitivity, from a simulation and from a recording."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system

RIGS = [af.Rig.paper(), af.Rig(dead_time=0.3e-3, amp_bandwidth=2000.0, sensor_bandwidth=8000.0, mass_loading=0.1)]
CONTROLLERS = [af.PID.paper(), af.PID.paper().to_controller() * af.notch(700.0)]


@pytest.mark.parametrize("rig", RIGS)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_one_axis_is_the_one_by_one_case(rig: af.Rig, controller) -> None:  # noqa: ANN001
    f = np.arange(1.0, 201.0)
    R = system.predict(rig, controller, f)
    assert R.shape == (200, 1, 1)
    np.testing.assert_allclose(R[:, 0, 0], af.predict(rig, controller, f), rtol=1e-12)
    poles = np.sort_complex(system.closed_loop_poles(rig, controller))
    np.testing.assert_allclose(poles, np.sort_complex(af.closed_loop_poles(rig, controller)), atol=1e-12)
    np.testing.assert_allclose(system.sensitivity(rig, controller, f)[:, 0, 0], af.sensitivity(rig, controller, f),
                               rtol=1e-12)  # fmt: skip
    k, c = system.effective_coefficients(rig, controller, f)
    k1, c1 = af.effective_coefficients(rig, controller, f)
    np.testing.assert_allclose(k[:, 0, 0], k1, rtol=1e-12)
    np.testing.assert_allclose(c[:, 0, 0], c1, rtol=1e-12)
    assert system.stability_margin(rig, controller).peak == pytest.approx(af.stability_margin(rig, controller).peak,
                                                                          rel=1e-12)  # fmt: skip


def test_one_axis_experiment_through_the_dense_engine_matches_the_core() -> None:
    """The N-axis experiment (dense loop, N x N estimator) of a quiet one-axis rig equals the one-axis core's."""
    rig = af.Rig(amp_bandwidth=3000.0, eddy_bandwidth=2000.0, sensor_bandwidth=1e4, mass_loading=0.06,
                 force_coupling_tau=1.0, dead_time=0.1e-3)  # fmt: skip
    sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)
    dense = system.run_experiment(rig, af.PID.paper(), sphs, periods=3)
    core = af.run_experiment(rig, af.PID.paper(), sphs, periods=3)
    np.testing.assert_allclose(dense.k[:, 0, 0], core.k, rtol=1e-9)
    np.testing.assert_allclose(dense.c[:, 0, 0], core.c, rtol=1e-8, atol=1e-9 * np.abs(core.c).max())


@pytest.mark.parametrize("which", ["one axis", "rotor"])
def test_measured_sensitivity_is_the_exact_output_sensitivity(which: str) -> None:
    if which == "one axis":
        rig, controller = af.Rig(amp_bandwidth=3000.0, sensor_bandwidth=1e4, dead_time=1e-4), af.PID.paper()
    else:
        rotor = af.RotorRig.example(speed=800.0).rotor
        rig, controller = (
            af.RotorRig(rotor, af.Rig(amp_bandwidth=3000.0, dead_time=1e-4)),
            af.RotorRig.example_controller(),
        )
    sphs = af.schroeder_multisine(f0=2.0, f_max=1000.0, rms=1e-6)
    measured = af.measure_sensitivity(rig, controller, sphs, periods=3)
    exact = af.sensitivity(rig, controller, measured.freq, at="sensors")
    exact = exact.reshape(measured.S.shape)
    np.testing.assert_allclose(measured.S, exact, rtol=0, atol=1e-9 * np.abs(exact).max())
    diagonal = np.abs(np.diagonal(exact, axis1=1, axis2=2))
    np.testing.assert_allclose(measured.peak, diagonal.max(axis=0), rtol=1e-9)
    assert measured.zone == tuple(
        "ABCD"[min(3, int(np.searchsorted([3, 4, 5], p, side="right")))] for p in measured.peak
    )
    assert np.all(measured.S_std < 1e-12 * np.abs(measured.S).max() + 1e-300) or which == "rotor"
    assert "zone" in measured.table()


def test_sensitivity_from_a_recording() -> None:
    """A one-axis loop with the test signal added at the sensors' sum, run sample by sample in the core; the
    recorded test signal and signal after the sum give the exact sensitivity at the excited lines."""
    rig, pid = af.Rig(amp_bandwidth=3000.0), af.PID.paper()
    sphs = af.schroeder_multisine(f0=4.0, f_max=400.0, rms=1e-6)
    model = system.loop_model(rig, pid)
    injection = np.tile(sphs.samples, 40)
    _, out = af._core.mimo_simulate(M=model.M, Bf=model.Bn, Bn=model.Bn, C=model.C[:1], Dn=model.Dn[:1],
                                    transducer_pole=np.zeros(1), sensor_noise=np.zeros(1), force_noise=np.zeros(1),
                                    force=injection[:, None], seed=0)  # fmt: skip
    after = out[:, 0] + injection
    measured = af.identify_sensitivity(injection, after, fs=4000.0, f0=4.0, settle_periods=30)
    np.testing.assert_allclose(measured.freq, sphs.freq)
    exact = af.sensitivity(rig, pid, measured.freq)
    np.testing.assert_allclose(measured.S[:, 0, 0], exact, rtol=1e-7)
    with pytest.raises(ValueError, match="signal shape"):
        af.identify_sensitivity(injection, after[:-1], fs=4000.0, f0=4.0)
