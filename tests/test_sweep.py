"""Gain sweeps: bit-for-bit equal to single runs, on any number of workers and executors."""

from __future__ import annotations

import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast._sweep_result import unit_of

FIELDS = ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth", "unexcited_displacement")


@pytest.fixture(scope="module")
def setup():
    rig = af.Rig(amp_bandwidth=1500.0, eddy_bandwidth=800.0, sensor_bandwidth=5000.0, sensor_noise=2e-8,
                 force_noise=1e-3, mass_loading=0.03, force_coupling_tau=0.5)  # fmt: skip
    pid = af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=1000.0)
    excitation = af.schroeder_multisine(lines="odd", f_max=100.0)
    return rig, pid, excitation


def same(a: af.SweepResult, b: af.SweepResult) -> None:
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.status, b.status)


@pytest.mark.parametrize("pid", [af.PID.paper(), af.PID(kp=2e3, ki=1e4, kd=4.0, derivative_cutoff=None, delay=2)])
def test_gain_sweeps_make_the_controllers_of_single_runs(pid) -> None:
    """A PID-gain sweep makes its core controllers from the gain arrays (PID._core_controllers): the
    matrices of each point's own PID, bit for bit, with the integral or the derivative state dropped where
    its gain is zero."""
    rng = np.random.default_rng(5)
    gains = np.column_stack([rng.uniform(1e3, 4e3, 30), rng.uniform(0, 3e4, 30), rng.uniform(0, 6, 30)])
    gains[::4, 1] = 0.0
    gains[1::5, 2] = 0.0
    made = pid._core_controllers(gains)
    for (kp, ki, kd), core in zip(gains, made):
        own = replace(pid, kp=kp, ki=ki, kd=kd)._to_core()
        assert core.order == own.order == int(ki != 0) + int(kd != 0)
        for name in ("A", "B", "C", "D", "fs", "delay"):
            np.testing.assert_array_equal(getattr(core, name), getattr(own, name), err_msg=name)


def test_sweep_points_equal_single_runs_bit_for_bit(setup) -> None:
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, kp=[500.0, 1800.0, 2400.0], kd=[0.0, 4.0, 6.0], seed=11, periods=4)
    assert result.shape == (3, 3)
    assert list(result.status[:3]) == ["unstable"] * 3  # kp = 500 A/m: negative net stiffness
    for i, status in enumerate(result.status):  # flagged exactly where the loop's poles say so
        point = replace(pid, kp=result.points["kp"][i], kd=result.points["kd"][i])
        assert (status == "unstable") == (np.abs(af.closed_loop_poles(rig, point)).max() >= 1)
    ok = np.flatnonzero(result.status == "ok")
    assert ok.size >= 4
    for i in ok:
        point = replace(pid, kp=result.points["kp"][i], kd=result.points["kd"][i])
        single = af.run_experiment(rig, point, excitation, periods=4, seed=int(result.seeds[i]))
        for name in ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth"):
            np.testing.assert_array_equal(getattr(result, name)[i], getattr(single, name), err_msg=name)
        np.testing.assert_array_equal(result.unexcited_displacement[i], single.unexcited.displacement)
    for i in np.flatnonzero(result.status == "unstable"):
        assert np.all(np.isnan(result.k[i])) and np.all(np.isnan(result.H[i]))


