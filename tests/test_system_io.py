"""Results of N axes: EstimateN and SweepResultN saved and loaded exactly, damaged files refused naming them,
the xarray and pandas views, and the N x N coefficient figure."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system

SPHS = af.schroeder_multisine(f0=20.0, f_max=200.0)


@pytest.fixture(scope="module")
def rotor_estimate() -> system.EstimateN:
    return af.run_experiment(af.RotorRig.example(), af.RotorRig.example_controller(), SPHS, periods=3, seed=1)


@pytest.fixture(scope="module")
def two_axis_estimate() -> system.EstimateN:
    return system.run_experiment(af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=100.0),
                                 periods=3, seed=2)  # fmt: skip


@pytest.fixture(scope="module")
def rotor_sweep() -> system.SweepResultN:
    result = af.sweep(af.RotorRig.example(), af.RotorRig.example_controller(), af.schroeder_multisine(f0=40.0,
                      f_max=120.0), speed=[0.0, 1000.0], kd=[8.0, 10.0], periods=2, seed=3, progress=False)  # fmt: skip
    # a point flagged unstable, NaN as sweep leaves it, to see NaN and the status survive a file
    nan = {n: getattr(result, n).copy() for n in ("k", "c", "k_std", "c_std", "receptance")}
    for values in nan.values():
        values[1] = np.nan
    return dataclasses.replace(result, stable=np.array([True, False, True, True]), **nan)


@pytest.mark.parametrize("suffix", [".nc", ".npz", ".csv"])
@pytest.mark.parametrize("which", ["rotor_estimate", "two_axis_estimate"])
def test_estimate_round_trip_is_exact(suffix: str, which: str, tmp_path: Path, request) -> None:
    est = request.getfixturevalue(which)
    path = est.save(tmp_path / f"e{suffix}")
    back = af.load_estimate(path)
    assert isinstance(back, system.EstimateN)
    assert back == est  # every array bit for bit, periods and axes
    assert back.axes == est.axes and back.periods == est.periods
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left


def _flip(path: Path, where: float = 0.5) -> None:
    data = bytearray(path.read_bytes())
    data[int(len(data) * where)] ^= 0x10
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("suffix", [".nc", ".npz", ".csv"])
@pytest.mark.parametrize("where", [0.3, 0.6, 0.9])
def test_damaged_estimate_is_refused_naming_the_file(suffix: str, where: float, rotor_estimate, tmp_path) -> None:
    path = rotor_estimate.save(tmp_path / f"rotor{suffix}")
    _flip(path, where)
    with pytest.raises(ValueError, match=rf"rotor\{suffix}.*damaged"):
        af.load_estimate(path)


def test_estimate_files_refuse_other_suffixes_and_keep_the_old_file(rotor_estimate, tmp_path, monkeypatch) -> None:
    with pytest.raises(ValueError, match=r"path must be a file name ending in .nc, .npz or .csv, got '.*e.xlsx'"):
        rotor_estimate.save(tmp_path / "e.xlsx")
    path = rotor_estimate.save(tmp_path / "e.npz")
    before = path.read_bytes()

    def fail(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", fail)
    with pytest.raises(OSError, match="could not write .*e.npz.*unchanged"):
        rotor_estimate.save(path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["e.npz"]


def test_one_axis_estimates_still_load(tmp_path) -> None:
    est = af.run_experiment(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=100.0), seed=1)
    for suffix in (".csv", ".nc"):
        back = af.load_estimate(est.save(tmp_path / f"one{suffix}"))
        assert isinstance(back, af.Estimate) and back == est


def test_estimate_to_xarray(rotor_estimate) -> None:
    est = rotor_estimate
    ds = est.to_xarray()
    assert ds.k.dims == ("freq", "out", "in") and ds.force.dims == ("freq", "channel", "experiment")
    assert list(ds.out.values) == list(ds["in"].values) == list(est.axes)
    units = {"k": "N/m", "c": "N s/m", "H": "N/m", "receptance": "m/N", "k_std": "N/m", "force": "N", "freq": "Hz"}
    assert {name: ds[name].attrs["units"] for name in units} == units
    entry = ds.k.sel({"out": "A.x", "in": "B.x"}).values
    assert np.array_equal(entry, est.k[:, 0, 2])
    assert np.array_equal(ds.H.values, est.H) and np.array_equal(ds.displacement.values, est.displacement)
    assert ds.attrs["periods"] == 3


def test_estimate_to_dataframe_is_long_form(rotor_estimate) -> None:
    est = rotor_estimate
    frame = est.to_dataframe()
    lines, N = est.freq.size, len(est.axes)
    assert len(frame) == lines * N * N
    assert list(frame.columns[:5]) == ["freq_Hz", "i", "j", "H_real_N_per_m", "H_imag_N_per_m"]
    row = frame[(frame.freq_Hz == est.freq[3]) & (frame.i == "B.y") & (frame.j == "A.x")]
    assert len(row) == 1
    assert row.k_N_per_m.item() == est.k[3, 3, 0] and row.c_std_Ns_per_m.item() == est.c_std[3, 3, 0]
    assert row.receptance_imag_m_per_N.item() == est.receptance[3, 3, 0].imag


@pytest.mark.parametrize("suffix", [".nc", ".npz"])
def test_sweep_round_trip_is_exact(suffix: str, rotor_sweep, tmp_path) -> None:
    path = rotor_sweep.save(tmp_path / f"s{suffix}")
    back = system.SweepResultN.load(path)
    assert back == rotor_sweep  # NaN rows included
    assert list(back.status) == ["ok", "unstable", "ok", "ok"]
    assert list(back.params) == ["speed", "kd"]


@pytest.mark.parametrize("suffix", [".nc", ".npz"])
def test_damaged_sweep_is_refused_naming_the_file(suffix: str, rotor_sweep, tmp_path) -> None:
    path = rotor_sweep.save(tmp_path / f"grid{suffix}")
    _flip(path)
    with pytest.raises(ValueError, match=rf"grid\{suffix}.*damaged"):
        system.SweepResultN.load(path)


def test_sweep_views(rotor_sweep) -> None:
    ds = rotor_sweep.to_xarray()
    assert ds.k.dims == ("point", "freq", "out", "in")
    assert ds.speed.attrs["units"] == "rad/s" and ds.kd.attrs["units"] == "A s/m"
    assert np.array_equal(ds.speed.values, rotor_sweep.params["speed"])
    assert list(ds.status.values) == ["ok", "unstable", "ok", "ok"]
    assert np.array_equal(ds.k.values, rotor_sweep.k, equal_nan=True)
    frame = rotor_sweep.to_dataframe()
    assert len(frame) == 4 * rotor_sweep.freq.size * 16
    row = frame[(frame.speed == 1000.0) & (frame.kd == 8.0) & (frame.i == "A.y") & (frame.j == "A.y")]
    assert np.array_equal(row.k_N_per_m.to_numpy(), rotor_sweep.k[2, :, 1, 1])
    assert set(frame.status[frame.kd == 10.0][frame.speed == 0.0]) == {"unstable"}


# -- the figure ---------------------------------------------------------------------------------------------------


def test_every_swept_path_carries_its_unit() -> None:
    # A two-axis process's numbers, an off-diagonal gain and the two-axis spelling of an axis' field had no unit.
    pytest.importorskip("xarray")
    paths = {"kxy": [0.0, 1e4], "cyx": [0.0, 1.0], "sensor_angle": [0.0, 0.01], "cross_kp": [0.0, 1.0],
             "x_amp_bandwidth": [1e3, 2e3], "y.dead_time": [0.0, 1e-5], "kd": [3.0, 4.0]}  # fmt: skip
    result = af.two_axis.sweep(af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), grid="zip",
                               periods=2, **paths)  # fmt: skip
    ds = result.to_xarray()
    assert {path: ds[path].attrs["units"] for path in paths} == {
        "kxy": "N/m", "cyx": "N s/m", "sensor_angle": "rad", "cross_kp": "A/m", "x_amp_bandwidth": "Hz",
        "y.dead_time": "s", "kd": "A s/m"}  # fmt: skip


def _panels(fig) -> dict[str, object]:  # noqa: ANN001
    return {ax.get_title(): ax for ax in fig.axes if ax.get_visible()}


def test_plot_all_terms_draws_every_entry_with_effective(rotor_estimate) -> None:
    est = rotor_estimate
    K, C = af.effective_coefficients(af.RotorRig.example(), af.RotorRig.example_controller(), est.freq)
    fig = est.plot(effective=(K, C))
    panels = _panels(fig)
    assert len(panels) == 32
    for i, a in enumerate(est.axes):
        for j, b in enumerate(est.axes):
            k_ax, c_ax = panels[f"k[{a}, {b}] (kN/m)"], panels[f"c[{a}, {b}] (N s/m)"]
            assert np.array_equal(k_ax.lines[0].get_xdata(), est.freq)
            assert np.array_equal(k_ax.lines[0].get_ydata(), est.k[:, i, j] / 1e3)
            assert np.array_equal(k_ax.lines[1].get_ydata(), K[:, i, j] / 1e3)
            assert np.array_equal(c_ax.lines[0].get_ydata(), est.c[:, i, j])
            assert np.array_equal(c_ax.lines[1].get_ydata(), C[:, i, j])
            assert k_ax.get_xscale() == "log"
    assert panels["c[B.y, B.y] (N s/m)"].get_xlabel() == "frequency (Hz)"


def test_plot_direct_cross_and_chosen_terms(rotor_estimate, two_axis_estimate) -> None:
    est = rotor_estimate
    direct = _panels(est.plot(terms="direct", smoothed=True))
    assert sorted(direct) == sorted(
        f"{q}[{a}, {a}] ({u})" for a in est.axes for q, u in (("k", "kN/m"), ("c", "N s/m"))
    )
    assert np.array_equal(direct["k[B.x, B.x] (kN/m)"].lines[0].get_ydata(), est.k_smooth[:, 2, 2] / 1e3)
    assert len(direct["k[B.x, B.x] (kN/m)"].lines) == 1  # no effective overlay asked for
    cross = _panels(est.plot(terms="cross"))
    assert len(cross) == 24 and "k[A.x, A.x] (kN/m)" not in cross
    chosen = _panels(est.plot(terms=[("A.x", "B.x")]))
    assert sorted(chosen) == ["c[A.x, B.x] (N s/m)", "k[A.x, B.x] (kN/m)"]
    two = two_axis_estimate
    panels = _panels(af.plot_coefficients_n(two))
    assert len(panels) == 8
    assert np.array_equal(panels["c[x, y] (N s/m)"].lines[0].get_ydata(), two.c[:, 0, 1])


def test_plot_refuses_unknown_terms_and_effective_shapes(rotor_estimate) -> None:
    with pytest.raises(ValueError, match=r"terms must be 'all', 'direct', 'cross' or a list of \(out, in\) pairs"):
        rotor_estimate.plot(terms=[("A.x", "C.x")])
    with pytest.raises(ValueError, match=r"effective must be \(K_eff, C_eff\), each of shape \(10, 4, 4\)"):
        rotor_estimate.plot(effective=(rotor_estimate.k[:, :2, :2], rotor_estimate.c[:, :2, :2]))


def test_fit_command_refuses_an_estimate_of_n_axes(rotor_estimate, tmp_path, capsys) -> None:
    """Before: amb-fast fit of an EstimateN's file failed on a missing attribute (AttributeError: blocks)."""
    from cli_helpers import one_error_line, run

    path = rotor_estimate.save(tmp_path / "rotor.csv")
    status, _, err = run(capsys, "fit", str(path))
    assert status == 2
    assert "rotor.csv' holds an estimate of 4 axes; the fit takes a one-axis estimate" in one_error_line(err)


