"""The command's options (issue 25, cases 7, 8, 12, 15): defaults follow the options given and only values the
user gave are refused; the library's messages name options, not keyword arguments; ``amb-fast sweep`` takes
any rig field or controller parameter (``--vary``); value lists refuse empty items; a sweep's CSV is
:meth:`SweepResult.save`'s, without numpy's warning on the NaN rows of unstable points."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
from amb_fast.cli._options import IDENTIFY_OPTION_NAMES, MODEL_OPTION_NAMES, cli_text, default_f_max
from cli_helpers import one_error_line, run


def table_lines(out: str) -> list[float]:
    """The frequencies (Hz) of the k/c table's rows."""
    rows = out.split("f (Hz)", 1)[1].splitlines()[1:]
    return [float(row.split()[0]) for row in rows if row.strip() and row.split()[0][0].isdigit()]


# -- case 8: defaults follow the options given ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("options", "band"),
    [
        (["--f-max", "20"], (1.0, 20.0)),
        (["--lines", "odd"], (1.0, 199.0)),
        (["--f0", "0.5", "--f-max", "20"], (0.5, 20.0)),
        (["--f0", "50"], (50.0, 200.0)),
    ],
)
def test_run_tabulates_lines_within_the_band_of_the_options_given(capsys, options, band) -> None:
    """Was: exit 2, "--at must be within the excited band 1-20 Hz, got [40.0, 100.0, 200.0]" (a default)."""
    status, out, err = run(capsys, "run", "--periods", "2", *options)
    assert status == 0, err
    at = table_lines(out)
    assert len(at) >= 3 and at[0] == band[0] and at[-1] == band[1]
    assert all(band[0] <= f <= band[1] for f in at)


def test_the_paper_table_stays_the_default_where_the_band_holds_it(capsys) -> None:
    status, out, _ = run(capsys, "run", "--periods", "2")
    assert status == 0 and table_lines(out) == [10.0, 40.0, 100.0, 200.0]


def test_an_at_the_user_gave_outside_the_band_is_still_refused(capsys) -> None:
    status, _, err = run(capsys, "run", "--f-max", "20", "--at", "10,40")
    assert status == 2
    assert "--at must be within the excited band 1-20 Hz, got [40.0]" in one_error_line(err)


def test_the_default_f_max_stays_below_the_nyquist_frequency_of_the_fs_given(capsys, tmp_path) -> None:
    """Was: exit 2, "f_max must be ... below fs/2 (150.0 Hz), got 200.0" for ``--fs 300`` (200 Hz a default)."""
    out = tmp_path / "s.npz"
    status, _, err = run(capsys, "sweep", "--fs", "300", "--kp", "2400", "--periods", "2", "--out", str(out),
                         "--no-progress")  # fmt: skip
    assert status == 0, err
    assert af.load_sweep(out).freq[-1] == 149.0  # the highest harmonic of 1 Hz below 150 Hz
    assert default_f_max(1.0, 4000.0) == 200.0 and default_f_max(250.0, 4000.0) == 250.0
    assert default_f_max(0.5, 300.0) == 149.5


def test_a_band_without_resonance_says_so_instead_of_nan(capsys) -> None:
    """Was: "natural frequency   nan Hz"."""
    status, out, _ = run(capsys, "run", "--periods", "2", "--f-max", "20")
    assert status == 0 and " nan " not in out
    assert "natural frequency   none in 1-20 Hz (Re F/Y > 0 throughout: the resonance lies above 20 Hz" in out
    status, out, _ = run(capsys, "run", "--periods", "2", "--f0", "50")  # lines 50-200 Hz, resonance ~40 Hz
    assert status == 0 and " nan " not in out
    assert "natural frequency   none in 50-200 Hz (Re F/Y <= 0 throughout: the resonance lies below 50 Hz" in out


