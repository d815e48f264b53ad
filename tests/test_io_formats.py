"""Recordings as acquisition systems write them (session 4): quoted numbers in any row, Latin-1/Windows-1252
and UTF-16 text, a row with a lost sample, units after a slash, LabVIEW's unit labels, MATLAB structs; and a
hand-built :class:`amb_fast.Recording` checked like a loaded one.

Every file is written here, a few rows long.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import amb_fast as af

FS = 4000.0
N = 16
T = np.arange(N) / FS
F = np.sin(np.arange(N))  # N
Y = 1e-6 * np.cos(np.arange(N))  # m


def rows(sep: str = ",", y_scale: float = 1.0, end: str = "\n", comma: bool = False) -> list[str]:
    """The data lines time, force, displacement (times y_scale), %.10g; decimal commas if comma."""
    out = []
    for t, f, y in zip(T, F, Y * y_scale):
        line = sep.join(f"{v:.10g}" for v in (t, f, y))
        out.append((line.replace(".", ",") if comma else line) + end)
    return out


def check(rec: af.Recording) -> None:
    assert rec.fs == FS
    np.testing.assert_allclose(rec.force, F, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rec.displacement, Y, rtol=1e-9, atol=1e-18)


# -- item 1: quoted numbers ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("quoted", [[5], [1, 3, 5, 7, 9, 11, 13], list(range(N))], ids=["one-middle", "some", "all"])
def test_quoted_numbers_in_any_row_are_read(tmp_path, text_parser, quoted) -> None:
    """numpy's parser stripped the quotes only when the first or last line of a block had them: a quoted
    middle row was refused ("could not convert string '"-0.9589242747"'")."""
    lines = rows()
    for j in quoted:
        lines[j] = ",".join(f'"{v}"' for v in lines[j].strip().split(",")) + "\n"
    path = tmp_path / "quoted.csv"
    path.write_text('"time","force","displacement"\n' + "".join(lines))
    check(af.load_recording(path))


# -- item 3: encodings, line ends, separators ------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", ["latin-1", "cp1252"])
def test_a_latin1_or_windows_header_with_micro_is_read(tmp_path, text_parser, encoding) -> None:
    """µ is the one byte 0xB5 there: was refused (pandas: "'utf-8' codec can't decode byte 0xb5", numpy: the
    unit read as '\ufffdm' and refused)."""
    path = tmp_path / "eu.csv"
    text = "Zeit [s];Kraft [N];Weg [µm]\r\n" + "".join(rows(";", 1e6, "\r\n", comma=True))
    path.write_bytes(text.encode(encoding))
    rec = af.load_recording(path, force="Kraft", displacement="Weg")
    check(rec)
    assert "'Weg [µm]' (µm -> m)" in rec.source


def test_utf16_text_as_excel_saves_unicode_text(tmp_path, text_parser) -> None:
    path = tmp_path / "excel.txt"
    path.write_text("time\tforce\tdisplacement [µm]\r\n" + "".join(rows("\t", 1e6, "\r\n")), encoding="utf-16")
    check(af.load_recording(path))


@pytest.mark.parametrize(
    ("header", "sep", "end", "comma", "bom"),
    [("time;force;displacement\n", ";", "\n", True, False), ("time,force,displacement\r\n", ",", "\r\n", False, True),
     ("time\tforce\tdisplacement\n", "\t", "\n", False, False), ("time;force;displacement;\n", ";", ";\n", True, False),
     ("time,force,displacement,\n", ",", "\n", False, False), ("time,force,displacement\n", ",", ",\n", False, False)],
    ids=["semicolon-decimal-comma", "bom-crlf", "tab", "trailing-semicolons", "trailing-in-header", "trailing-in-data"],
)  # fmt: skip
def test_usual_dialects_are_read_exactly(tmp_path, text_parser, header, sep, end, comma, bom) -> None:
    """These were already read right (audit); kept so they stay so."""
    path = tmp_path / "d.csv"
    path.write_text(("\ufeff" if bom else "") + header + "".join(rows(sep, 1.0, end, comma)), newline="")
    check(af.load_recording(path))


def test_comma_separated_quoted_decimal_commas(tmp_path, text_parser) -> None:
    """ "0,00025","0,841","5,4e-07": was refused ("could not read it as a table")."""
    path = tmp_path / "q.csv"
    quoted = [",".join(f'"{v}"' for v in line.strip().split(",")).replace(".", ",") + "\n" for line in rows()]
    path.write_text('"time","force","displacement"\n' + "".join(quoted))
    check(af.load_recording(path))


@pytest.mark.parametrize("broken", ["0.001,,1e-6", "0.001,0.5"], ids=["empty-field", "short-row"])
def test_a_row_with_a_lost_sample_is_refused_not_taken_for_the_header(tmp_path, text_parser, broken) -> None:
    """Was: the broken row was taken for the header and the rows above it dropped: the default names were
    "not found", and by index (force=1, displacement=2, time=0) 11 of 16 rows were read without a word."""
    lines = rows()
    lines[4] = broken + "\n"
    path = tmp_path / "gap.csv"
    path.write_text("time,force,displacement\n" + "".join(lines))
    match = rf"gap.csv: line 6 \('{broken}'\) is a row of numbers with a field empty or missing"
    for keys in ({}, {"force": 1, "displacement": 2, "time": 0}):
        with pytest.raises(ValueError, match=match):
            af.load_recording(path, **keys)


def test_a_nan_sample_is_refused_naming_the_file(tmp_path, text_parser) -> None:
    lines = rows()
    lines[4] = f"{T[4]:.10g},NaN,{Y[4]:.10g}\n"
    path = tmp_path / "nan.csv"
    path.write_text("time,force,displacement\n" + "".join(lines))
    with pytest.raises(ValueError, match=r"force must be finite, got nan at sample 4 \(nan.csv: force 'force'"):
        af.load_recording(path)


# -- item 2: a hand-built Recording ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"displacement": np.ones(15)}, "displacement samples must be as many as force's (16), got 15"),
     ({"fs": 0.0}, "fs must be a finite number > 0 (Hz), got 0.0"),
     ({"fs": -4000.0}, "fs must be a finite number > 0 (Hz), got -4000.0"),
     ({"fs": math.nan}, "fs must be a finite number > 0 (Hz), got nan"),
     ({"fs": "4000"}, "fs must be a finite number > 0 (Hz), got '4000'"),
     ({"force": np.ones((16, 2))}, "force shape must be one-dimensional (samples,), got (16, 2)"),
     ({"displacement": np.ones((16, 1))}, "displacement shape must be one-dimensional (samples,), got (16, 1)"),
     ({"force": np.r_[np.ones(3), math.inf, np.ones(12)]}, "force must be finite, got inf at sample 3"),
     ({"displacement": np.r_[np.ones(9), math.nan, np.ones(6)]}, "displacement must be finite, got nan at sample 9"),
     ({"force": ["a"] * 16}, "force must be samples (a 1-D array of numbers), got list"),
     ({"force": np.ones(1), "displacement": np.ones(1)}, "force samples must be at least 2, got 1"),
     ({"source": 3}, "source must be a str, got 3")],
)  # fmt: skip
def test_a_hand_built_recording_is_checked_at_construction(kwargs, message) -> None:
    """Was: every one of these built a Recording (fs NaN or -4000 Hz, channels of 16 and 15 samples, ...)."""
    given = {"force": F, "displacement": Y, "fs": FS, **kwargs}
    with pytest.raises(ValueError) as caught:
        af.Recording(**given)
    assert str(caught.value) == message


def test_a_hand_built_recording_holds_float_arrays_and_a_float_fs() -> None:
    rec = af.Recording([0, 1, 2], [0.0, 1e-6, 2e-6], 4000)
    assert rec.force.dtype == np.float64 and rec.force.shape == (3,) and rec.force[2] == 2.0
    assert isinstance(rec.fs, float) and rec.fs == 4000.0
    assert rec == af.Recording(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1e-6, 2e-6]), 4000.0)


# -- item 3: units in the header and the metadata --------------------------------------------------------------------


@pytest.mark.parametrize(
    "header",
    ["time,Force/N,Displacement/µm", "Zeit/s,Kraft/N,Weg/um", "Time in s,Force in N,Displacement in um",
     "time s,force N,displacement um"],
    ids=["slash", "slash-german", "in", "last-word"],
)  # fmt: skip
def test_a_unit_after_a_slash_or_as_the_last_word_is_applied(tmp_path, text_parser, header) -> None:
    """Was: not found by the default names, and chosen by index or exact name the um column was read as m."""
    path = tmp_path / "u.csv"
    path.write_text(header + "\n" + "".join(rows(",", 1e6)), encoding="utf-8")
    names = header.split(",")
    check(af.load_recording(path, force=1, displacement=2, time=0))
    by_name = af.load_recording(path, force=names[1].split("/")[0].split(" ")[0], displacement=names[2])
    check(by_name)
    assert f"{names[2]!r} (" in by_name.source


def test_a_model_path_is_not_a_unit() -> None:
    assert af.io.split_unit("Platform/Force") == ("Platform/Force", None)
    assert af.io.split_unit("Model Root/Sensors/Gap_m") == ("Model Root/Sensors/Gap", "m")
    assert af.io.split_unit("Velocity/m/s") == ("Velocity", "m/s")
    assert af.io.split_unit("Coil A") == ("Coil A", None)  # a current's channel keeps its name: 'A' is not scaled


LVM_HEAD = (
    "LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\nDecimal_Separator\t.\n"
    "Multi_Headings\tNo\nX_Columns\tOne\nTime_Pref\tRelative\nDate\t2026/11/27\nTime\t10:00:00\n***End_of_Header***\t\n\n"
    "Channels\t2\t\nSamples\t16\t16\t\nDate\t2026/11/27\t2026/11/27\t\nTime\t10:00:00\t10:00:00\t\n"
    "Y_Unit_Label\t{units}\t\nX_Dimension\tTime\tTime\t\nX0\t0.0E+0\t0.0E+0\t\nDelta_X\t0.000250\t0.000250\t\n"
    "***End_of_Header***\t\t\t\nX_Value\tforce\tdisplacement\tComment\n"
)


@pytest.mark.parametrize(("units", "y_scale"), [("Newtons\tMeters", 1.0), ("N\tmm", 1e3), ("N\tum", 1e6)])
def test_labviews_unit_labels_scale_the_channels(tmp_path, text_parser, units, y_scale) -> None:
    """Was: LabVIEW's Y_Unit_Label line was skipped with the metadata: a displacement in mm read as m."""
    path = tmp_path / "rig.lvm"
    path.write_text(LVM_HEAD.format(units=units) + "".join(rows("\t", y_scale)))
    check(af.load_recording(path))