def test_each_loader_refuses_the_others_files(rotor_estimate, rotor_sweep, tmp_path) -> None:
    """Before: load_sweep of an estimate's file raised KeyError 'grid' (.nc) or 'status' (.npz), load_estimate of
    a sweep's .nc KeyError 'amb_fast'."""
    one_sweep = af.sweep(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), kd=[2.0], periods=2,
                         progress=False)  # fmt: skip
    for suffix in (".nc", ".npz"):
        estimate_file = rotor_estimate.save(tmp_path / f"est{suffix}")
        with pytest.raises(ValueError, match=rf"path must be a file written by SweepResult.save .*est\{suffix}'"):
            af.load_sweep(estimate_file)
        with pytest.raises(ValueError, match=r"path must be a(n .npz| .nc) file written by SweepResultN.save"):
            system.SweepResultN.load(estimate_file)
        for sweep in (one_sweep, rotor_sweep):
            sweep.save(tmp_path / f"sweep{suffix}")
            with pytest.raises(ValueError, match=r"path must be a(n .npz| .nc) file written by Estimate"):
                af.load_estimate(tmp_path / f"sweep{suffix}")


@pytest.mark.parametrize("suffix", [".nc", ".npz"])
def test_load_sweep_reads_sweeps_of_n_axes(suffix: str, rotor_sweep, tmp_path) -> None:
    """Before: af.load_sweep refused a SweepResultN's file ("path must be a file written by SweepResult.save");
    it now reads every sweep, as load_estimate reads every estimate."""
    back = af.load_sweep(rotor_sweep.save(tmp_path / f"s{suffix}"))
    assert isinstance(back, system.SweepResultN) and back == rotor_sweep
    assert list(back.status) == ["ok", "unstable", "ok", "ok"]
