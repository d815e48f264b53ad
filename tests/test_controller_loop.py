"""Any digital controller in every path: the core loops, prediction, sweeps, effective coefficients."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import reference

QUIET = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)


def rel(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(actual - expected) / np.abs(expected)))


@pytest.fixture(scope="module")
def sphs() -> af.Multisine:
    return af.schroeder_multisine(f0=1.0, f_max=200.0)


def random_controller(seed: int) -> af.Controller:
    """The paper PID in series with 1-3 random second-order sections whose poles and zeros lie at
    high frequency (radius 0.1-0.6), normalised to unit gain at DC: orders 4 to 8, the loop stays
    stable, and every representation is well conditioned."""
    rng = np.random.default_rng(seed)
    sections = []
    for _ in range(rng.integers(1, 4)):
        r_p, r_z = rng.uniform(0.1, 0.6, 2)
        a_p, a_z = rng.uniform(0.3, 2.8, 2)
        z = [r_z * np.exp(1j * a_z), r_z * np.exp(-1j * a_z)]
        p = [r_p * np.exp(1j * a_p), r_p * np.exp(-1j * a_p)]
        gain = np.prod(1 - np.array(p)).real / np.prod(1 - np.array(z)).real
        sections.append(af.Controller.from_zpk(z, p, gain, fs=4000.0))
    return af.series(af.PID.paper().to_controller(), *sections)


@pytest.mark.parametrize("seed", range(6))
def test_random_controllers_agree_with_prediction_and_the_reference(seed, sphs, rng) -> None:
    controller = random_controller(seed)
    assert 4 <= controller.order <= 8
    est = af.run_experiment(QUIET, controller, sphs, periods=2)
    exact = af.predict(QUIET, controller, est.freq)
    assert rel(est.receptance, exact) < 1e-9
    dc = replace(QUIET, force_coupling_tau=None)
    assert rel(reference.receptance(dc, controller, est.freq), af.predict(dc, controller, est.freq)) < 1e-9
    force = rng.standard_normal(3000)
    y, i = reference.simulate(QUIET, controller, force)
    trace = af.simulate(QUIET, controller, force)
    assert float(np.max(np.abs(trace.displacement - y)) / np.max(np.abs(y))) < 1e-9
    assert float(np.max(np.abs(trace.current - i)) / np.max(np.abs(i))) < 1e-9


def test_pid_as_a_controller_runs_bit_for_bit_the_same(sphs) -> None:
    rig, pid = af.Rig.paper(), replace(af.PID.paper(), delay=1)
    controller = pid.to_controller()
    force = np.tile(sphs.samples, 2)
    a, b = af.simulate(rig, pid, force, seed=4), af.simulate(rig, controller, force, seed=4)
    assert np.array_equal(a.displacement, b.displacement) and np.array_equal(a.force, b.force)
    e1 = af.run_experiment(rig, pid, sphs, seed=9)
    e2 = af.run_experiment(rig, controller, sphs, seed=9)
    assert np.array_equal(e1.H, e2.H) and np.array_equal(e1.k_std, e2.k_std)


def test_sweeps_over_a_notch_frequency_and_a_rig_field_equal_single_runs(sphs) -> None:
    rig = af.Rig.paper()
    controller = af.PID.paper().to_controller() * af.notch(700.0) * af.low_pass(1500.0, order=2)
    notch = af.sweep(rig, controller, sphs, notch_freq=[600.0, 700.0, 900.0], periods=3, seed=2, progress=False)
    for j, freq in enumerate(notch.points["notch_freq"]):
        single = af.run_experiment(rig, controller.with_params(notch_freq=float(freq)), sphs, periods=3,
                                   seed=int(notch.seeds[j]))  # fmt: skip
        assert np.array_equal(notch.H[j], single.H)
    amp = af.sweep(rig, controller, sphs, amp_bandwidth=[1500.0, 3000.0], periods=3, seed=3, progress=False)
    for j, bandwidth in enumerate(amp.points["amp_bandwidth"]):
        single = af.run_experiment(replace(rig, amp_bandwidth=float(bandwidth)), controller, sphs, periods=3,
                                   seed=int(amp.seeds[j]))  # fmt: skip
        assert np.array_equal(amp.H[j], single.H)


def test_sweep_with_a_factory_and_unknown_names(sphs) -> None:
    def factory(kp: float, tau: float) -> tuple[af.Rig, af.PID]:
        return replace(af.Rig.paper(), dead_time=tau), replace(af.PID.paper(), kp=kp)

    result = af.sweep(factory, sphs, kp=[2200.0, 2600.0], tau=[0.0, 1e-4], grid="zip", periods=3, progress=False)
    single = af.run_experiment(*factory(2600.0, 1e-4), sphs, periods=3, seed=int(result.seeds[1]))
    assert np.array_equal(result.H[1], single.H)
    with pytest.raises(ValueError, match="sweep axis must be a numeric Rig field or a controller parameter"):
        af.sweep(af.Rig.paper(), af.PID.paper(), sphs, notch_freq=[700.0])


def test_unstable_points_are_flagged_before_simulating(sphs) -> None:
    controller = af.PID.paper().to_controller()
    result = af.sweep(af.Rig.paper(), controller, sphs, kp=[2400.0, 300.0], periods=3, progress=False)
    assert list(result.status) == ["ok", "unstable"]
    with pytest.raises(af.UnstableLoopError, match="unstable"):
        af.run_experiment(af.Rig.paper(), controller.with_params(kp=300.0), sphs)


def test_effective_coefficients_use_the_continuous_design_unless_asked(sphs) -> None:
    pid = af.PID.paper()
    controller = pid.to_controller()
    f = sphs.freq
    k1, c1 = af.effective_coefficients(QUIET, pid, f)
    k2, c2 = af.effective_coefficients(QUIET, controller, f)
    assert rel(k2, k1) < 1e-12 and rel(c2, c1) < 1e-12
    k3, c3 = af.effective_coefficients(QUIET, pid, f, discrete=True)
    k4, c4 = af.effective_coefficients(QUIET, controller, f, discrete=True)
    assert rel(k4, k3) < 1e-9 and rel(c4, c3) < 1e-9
    raw = af.Controller.from_tf(*controller.to_tf(), fs=4000.0)  # no continuous design: G(z)
    k5, _ = af.effective_coefficients(QUIET, raw, f)
    assert rel(k5, k3) < 1e-9


def test_margins_and_poles_take_any_controller() -> None:
    controller = af.PID.paper().to_controller() * af.low_pass(1500.0, order=2)
    margin = af.stability_margin(QUIET, controller)
    assert margin.stable and margin.peak > af.stability_margin(QUIET, af.PID.paper()).peak
    poles = af.closed_loop_poles(QUIET, controller)
    assert poles.size == 5 + controller.order and np.all(np.abs(poles) < 1)
