"""Files in and out (amb_fast.io): the readers for what rigs write, atomic writes, saved results and checksums.

Every file is generated here; none is a fixture.
"""

from __future__ import annotations

import os
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import amb_fast as af
from amb_fast.io import _atomic

FS = 4000.0


@pytest.fixture(scope="module")
def recording() -> tuple[np.ndarray, np.ndarray]:
    """Force (N) and displacement (m) of the paper rig, 8 periods of a 1-100 Hz multisine."""
    ms = af.schroeder_multisine(f_max=100.0)
    trace = af.simulate(af.Rig.paper(), af.PID.paper(), np.tile(ms.samples, 8), seed=1)
    return trace.force, trace.displacement


def write_rows(path: Path, header: str, rows: np.ndarray, fmt: str, delimiter: str, comma: bool = False) -> None:
    with open(path, "w") as handle:
        handle.write(header)
        for row in rows:
            line = delimiter.join(fmt % v for v in row)
            handle.write((line.replace(".", ",") if comma else line) + "\n")


# -- CSV dialects ---------------------------------------------------------------------------------------------------


def test_semicolons_decimal_commas_quoted_header_and_a_units_row(tmp_path, recording, text_parser) -> None:
    force, displacement = recording
    t = np.arange(force.size) / FS
    path = tmp_path / "rig.csv"
    rows = np.column_stack([t, force / 1e3, displacement * 1e3])  # kN and mm, named in the units row
    write_rows(path, '"time";"Force";"Disp"\n"s";"kN";"mm"\n', rows, "%.15e", ";", comma=True)
    rec = af.load_recording(path, force="Force", displacement="Disp")
    assert rec.fs == pytest.approx(FS, rel=1e-9)
    np.testing.assert_allclose(rec.force, force, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-13, atol=1e-20)
    assert "Force [kN]" in rec.source and "Disp [mm]" in rec.source


def test_tabs_units_in_names_extra_columns_and_channels_by_index(tmp_path, recording, text_parser) -> None:
    force, displacement = recording
    path = tmp_path / "rig.tsv"
    rows = np.column_stack([np.arange(force.size) / FS, np.ones(force.size), force, displacement * 1e6])
    write_rows(path, "time\tsupply [V]\tforce [N]\tdisplacement [um]\n", rows, "%.17g", "\t")
    by_name = af.load_recording(path)
    by_index = af.load_recording(path, force=2, displacement=3)
    for rec in (by_name, by_index):
        np.testing.assert_array_equal(rec.force, force)
        np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-15)
    with pytest.raises(ValueError, match="the force channel 'supply \\[V\\]' has unit 'V'"):
        af.load_recording(path, force="supply")


def test_blank_separated_text_with_comment_lines_and_a_unit_suffix(tmp_path, recording, text_parser) -> None:
    force, displacement = recording
    path = tmp_path / "rig.txt"
    rows = np.column_stack([np.arange(force.size) / FS, force, displacement * 1e3])
    write_rows(path, "# rig 3, morning run\n% exported by a scope\ntime force displacement_mm\n", rows, "%.17g", "   ")
    rec = af.load_recording(path)
    np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-15)
    assert rec.fs == pytest.approx(FS)


def test_duplicate_column_names_are_refused_not_one_silently_chosen(tmp_path, text_parser) -> None:
    path = tmp_path / "dup.csv"
    write_rows(path, "time,force,force,displacement\n", np.ones((20, 4)) * np.arange(20)[:, None] / FS, "%.17g", ",")
    with pytest.raises(ValueError, match="ambiguous: columns \\['1: force', '2: force'\\]"):
        af.load_recording(path, fs=FS)
    assert af.load_recording(path, force=2, fs=FS).force[3] == 3.0 / FS


def test_fs_must_agree_with_the_time_column(tmp_path, recording, text_parser) -> None:
    path = tmp_path / "rec.csv"
    af.save_recording(path, force=recording[0], displacement=recording[1], fs=FS)
    with pytest.raises(
        ValueError, match=r"fs must agree with rec.csv's time column 'time' \(4000 Hz\) within 0.1 %, got 4"
    ):
        af.load_recording(path, fs=4.0)
    assert af.load_recording(path, fs=4001.0).fs == 4001.0  # within 0.1 %: the given value is used
    gap = tmp_path / "gap.csv"
    t = np.r_[np.arange(10), np.arange(12, 20)] / FS  # two samples missing
    write_rows(gap, "time,force,displacement\n", np.column_stack([t, t, t]), "%.17g", ",")
    with pytest.raises(ValueError, match=r"not a uniform clock: at data row 10 \(t = 0.003\)"):
        af.load_recording(gap)