def test_labviews_volts_or_a_label_per_column_missing_are_refused(tmp_path, text_parser) -> None:
    path = tmp_path / "v.lvm"
    path.write_text(LVM_HEAD.format(units="Volts\tVolts") + "".join(rows("\t")))
    with pytest.raises(ValueError, match=r"the force channel 'force \[V\]' has unit 'V'"):
        af.load_recording(path)
    path.write_text(LVM_HEAD.format(units="Newtons") + "".join(rows("\t")))
    with pytest.raises(ValueError, match=r"line 'Y_Unit_Label\\tNewtons' gives 1 units for the 2 columns "
                                         r"\['force', 'displacement'\]: which unit is whose is not known"):  # fmt: skip
        af.load_recording(path)


def test_a_units_line_above_the_header_scales_and_a_units_id_does_not(tmp_path, text_parser) -> None:
    """Was: "Units;s;N;um" above the header was skipped as metadata: um read as m."""
    path = tmp_path / "daq.csv"
    path.write_text("Device;DAQ 7\nUnits;s;N;um\nTime;Force;Displacement\n" + "".join(rows(";", 1e6)))
    check(af.load_recording(path))
    path.write_text("Device;DAQ 7\nUnit;B2\nTime;Force;Displacement\n" + "".join(rows(";")))  # the rig's unit B2
    check(af.load_recording(path))


