"""The identification pipeline against exact prediction, the numpy reference pipeline, and itself."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import amb_fast as af
from amb_fast import reference


def rel(actual: np.ndarray, expected: np.ndarray) -> float:
    """Largest error relative to each value."""
    return float(np.max(np.abs(actual - expected) / np.abs(expected)))


def rel_max(actual: np.ndarray, expected: np.ndarray) -> float:
    """Largest error relative to the largest value (for quantities that cross zero, like c)."""
    return float(np.max(np.abs(actual - expected)) / np.max(np.abs(expected)))


@pytest.fixture(scope="module")
def sphs() -> af.Multisine:
    return af.schroeder_multisine()


@pytest.mark.parametrize(
    ("delay", "cutoff", "ki"), [(1, 1000.0, 20000.0), (0, None, 20000.0), (2, 1000.0, 0.0), (1, None, 5000.0)]
)
def test_noise_free_experiment_matches_exact_prediction(lagged_rig, sphs, delay, cutoff, ki) -> None:
    pid = af.PID(kp=2000.0, ki=ki, kd=5.0, derivative_cutoff=cutoff, delay=delay)
    est = af.run_experiment(lagged_rig, pid, sphs)
    assert rel(est.receptance, af.predict(lagged_rig, pid, est.freq)) < 1e-9
    # Eq. 9 applied to the exact H.
    H = 1 / af.predict(lagged_rig, pid, est.freq)
    w = 2 * np.pi * est.freq
    assert rel(est.k, lagged_rig.mass * w**2 + H.real) < 1e-9
    assert rel(est.c, H.imag / w) < 1e-9


def test_mass_loading_and_ac_coupled_transducer_are_predicted_exactly(lagged_rig, pid, sphs) -> None:
    rig = replace(lagged_rig, mass_loading=0.04, force_coupling_tau=1.5)
    est = af.run_experiment(rig, pid, sphs)  # settles the transducer too: ~30 s of excitation
    assert est.periods == 10
    assert rel(est.receptance, af.predict(rig, pid, est.freq)) < 1e-9
    # The extra moving mass appears in the actual stiffness as -dm w^2 (paper eq. 9 uses m alone).
    loaded = af.predict(replace(lagged_rig, mass_loading=0.04), pid, sphs.freq)
    plain = af.predict(lagged_rig, pid, sphs.freq)
    w = 2 * np.pi * sphs.freq
    np.testing.assert_allclose((1 / loaded - 1 / plain).real, -0.04 * w**2, rtol=2e-2)
    # AC coupling leads the recorded force: Re H gains -Im H / (w tau) at the lowest lines.
    coupled = af.predict(replace(lagged_rig, force_coupling_tau=1.5), pid, sphs.freq[:3])
    H = 1 / plain[:3]
    np.testing.assert_allclose((1 / coupled).real - H.real, -H.imag / (w[:3] * 1.5), rtol=0.05)


def test_prediction_matches_transfer_function_composition(lagged_rig, pid) -> None:
    freq = np.linspace(0.5, 1999.0, 300)
    assert rel(af.predict(lagged_rig, pid, freq), reference.receptance(lagged_rig, pid, freq)) < 1e-11


def test_experiment_matches_numpy_reference_pipeline(lagged_rig, pid, sphs) -> None:
    settle, periods = 3, 10
    est = af.run_experiment(lagged_rig, pid, sphs, periods=periods, settle_periods=settle)
    record = np.tile(sphs.samples, settle + periods)
    lines = sphs.harmonics

    # The same simulated data through the numpy pipeline: agreement to rounding.
    trace = af.simulate(lagged_rig, pid, record)
    keep = slice(settle * 4000, None)
    ref = reference.pipeline(trace.force[keep], trace.displacement[keep], 4000, lines, lagged_rig.mass, 4000.0, 5)
    for name in ("H", "k", "c", "k_smooth", "c_smooth", "force", "displacement"):
        assert rel_max(getattr(est, name), ref[name]) < 1e-12, name

    # The pure-numpy loop's data through the numpy pipeline: agrees with exact prediction too.
    displacement, _ = reference.simulate(lagged_rig, pid, record)
    ref = reference.pipeline(record[keep], displacement[keep], 4000, lines, lagged_rig.mass, 4000.0, 5)
    assert rel(1 / ref["H"], af.predict(lagged_rig, pid, sphs.freq)) < 1e-9


def test_noise_free_standard_errors_vanish_and_unexcited_lines_are_empty(lagged_rig, pid) -> None:
    ms = af.schroeder_multisine(lines="odd")
    est = af.run_experiment(lagged_rig, pid, ms)
    assert np.all(est.k_std <= 1e-9 * np.abs(est.k))
    assert np.all(est.c_std <= 1e-9 * np.abs(est.c))
    np.testing.assert_array_equal(est.unexcited.freq, np.arange(2, 200, 2))
    assert est.unexcited.displacement.max() < 1e-9 * np.abs(est.displacement).min()


def test_standard_errors_give_honest_coverage(lagged_rig, pid, sphs) -> None:
    """With sensor noise, the 95 % t-interval from k_std / c_std covers the noise-free value 93-97 %
    of the time (pooled over lines and both coefficients)."""
    noisy = replace(lagged_rig, sensor_noise=1e-6)
    truth = af.run_experiment(lagged_rig, pid, sphs)
    lines = np.array([4, 19, 49, 99, 149, 199])  # indices: 5, 20, 50, 100, 150, 200 Hz
    hits = []
    for seed in range(250):
        est = af.run_experiment(noisy, pid, sphs, seed=seed, settle_periods=3)
        t = stats.t.ppf(0.975, est.blocks - 1)
        hits.append(np.abs(est.k[lines] - truth.k[lines]) <= t * est.k_std[lines])
        hits.append(np.abs(est.c[lines] - truth.c[lines]) <= t * est.c_std[lines])
    coverage = np.mean(hits)
    assert 0.93 <= coverage <= 0.97, coverage


def test_nonlinear_distortion_shows_on_unexcited_lines(lagged_rig, pid) -> None:
    ms = af.schroeder_multisine(rms=3.0, lines="random-odd", seed=3)  # peaks at ~26 % of the air gap
    levels = {}
    for law in ("linear", "nonlinear"):
        rig = replace(lagged_rig, force_law=law, sensor_noise=1e-9)
        u = af.run_experiment(rig, pid, ms, seed=1).unexcited
        odd = np.rint(u.freq).astype(int) % 2 == 1
        levels[law] = (np.median(u.displacement[odd]), np.median(u.displacement[~odd]))
    noise_floor = levels["linear"][1]
    # The pair's force law is odd: distortion lands on the odd lines left out, not on the even ones.
    assert levels["nonlinear"][0] > 100 * noise_floor
    assert levels["nonlinear"][1] < 3 * noise_floor
    assert levels["linear"][0] < 3 * noise_floor


@pytest.mark.parametrize("suffix", [".csv", ".mat"])
def test_identify_on_saved_recording_equals_run_experiment(lagged_rig, pid, sphs, tmp_path, suffix) -> None:
    rig = replace(lagged_rig, sensor_noise=2e-8, force_noise=1e-3)
    settle, periods = 3, 6
    # From rest, run_experiment runs the loop that simulate runs, with the same noise streams.
    est = af.run_experiment(rig, pid, sphs, periods=periods, settle_periods=settle, seed=42, start="rest")
    trace = af.simulate(rig, pid, np.tile(sphs.samples, settle + periods), seed=42)
    trace.save(tmp_path / f"rec{suffix}")
    rec = af.load_recording(tmp_path / f"rec{suffix}")
    assert rec.fs == pytest.approx(4000.0, rel=1e-12)
    again = af.identify(rec.force, rec.displacement, fs=rec.fs, f0=1.0, mass=rig.mass, f_max=200.0,
                        settle_periods=settle)  # fmt: skip
    for name in ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth"):
        np.testing.assert_array_equal(getattr(again, name), getattr(est, name), err_msg=name)
    np.testing.assert_array_equal(again.unexcited.displacement, est.unexcited.displacement)


def test_identify_detects_excited_lines_and_handles_dspace_exports(lagged_rig, pid, tmp_path) -> None:
    from scipy.io import savemat

    ms = af.schroeder_multisine(lines="odd", f_max=100.0)
    trace = af.simulate(lagged_rig, pid, np.tile(ms.samples, 5))
    channels = np.empty(2, dtype=[("Name", object), ("Data", object)])
    channels[0] = ("Model Root/Force", trace.force)
    channels[1] = ("Model Root/Disp", trace.displacement)
    savemat(tmp_path / "dspace.mat", {"rec": {"X": {"Data": trace.time}, "Y": channels}})
    rec = af.load_recording(tmp_path / "dspace.mat", force="Force", displacement="Disp")
    est = af.identify(rec.force, rec.displacement, fs=rec.fs, f0=1.0, mass=0.92, settle_periods=2)
    np.testing.assert_array_equal(est.freq, ms.freq)
    assert rel(est.receptance, af.predict(lagged_rig, pid, ms.freq)) < 1e-9


def test_identify_truncates_partial_periods_with_a_warning(lagged_rig, pid, sphs) -> None:
    trace = af.simulate(lagged_rig, pid, np.concatenate([np.tile(sphs.samples, 5), sphs.samples[:123]]))
    with pytest.warns(UserWarning, match="dropped the last 123 samples"):
        est = af.identify(trace.force, trace.displacement, fs=4000.0, f0=1.0, mass=0.92, f_max=200.0,
                          settle_periods=2)  # fmt: skip
    assert est.periods == 3


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (dict(f0=3.0), "fs/f0 must be a whole number"),
        (dict(f_max=2000.0), "f_max must be at least f0 .* below fs/2"),
        (dict(lines=[5.0, 300.0], f_max=200.0), "lines must be within the band"),
        (dict(settle_periods=4), "periods after settling must be >= 2"),
        (dict(settle_periods=5), "recording length must be at least settle_periods \\+ 1 periods"),
        (dict(median_window=4), "median_window must be odd"),
        (dict(mass=0.0), "mass must be"),
    ],
)
def test_identify_rejects_bad_input(lagged_rig, pid, sphs, change, message) -> None:
    trace = af.simulate(lagged_rig, pid, np.tile(sphs.samples, 5))
    kwargs = dict(fs=4000.0, f0=1.0, mass=0.92, f_max=200.0, settle_periods=0) | change
    with pytest.raises(ValueError, match=message):
        af.identify(trace.force, trace.displacement, **kwargs)


def test_identify_names_non_finite_samples_and_mismatched_lengths(lagged_rig, pid, sphs) -> None:
    trace = af.simulate(lagged_rig, pid, np.tile(sphs.samples, 4))
    displacement = trace.displacement.copy()
    displacement[9001] = np.nan
    with pytest.raises(ValueError, match="displacement must be finite, got nan at sample 9001"):
        af.identify(trace.force, displacement, fs=4000.0, f0=1.0, mass=0.92, f_max=200.0)
    with pytest.raises(ValueError, match="displacement length"):
        af.identify(trace.force, trace.displacement[:-1], fs=4000.0, f0=1.0, mass=0.92, f_max=200.0)


def test_run_experiment_rejects_unstable_loops_and_single_periods(lagged_rig, sphs) -> None:
    soft = af.PID(kp=500.0, ki=0.0, kd=5.0)
    with pytest.raises(af.UnstableLoopError, match="kp=500.0") as info:
        af.run_experiment(lagged_rig, soft, sphs)
    assert np.all(np.abs(info.value.poles) >= 1)
    with pytest.raises(ValueError, match="periods must be a whole number >= 2"):
        af.run_experiment(lagged_rig, af.PID(kp=2000.0, ki=0.0, kd=5.0), sphs, periods=1)
