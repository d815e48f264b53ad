"""``amb-fast identify`` (issue 25, cases 7, 9, 13): every mistake in the options or the file exits 2, the input is
checked before the outputs; the k/c table, ``--at``, ``--figure``, ``--time``, ``--lines``; the mass it used is
said, and a file that records none needs ``--mass``; messages and warnings name options."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from cli_helpers import one_error_line, run

FS = 4000.0


@pytest.fixture
def trace():  # noqa: ANN201
    """Six periods of the paper experiment (1-100 Hz), with the rig's mass 1.5 kg (not the paper's 0.92)."""
    rig = replace(af.Rig.paper(), mass=1.5, force_coupling_tau=None)
    ms = af.schroeder_multisine(f_max=100.0)
    return af.simulate(rig, af.PID.paper(), np.tile(ms.samples, 6), seed=3)


@pytest.fixture
def recorded(tmp_path, monkeypatch, trace):  # noqa: ANN201
    """rec.csv as amb_fast writes it (its rig, with the mass, in the trailing metadata) and plain.csv as a DAQ
    would (the same numbers, a clock column named 'clock', no metadata), in the current directory."""
    monkeypatch.chdir(tmp_path)
    trace.save(tmp_path / "rec.csv")
    table = np.column_stack([trace.time, trace.force, trace.displacement])
    np.savetxt(tmp_path / "plain.csv", table, delimiter=",", header="clock,force,displacement", comments="",
               fmt="%.17g")  # fmt: skip
    return trace


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--f-max", "3000"], "--f-max must be at least --f0 (1.0 Hz) and below --fs/2 (2000.0 Hz), got 3000.0"),
        (["--median-window", "4"], "--median-window must be odd, got 4"),
        (["--settle-periods", "10"], "recording length must be at least --settle-periods + 1 periods"),
        (["--f0", "0.7"], "--fs/--f0 must be a whole number of samples per period"),
        (["--at", "500", "--settle-periods", "2"], "--at must be within the excited band 1-100 Hz, got [500.0]"),
        (["--force", "nope"], "rec.csv has no channel 'nope' for the force"),
        (["--time", "nope"], "rec.csv has no channel 'nope' for the time"),
        (["--fs", "5000"], "--fs must agree with rec.csv's time column 'time' (4000 Hz)"),
    ],
)
def test_mistakes_in_options_or_the_file_exit_2_and_write_nothing(capsys, tmp_path, recorded, args, message) -> None:
    """Was: exit status 1 for the first four (found by identify, after the check phase), with the keyword
    arguments' names (f_max, median_window, settle_periods, fs/f0)."""
    status, out, err = run(capsys, "identify", "rec.csv", *args)
    assert status == 2
    assert message in one_error_line(err)
    assert out == "" and not (tmp_path / "identify-output").exists()


def test_unreadable_files_exit_2(capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.mat").write_bytes(b"MATLAB 5.0 garbage" + bytes(range(256)) * 3)
    (tmp_path / "bad.csv").write_bytes(bytes(range(256)) * 3)
    (tmp_path / "dir.csv").mkdir()
    for name, message in (("bad.mat", "bad.mat is not a readable MATLAB file"), ("bad.csv", "bad.csv"),
                          ("dir.csv", "the recording 'dir.csv' is not a file")):  # fmt: skip
        status, _, err = run(capsys, "identify", name, "--mass", "1")
        assert status == 2 and message in one_error_line(err), (name, err)


def test_a_missing_input_is_named_before_the_outputs(capsys, tmp_path, monkeypatch) -> None:
    """Was: "--out: the directory 'nowhere' does not exist" for a file that does not exist either."""
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, "identify", "missing.csv", "--out", "nowhere/ident")
    assert status == 2
    assert one_error_line(err) == "amb-fast: error: the recording 'missing.csv' does not exist"


