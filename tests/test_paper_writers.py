"""The cheaper writers of ``amb-fast paper``: a sweep's NetCDF without xarray is the file ``SweepResult.save``
writes, and a figure is drawn once by ``savefig`` (no second, layout-only draw)."""

from __future__ import annotations

import io

import numpy as np
import pytest

import amb_fast as af
from amb_fast._sweep_result import save_netcdf_with_xarray
from amb_fast.io._netcdf import read_netcdf, write_sweep_netcdf

FIELDS = ("freq", "H", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "status", "settle_periods", "seeds",
          "unexcited_freq", "unexcited_displacement")  # fmt: skip


CASES = ("one gain, as the paper", "two gains", "an unstable point (NaN)", "unexcited lines",
         "zip grid (xarray's writer)")  # fmt: skip


@pytest.fixture(scope="module")
def sweeps() -> dict[str, af.SweepResult]:
    pid = af.PID.paper()
    small = af.schroeder_multisine(f_max=20.0)

    def run(rig: af.Rig, excitation: af.Multisine, **kw) -> af.SweepResult:  # noqa: ANN003
        return af.sweep(rig, pid, excitation, periods=2, seed=3, progress=False, **kw)

    return {
        "one gain, as the paper": run(af.Rig.paper(), af.schroeder_multisine(), ki=pid.ki * np.array([0.67, 1.0])),
        "two gains": run(af.Rig(), small, kp=[2200.0, 2600.0], kd=[2.0, 3.0, 4.0]),
        "an unstable point (NaN)": run(af.Rig(), small, kp=[2200.0, 300.0]),
        "unexcited lines": run(
            af.Rig(sensor_noise=1e-8), af.schroeder_multisine(f_max=40.0, lines="odd"), kd=[2.0, 3.0]
        ),
        "zip grid (xarray's writer)": run(af.Rig(), small, kp=[2200.0, 2600.0], kd=[2.0, 3.0], grid="zip"),
    }


def _hdf5_content(path) -> dict:  # noqa: ANN001
    """Every HDF5 dataset's type, shape, chunks, filters, fill value, attributes and values; the root attributes."""
    import h5py

    content: dict = {}
    with h5py.File(path, "r") as f:
        content["/"] = {key: repr(value) for key, value in f.attrs.items()}

        def visit(name: str, obj) -> None:  # noqa: ANN001
            if not isinstance(obj, h5py.Dataset):
                return
            attrs = {k: repr(v) for k, v in obj.attrs.items() if k not in ("DIMENSION_LIST", "REFERENCE_LIST")}
            if "DIMENSION_LIST" in obj.attrs:
                attrs["dimensions"] = [f[ref[0]].name for ref in obj.attrs["DIMENSION_LIST"]]
            content[name] = {"dtype": str(obj.dtype), "shape": obj.shape, "chunks": obj.chunks,
                             "fletcher32": obj.fletcher32, "compression": obj.compression, "attrs": attrs,
                             "values": repr(obj[...].tolist())}  # fmt: skip

        f.visititems(visit)
    return content


@pytest.mark.parametrize("case", CASES)
def test_a_sweep_written_without_xarray_is_the_file_save_writes(tmp_path, sweeps, case) -> None:
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    result = sweeps[case]
    reference, direct = tmp_path / "save.nc", tmp_path / "direct.nc"
    save_netcdf_with_xarray(result, reference)  # the reference: xarray's file of to_xarray()
    assert write_sweep_netcdf(result, direct) == direct
    assert _hdf5_content(direct) == _hdf5_content(reference)
    with xr.open_dataset(reference, engine="h5netcdf") as a, xr.open_dataset(direct, engine="h5netcdf") as b:
        assert a.load().identical(b.load())
    read_netcdf(direct)  # its checksums (file SHA-256, dataset SHA-256, fletcher32) hold
    back = af.load_sweep(direct)
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(back, name), getattr(result, name), err_msg=name)
    assert back.grid == result.grid and back.shape == result.shape and back.meta == result.meta
    assert {k: v.tolist() for k, v in back.points.items()} == {k: v.tolist() for k, v in result.points.items()}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["direct.nc", "save.nc"]  # no temporary file left


def test_a_sweep_written_without_xarray_is_refused_when_damaged(tmp_path, sweeps) -> None:
    pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path = write_sweep_netcdf(sweeps["two gains"], tmp_path / "s.nc")
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="damaged"):
        af.load_sweep(path)


def test_figures_are_drawn_once_by_savefig(monkeypatch) -> None:
    """tight_layout used to leave a placeholder layout engine behind, which made savefig draw every figure twice;
    the two-axis figure's constrained layout did the same."""
    pytest.importorskip("matplotlib")
    from dataclasses import replace

    from matplotlib.figure import Figure

    import amb_fast.two_axis as ta

    estimate = af.run_experiment(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), periods=2)
    coupled = replace(ta.TwoAxisRig.paper(), kxy=1e4, kyx=-1e4)
    sphs = af.schroeder_multisine(f0=20.0, f_max=100.0)
    estimate2 = ta.run_experiment(coupled, af.PID.paper(), sphs, periods=2, seed=1)
    effective2 = ta.effective_coefficients(coupled, af.PID.paper(), estimate2.freq)
    draws = {"n": 0}
    draw = Figure.draw

    def counted(self, renderer):  # noqa: ANN001, ANN202
        draws["n"] += 1
        return draw(self, renderer)

    monkeypatch.setattr(Figure, "draw", counted)
    for fig in (af.plot_actual(estimate), af.plot_estimate(estimate),
                af.plot_coefficients2(estimate2, effective=effective2)):  # fmt: skip
        assert fig.get_layout_engine() is None
        left = fig.subplotpars.left
        draws["n"] = 0
        fig.savefig(io.BytesIO(), format="png", dpi=50)
        assert draws["n"] == 1
        assert fig.subplotpars.left == left  # the layout stays the one tight_layout made