def test_a_sweep_of_one_controller_shape_checks_stability_in_the_core(setup, monkeypatch) -> None:
    """kp alone (every point has the PID's two states) from the steady start: the settling time needs no
    poles, so the core's workers check each point's stability as they run them (not the calling thread
    first). The same flags as the loop's poles, NaN rows for the unstable points, the rest bit for bit."""
    from amb_fast import _sweep

    rig, pid, excitation = setup

    def not_here(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("the stability check ran in the calling thread")

    monkeypatch.setattr(_sweep, "_radius_of_gains", not_here)
    kp = [500.0, 1800.0, 300.0, 2400.0, 2600.0]
    for workers in (1, 2):
        result = af.sweep(rig, pid, excitation, kp=kp, seed=11, periods=4, workers=workers, progress=False)
        for i, status in enumerate(result.status):
            point = replace(pid, kp=kp[i])
            assert (status == "unstable") == (np.abs(af.closed_loop_poles(rig, point)).max() >= 1)
        assert list(result.status) == ["unstable", "ok", "unstable", "ok", "ok"]
        for i in (0, 2):
            assert np.all(np.isnan(result.k[i])) and np.all(np.isnan(result.H[i]))
        for i in (1, 3, 4):
            single = af.run_experiment(rig, replace(pid, kp=kp[i]), excitation, periods=4, seed=int(result.seeds[i]))
            np.testing.assert_array_equal(result.k[i], single.k)
            np.testing.assert_array_equal(result.H[i], single.H)


def test_workers_and_executors_change_nothing(setup) -> None:
    rig, pid, excitation = setup
    kwargs = dict(kp=np.linspace(1800, 2600, 7), ki=[0.0, 1e4, 3e4], seed=5, periods=3)
    serial = af.sweep(rig, pid, excitation, workers=1, **kwargs)
    same(serial, af.sweep(rig, pid, excitation, workers=2, **kwargs))
    same(serial, af.sweep(rig, pid, excitation, workers=2, chunk_size=4, **kwargs))
    with ThreadPoolExecutor(3) as pool:
        same(serial, af.sweep(rig, pid, excitation, executor=pool, chunk_size=5, **kwargs))
        # Chunks that split across the core's own threads too.
        same(serial, af.sweep(rig, pid, excitation, executor=pool, workers=2, chunk_size=9, **kwargs))


def test_dask_local_cluster_gives_the_same_sweep(setup) -> None:
    distributed = pytest.importorskip("distributed")
    rig, pid, excitation = setup
    kwargs = dict(kp=np.linspace(1800, 2600, 6), kd=[4.0, 6.0], seed=9, periods=3)
    serial = af.sweep(rig, pid, excitation, **kwargs)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as client:
            same(serial, af.sweep(rig, pid, excitation, executor=client.get_executor(), chunk_size=3, **kwargs))


def test_zip_grid_and_validation(setup) -> None:
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, kp=[2000.0, 2200.0], ki=[1e4, 2e4], grid="zip", periods=2)
    np.testing.assert_array_equal(result.points["ki"], [1e4, 2e4])
    assert result.shape == (2,)
    with pytest.raises(ValueError, match="lengths must be equal"):
        af.sweep(rig, pid, excitation, kp=[1.0, 2.0], ki=[1.0], grid="zip")
    with pytest.raises(ValueError, match="kp must be finite"):
        af.sweep(rig, pid, excitation, kp=[2000.0, np.nan])
    with pytest.raises(ValueError, match="at least one swept parameter"):
        af.sweep(rig, pid, excitation)
    with pytest.raises(ValueError, match="grid must be"):
        af.sweep(rig, pid, excitation, kp=[2000.0], grid="cartesian")


def test_touchdown_is_flagged_and_the_rest_is_intact() -> None:
    rig = af.Rig(force_law="nonlinear", amp_bandwidth=1500.0)
    pid = af.PID(kp=2000.0, ki=0.0, kd=5.0)
    big = af.schroeder_multisine(rms=6.0, f_max=50.0)  # pushes the soft loop into the magnets
    result = af.sweep(rig, pid, big, kp=[1300.0, 6000.0], periods=2, settle_periods=1)
    assert list(result.status) == ["touchdown", "ok"]
    assert np.all(np.isnan(result.k[0])) and np.all(np.isfinite(result.k[1]))


@pytest.mark.parametrize("suffix", [".npz", ".nc"])
def test_a_loaded_sweep_keeps_every_bit_of_H(setup, tmp_path, suffix) -> None:
    # The .nc file holds H as H_real and H_imag: joined back as written (``real + 1j * imag`` made -0.0 into
    # 0.0 and an infinite imaginary part into a NaN real one).
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, kd=[4.0, 5.0], periods=2)
    H = result.H.copy()
    H[0, 0], H[0, 1], H[1, 2] = complex(1.5, -0.0), complex(-2.0, np.inf), complex(-0.0, 3.0)
    path = tmp_path / f"sweep{suffix}"
    replace(result, H=H).save(path)
    back = af.load_sweep(path).H
    for part in ("real", "imag"):
        np.testing.assert_array_equal(getattr(back, part), getattr(H, part))
        np.testing.assert_array_equal(np.signbit(getattr(back, part)), np.signbit(getattr(H, part)))