def test_warnings_name_options(capsys, recorded) -> None:
    status, _, err = run(capsys, "identify", "rec.csv")  # settle periods left at 0: a start transient
    assert status == 0
    warnings = [line for line in err.splitlines() if line.startswith("amb-fast: warning: ")]
    assert len(warnings) == 1 and warnings[0].endswith("skip it with --settle-periods")
    assert "settle_periods" not in err


def test_identify_prints_the_table_and_the_mass_of_the_file(capsys, tmp_path, recorded, trace) -> None:
    """Was: no table, and 0.92 kg assumed for any file (here a 1.5 kg rig: every k off by 0.58 kg x w^2)."""
    status, out, err = run(capsys, "identify", "rec.csv", "--settle-periods", "2", "--at", "10,40", "--out", "ident")
    assert status == 0, err
    assert "mass                1.5 kg (recorded in rec.csv)" in out
    rows = out.split("f (Hz)", 1)[1].splitlines()[1:3]
    want = af.identify(trace.force, trace.displacement, fs=FS, f0=1.0, mass=1.5, settle_periods=2)
    for row, f in zip(rows, (10, 40)):
        fields = row.split()
        assert float(fields[0]) == f
        np.testing.assert_allclose(float(fields[1]), want.k[f - 1], rtol=1e-5)  # printed to 6 digits
        np.testing.assert_allclose(float(fields[3]), want.c[f - 1], rtol=1e-5)
    saved = af.load_estimate(tmp_path / "ident" / "estimate.csv")
    assert saved.meta["mass"] == 1.5
    np.testing.assert_allclose(saved.k, want.k, rtol=1e-12)


def test_a_file_without_a_mass_needs_mass(capsys, tmp_path, recorded) -> None:
    status, _, err = run(capsys, "identify", "plain.csv", "--time", "clock")
    assert status == 2
    assert "--mass is needed: plain.csv does not record the moving mass (kg)" in one_error_line(err)
    assert not (tmp_path / "identify-output").exists()
    status, out, err = run(capsys, "identify", "plain.csv", "--time", "clock", "--mass", "1.5", "--settle-periods",
                           "2")  # fmt: skip
    assert status == 0, err
    assert "mass                1.5 kg (--mass)" in out and "24000 samples at 4000 Hz" in out


def test_time_names_the_time_column_by_name_index_or_none(capsys, tmp_path, recorded) -> None:
    """Was: no ``--time`` option (``time=`` of load_recording); a clock column of another name gave no fs."""
    for args in (["--time", "0"], ["--time", "none", "--fs", "4000"]):
        status, out, err = run(capsys, "identify", "plain.csv", "--mass", "1.5", "--settle-periods", "2",
                               "--overwrite", *args)  # fmt: skip
        assert status == 0, (args, err)
        assert "24000 samples at 4000 Hz" in out


def test_figure_writes_the_figure_where_asked(capsys, tmp_path, recorded) -> None:
    pytest.importorskip("matplotlib")
    status, out, err = run(capsys, "identify", "rec.csv", "--settle-periods", "2", "--figure", "k.svg", "--out", "i")
    assert status == 0, err
    assert (tmp_path / "k.svg").read_text().lstrip().startswith("<?xml")
    assert sorted(p.name for p in (tmp_path / "i").iterdir()) == ["estimate.csv"]
    assert "wrote i/estimate.csv and k.svg" in out
    status, _, err = run(capsys, "identify", "rec.csv", "--figure", "k.svg", "--out", "j")
    assert status == 2 and "--figure: 'k.svg' exists; pass --overwrite" in one_error_line(err)


def test_the_default_table_follows_the_band(capsys, recorded) -> None:
    """The recording's band is 1-100 Hz: the paper's 200 Hz row is out of it, so four lines spread over it."""
    status, out, err = run(capsys, "identify", "rec.csv", "--settle-periods", "2", "--f-max", "20")
    assert status == 0, err
    rows = [line.split() for line in out.split("f (Hz)", 1)[1].splitlines()[1:] if line[:8].strip().isdigit()]
    at = [float(row[0]) for row in rows]
    assert at[0] == 1.0 and at[-1] == 20.0 and len(at) == 4
    assert "natural frequency   none in 1-20 Hz (Re F/Y > 0 throughout" in out