@pytest.mark.parametrize(("columns", "rows"), [(6, 300_000), (40, 60_000)], ids=["6-columns", "40-columns"])
def test_a_large_csv_keeps_only_the_chosen_columns(tmp_path, text_parser, columns, rows) -> None:
    """Peak traced memory while reading a 20-30 MB CSV stays under 2x the two float64 channels however many
    columns it has; the control (numpy's loadtxt of the whole table) is measured the same way and exceeds it."""
    rng = np.random.default_rng(0)
    table = np.column_stack([np.arange(rows) / FS, rng.standard_normal((rows, columns - 1))])
    names = ["time", "a", "force", "b", "displacement"] + [f"x{j}" for j in range(columns - 5)]
    path = tmp_path / "big.csv"
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.9g")
    assert path.stat().st_size > 15e6
    channels = 2 * rows * 8
    af.load_recording(path)  # the parser's first-use allocations are not the file's
    tracemalloc.start()
    try:
        rec = af.load_recording(path)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.reset_peak()
        np.loadtxt(path, delimiter=",", skiprows=1)
        control = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_allclose(rec.force[:5], table[:5, 2], rtol=1e-8)
    assert channels <= peak < 2 * channels, (peak, channels)  # the time column held too, for its fit
    assert control > 2 * channels  # the measure sees a whole-table read


# -- MATLAB ---------------------------------------------------------------------------------------------------------


def dspace(t: np.ndarray, channels: dict[str, np.ndarray]) -> dict:
    """A dSPACE ControlDesk export as scipy writes MATLAB structs: X.Data time, Y(k).Name / Y(k).Data."""
    Y = np.zeros((1, len(channels)), dtype=[("Name", "O"), ("Data", "O")])
    for k, (name, data) in enumerate(channels.items()):
        Y[0, k]["Name"], Y[0, k]["Data"] = name, data
    X = np.zeros((1, 1), dtype=[("Data", "O")])
    X[0, 0]["Data"] = t
    return {"X": X, "Y": Y}


def test_mat_with_text_and_cells_reads_the_numeric_variables(tmp_path, recording) -> None:
    from scipy.io import savemat

    force, displacement = recording
    path = tmp_path / "run.mat"
    savemat(path, {"force": force, "displacement": displacement, "fs": FS, "note": "rig 3, morning",
                   "settings": np.array([1.0, "gain"], dtype=object)})  # fmt: skip
    rec = af.load_recording(path)
    np.testing.assert_array_equal(rec.force, force)
    assert rec.fs == FS


def test_mat_with_two_dspace_recordings_is_never_mixed(tmp_path, recording) -> None:
    from scipy.io import savemat

    force, displacement = recording
    t = np.arange(force.size) / FS
    names = {"Model Root/Sensors/Force": force, "Model Root/Sensors/displacement": displacement}
    second = {"Model Root/Sensors/Force": 2 * force, "Model Root/Sensors/displacement": displacement}
    path = tmp_path / "two.mat"
    savemat(path, {"morning": dspace(t, names), "evening": dspace(t, second)})
    with pytest.raises(
        ValueError, match=r"holds several recordings \['evening', 'morning'\]: choose one with recording="
    ):
        af.load_recording(path, force="Force")
    rec = af.load_recording(path, force="Force", recording="evening")
    np.testing.assert_array_equal(rec.force, 2 * force)
    assert rec.fs == pytest.approx(FS) and "evening" in rec.source
    with pytest.raises(ValueError, match="recording must be one of"):
        af.load_recording(path, force="Force", recording="noon")