@pytest.mark.parametrize("suffix", [".npz", ".nc"])
def test_save_load_round_trip_and_xarray(setup, tmp_path, suffix) -> None:
    if suffix == ".nc":
        pytest.importorskip("xarray")
        pytest.importorskip("h5netcdf")
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, kp=[1000.0, 2000.0, 2400.0], kd=[4.0, 6.0], seed=1, periods=2)
    result.save(tmp_path / f"sweep{suffix}")
    loaded = af.load_sweep(tmp_path / f"sweep{suffix}")
    same(result, loaded)
    for name in ("seeds", "settle_periods", "freq", "unexcited_freq"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(result, name))
    assert loaded.grid == "product" and loaded.meta == result.meta
    for name in ("kp", "kd"):
        np.testing.assert_array_equal(loaded.points[name], result.points[name])
        np.testing.assert_array_equal(loaded.axes[name], result.axes[name])


def test_to_xarray_dims_and_coordinates(setup) -> None:
    pytest.importorskip("xarray")
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, kp=[2000.0, 2400.0], kd=[4.0, 5.0, 6.0], periods=2)
    ds = result.to_xarray()
    assert ds.k.dims == ("kp", "kd", "freq")
    np.testing.assert_array_equal(ds.kp, [2000.0, 2400.0])
    np.testing.assert_array_equal(ds.freq, excitation.freq)
    assert ds.k.attrs["units"] == "N/m"
    # The grid point (kp=2400, kd=4) is row 3 of the flat result.
    np.testing.assert_array_equal(ds.k.sel(kp=2400.0, kd=4.0), result.k[3])


def test_a_swept_dead_time_and_fs_carry_their_units(setup) -> None:
    # The sweep's units are the parameters' own table: dead_time in s, fs in Hz (both were reported as "").
    rig, pid, excitation = setup
    result = af.sweep(rig, pid, excitation, dead_time=[0.0, 1e-4], periods=2)
    assert "dead_time: [0, 0.0001] s" in repr(result)
    assert (unit_of("dead_time"), unit_of("fs"), unit_of("kp")) == ("s", "Hz", "A/m")
    pytest.importorskip("xarray")
    assert result.to_xarray().dead_time.attrs["units"] == "s"


def test_vectorised_prediction_matches_one_by_one(setup) -> None:
    rig, pid, excitation = setup
    kp = np.array([1800.0, 2200.0, 2600.0])
    batch = af.predict(rig, pid, excitation.freq, kp=kp, kd=[[4.0], [6.0]])  # broadcast: 2 x 3 gain sets
    assert batch.shape == (6, excitation.freq.size)
    for row, (d, p) in enumerate([(d, p) for d in (4.0, 6.0) for p in kp]):
        single = af.predict(rig, replace(pid, kp=p, kd=d), excitation.freq)
        np.testing.assert_allclose(batch[row], single, rtol=1e-11)
    k, c = af.effective_coefficients(rig, pid, excitation.freq, ki=[0.0, 1e4], discrete=True)
    k1, c1 = af.effective_coefficients(rig, replace(pid, ki=1e4), excitation.freq, discrete=True)
    np.testing.assert_allclose(k[1], k1, rtol=1e-12)
    np.testing.assert_allclose(c[1], c1, rtol=1e-11)


def test_progress_bar_when_asked_and_quiet_otherwise(setup, capsys) -> None:
    pytest.importorskip("tqdm")
    rig, pid, excitation = setup
    af.sweep(rig, pid, excitation, kp=[2000.0, 2200.0], periods=2, progress=True)
    assert "2/2" in capsys.readouterr().err
    af.sweep(rig, pid, excitation, kp=[2000.0, 2200.0], periods=2, progress=False)
    assert capsys.readouterr().err == ""