def test_a_mat_file_written_by_amb_fast_gives_its_mass(capsys, tmp_path, monkeypatch, trace) -> None:
    monkeypatch.chdir(tmp_path)
    trace.save(tmp_path / "rec.mat")
    status, out, err = run(capsys, "identify", "rec.mat", "--settle-periods", "2")
    assert status == 0, err
    assert "mass                1.5 kg (recorded in rec.mat)" in out
    np.testing.assert_allclose(af.load_estimate(tmp_path / "identify-output" / "estimate.csv").meta["mass"], 1.5)


def test_a_recording_in_volts_is_read_with_its_calibration(capsys, tmp_path, recorded) -> None:
    """A DAQ that recorded volts (force 0.005 V/N, probe 8 V/mm): refused without its calibration (before: no
    way to give it but rescaling the file), identified with --force-scale / --displacement-scale."""
    table = np.column_stack([recorded.time, recorded.force * 0.005, recorded.displacement * 8e3])
    np.savetxt(tmp_path / "volts.csv", table, delimiter=",", header="time [s],force [V],displacement [V]",
               comments="", fmt="%.17g")  # fmt: skip
    status, _, err = run(capsys, "identify", "volts.csv", "--mass", "1.5", "--settle-periods", "2")
    assert status == 2 and "the force channel 'force [V]' has unit 'V'" in one_error_line(err)
    status, out, err = run(capsys, "identify", "volts.csv", "--mass", "1.5", "--settle-periods", "2",
                           "--force-scale", "200", "--displacement-scale", "1.25e-4", "--out", "v")  # fmt: skip
    assert status == 0, err
    status, out2, err = run(capsys, "identify", "plain.csv", "--time", "clock", "--mass", "1.5", "--settle-periods",
                            "2", "--out", "p")  # fmt: skip
    assert status == 0, err
    volts, plain = af.load_estimate(tmp_path / "v" / "estimate.csv"), af.load_estimate(tmp_path / "p" / "estimate.csv")
    np.testing.assert_allclose(volts.H, plain.H, rtol=1e-9)  # the same estimate as from the file in N and m
    status, _, err = run(capsys, "identify", "volts.csv", "--mass", "1.5", "--force-scale", "0")
    assert status == 2 and "--force-scale must be a finite number != 0 (N per unit of the file), got 0" in err


def test_load_recording_scale_applies_a_channels_calibration(tmp_path) -> None:
    t = np.arange(16) / 4000.0
    f, y = np.sin(2 * np.pi * 250 * t), np.cos(2 * np.pi * 250 * t)
    np.savetxt(tmp_path / "v.csv", np.column_stack([t, f, y]), delimiter=",", comments="",
               header="time [s],force [V],displacement [mV]", fmt="%.17g")  # fmt: skip
    with pytest.raises(ValueError, match=r"or the channel's calibration as scale=\{'force': SI per unit\}"):
        af.load_recording(tmp_path / "v.csv")
    rec = af.load_recording(tmp_path / "v.csv", scale={"force": 200.0, "displacement": -1e-4})
    np.testing.assert_array_equal(rec.force, f * 200.0)
    np.testing.assert_array_equal(rec.displacement, y * -1e-4)  # the label (mV) is not read: the scale is all
    assert "force 'force [V]' (x 200 N per unit of the file)" in rec.source
    for bad, message in (({"forces": 1.0}, "scale must be keys 'force' and/or 'displacement'"),
                         ({"force": 0.0}, r"scale\['force'\] must be a finite number != 0"),
                         ({"displacement": np.nan}, r"scale\['displacement'\] must be a finite number")):  # fmt: skip
        with pytest.raises(ValueError, match=message):
            af.load_recording(tmp_path / "v.csv", scale=bad)