def write_mat73(path: Path, variables: dict[str, np.ndarray], exports: dict[str, dict[str, np.ndarray]]) -> None:
    """A MATLAB v7.3 file as MATLAB lays it out: HDF5 behind a 512-byte header, column-major arrays, struct
    arrays as groups of object references into '#refs#', text as uint16 'char'."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")
        for name, value in variables.items():
            f.create_dataset(name, data=np.atleast_2d(value)).attrs["MATLAB_class"] = np.bytes_("double")
        f.create_dataset("note", data=np.array([[ord(c)] for c in "rig 3"], dtype=np.uint16)).attrs["MATLAB_class"] = (
            np.bytes_("char")
        )
        for name, channels in exports.items():
            group = f.create_group(name)
            group.attrs["MATLAB_class"] = np.bytes_("struct")
            x = group.create_group("X")
            x.attrs["MATLAB_class"] = np.bytes_("struct")
            x.create_dataset("Data", data=channels.pop("time")[None, :])
            y = group.create_group("Y")
            y.attrs["MATLAB_class"] = np.bytes_("struct")
            name_refs, data_refs = [], []
            for k, (channel, data) in enumerate(channels.items()):
                label = refs.create_dataset(f"{name}_n{k}", data=np.array([[ord(c)] for c in channel], np.uint16))
                label.attrs["MATLAB_class"] = np.bytes_("char")
                name_refs.append(label.ref)
                data_refs.append(refs.create_dataset(f"{name}_d{k}", data=data[None, :]).ref)
            y.create_dataset("Name", data=np.array(name_refs, dtype=h5py.ref_dtype)[:, None])
            y.create_dataset("Data", data=np.array(data_refs, dtype=h5py.ref_dtype)[:, None])
    with open(path, "r+b") as handle:
        handle.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, written by amb_fast's tests".ljust(116) + bytes(12))


def test_mat_v73_variables_and_dspace_exports(tmp_path, recording) -> None:
    force, displacement = recording
    t = np.arange(force.size) / FS
    plain = tmp_path / "plain73.mat"
    write_mat73(plain, {"force": force, "displacement": displacement, "fs": np.array(FS)}, {})
    rec = af.load_recording(plain)
    np.testing.assert_array_equal(rec.force, force)
    np.testing.assert_array_equal(rec.displacement, displacement)
    assert rec.fs == FS

    exports = tmp_path / "dspace73.mat"
    write_mat73(exports, {}, {
        "run1": {"time": t, "Platform/Force": force, "Platform/displacement": displacement},
        "run2": {"time": t, "Platform/Force": -force, "Platform/displacement": displacement},
    })  # fmt: skip
    with pytest.raises(ValueError, match=r"holds several recordings \['run1', 'run2'\]"):
        af.load_recording(exports, force="Force")
    rec = af.load_recording(exports, force="Force", recording="run2")
    np.testing.assert_array_equal(rec.force, -force)
    assert rec.fs == pytest.approx(FS)


# -- TDMS -----------------------------------------------------------------------------------------------------------


def test_tdms_groups_are_recordings_and_units_are_scaled(tmp_path, recording) -> None:
    nptdms = pytest.importorskip("nptdms")
    force, displacement = recording
    path = tmp_path / "rig.tdms"
    props = {"wf_increment": 1 / FS}
    mm = {**props, "unit_string": "mm"}
    with nptdms.TdmsWriter(path) as writer:
        writer.write_segment([
            nptdms.ChannelObject("run A", "Force", force, properties={**props, "unit_string": "N"}),
            nptdms.ChannelObject("run A", "Displacement", displacement * 1e3, properties=mm),
            nptdms.ChannelObject("run B", "Force", force, properties=props),
        ])  # fmt: skip
    with pytest.raises(ValueError, match=r"holds several recordings \['run A', 'run B'\]"):
        af.load_recording(path, force="Force", displacement="Displacement")
    rec = af.load_recording(path, force="Force", displacement="Displacement", recording="run A")
    np.testing.assert_array_equal(rec.force, force)
    np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-15)
    assert rec.fs == pytest.approx(FS)


# -- atomic writes --------------------------------------------------------------------------------------------------


def test_a_write_that_fails_part_way_leaves_the_old_file_intact(tmp_path, recording, monkeypatch) -> None:
    force, displacement = recording
    path = tmp_path / "rec.csv"
    af.save_recording(path, force=force, displacement=displacement, fs=FS)
    before = path.read_bytes()

    real_savetxt = np.savetxt
    calls = {"n": 0}

    def full_disk(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202 - the second chunk finds the disk full
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError(28, "No space left on device")
        return real_savetxt(*args, **kwargs)

    monkeypatch.setattr(np, "savetxt", full_disk)
    long = np.tile(force, 20)
    with pytest.raises(OSError, match="could not write .*rec.csv.*the old file, if any, is unchanged.*No space left"):
        af.save_recording(path, force=long, displacement=np.tile(displacement, 20), fs=FS)
    assert calls["n"] == 2
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["rec.csv"]  # no temporary file left behind


def test_a_failed_replace_leaves_the_old_estimate_and_a_netcdf_failure_too(tmp_path, monkeypatch) -> None:
    est = af.run_experiment(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=50.0), periods=3)
    for name in ("est.csv", "est.nc"):
        path = tmp_path / name
        est.save(path)
        before = path.read_bytes()

        def no_replace(src, dst):  # noqa: ANN001, ANN202
            raise OSError(5, "Input/output error")

        monkeypatch.setattr(os, "replace", no_replace)
        with pytest.raises(OSError, match="could not write"):
            est.save(path)
        monkeypatch.undo()
        assert path.read_bytes() == before
        assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


@pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")
def test_written_files_get_ordinary_permissions_and_replaced_files_keep_theirs(tmp_path) -> None:
    """mkstemp makes owner-only files (0600); what a user writes must be readable as any file they create."""
    umask = os.umask(0o022)
    try:
        for name in ("new.csv", "new.nc", "new.txt"):
            path = tmp_path / name
            if name.endswith(".txt"):
                _atomic.atomic_text(path, "x")
            else:
                af.run_experiment(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), periods=2).save(path)
            assert path.stat().st_mode & 0o777 == 0o644, name
        path = tmp_path / "new.txt"
        path.chmod(0o640)
        _atomic.atomic_text(path, "y")
        assert path.stat().st_mode & 0o777 == 0o640 and path.read_text() == "y"
    finally:
        os.umask(umask)


@pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")
def test_rig_and_controller_files_get_ordinary_permissions(tmp_path) -> None:
    """save_rig and save_controller wrote through mkstemp and left the files owner-only (0600)."""
    umask = os.umask(0o022)
    try:
        rig = af.save_rig(af.Rig(), tmp_path / "rig.toml")
        controller = af.save_controller(af.PID.paper(), tmp_path / "c.toml")
        assert [p.stat().st_mode & 0o777 for p in (rig, controller)] == [0o644, 0o644]
        assert af.load_rig(rig) == af.Rig() and af.load_controller(controller).fs == 4000.0
    finally:
        os.umask(umask)


@pytest.mark.parametrize("suffix", [".csv", ".mat"])
@pytest.mark.parametrize("samples", [5, 20])
def test_channels_of_different_lengths_are_refused_before_writing(tmp_path, suffix, samples) -> None:
    """A CSV kept the first 10 of 20 displacement samples silently (or failed with numpy's concatenation error);
    a .mat was written that load_recording then refused."""
    path = tmp_path / f"rec{suffix}"
    with pytest.raises(ValueError, match=rf"displacement samples must be as many as force's \(10\), got {samples}"):
        af.save_recording(path, force=np.ones(10), displacement=np.zeros(samples), fs=FS)
    assert not path.exists()


def test_a_missing_directory_is_a_clear_error(tmp_path) -> None:
    with pytest.raises(OSError, match="the directory .*nowhere.* does not exist"):
        af.save_recording(tmp_path / "nowhere" / "rec.csv", force=[1.0, 2.0], displacement=[0.0, 0.0], fs=FS)


# -- estimates out and back -----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def estimate() -> af.Estimate:
    rig = af.Rig(sensor_noise=1e-8, force_noise=1e-3)
    return af.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(lines="odd"), periods=4, seed=11)


@pytest.mark.parametrize("suffix", [".csv", ".nc"])
def test_estimates_round_trip_with_unexcited_lines_and_metadata(tmp_path, estimate, suffix) -> None:
    if suffix == ".nc":
        pytest.importorskip("xarray")
    path = estimate.save(tmp_path / f"est{suffix}")
    back = af.load_estimate(path)
    for name in ("freq", "H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force",
                 "displacement", "weak"):  # fmt: skip
        np.testing.assert_array_equal(getattr(back, name), getattr(estimate, name), err_msg=name)
    for name in ("freq", "force", "displacement"):
        np.testing.assert_array_equal(getattr(back.unexcited, name), getattr(estimate.unexcited, name))
    np.testing.assert_array_equal(back.unexcited.freq, np.arange(2.0, 200.0, 2.0))  # the even lines below 199 Hz
    assert (back.periods, back.blocks, back.saturated_samples) == (4, 4, 0)
    assert back.meta["seed"] == 11 and back.meta["controller"]["kp"] == 2400.0
    assert back.meta["rig"]["sensor_noise"] == 1e-8 and back.meta["source"] == "run_experiment"
    assert af.__version__ in path.read_bytes().decode(errors="replace") or suffix == ".nc"


def test_every_saved_file_records_version_rig_controller_and_seed(tmp_path, estimate) -> None:
    xr = pytest.importorskip("xarray")
    estimate.save(tmp_path / "e.nc")
    with xr.open_dataset(tmp_path / "e.nc", engine="h5netcdf") as ds:
        assert ds.attrs["amb_fast_version"] == af.__version__
        assert '"seed": 11' in ds.attrs["amb_fast"] and '"kp": 2400.0' in ds.attrs["amb_fast"]
    result = af.sweep(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), kp=[2300.0], periods=2, seed=5)
    result.save(tmp_path / "s.nc")
    back = af.load_sweep(tmp_path / "s.nc")
    assert (
        back.meta["seed"] == 5
        and back.meta["amb_fast_version"] == af.__version__
        and back.meta["controller"]["kd"] == 3.0
    )


@pytest.mark.parametrize("suffix", [".csv", ".nc"])
def test_flipped_bytes_are_refused_not_read_as_other_numbers(tmp_path, estimate, suffix) -> None:
    if suffix == ".nc":
        pytest.importorskip("xarray")
    path = estimate.save(tmp_path / f"est{suffix}")
    data = path.read_bytes()
    refused = same = 0
    for position in np.linspace(0, len(data) - 1, 60).astype(int):
        damaged = bytearray(data)
        damaged[position] ^= 0x10
        path.write_bytes(bytes(damaged))
        try:
            back = af.load_estimate(path)
        except ValueError:
            refused += 1
            continue
        np.testing.assert_array_equal(back.H, estimate.H)  # a byte that holds no number (padding): same values
        np.testing.assert_array_equal(back.unexcited.force, estimate.unexcited.force)
        same += 1
    assert refused > 0 and refused + same == 60
    if suffix == ".nc":  # the file's own SHA-256 is checked before HDF5 reads a byte: every flip is refused
        assert refused == 60


def test_a_damaged_hdf5_header_is_refused_before_hdf5_reads_it(tmp_path, estimate) -> None:
    """HDF5 can loop forever on damaged metadata (seen: a flipped byte in a dimension-scale record); every
    byte of the first 8 kB, where HDF5 keeps its metadata, is refused without opening the file."""
    xr = pytest.importorskip("xarray")
    path = estimate.save(tmp_path / "est.nc")
    data = path.read_bytes()
    with xr.open_dataset(path, engine="h5netcdf") as ds:  # other tools read the file as usual
        np.testing.assert_array_equal(ds.k.values, estimate.k)
    for position in range(0, min(len(data), 8192), 97):
        damaged = bytearray(data)
        damaged[position] ^= 0x55
        path.write_bytes(bytes(damaged))
        with pytest.raises(ValueError, match="damaged"):
            af.load_estimate(path)


def test_flipped_bytes_in_a_sweep_file_are_refused(tmp_path) -> None:
    pytest.importorskip("xarray")
    result = af.sweep(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=20.0), kp=[2200.0, 2600.0], periods=2,
                      seed=3)  # fmt: skip
    npz = tmp_path / "flag.npz"
    result.save(npz)
    data = bytearray(npz.read_bytes())
    data[data.index(b"PK\x01\x02") + 8] ^= 0x01  # a member's "encrypted" flag (central directory): zipfile's
    # RuntimeError, refused as damaged
    npz.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="damaged"):
        af.load_sweep(npz)
    for suffix in (".nc", ".npz"):
        path = tmp_path / f"s{suffix}"
        result.save(path)
        data = bytearray(path.read_bytes())
        for position in np.linspace(len(data) // 3, len(data) - 50, 25).astype(int):
            damaged = bytearray(data)
            damaged[position] ^= 0x01
            path.write_bytes(bytes(damaged))
            try:
                back = af.load_sweep(path)
            except ValueError:
                continue
            np.testing.assert_array_equal(back.k, result.k)


def test_xarray_and_dataframe_views(estimate) -> None:
    pd = pytest.importorskip("pandas")
    pytest.importorskip("xarray")
    ds = estimate.to_xarray()
    assert ds.k.attrs["units"] == "N/m" and ds.sizes["freq"] == 100 and ds.sizes["unexcited_freq"] == 99
    np.testing.assert_array_equal(ds.H.values, estimate.H)
    frame = estimate.to_dataframe()
    assert isinstance(frame, pd.DataFrame) and len(frame) == 199 and frame.index.name == "freq_Hz"
    assert frame["excited"].sum() == 100
    np.testing.assert_array_equal(frame.loc[frame["excited"], "k_N_per_m"].to_numpy(), estimate.k)
    result = af.sweep(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=10.0), kp=[2200.0, 2600.0], periods=2)
    table = result.to_dataframe()
    assert len(table) == 20 and set(table["kp"]) == {2200.0, 2600.0}


def test_load_estimate_refuses_other_files(tmp_path) -> None:
    other = tmp_path / "other.csv"
    other.write_text("freq,k\n1,2\n")
    with pytest.raises(ValueError, match="not an estimate written by amb_fast"):
        af.load_estimate(other)
    sheet = tmp_path / "est.xlsx"
    sheet.write_bytes(b"PK")
    with pytest.raises(ValueError, match="path must be a file name ending in .csv or .nc"):
        af.load_estimate(sheet)


def test_a_netcdf_write_is_refused_before_it_starts_on_a_full_disk(tmp_path, estimate, monkeypatch) -> None:
    """h5py can crash the process on a full disk; the free space is checked first."""
    import shutil
    from collections import namedtuple

    pytest.importorskip("xarray")
    path = estimate.save(tmp_path / "est.nc")
    before = path.read_bytes()
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda _: usage(10**9, 10**9 - 1000, 1000))
    with pytest.raises(
        OSError, match="1000 bytes free on its disk, .* needed \\(the old file, if any, is unchanged\\)"
    ):
        estimate.save(path)
    assert path.read_bytes() == before


def test_saved_recordings_record_the_run_and_still_read_back(tmp_path) -> None:
    ms = af.schroeder_multisine(f_max=20.0)
    trace = af.simulate(af.Rig(sensor_noise=1e-9), af.PID.paper(), np.tile(ms.samples, 3), seed=9)
    for name in ("rec.csv", "rec.mat"):
        trace.save(tmp_path / name)
        rec = af.load_recording(tmp_path / name)
        np.testing.assert_array_equal(rec.force, trace.force)
        np.testing.assert_array_equal(rec.displacement, trace.displacement)
    text = (tmp_path / "rec.csv").read_text().splitlines()
    assert text[-2] == f"# amb_fast {af.__version__}" and '"seed": 9' in text[-1] and '"kp": 2400.0' in text[-1]
    from scipy.io import loadmat

    assert '"seed": 9' in str(loadmat(tmp_path / "rec.mat")["amb_fast"][0])


@pytest.mark.parametrize("suffix", [".csv", ".mat"])
@pytest.mark.parametrize(
    ("force", "message"),
    [
        (np.r_[1.0, np.nan, 1.0], r"force must be finite, got nan at sample 1"),
        (np.r_[1.0], r"force samples must be at least 2, got 1"),
    ],
)
def test_save_recording_writes_nothing_load_recording_would_refuse(tmp_path, suffix, force, message) -> None:
    # Before: the file was written (NaN samples, one sample) and load_recording then refused it.
    path = tmp_path / f"r{suffix}"
    with pytest.raises(ValueError, match=message):
        af.save_recording(path, force=force, displacement=np.zeros(force.size), fs=4000.0)
    assert not path.exists()