# -- case 7: messages name options ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("library", "command"),
    [
        ("f_max must be at least f0 (1.0 Hz) and below fs/2 (2000.0 Hz), got 3000.0",
         "--f-max must be at least --f0 (1.0 Hz) and below --fs/2 (2000.0 Hz), got 3000.0"),
        ("fs/f0 must be a whole number of samples per period, got 5714.3",
         "--fs/--f0 must be a whole number of samples per period, got 5714.3"),
        ("median_window must be odd, got 4", "--median-window must be odd, got 4"),
        ("a start transient is in the estimate; skip it with settle_periods=",
         "a start transient is in the estimate; skip it with --settle-periods"),
        ("x.csv has neither 'fs' nor a time column: pass fs= (Hz; on the command line --fs)",
         "x.csv has neither 'fs' nor a time column: pass --fs (Hz)"),
        ("by 0-based index (force=1, displacement=2; on the command line --force 1 --displacement 2)",
         "by 0-based index (--force 1 --displacement 2)"),
        ("choose one with recording=NAME", "choose one with --recording NAME"),
        ("pass fs=, or time=None to ignore the column", "pass --fs, or --time none to ignore the column"),
        # The data and prose are left alone: "force must be finite" is about the samples.
        ("force must be finite, got nan at sample 3", "force must be finite, got nan at sample 3"),
        ("the wrong lines (pass lines= or f_max=)", "the wrong lines (pass --lines or --f-max)"),
        ("recording length must be at least settle_periods + 1 periods",
         "recording length must be at least --settle-periods + 1 periods"),
    ],
)  # fmt: skip
def test_the_library_messages_name_the_identify_options(library, command) -> None:
    assert cli_text(library, IDENTIFY_OPTION_NAMES) == command


def test_the_library_messages_name_the_model_options(capsys) -> None:
    assert cli_text("bias_current must be a finite number > 0 (A), got 0.0", MODEL_OPTION_NAMES) == (
        "--bias-current must be a finite number > 0 (A), got 0.0"
    )
    status, _, err = run(capsys, "run", "--f0", "3")  # 4000/3 samples per period: the library refuses it
    assert status == 2
    assert "--fs/--f0 must be a whole number of samples per period" in one_error_line(err)
    status, _, err = run(capsys, "run", "--f-max", "3000")
    assert status == 2 and "--f-max must be at least --f0 (1.0 Hz) and below --fs/2 (2000.0 Hz)" in err


# -- case 15: value lists -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sweep", "--kp", "2000,,3000"], "argument --kp: an empty value in '2000,,3000'"),
        (["sweep", "--kp", "2000,3000,"], "argument --kp: an empty value in '2000,3000,'"),
        (["sweep", "--kd", "1:3:0"], "argument --kd: 'start:stop:count' needs a count >= 1, got '1:3:0'"),
        (["run", "--at", "10,,40"], "argument --at: an empty value in '10,,40'"),
    ],
)
def test_value_lists_refuse_empty_items(capsys, tmp_path, monkeypatch, args, message) -> None:
    """Was: ``--kp 2000,,3000`` ran a 2-point sweep."""
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, *args)
    assert status == 2 and message in one_error_line(err)
    assert list(tmp_path.iterdir()) == []


# -- case 12: sweep any rig field or controller parameter ----------------------------------------------------


def test_sweep_varies_a_rig_field_as_the_api_does(capsys, tmp_path) -> None:
    out = tmp_path / "s.npz"
    status, stdout, err = run(capsys, "sweep", "--kd", "2,3", "--vary", "amp_bandwidth=1000,3000", "--f-max", "50",
                              "--periods", "2", "--out", str(out), "--no-progress")  # fmt: skip
    assert status == 0, err
    assert "4 points: 4 ok" in stdout
    got = af.load_sweep(out)
    want = af.sweep(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=50.0), kd=[2.0, 3.0],
                    amp_bandwidth=[1000.0, 3000.0], periods=2, seed=2026, progress=False)  # fmt: skip
    assert got.shape == (2, 2) and list(got.axes) == ["kd", "amp_bandwidth"]
    np.testing.assert_array_equal(got.points["amp_bandwidth"], [1000.0, 3000.0, 1000.0, 3000.0])
    np.testing.assert_array_equal(got.k, want.k)
    np.testing.assert_array_equal(got.c, want.c)