LANE_CASES = {
    # Every shape of the linear kernel that sweeps run in SIMD lanes: a dead time with a whole sample
    # and a fraction, a computation delay, a current limit that clips some points, no lags at all
    # (the sensor reads y itself; the command is the current), a 6-state controller.
    "dead time and delay": (dict(dead_time=1.5 / 4000), dict(delay=1)),
    "current limit": (dict(current_limit=0.108), {}),
    "no lags": (dict(amp_bandwidth=None, eddy_bandwidth=None, sensor_bandwidth=None), {}),
}


@pytest.mark.parametrize("case", [*LANE_CASES, "6-state controller"])
def test_points_run_side_by_side_equal_single_runs_bit_for_bit(setup, case) -> None:
    rig, pid, excitation = setup
    if case == "6-state controller":
        controller = pid.to_controller() * af.notch(700.0) * af.low_pass(1500.0, order=2)
        kp = np.linspace(1800.0, 2600.0, 6)  # lanes of four (AVX2) and two, or three lanes of two
        result = af.sweep(rig, controller, excitation, kp=kp, seed=3, periods=3, progress=False)
        singles = [controller.with_params(kp=k) for k in kp]
    else:
        rig_changes, pid_changes = LANE_CASES[case]
        rig, pid = replace(rig, **rig_changes), replace(pid, **pid_changes)
        kp = np.linspace(1800.0, 2600.0, 6)
        result = af.sweep(rig, pid, excitation, kp=kp, seed=3, periods=3, progress=False)
        singles = [replace(pid, kp=k) for k in kp]
    if case == "current limit":  # the limit (peak command ~0.11 A) clips some points only
        assert "saturated" in list(result.status) and "ok" in list(result.status)
    else:
        assert list(result.status) == ["ok"] * len(kp)
    for i, point in enumerate(singles):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            single = af.run_experiment(rig, point, excitation, periods=3, seed=int(result.seeds[i]))
        if single.saturated_samples:
            assert result.status[i] == "saturated"
            continue
        for name in ("H", "k", "c", "k_std", "c_std", "k_smooth", "c_smooth"):
            np.testing.assert_array_equal(getattr(result, name)[i], getattr(single, name), err_msg=f"{name} at {i}")


def test_a_linear_point_reaching_its_clearance_is_flagged_beside_the_others(setup) -> None:
    rig, pid, excitation = setup
    rig = replace(rig, clearance=5e-5)
    kp = [1300.0, 2400.0, 2500.0]  # the soft point moves most
    result = af.sweep(rig, pid, excitation, kp=kp, seed=4, periods=3, progress=False)
    for i, k in enumerate(kp):
        try:
            single = af.run_experiment(rig, replace(pid, kp=k), excitation, periods=3, seed=int(result.seeds[i]))
        except af.TouchdownError:
            assert result.status[i] == "touchdown"
            assert np.all(np.isnan(result.k[i]))
            continue
        assert result.status[i] == "ok"
        np.testing.assert_array_equal(result.k[i], single.k)
    assert list(result.status) == ["touchdown", "ok", "ok"]


def test_a_sweeps_arrays_own_the_cores_memory_and_are_writable(setup) -> None:
    """The core's arrays are handed over without a copy: numpy arrays that keep the core's memory alive as
    long as any view of them lives, and writable like any result."""
    import gc

    rig, pid, excitation = setup
    kwargs = dict(kp=[2000.0, 2400.0], seed=3, periods=3, progress=False)
    row = af.sweep(rig, pid, excitation, **kwargs).k[1]  # a view; the result itself is gone
    gc.collect()
    _ = [np.ones(10_000) for _ in range(100)]  # reuse whatever memory was freed
    again = af.sweep(rig, pid, excitation, **kwargs)
    np.testing.assert_array_equal(row, again.k[1])
    for name in FIELDS:
        assert getattr(again, name).flags.writeable, name
    again.k[0, 0] = 0.0
    assert af.sweep(rig, pid, excitation, **kwargs).k[0, 0] != 0.0
