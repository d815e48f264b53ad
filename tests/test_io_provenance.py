"""Where a recording's fs came from, and the errors that help choose the time column (issue 25, cases 4, 5
and 7): a refused fs names the file's clock, two candidate time columns are never guessed between, every
"no time column" error lists the columns and names ``time=``, a unit's scaling is stated in the source."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import savemat

import amb_fast as af
from amb_fast import cli

FS = 4000.0


def write(path, header: str, columns: list[np.ndarray], formats: list[str]) -> None:
    rows = [",".join(f % v for f, v in zip(formats, row)) for row in zip(*columns)]
    path.write_text(header + "\n" + "\n".join(rows) + "\n")


@pytest.fixture
def short() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(800) / FS
    return t, np.sin(2 * np.pi * 10 * t), 1e-5 * np.cos(2 * np.pi * 10 * t)


def test_two_candidate_time_columns_are_an_error_naming_both(tmp_path, short) -> None:
    """Was: neither taken, then "has neither 'fs' nor a time column" although the file has two."""
    t, f, y = short
    path = tmp_path / "two.csv"
    write(path, "t,Zeit,force,displacement", [t, t, f, y], ["%.6f", "%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"columns \['0: t', '1: Zeit'\] could each be the time column: choose one "
                       r"with time=NAME or its 0-based index"):  # fmt: skip
        af.load_recording(path)
    assert af.load_recording(path, time="Zeit").fs == FS
    assert af.load_recording(path, time=0).fs == FS
    assert af.load_recording(path, time=None, fs=FS).fs_from == "fs= (given)"


def test_no_time_column_lists_the_columns_and_names_the_time_option(tmp_path, short) -> None:
    t, f, y = short
    path = tmp_path / "clock.csv"
    write(path, "stamp_s,force,displacement", [t, f, y], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"clock.csv has neither 'fs' nor a time column \(its columns are 0: "
                       r"'stamp_s', 1: 'force', 2: 'displacement'\): pass fs= .*time=NAME or its 0-based "
                       r"index"):  # fmt: skip
        af.load_recording(path)
    rec = af.load_recording(path, time="stamp")  # the unit suffix _s left out
    assert rec.fs == FS and rec.fs_from == "the time column 'stamp_s' of clock.csv"


def test_source_states_each_unit_scaling_and_sec_is_a_time_unit(tmp_path, short) -> None:
    t, f, y = short
    path = tmp_path / "units.csv"
    write(path, "Time [sec],Force [kN],Displacement [um]", [t, f / 1e3, y * 1e6], ["%.6f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    assert rec.source == ("units.csv: force 'Force [kN]' (kN -> N), displacement 'Displacement [um]' (um -> m); "
                          "fs 4000 Hz from its time column 'Time [sec]'")  # fmt: skip
    np.testing.assert_allclose(rec.displacement, y, rtol=1e-14)
    np.testing.assert_allclose(rec.force, f, rtol=1e-14)
    assert rec.fs_note() == "fs 4000 Hz (from the time column 'Time [sec]' of units.csv)"


def test_fs_from_names_a_mat_files_variable(tmp_path, short) -> None:
    _, f, y = short
    savemat(tmp_path / "r.mat", {"force": f, "displacement": y, "fs": FS})
    assert af.load_recording(tmp_path / "r.mat").fs_from == "the 'fs' variable of r.mat"


def test_a_refused_fs_says_it_came_from_the_time_column(tmp_path, capsys) -> None:
    """A clock at 4000.1 Hz is uniform (so taken), but 4000.1 / 1 Hz is no whole number of samples: the error
    names the column fs came from (was: only "fs/f0 must be a whole number ..., got 4000.100002")."""
    n = 8000
    t = np.arange(n) / 4000.1
    f = np.tile(af.schroeder_multisine(f0=1.0, f_max=50.0).samples, 2)
    path = tmp_path / "drift.csv"
    write(path, "Time [s],force,displacement", [t, f, 1e-6 * f], ["%.9f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    assert abs(rec.fs - 4000.1) < 1e-3
    status = cli.main(["identify", str(path), "--f0", "1", "--mass", "0.92", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2  # a mistake in the input file (case 9)
    assert "--fs/--f0 must be a whole number of samples per period" in err  # the command's words (case 7)
    assert "(from the time column 'Time [s]' of drift.csv)" in err


def test_an_absolute_clock_gives_fs_to_its_digits(tmp_path) -> None:
    """Unix timestamps (1.7e9 s, written %.6f; 2 s at 4 kHz): the fit on t - t[0] gives 4000 Hz (was 3999.998:
    the offset swamped the least-squares sum)."""
    t = np.arange(8000) / FS
    f, y = np.sin(2 * np.pi * 10 * t), 1e-5 * np.cos(2 * np.pi * 10 * t)
    path = tmp_path / "unix.csv"
    write(path, "timestamp,force,displacement", [1.7e9 + t, f, y], ["%.6f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    assert rec.fs == FS
    assert rec.fs_from == "the time column 'timestamp' of unix.csv"


def test_tdms_channels_keep_their_indices_and_fs_names_wf_increment(tmp_path, short) -> None:
    """The fs taken from wf_increment was inserted after the first channel: index 1 was 'fs', not the second
    channel, and fs was said to come from an 'fs' variable."""
    pytest.importorskip("nptdms")
    from nptdms import ChannelObject, TdmsWriter

    _, f, y = short
    path = tmp_path / "shaker.tdms"
    with TdmsWriter(path) as writer:
        timing = {"wf_increment": 1 / FS}
        force = ChannelObject("run", "Force", f, properties={"unit_string": "N", **timing})
        writer.write_segment([force, ChannelObject("run", "Gap", y * 1e3, properties={"unit_string": "mm", **timing})])
    rec = af.load_recording(path, force=0, displacement=1)
    np.testing.assert_allclose(rec.displacement, y, rtol=1e-14)
    assert rec.fs == FS and rec.fs_from == "the channels' wf_increment of shaker.tdms recording 'run'"


def test_channels_of_different_lengths_are_refused_naming_both(tmp_path, short) -> None:
    """A .mat file's scalar 'fs' chosen by index as the displacement loaded as one sample (was: no error)."""
    _, f, y = short
    savemat(tmp_path / "r.mat", {"force": f, "fs": FS, "displacement": y})
    with pytest.raises(ValueError, match=r"r.mat: the force 'force' has 800 samples and the displacement 'fs' 1: "
                       r"choose two channels of the same recording"):  # fmt: skip
        af.load_recording(tmp_path / "r.mat", force=0, displacement=1)