# -- item 3: MATLAB layouts ------------------------------------------------------------------------------------------


def simulink_signals(labels: list[str], values: list[np.ndarray]) -> np.ndarray:
    """signals(k).values/.label/.blockName as scipy writes a MATLAB struct array."""
    signals = np.zeros(len(labels), dtype=[("values", object), ("dimensions", object), ("label", object),
                                           ("blockName", object)])  # fmt: skip
    for k, (label, value) in enumerate(zip(labels, values)):
        signals[k] = (value, float(np.shape(value)[1]), label, f"rig/Scope{k}")
    return signals


@pytest.mark.parametrize(
    "variables",
    [{"data": {"time": T, "force": F, "displacement": Y}},
     {"meas": {"fs": FS, "force": F[:, None], "displacement": Y[:, None], "note": "rig 3"}},
     {"ScopeData": {"time": T[:, None], "blockName": "rig/Scope",
                    "signals": simulink_signals(["force", "displacement"], [F[:, None], Y[:, None]])}}],
    ids=["struct-of-channels", "struct-with-fs", "simulink-structure-with-time"],
)  # fmt: skip
def test_mat_structs_of_channels_are_recordings(tmp_path, variables) -> None:
    """Was: "holds no channels: the file is empty or damaged" (every struct but dSPACE's was skipped)."""
    from scipy.io import savemat

    path = tmp_path / "s.mat"
    savemat(path, variables)
    rec = af.load_recording(path)
    check(rec)
    assert f"s.mat recording {next(iter(variables))!r}" in rec.source


