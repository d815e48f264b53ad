"""An estimate's NetCDF file is written with h5netcdf alone (``Estimate.save``), without importing xarray: the
file xarray writes from ``Estimate.to_xarray()`` (``save_estimate_with_xarray``, the reference), byte for byte,
booleans encoded as xarray encodes them, and it reads back as ``to_xarray()``'s Dataset."""

from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np
import pytest

import amb_fast as af
from amb_fast.io import _netcdf
from amb_fast.io._netcdf import read_netcdf, save_estimate_with_xarray, write_dataset_netcdf, write_estimate_netcdf
from test_paper_writers import _hdf5_content

pytest.importorskip("h5netcdf")
xr = pytest.importorskip("xarray")

FIELDS = ("freq", "H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force", "displacement",
          "weak")  # fmt: skip
CASES = ("the paper's run (no unexcited line)", "odd lines, one weak", "weak lines every other", "weak left None",
         "identified from a recording")  # fmt: skip


@pytest.fixture(scope="module")
def estimates() -> dict[str, af.Estimate]:
    pid = af.PID.paper()
    paper = af.run_experiment(af.Rig.paper(), pid, af.schroeder_multisine(f_max=50.0), periods=3, seed=1)
    odd = af.schroeder_multisine(f_max=50.0, lines="odd", rms=1.0)
    noisy = af.run_experiment(af.Rig(sensor_noise=1e-5, force_noise=1.0), pid, odd, periods=3, seed=2)
    assert 0 < noisy.weak.sum() < noisy.weak.size  # both values of the boolean in the file
    ms = af.schroeder_multisine(f_max=100.0)
    trace = af.simulate(af.Rig.paper(), pid, np.tile(ms.samples, 6), seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # what identify says about the recording is not the point here
        identified = af.identify(trace.force, trace.displacement, fs=ms.fs, f0=ms.f0, mass=0.98, f_max=100.0,
                                 settle_periods=2)  # fmt: skip
    return {
        CASES[0]: paper,
        CASES[1]: noisy,
        CASES[2]: dataclasses.replace(noisy, weak=np.arange(noisy.freq.size) % 2 == 0),
        CASES[3]: dataclasses.replace(paper, weak=None),
        CASES[4]: identified,
    }


def _assert_same_file(direct, reference) -> None:  # noqa: ANN001
    """The two files hold the same HDF5 datasets (type, shape, chunks, filters, fill value, attributes, values)
    and root attributes, and the same bytes."""
    assert _hdf5_content(direct) == _hdf5_content(reference)
    assert direct.read_bytes() == reference.read_bytes()


def _as_to_xarray(ds):  # noqa: ANN001, ANN202
    """A saved estimate's Dataset with its complex variables joined again and the file's own attributes
    (version, checksum) dropped: what ``Estimate.to_xarray()`` gives."""
    ds = ds.copy()
    for name in [str(n)[: -len("_real")] for n in ds.data_vars if str(n).endswith("_real")]:
        real, imag = ds[f"{name}_real"], ds[f"{name}_imag"]
        assert real.dims == imag.dims and real.attrs == imag.attrs, name
        values = np.empty(real.shape, complex)
        values.real, values.imag = real.values, imag.values  # exact, unlike real + 1j * imag
        ds[name] = xr.Variable(real.dims, values, dict(real.attrs))
        ds = ds.drop_vars([f"{name}_real", f"{name}_imag"])
    ds.attrs = {k: v for k, v in ds.attrs.items() if k not in ("amb_fast_version", "sha256")}
    return ds


def _assert_reads_as_to_xarray(path, estimate: af.Estimate) -> None:  # noqa: ANN001
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        back = _as_to_xarray(ds.load())
    expected = estimate.to_xarray()
    xr.testing.assert_identical(back, expected)
    dtypes = {name: back[name].dtype for name in back.variables}
    assert dtypes == {name: expected[name].dtype for name in expected.variables}  # identical() compares values only


@pytest.mark.parametrize("case", CASES)
def test_an_estimate_written_without_xarray_is_the_file_xarray_writes(tmp_path, estimates, case) -> None:
    estimate = estimates[case]
    reference, direct = tmp_path / "xarray.nc", tmp_path / "direct.nc"
    save_estimate_with_xarray(estimate, reference)
    assert write_estimate_netcdf(estimate, direct) == direct
    _assert_same_file(direct, reference)
    with xr.open_dataset(reference, engine="h5netcdf") as a, xr.open_dataset(direct, engine="h5netcdf") as b:
        xr.testing.assert_identical(a.load(), b.load())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["direct.nc", "xarray.nc"]  # no temporary file left


@pytest.mark.parametrize("case", CASES)
def test_the_file_reads_back_as_to_xarray_and_as_the_estimate(tmp_path, estimates, case) -> None:
    estimate = estimates[case]
    path = estimate.save(tmp_path / "est.nc")
    _assert_reads_as_to_xarray(path, estimate)
    ds = read_netcdf(path)  # its checksums (file SHA-256, dataset SHA-256, fletcher32) hold
    assert ds.weak.dtype == bool and ds.weak.attrs == {"description": "force or displacement under 10x the "
                                                       "unexcited level"}  # fmt: skip
    assert ds.weak.encoding["dtype"] == "bool" and ds.weak.encoding["fletcher32"]
    back = af.load_estimate(path)
    for name in FIELDS:
        expected = getattr(estimate, name)
        if name == "weak" and expected is None:
            expected = np.zeros(estimate.freq.size, bool)
        np.testing.assert_array_equal(getattr(back, name), expected, err_msg=name)
        assert getattr(back, name).dtype == np.asarray(expected).dtype, name
    for name in ("freq", "force", "displacement"):
        np.testing.assert_array_equal(getattr(back.unexcited, name), getattr(estimate.unexcited, name))
    assert (back.periods, back.blocks, back.saturated_samples) == (estimate.periods, estimate.blocks,
                                                                    estimate.saturated_samples)  # fmt: skip
    assert back.meta["source"] == estimate.meta["source"] and back.meta["seed"] == estimate.meta["seed"]


def _int8_without_dtype(values, attrs):  # noqa: ANN001, ANN202
    return (values.astype("i1"), attrs) if values.dtype.kind == "b" else (values, attrs)


def _uint8_marked_bool(values, attrs):  # noqa: ANN001, ANN202
    return (values.astype("u1"), {**attrs, "dtype": "bool"}) if values.dtype.kind == "b" else (values, attrs)


def _float_marked_bool(values, attrs):  # noqa: ANN001, ANN202
    return (values.astype(float), {**attrs, "dtype": "bool"}) if values.dtype.kind == "b" else (values, attrs)


@pytest.mark.parametrize(
    ("encode", "reads_as_to_xarray"),
    [(_int8_without_dtype, False), (_uint8_marked_bool, True), (_float_marked_bool, True)],
    ids=["int8 without dtype: bool", "uint8 marked bool", "float marked bool"],
)
def test_a_wrong_boolean_encoding_is_caught(tmp_path, estimates, monkeypatch, encode, reads_as_to_xarray) -> None:
    """The checks above fail for booleans encoded otherwise than xarray does (int8 with the attribute ``dtype:
    "bool"``): the file comparison always; the round trip through xarray when xarray does not decode them back
    to bool. (h5netcdf itself refuses numpy's bool for a NetCDF file.)"""
    estimate = estimates["weak lines every other"]
    reference, direct = tmp_path / "xarray.nc", tmp_path / "direct.nc"
    save_estimate_with_xarray(estimate, reference)
    monkeypatch.setattr(_netcdf, "_encoded", encode)
    write_estimate_netcdf(estimate, direct)
    with pytest.raises(AssertionError):
        _assert_same_file(direct, reference)
    if reads_as_to_xarray:  # xarray decodes any integer marked bool: only the file comparison sees this one
        _assert_reads_as_to_xarray(direct, estimate)
    else:
        with pytest.raises(AssertionError):
            _assert_reads_as_to_xarray(direct, estimate)


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary_file(tmp_path, estimates, monkeypatch) -> None:
    path = estimates["odd lines, one weak"].save(tmp_path / "est.nc")
    before = path.read_bytes()

    def fail(values, attrs):  # noqa: ANN001, ANN202
        raise RuntimeError("the writer stopped half-way")

    monkeypatch.setattr(_netcdf, "_encoded", fail)
    with pytest.raises(RuntimeError, match="half-way"):
        estimates["the paper's run (no unexcited line)"].save(path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["est.nc"]


@pytest.mark.parametrize(
    ("data", "coords"),
    [
        ({"k": (("point",), np.ones(2), {})}, {"kp": (("point",), np.ones(2), {})}),  # xarray: a coordinates attribute
        ({"t": (("freq",), np.array(["2026-01-01", "2026-01-02"], "M8[D]"), {})}, {}),  # dates: xarray's units
        ({"f": (("freq",), np.array([True, False]), {"dtype": "bool"})}, {}),  # not encoded by xarray
        ({"s": ((), np.float64(1.0), {})}, {}),  # a scalar
        ({"k": (("freq",), np.ones(2), {"_FillValue": -1.0})}, {}),  # an attribute of xarray's CF encoding
    ],
    ids=[
        "a coordinate along another dimension",
        "dates",
        "a boolean with a dtype attribute",
        "a scalar",
        "a fill value",
    ],  # fmt: skip
)
def test_what_the_direct_writer_does_not_lay_out_is_left_to_xarray(tmp_path, data, coords) -> None:
    assert write_dataset_netcdf(tmp_path / "x.nc", data, coords, {}) is False
    assert list(tmp_path.iterdir()) == []


def test_without_xarray_every_view_and_reader_says_what_needs_it(tmp_path, estimates, monkeypatch) -> None:
    ms = af.schroeder_multisine(f_max=20.0)
    path = estimates["odd lines, one weak"].save(tmp_path / "e.nc")
    results = {
        "Estimate": estimates["odd lines, one weak"],
        "SweepResult": af.sweep(af.Rig(), af.PID.paper(), ms, kd=[3.0], periods=2, progress=False),
        "EstimateN": af.two_axis.run_experiment(af.TwoAxisRig.paper(), af.PID.paper(), ms, periods=2),
    }
    monkeypatch.setitem(sys.modules, "xarray", None)  # import xarray now fails as when it is not installed
    for name, result in results.items():
        with pytest.raises(ImportError, match=r"^to_xarray needs xarray: pip install 'amb_fast\[xarray\]'$"):
            result.to_xarray()
            pytest.fail(f"{name}.to_xarray() without xarray")
    with pytest.raises(ImportError, match=r"^reading \.nc needs xarray and h5netcdf: pip install 'amb_fast\[xarray\]'"):
        af.load_estimate(path)
