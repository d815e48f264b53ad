"""Files as acquisition systems write them (issue 25, cases 4-6): rounded clocks, headers with units and
other cases, metadata before the header, trailing delimiters, files with no header."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af

FS = 4000.0


@pytest.fixture(scope="module")
def channels() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ms = af.schroeder_multisine(f0=1.0, f_max=200.0)
    trace = af.simulate(af.Rig.paper(), af.PID.paper(), np.tile(ms.samples, 4), seed=2)
    return trace.time, trace.force, trace.displacement


def write(path, header: str, columns: list[np.ndarray], formats: list[str], sep: str = ",", end: str = "") -> None:
    rows = [sep.join(f % v for f, v in zip(formats, row)) + end for row in zip(*columns)]
    path.write_text(header + "\n".join(rows) + "\n")


def test_a_rounded_clock_gives_its_round_fs_and_identify_runs(tmp_path, channels) -> None:
    """%.4f at 4 kHz: steps of 0.2 and 0.3 ms; the fit over the column gives 4000 Hz (was 4000.00667)."""
    t, f, y = channels
    path = tmp_path / "rounded.csv"
    write(path, "time,force,displacement\n", [t, f, y], ["%.4f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    assert rec.fs == 4000.0
    assert "fs 4000 Hz from its time column 'time'" in rec.source
    est = af.identify(rec.force, rec.displacement, fs=rec.fs, f0=1.0, mass=0.92, settle_periods=1)
    assert est.freq.size == 200
    # Milliseconds with three decimals (0.25 ms steps written 0.250, 0.500, ...): exact, 4000 Hz too.
    ms = tmp_path / "ms.csv"
    write(ms, "t [ms],force,displacement\n", [t * 1e3, f, y], ["%.3f", "%.17g", "%.17g"])
    assert af.load_recording(ms).fs == 4000.0


def test_a_clock_that_jumps_is_refused_naming_the_row(tmp_path, channels) -> None:
    t, f, y = channels
    jumped = t.copy()
    jumped[5000:] += 0.5 / FS  # half a sample late from row 5000 on
    path = tmp_path / "jump.csv"
    write(path, "time,force,displacement\n", [jumped, f, y], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"time column 'time' is not a uniform clock: at data row 5000"):
        af.load_recording(path)
    assert af.load_recording(path, time=None, fs=FS).fs == FS  # the way out the message names


@pytest.mark.parametrize(
    ("header", "time_scale", "y_scale"),
    [("Time [s],Force [N],Displacement [um]", 1.0, 1e-6), ("TIME,FORCE,DISPLACEMENT", 1.0, 1.0),
     ("Time (s),Force (N),Displacement (m)", 1.0, 1.0), ("t [ms],force [N],displacement [mm]", 1e3, 1e-3),
     ("Zeit [s],Force,Displacement", 1.0, 1.0)],
)  # fmt: skip
def test_usual_headers_are_found_with_the_defaults(tmp_path, channels, header, time_scale, y_scale) -> None:
    t, f, y = channels
    path = tmp_path / "headers.csv"
    write(path, header + "\n", [t * time_scale, f, y / y_scale], ["%.10f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    assert rec.fs == FS
    np.testing.assert_allclose(rec.displacement, y, rtol=1e-14)
    np.testing.assert_array_equal(rec.force, f)


def test_not_found_names_the_columns(tmp_path, channels) -> None:
    t, f, y = channels
    path = tmp_path / "other.csv"
    write(path, "time,F_shaker,x_probe\n", [t, f, y], ["%.10f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"no channel 'force' for the force; its columns are 0: 'time', 1: "
                       r"'F_shaker', 2: 'x_probe'"):  # fmt: skip
        af.load_recording(path)
    rec = af.load_recording(path, force="f_shaker", displacement="X_PROBE")  # without case
    np.testing.assert_array_equal(rec.force, f)


def test_metadata_before_the_header_and_trailing_delimiters(tmp_path, channels) -> None:
    """LabVIEW's LVM header blocks, a DAQ's key: value preamble, a delimiter ending every line: the header is
    found, and no sample is lost."""
    t, f, y = channels
    lvm = tmp_path / "run.lvm.txt"
    block = "LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nDecimal_Separator\t.\n***End_of_Header***\t\n\n"
    segment = "Channels\t2\t\nSamples\t16000\t16000\t\nDate\t2026/11/27\t2026/11/27\t\n***End_of_Header***\t\n"
    write(lvm, block + segment + "X_Value\tForce\tDisplacement\tComment\n", [t, f, y], ["%.6f", "%.17g", "%.17g"],
          sep="\t", end="\t")  # fmt: skip
    rec = af.load_recording(lvm)
    assert rec.fs == FS and rec.force.size == t.size
    np.testing.assert_array_equal(rec.force, f)
    daq = tmp_path / "daq.csv"
    write(daq, "Device: NI 9234\nSample rate: 4000 Hz\nOperator: test\ntime,force,displacement\n", [t, f, y],
          ["%.6f", "%.17g", "%.17g"], end=",")  # fmt: skip
    rec = af.load_recording(daq)
    np.testing.assert_array_equal(rec.displacement, y)
    assert rec.force.size == t.size


def test_a_file_without_header_is_read_by_index_and_loses_no_sample(tmp_path, channels) -> None:
    t, f, y = channels
    path = tmp_path / "bare.csv"
    write(path, "", [t, f, y], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"no header row naming its 3 columns: choose the force and the displacement"):
        af.load_recording(path)
    rec = af.load_recording(path, force=1, displacement=2, time=0)
    assert rec.force.size == t.size and rec.fs == FS
    np.testing.assert_array_equal(rec.force, f)
    assert af.load_recording(path, force=1, displacement=2, fs=FS).force[0] == f[0]  # the first row is data


def test_labviews_lvm_file_is_read_as_labview_writes_it(tmp_path, channels) -> None:
    """A .lvm file (was refused by its suffix): two header blocks each ending in ***End_of_Header***, decimal
    commas, X_Value as the time column, an empty Comment column."""
    t, f, y = channels
    head = "\n".join([
        "LabVIEW Measurement\t", "Writer_Version\t2\t", "Reader_Version\t2\t", "Separator\tTab\t",
        "Decimal_Separator\t,\t", "Multi_Headings\tNo\t", "X_Columns\tOne\t", "Time_Pref\tRelative\t",
        "Date\t2026/11/27\t", "Time\t01:00:00,0\t", "***End_of_Header***\t", "\t", "Channels\t2\t\t",
        "Samples\t16000\t16000\t", "Y_Unit_Label\tNewtons\tMeters\t", "X_Dimension\tTime\tTime\t",
        "X0\t0,0000000000000000E+0\t0,0000000000000000E+0\t", "Delta_X\t2,500000E-4\t2,500000E-4\t",
        "***End_of_Header***\t\t\t", "X_Value\tForce\tDisplacement\tComment\n",
    ])  # fmt: skip
    rows = "\n".join(f"{a:.6f}\t{b:.17g}\t{c:.17g}".replace(".", ",") for a, b, c in zip(t, f, y))
    path = tmp_path / "run_07.lvm"
    path.write_text(head + rows + "\n")
    rec = af.load_recording(path)
    assert rec.fs == FS and rec.force.size == t.size
    np.testing.assert_array_equal(rec.force, f)
    assert rec.fs_from == "the time column 'X_Value' of run_07.lvm"


def test_a_units_row_with_a_unit_amb_fast_does_not_scale_keeps_the_header(tmp_path, channels) -> None:
    """A units row 's,V,um' was taken for the header (the header above it skipped as metadata, the columns
    named 's', 'V', 'um'); now the header stays and the force in V is refused naming its unit."""
    t, f, y = channels
    path = tmp_path / "volts.csv"
    write(path, "time,force,displacement\ns,V,um\n", [t, f, y * 1e6], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"the force channel 'force \[V\]' has unit 'V'; amb_fast needs one of N"):
        af.load_recording(path)
    assert af.io.sniff(path).names == ["time [s]", "force [V]", "displacement [um]"]


def test_a_rate_stated_in_the_metadata_gives_fs(tmp_path, channels) -> None:
    """A DAQ's "Sample rate: 4000 Hz" above a header without a time column was ignored (fs= was asked for)."""
    _, f, y = channels
    for preamble, expected in [("Device: NI 9234\nSample rate: 4000 Hz\n", 4000.0),
                               ("Sampling Frequency = 4 kHz\n", 4000.0),
                               ('"Sample Rate (Hz)",2000\n', 2000.0),
                               ("Delta_X\t0.000250\t0.000250\t\n", 4000.0),
                               ("Sample interval: 0.5 ms\n", 2000.0)]:  # fmt: skip
        path = tmp_path / "daq.csv"
        write(path, preamble + "force,displacement\n", [f, y], ["%.17g", "%.17g"])
        rec = af.load_recording(path)
        assert rec.fs == expected, preamble
        assert "from its metadata line" in rec.source
        np.testing.assert_array_equal(rec.force, f)
    with pytest.raises(ValueError, match=r"fs must agree with daq.csv's metadata line 'Sample interval: 0.5 ms'"):
        af.load_recording(path, fs=4000.0)
    # "fs: 16 bit" states no rate: still refused for want of fs
    write(path, "fs: 16 bit\nforce,displacement\n", [f, y], ["%.17g", "%.17g"])
    with pytest.raises(ValueError, match="has neither 'fs' nor a time column"):
        af.load_recording(path)