def test_mat_matrix_columns_and_a_simulink_signal_of_two_columns_are_channels(tmp_path) -> None:
    """Simulink's 'Array' format [t, y1, y2], and a scope's two inputs logged as one signal. Was: refused
    ("force must be a channel index 0..0")."""
    from scipy.io import savemat

    path = tmp_path / "a.mat"
    savemat(path, {"ScopeData": np.column_stack([T, F, Y])})
    check(af.load_recording(path, force="ScopeData column 2", displacement=2, time=0))
    savemat(path, {"ScopeData": {"time": T, "signals": simulink_signals([""], [np.column_stack([F, Y])])}})
    rec = af.load_recording(path, force=1, displacement="rig/Scope0 column 2")
    check(rec)
    assert "force 'rig/Scope0 column 1'" in rec.source


def test_mat_without_a_readable_layout_names_each_variable(tmp_path) -> None:
    """Was: "holds no channels: the file is empty or damaged"."""
    from scipy.io import savemat

    path = tmp_path / "c.mat"
    cell = np.empty(2, dtype=object)
    cell[:] = [F, Y]
    savemat(path, {"channels": cell, "note": "rig 3", "meta": {"operator": "A. B."}})
    with pytest.raises(ValueError, match=r"c.mat holds no channel amb_fast reads: its variables are 'channels' \(a "
                                         r"cell array or other non-numeric value\), 'note' \(text\), 'meta' \(a struct "
                                         r"without numeric fields\). amb_fast reads numeric variables"):  # fmt: skip
        af.load_recording(path)


