"""A fractional dead time from the current command to the amplifier (Rig.dead_time), exact in every path."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import reference

T = 1.0 / 4000.0
DEAD_TIMES = [0.3 * T, 1.0 * T, 2.6 * T]


def rel(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(actual - expected)) / np.max(np.abs(expected)))


@pytest.fixture(scope="module")
def sphs() -> af.Multisine:
    return af.schroeder_multisine(f0=1.0, f_max=200.0)


QUIET = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)


@pytest.mark.parametrize("dead_time", DEAD_TIMES)
def test_experiment_equals_prediction_and_the_reference(dead_time, sphs) -> None:
    rig, pid = replace(QUIET, dead_time=dead_time), af.PID.paper()
    est = af.run_experiment(rig, pid, sphs, periods=2)
    exact = af.predict(rig, pid, est.freq)
    assert rel(est.receptance, exact) < 1e-9
    dc = replace(rig, force_coupling_tau=None)  # the reference composes the plant with the PID only
    assert rel(reference.receptance(dc, pid, est.freq), af.predict(dc, pid, est.freq)) < 1e-9


@pytest.mark.parametrize("dead_time", DEAD_TIMES)
def test_simulation_equals_the_reference_loop(dead_time, rng) -> None:
    rig = af.Rig(amp_bandwidth=1500.0, eddy_bandwidth=800.0, sensor_bandwidth=5000.0, dead_time=dead_time)
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0, delay=1)
    force = rng.standard_normal(4000)
    y, i = reference.simulate(rig, pid, force)
    trace = af.simulate(rig, pid, force)
    assert rel(trace.displacement, y) < 1e-9 and rel(trace.current, i) < 1e-9


def test_nonlinear_law_with_a_fractional_dead_time_matches_the_reference() -> None:
    rig = af.Rig(amp_bandwidth=1500.0, dead_time=1.7 * T, force_law="nonlinear", substeps=8)
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0)
    force = 0.3 * np.sin(0.05 * np.arange(3000))
    y, _ = reference.simulate(rig, pid, force)
    assert rel(af.simulate(rig, pid, force).displacement, y) < 1e-7


def test_a_dead_time_of_whole_samples_is_a_computation_delay(sphs) -> None:
    """Exactly one sample of dead time and one sample of controller delay are the same loop."""
    pid = af.PID.paper()
    late = af.predict(replace(QUIET, dead_time=T), pid, sphs.freq)
    delayed = af.predict(QUIET, replace(pid, delay=1), sphs.freq)
    assert rel(late, delayed) < 1e-12
    force = np.tile(sphs.samples, 2)
    a = af.simulate(replace(QUIET, dead_time=T), pid, force).displacement
    b = af.simulate(QUIET, replace(pid, delay=1), force).displacement
    assert rel(a, b) < 1e-12


def test_dead_time_costs_phase_like_exp_minus_j_w_tau(sphs) -> None:
    """Between two dead times the loop's plant (command -> sensor) differs by exp(-j w dtau) up to
    the zero-order hold's fraction handling: checked on the open loop at low frequency, where the
    modified z-transform tends to the continuous delay."""
    rig0, rig1 = replace(QUIET, dead_time=0.0), replace(QUIET, dead_time=0.5 * T)
    f = np.array([5.0, 10.0, 20.0])
    p0 = af._linear.plant_responses(rig0, 4000.0, f)[1]
    p1 = af._linear.plant_responses(rig1, 4000.0, f)[1]
    expected = np.exp(-2j * np.pi * f * 0.5 * T)
    assert np.max(np.abs(p1 / p0 - expected)) < 1e-4


def test_sweep_over_dead_time_equals_single_runs_bit_for_bit(sphs) -> None:
    rig, pid = af.Rig.paper(), af.PID.paper()
    result = af.sweep(rig, pid, sphs, dead_time=[0.0, 0.4 * T, 1.5 * T], periods=3, seed=11, progress=False)
    assert list(result.status) == ["ok"] * 3
    for j, tau in enumerate(result.points["dead_time"]):
        single = af.run_experiment(replace(rig, dead_time=float(tau)), pid, sphs, periods=3, seed=int(result.seeds[j]))
        assert np.array_equal(result.H[j], single.H)


@pytest.mark.parametrize("bad", [-1e-6, float("nan"), float("inf")])
def test_bad_dead_time_is_refused(bad) -> None:
    with pytest.raises(ValueError, match="dead_time must be"):
        af.Rig(dead_time=bad)


# A dead time of more than 1000 controller samples (a mistyped 1 s for 1 ms) is refused at once: each
# sample is a state of the loop, and 4000 of them took minutes in the stability check before the run.
LATE = replace(QUIET, dead_time=1.0)


@pytest.mark.parametrize(
    "call",
    [
        lambda: af.stability_margin(LATE, af.PID.paper()),
        lambda: af.closed_loop_poles(LATE, af.PID.paper()),
        lambda: af.simulate(LATE, af.PID.paper(), np.zeros(8)),
        lambda: af.closed_loop_poles(af.RotorRig(af.RotorRig.example().rotor, LATE), af.PID.paper()),
        lambda: af.campbell(af.RotorRig(af.RotorRig.example().rotor, LATE), af.PID.paper(), [0.0, 100.0]),
    ],
    ids=["stability_margin", "poles", "simulate", "rotor poles", "campbell"],
)
def test_a_dead_time_of_more_than_1000_samples_is_refused_naming_it(call) -> None:
    with pytest.raises(ValueError, match=r"dead_time must be at most 1000 samples of the controller.*got 1"):
        call()


def test_1000_samples_of_dead_time_are_modelled() -> None:
    poles = af.closed_loop_poles(replace(QUIET, dead_time=1000 * T), af.PID.paper())
    assert poles.size > 1000 and np.all(np.isfinite(poles))


def test_the_command_refuses_a_dead_time_of_1_s_before_the_run(capsys) -> None:
    from cli_helpers import one_error_line, run

    status, _, err = run(capsys, "run", "--dead-time", "1", "--periods", "2")
    assert status == 2
    assert "--dead-time must be at most 1000 samples of the controller" in one_error_line(err)


@pytest.mark.parametrize(
    "make",
    [
        lambda: replace(af.PID.paper(), delay=4000),
        lambda: af.Controller.from_continuous([1.0], [1.0], fs=4000.0, delay=4000),
        lambda: af.notch(700.0, fs=4000.0) * af.Controller.from_continuous([1.0], [1.0], fs=4000.0, delay=1001),
    ],
    ids=["PID", "from_continuous", "series"],
)
def test_a_controller_delay_of_more_than_1000_samples_is_refused_naming_it(make) -> None:
    # the sibling of the rig's dead time: a controller's own delay is a state of the loop per sample too
    with pytest.raises(ValueError, match=r"delay must be at most 1000 samples \(each is a state of the loop\), got"):
        make()
    assert replace(af.PID.paper(), delay=1000).delay == 1000