def test_sweep_varies_a_parameter_of_a_controller_file(capsys, tmp_path) -> None:
    path = tmp_path / "ctrl.toml"
    path.write_text('fs = 4000.0\n\n[[block]]\ntype = "pid"\nkp = 2400.0\nki = 20000.0\nkd = 3.0\n'
                    'derivative_cutoff = 1000.0\n\n[[block]]\ntype = "notch"\nfreq = 700.0\n')  # fmt: skip
    out = tmp_path / "s.npz"
    status, _, err = run(capsys, "sweep", "--controller", str(path), "--vary", "notch-freq=600:800:3", "--f-max",
                         "50", "--periods", "2", "--out", str(out), "--no-progress")  # fmt: skip
    assert status == 0, err
    got = af.load_sweep(out)
    np.testing.assert_array_equal(got.points["notch_freq"], [600.0, 700.0, 800.0])
    controller = af.load_controller(path).with_params(notch_freq=800.0)
    point = af.run_experiment(af.Rig.paper(), controller, af.schroeder_multisine(f_max=50.0), periods=2,
                              seed=int(got.seeds[2]))  # fmt: skip
    np.testing.assert_array_equal(got.k[2], point.k)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--vary", "notch_freq=600,700"], "--vary: 'notch_freq' is neither a numeric rig field nor a parameter"),
        (["--vary", "amp_bandwidth"], "--vary takes NAME=VALUES (e.g. --vary amp_bandwidth=1000:3000:5), got"),
        (["--kd", "2,3", "--vary", "kd=4,5"], "--vary kd: kd is already swept (--kd)"),
        (["--amp-bandwidth", "2000", "--vary", "amp_bandwidth=1000,3000"],
         "--amp-bandwidth sets amp_bandwidth to one value and --vary sweeps it: give one of them"),
        (["--vary", "kyy=-5e4,,-6e4"], "--vary kyy: an empty value in '-5e4,,-6e4'"),
        (["--vary", "kd=2,3", "--vary", "mass=1,2,3", "--grid", "zip"],
         "--grid zip needs as many values of each swept parameter, got {'kd': 2, 'mass': 3}"),
        ([], "give at least one of --kp, --ki, --kd, --vary"),
    ],
)  # fmt: skip
def test_sweep_refuses_wrong_axes_before_any_work(capsys, tmp_path, monkeypatch, args, message) -> None:
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, "sweep", "--periods", "2", *args)
    assert status == 2 and message in one_error_line(err)
    assert list(tmp_path.iterdir()) == []


# -- case 15: a sweep's CSV --------------------------------------------------------------------------------


def test_sweep_result_saves_csv_as_the_command_writes_it_without_warnings(capsys, tmp_path) -> None:
    """Was: ``SweepResult.save("x.csv")`` refused (ValueError), and the command's CSV of a sweep with an unstable
    point printed numpy's "invalid value encountered in scalar divide" (filterwarnings=error makes it fail)."""
    ms = af.schroeder_multisine(f_max=20.0)
    result = af.sweep(af.Rig.paper(), af.PID.paper(), ms, kp=[100.0, 2400.0], periods=2, seed=2026, progress=False)
    assert result.status.tolist() == ["unstable", "ok"]
    result.save(tmp_path / "api.csv")
    status, _, err = run(capsys, "sweep", "--kp", "100,2400", "--f-max", "20", "--periods", "2", "--out",
                         str(tmp_path / "cli.csv"), "--no-progress")  # fmt: skip
    assert status == 0 and "warning" not in err
    text = (tmp_path / "api.csv").read_text()
    assert text == (tmp_path / "cli.csv").read_text()
    rows = [line.split(",") for line in text.splitlines() if not line.startswith("#")]
    assert rows[0] == ["kp", "status", "freq_Hz", "k_N_per_m", "c_Ns_per_m", "k_std_N_per_m", "c_std_Ns_per_m",
                       "receptance_abs_m_per_N"]  # fmt: skip
    assert len(rows) == 1 + 2 * 20
    assert all(row[1] == "unstable" and row[3:] == ["nan"] * 5 for row in rows[1:21])
    ok = np.array([[float(v) for v in row[2:]] for row in rows[21:]])
    np.testing.assert_array_equal(ok[:, 0], ms.freq)
    np.testing.assert_allclose(ok[:, 1], result.k[1], rtol=1e-15)
    np.testing.assert_allclose(ok[:, 5], np.abs(1 / result.H[1]), rtol=1e-15)
    assert text.splitlines()[-1].startswith("# meta: ")
    with pytest.raises(ValueError, match=r"a sweep's \.csv is for other tools"):
        af.load_sweep(tmp_path / "api.csv")


def test_rotor_sensitivity_refuses_periods_before_the_run_and_keeps_its_band_below_nyquist(capsys) -> None:
    """Siblings in ``amb-fast rotor``: ``--periods 1`` was exit status 1 ("periods must be ...", a failed run);
    its 2-1000 Hz test signal was fixed whatever the controller's fs."""
    status, _, err = run(capsys, "rotor", "sensitivity", "--periods", "1")
    assert status == 2 and "--periods must be a whole number >= 2, got 1" in one_error_line(err)
    assert default_f_max(2.0, 4000.0, 1000.0) == 1000.0 and default_f_max(2.0, 1500.0, 1000.0) == 748.0