def write_mat73_structs(path) -> None:
    """A v7.3 file as MATLAB lays out a struct of channels and a Simulink 'Structure with time' (signals a
    1x2 struct array: a reference per element into '#refs#'); column-major arrays, text as uint16 'char'."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")
        data = f.create_group("data")
        data.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, values in (("time", T), ("force", F), ("displacement", Y)):
            data.create_dataset(name, data=values[None, :]).attrs["MATLAB_class"] = np.bytes_("double")
        scope = f.create_group("ScopeData")
        scope.attrs["MATLAB_class"] = np.bytes_("struct")
        scope.create_dataset("time", data=T[None, :])
        signals = scope.create_group("signals")
        signals.attrs["MATLAB_class"] = np.bytes_("struct")
        labels, values = [], []
        for k, (label, v) in enumerate((("force", F), ("displacement", Y))):
            text = refs.create_dataset(f"l{k}", data=np.array([[ord(c)] for c in label], np.uint16))
            text.attrs["MATLAB_class"] = np.bytes_("char")
            labels.append(text.ref)
            values.append(refs.create_dataset(f"v{k}", data=v[None, :]).ref)
        signals.create_dataset("label", data=np.array(labels, dtype=h5py.ref_dtype)[:, None])
        signals.create_dataset("values", data=np.array(values, dtype=h5py.ref_dtype)[:, None])
    with open(path, "r+b") as handle:
        handle.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, written by amb_fast's tests".ljust(116) + bytes(12))


def test_mat73_structs_of_channels_and_simulink(tmp_path) -> None:
    path = tmp_path / "s73.mat"
    write_mat73_structs(path)
    with pytest.raises(ValueError, match=r"holds several recordings \['ScopeData', 'data'\]"):
        af.load_recording(path)
    for name in ("data", "ScopeData"):
        check(af.load_recording(path, recording=name))


# -- item 3: LabVIEW segments, and rows above the header -------------------------------------------------------------

LVM_FILE = "LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nX_Columns\tOne\n***End_of_Header***\t\n\n"
LVM_SEGMENT = ("Channels\t2\t\nSamples\t{n}\t{n}\t\nY_Unit_Label\tNewtons\t{unit}\t\nDelta_X\t0.000250\t0.000250\t\n"
               "***End_of_Header***\t\t\t\nX_Value\tforce\tdisplacement\tComment\n")  # fmt: skip


@pytest.mark.parametrize("cuts", [[8], [3, 9, 12], [300]], ids=["two", "four", "second-after-the-sniffed-lines"])
def test_a_labview_file_with_a_header_per_segment_is_one_recording(tmp_path, text_parser, cuts) -> None:
    """Write To Measurement File's "one header per segment". Was: the segments before the last one in the
    first 256 lines dropped without a word (8 of 16 samples), or a later header refused as "not numeric"."""
    t, f, y = (
        (np.arange(600) / FS, np.sin(np.arange(600)), 1e-3 * np.cos(np.arange(600))) if cuts == [300] else (T, F, Y)
    )
    lines = [f"{a:.10g}\t{b:.10g}\t{c * 1e3:.10g}\n" for a, b, c in zip(t, f, y)]
    text = LVM_FILE
    for a, b in zip([0, *cuts], [*cuts, len(lines)]):
        text += "\n" + LVM_SEGMENT.format(n=b - a, unit="mm") + "".join(lines[a:b])
    path = tmp_path / "seg.lvm"
    path.write_text(text)
    rec = af.load_recording(path)
    assert rec.fs == FS and rec.force.size == t.size
    np.testing.assert_allclose(rec.force, f, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rec.displacement, y, rtol=1e-9, atol=1e-18)


def test_a_labview_segment_that_changes_units_or_columns_is_refused(tmp_path, text_parser) -> None:
    lines = rows("\t")
    path = tmp_path / "seg.lvm"
    first = LVM_FILE + LVM_SEGMENT.format(n=8, unit="Meters") + "".join(lines[:8])
    path.write_text(first + LVM_SEGMENT.format(n=8, unit="mm") + "".join(lines[8:]))
    changed = r"seg.lvm: the LabVIEW segment at line 23 states 'Y_Unit_Label\\tNewtons\\tmm', the first "
    with pytest.raises(ValueError, match=changed + r"'Y_Unit_Label\\tNewtons\\tMeters': another recording"):
        af.load_recording(path)
    path.write_text(first + LVM_SEGMENT.format(n=8, unit="Meters").replace("\tforce", "\tF") + "".join(lines[8:]))
    with pytest.raises(ValueError, match=r"line 26 has the columns 'X_Value\\tF\\tdisplacement\\tComment'"):
        af.load_recording(path)


def test_rows_of_numbers_above_the_header_are_refused_not_dropped(tmp_path, text_parser) -> None:
    """Two recordings joined: was read from the second header on, the first 8 rows dropped without a word."""
    lines = rows()
    path = tmp_path / "two.csv"
    path.write_text("time,force,displacement\n" + "".join(lines[:8]) + "time,force,displacement\n" + "".join(lines[8:]))
    with pytest.raises(ValueError, match=r"two.csv: rows of numbers at lines 2-9 come before line 10 "
                                         r"\('time,force,displacement'\), where the table read starts"):  # fmt: skip
        af.load_recording(path)


def test_a_clock_that_breaks_twice_names_the_first_break_and_the_worst_step(tmp_path, text_parser) -> None:
    """Was: only the first break (a 0.3-sample jitter at row 100), not the 2-sample gap at row 300."""
    t = np.arange(400) / FS
    t[100:] += 0.3 / FS
    t[300:] += 2.0 / FS
    path = tmp_path / "clock.csv"
    path.write_text("time,force,displacement\n" + "".join(f"{v:.17g},1.0,0.0\n" for v in t))
    with pytest.raises(ValueError, match=r"at data row 100 \(t = 0.025075\) the step is 0.000325 against .*; the worst "
                                         r"step, at data row 300, is 0.00075; cut the record"):  # fmt: skip
        af.load_recording(path)


# -- siblings: TDMS units and rates ----------------------------------------------------------------------------------


def write_tdms(path, channels: list[tuple[str, np.ndarray, dict]]) -> None:
    nptdms = pytest.importorskip("nptdms")
    with nptdms.TdmsWriter(path) as writer:
        writer.write_segment([nptdms.ChannelObject("run", n, v, properties=p) for n, v, p in channels])


def test_tdms_unit_names_as_daqmx_writes_them_are_scaled(tmp_path) -> None:
    """Was: refused ("has unit 'Millimeters'")."""
    path = tmp_path / "u.tdms"
    rate = {"wf_increment": 1 / FS}
    write_tdms(path, [("Force", F, {**rate, "unit_string": "Newtons"}),
                      ("Gap", Y * 1e3, {**rate, "unit_string": "Millimeters"})])  # fmt: skip
    rec = af.load_recording(path, force="Force", displacement="Gap")
    check(rec)
    assert "displacement 'Gap [mm]' (mm -> m)" in rec.source


def test_tdms_channels_at_different_rates_are_refused_and_a_slow_third_one_is_not(tmp_path) -> None:
    """Was: the first channel's wf_increment taken for both (the displacement at 2 kHz read as 4 kHz)."""
    path = tmp_path / "r.tdms"
    write_tdms(path, [("force", F, {"wf_increment": 1 / FS}), ("displacement", Y, {"wf_increment": 2 / FS})])
    with pytest.raises(ValueError, match=r"r.tdms: the channels 'force' 4000 Hz, 'displacement' 2000 Hz have "
                                         r"different rates \(their wf_increment\)"):  # fmt: skip
        af.load_recording(path)
    write_tdms(path, [("temperature", np.ones(2), {"wf_increment": 0.1}), ("force", F, {"wf_increment": 1 / FS}),
                      ("displacement", Y, {"wf_increment": 1 / FS})])  # fmt: skip
    check(af.load_recording(path))