def test_a_stated_rate_that_contradicts_the_time_column_is_refused(tmp_path, channels) -> None:
    t, f, y = channels
    path = tmp_path / "daq.csv"
    write(path, "Sample rate: 5000 Hz\ntime,force,displacement\n", [t, f, y], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"time column 'time' gives fs 4000 Hz but its metadata line "
                                         r"'Sample rate: 5000 Hz' states 5000 Hz"):  # fmt: skip
        af.load_recording(path)
    write(path, "Sample rate: 4000 Hz\nSampling rate: 5000 Hz\nforce,displacement\n", [f, y], ["%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"states two sampling rates: 'Sample rate: 4000 Hz' \(4000 Hz\) and"):
        af.load_recording(path)


def test_mega_is_not_milli(tmp_path, channels) -> None:
    """Units were compared in lower case: 'Force [MN]' read as mN, 1e9 times too small."""
    t, f, y = channels
    path = tmp_path / "mega.csv"
    write(path, "time,Force [MN],displacement\n", [t, f * 1e-6, y], ["%.6f", "%.17g", "%.17g"])
    rec = af.load_recording(path)
    np.testing.assert_allclose(rec.force, f, rtol=1e-12)
    assert "(MN -> N)" in rec.source
    write(path, "TIME,FORCE [MN],DISP [MM]\n", [t, f * 1e3, y * 1e3], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"the channel 'FORCE \[MN\]' has unit 'MN', written in capitals: meganewton "
                                         "or millinewton"):  # fmt: skip
        af.load_recording(path, force="force", displacement="disp")
    path.write_text(path.read_text().replace("[MN]", "[KN]"))
    rec = af.load_recording(path, force="force", displacement="disp")  # KN and MM: kN and mm, whatever the case
    np.testing.assert_allclose(rec.force, f * 1e6, rtol=1e-12)
    np.testing.assert_allclose(rec.displacement, y, rtol=1e-12)


def test_an_empty_or_cut_tdms_file_says_so(tmp_path) -> None:
    """Was "x.tdms holds several recordings []: choose one with recording=NAME"."""
    nptdms = pytest.importorskip("nptdms")
    path = tmp_path / "x.tdms"
    with nptdms.TdmsWriter(path) as writer:
        writer.write_segment([nptdms.ChannelObject("g", "force", np.ones(100)),
                              nptdms.ChannelObject("g", "displacement", np.ones(100))])  # fmt: skip
    path.write_bytes(path.read_bytes()[:10])
    with pytest.raises(ValueError, match=r"x.tdms holds no channels: the file is empty or damaged"):
        af.load_recording(path, fs=4000.0)


def test_a_header_with_fewer_names_than_columns_is_named_in_the_error(tmp_path, channels) -> None:
    """A header naming 2 of 3 columns was silently taken for no header ("no header row naming its 3 columns")."""
    t, f, y = channels
    path = tmp_path / "short.csv"
    write(path, "force,displacement\n", [t, f, y], ["%.6f", "%.17g", "%.17g"])
    with pytest.raises(ValueError, match=r"no header row naming its 3 columns \(the row above the data, "
                                         r"'force,displacement', has fewer names than the 3 data columns"):  # fmt: skip
        af.load_recording(path)
    rec = af.load_recording(path, force=1, displacement=2, time=0)  # by index, every sample kept
    np.testing.assert_array_equal(rec.force, f)


@pytest.mark.parametrize("fs", [np.nan, -4000.0, 0.0, np.zeros(0), np.array([4000.0, 2000.0])])
def test_an_fs_variable_that_is_not_one_positive_rate_is_refused(tmp_path, fs) -> None:
    """It became the Recording's fs as it was (nan, -4000, 0), raised an IndexError (empty) or was read as its
    first value (two)."""
    from scipy.io import savemat

    path = tmp_path / "rig.mat"
    x = np.sin(np.arange(400) / 10.0)
    savemat(path, {"force": x, "displacement": 1e-6 * x, "fs": fs})
    for given in (None, 4000.0):
        with pytest.raises(ValueError, match=r"rig.mat: its 'fs' variable must be one finite number > 0 \(Hz\), got"):
            af.load_recording(path, fs=given)