def test_tdms_unit_string_contradicting_the_name_is_refused(tmp_path) -> None:
    """Was: the name's unit (m) used and the unit_string (mm) ignored without a word."""
    path = tmp_path / "c.tdms"
    rate = {"wf_increment": 1 / FS}
    write_tdms(path, [("force", F, rate), ("displacement [m]", Y * 1e3, {**rate, "unit_string": "mm"})])
    with pytest.raises(ValueError, match=r"the channel 'displacement \[m\]' of group 'run' has unit_string 'mm', not "
                                         r"the unit of its name"):  # fmt: skip
        af.load_recording(path)
    write_tdms(path, [("force", F, rate), ("displacement [m]", Y, {**rate, "unit_string": "Meters"})])  # agree
    check(af.load_recording(path))


# -- siblings: a rate stated in the metadata -------------------------------------------------------------------------


def test_a_stated_rate_with_a_thousands_separator_is_not_read_as_a_decimal(tmp_path, text_parser) -> None:
    """Was: "Sample rate: 10,000 Hz" gave fs 10 Hz, and "10 000 Hz" 10 Hz, without a word."""
    body = "force,displacement\n" + "".join(f"{f:.10g},{y:.10g}\n" for f, y in zip(F, Y))
    path = tmp_path / "r.csv"
    path.write_text("Sample rate: 10,000 Hz\n" + body)
    with pytest.raises(ValueError, match=r"r.csv: its metadata line 'Sample rate: 10,000 Hz' states 10 Hz or 10000 Hz "
                                         r"\(a thousands separator or a decimal mark\?\): pass fs="):  # fmt: skip
        af.load_recording(path)
    assert af.load_recording(path, fs=10000.0).fs == 10000.0
    with pytest.raises(ValueError, match=r"one of them, not 7000"):
        af.load_recording(path, fs=7000.0)
    timed = tmp_path / "t.csv"  # a time column settles it
    timed.write_text("Sample rate: 4,000 Hz\ntime,force,displacement\n" + "".join(rows()))
    check(af.load_recording(timed))
    path.write_text("Sample rate: 10 000 Hz\n" + body)
    with pytest.raises(ValueError, match=r"r.csv has neither 'fs' nor a time column"):
        af.load_recording(path)


@pytest.mark.parametrize("line", ["Abtastrate: 4000 Hz", "Sample period: 0.25 ms", "dt = 0,250 ms",
                                  "Sample rate: 4.000 kHz"])  # fmt: skip
def test_more_ways_to_state_the_rate(tmp_path, text_parser, line) -> None:
    path = tmp_path / "r.csv"
    path.write_text(line + "\nforce,displacement\n" + "".join(f"{f:.10g},{y:.10g}\n" for f, y in zip(F, Y)))
    rec = af.load_recording(path)
    check(rec)
    assert rec.fs_from == f"the metadata line {line!r} of r.csv"
