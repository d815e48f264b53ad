"""The command: one-line errors with exit status 2 (usage, before any work) or 1 (a failed run), --version,
--debug, output paths checked before computing, never an overwrite without --overwrite, atomic writes."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import amb_fast as af
from amb_fast import cli
from cli_helpers import one_error_line, run


def test_version(capsys) -> None:
    status, out, _ = run(capsys, "--version")
    assert status == 0 and out.strip() == f"amb-fast {af.__version__}"


def test_a_touchdown_is_one_line_with_exit_status_1_and_a_traceback_only_with_debug(capsys) -> None:
    status, _, err = run(capsys, "run", "--force-law", "nonlinear", "--rms", "50")
    assert status == 1
    assert "touchdown: the platform reached its clearance" in one_error_line(err)
    status, _, err = run(capsys, "run", "--force-law", "nonlinear", "--rms", "50", "--debug")
    assert status == 1 and "Traceback" in err and "TouchdownError" in err


def test_the_package_and_the_command_load_scipy_signal_optimize_stats_only_when_used() -> None:
    """``import amb_fast`` and ``amb-fast --help`` leave out scipy.signal, scipy.optimize and scipy.stats
    (half a second of every start: they load with the first controller design or calibration), and the
    names that need them still resolve."""
    heavy = ("scipy.signal", "scipy.optimize", "scipy.stats", "matplotlib")
    code = (f"import sys, amb_fast, amb_fast.cli; amb_fast.cli.build_parser(); print([m for m in {heavy!r} "
            "if m in sys.modules]); amb_fast.fit_rig, amb_fast.calibration.Design, amb_fast.notch(50.0); "
            "print(sorted(m for m in ('scipy.signal', 'scipy.optimize') if m in sys.modules))")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "[]", out
    assert out[1] == "['scipy.optimize', 'scipy.signal']", out


XARRAY_AND_WHAT_IT_PROBES = ("xarray", "dask", "distributed", "pint")
WRITING_NETCDF = {
    "Estimate.save": "import amb_fast as af; af.run_experiment(af.Rig(), af.PID.paper(), af.schroeder_multisine("
    "f_max=20.0), periods=2, seed=4).save(path)",
    "amb-fast run --save": "import amb_fast.cli; assert amb_fast.cli.main(['run', '--periods', '2', '--seed', '4', "
    "'--save', path]) == 0",
    "amb-fast sweep --out": "import amb_fast.cli; assert amb_fast.cli.main(['sweep', '--kp', '2000,2400', "
    "'--periods', '2', '--seed', '4', '--no-progress', '--out', path]) == 0",
}


@pytest.mark.parametrize("how", WRITING_NETCDF)
def test_netcdf_files_are_written_without_importing_xarray(tmp_path, how) -> None:
    """An estimate's and a product grid's ``.nc`` files are written with h5netcdf alone: importing xarray (and the
    dask, distributed and pint it probes for) took ~1 s of ``amb-fast run --save x.nc``."""
    pytest.importorskip("h5netcdf")
    pytest.importorskip("xarray")  # to read the file back
    path = tmp_path / "out.nc"
    code = (f"import sys; path = sys.argv[1]; {WRITING_NETCDF[how]}; "
            f"print([m for m in {XARRAY_AND_WHAT_IT_PROBES!r} if m in sys.modules])")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout
    loaded = af.load_sweep(path) if "sweep" in how else af.load_estimate(path)
    assert loaded.meta["seed"] == 4


def test_the_command_line_as_a_separate_process(tmp_path) -> None:
    done = subprocess.run([sys.executable, "-m", "amb_fast", "sweep", "--kp", "2000", "--out", "s.xlsx"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip() == "amb-fast: error: --out must end in .nc, .npz, .csv, got 's.xlsx'"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sweep", "--kp", "2000:3000:100001", "--out", "s.xlsx"], "--out must end in .nc, .npz, .csv, got 's.xlsx'"),
        (["sweep", "--kp", "2000", "--out", "missing/s.nc"], "--out: the directory 'missing' does not exist"),
        (["sweep", "--kp", "2000,2100", "--kd", "1,2,3", "--grid", "zip"], "--grid zip needs as many values"),
        (["run", "--save", "est.xlsx"], "--save must end in .csv, .nc, got 'est.xlsx'"),
        (["run", "--save", "same.png", "--figure", "same.png"], "--save must end in .csv, .nc"),
        (["run", "--save", "a.csv", "--figure", "a.csv"], "--figure must end in .png, .pdf, .svg"),
        (["run", "--kp", "300"], "closed loop is unstable"),
        (["run", "--periods", "1"], "--periods must be a whole number >= 2"),
        (["run", "--kp", "fast"], "argument --kp: expected a number or 'none', got 'fast'"),
        (["identify", "missing.csv"], "the recording 'missing.csv' does not exist"),
        (["identify", "rec.csv", "--settle-periods", "-1"], "--settle-periods must be a whole number >= 0, got -1"),
        (["identify", "rec.csv", "--mass", "0"], "--mass must be a finite number > 0, got 0.0"),
        (["run", "--at", "500"], "--at must be within the excited band 1-200 Hz, got [500.0]"),
    ],
)
def test_mistakes_are_refused_before_any_work_with_exit_status_2(capsys, tmp_path, monkeypatch, args, message) -> None:
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, *args)
    assert status == 2
    assert message in one_error_line(err)
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_existing_outputs_are_never_overwritten_without_overwrite(capsys, tmp_path, monkeypatch, recorded) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sweep.nc").write_text("an earlier sweep")
    status, _, err = run(capsys, "sweep", "--kp", "2000", "--periods", "2", "--no-progress")  # the default name
    assert status == 2 and "'sweep.nc' exists; pass --overwrite to replace it" in one_error_line(err)
    assert (tmp_path / "sweep.nc").read_text() == "an earlier sweep"
    status, out, _ = run(capsys, "sweep", "--kp", "2000", "--periods", "2", "--no-progress", "--overwrite")
    assert status == 0 and "wrote sweep.nc" in out
    assert af.load_sweep(tmp_path / "sweep.nc").status.tolist() == ["ok"]

    (tmp_path / "est.csv").write_text("kept")
    status, _, err = run(capsys, "run", "--periods", "2", "--save", "est.csv")
    assert status == 2 and "exists; pass --overwrite" in one_error_line(err)
    assert (tmp_path / "est.csv").read_text() == "kept"

    (tmp_path / "ident").mkdir()
    (tmp_path / "ident" / "estimate.png").write_text("kept")
    status, _, err = run(capsys, "identify", "rec.csv", "--out", "ident")
    assert status == 2 and "'ident' already holds estimate.png; pass --overwrite" in one_error_line(err)


def test_a_failed_write_is_exit_status_1_and_keeps_the_old_file(capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "est.csv").write_text("the old estimate")

    def disk_full(src, dst):  # noqa: ANN001, ANN202
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", disk_full)
    status, out, err = run(capsys, "run", "--periods", "2", "--save", "est.csv", "--overwrite")
    assert status == 1 and "natural frequency" in out  # the run itself finished
    assert "could not write 'est.csv' (the old file, if any, is unchanged)" in one_error_line(err)
    assert (tmp_path / "est.csv").read_text() == "the old estimate"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["est.csv"]


@pytest.fixture
def recorded(tmp_path):  # noqa: ANN201
    rig, pid = af.Rig.paper(), af.PID.paper()
    ms = af.schroeder_multisine(f_max=100.0)
    trace = af.simulate(rig, pid, np.tile(ms.samples, 6), seed=3)
    trace.save(tmp_path / "rec.csv")
    return trace


def test_identify_checks_fs_against_the_time_column(capsys, tmp_path, monkeypatch, recorded) -> None:
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, "identify", "rec.csv", "--fs", "4", "--settle-periods", "2")
    assert status == 2
    assert "fs must agree with rec.csv's time column 'time' (4000 Hz) within 0.1 %, got 4" in one_error_line(err)
    assert not (tmp_path / "identify-output").exists()


def test_identify_warnings_are_one_line_each(capsys, tmp_path, monkeypatch, recorded) -> None:
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "identify", "rec.csv", "--out", "ident")  # settle periods left at 0
    assert status == 0, err
    warnings = [line for line in err.splitlines() if line.startswith("amb-fast: warning: ")]
    assert len(warnings) == 1 and "start transient" in warnings[0]
    assert af.load_estimate(tmp_path / "ident" / "estimate.csv").freq.size == 100


def test_identify_chooses_a_recording_of_a_mat_file(capsys, tmp_path, monkeypatch, recorded) -> None:
    from scipy.io import savemat

    monkeypatch.chdir(tmp_path)

    def export(force: np.ndarray) -> dict:
        Y = np.zeros((1, 2), dtype=[("Name", "O"), ("Data", "O")])
        Y[0, 0]["Name"], Y[0, 0]["Data"] = "Root/force", force
        Y[0, 1]["Name"], Y[0, 1]["Data"] = "Root/displacement", recorded.displacement
        X = np.zeros((1, 1), dtype=[("Data", "O")])
        X[0, 0]["Data"] = recorded.time
        return {"X": X, "Y": Y}

    savemat(tmp_path / "two.mat", {"first": export(recorded.force), "second": export(recorded.force)})
    status, _, err = run(capsys, "identify", "two.mat", "--settle-periods", "2", "--mass", "0.92")
    assert status == 2 and "holds several recordings ['first', 'second']" in one_error_line(err)
    status, out, err = run(capsys, "identify", "two.mat", "--settle-periods", "2", "--mass", "0.92", "--recording",
                           "second")  # fmt: skip
    assert status == 0, err
    assert "100 lines from 1 to 100 Hz" in out


def test_saved_files_record_version_rig_controller_and_seed(capsys, tmp_path, monkeypatch) -> None:
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, "run", "--periods", "2", "--seed", "17", "--figure", "est.png", "--save", "est.csv")
    assert status == 0, err
    png = (tmp_path / "est.png").read_bytes()
    assert f"amb_fast {af.__version__}".encode() in png and b'"seed": 17' in png and b'"kp": 2400.0' in png
    assert af.load_estimate(tmp_path / "est.csv").meta["seed"] == 17
    status, _, err = run(capsys, "sweep", "--kp", "2000,2400", "--periods", "2", "--seed", "5", "--out", "s.csv",
                         "--no-progress")  # fmt: skip
    assert status == 0, err
    trailer = (tmp_path / "s.csv").read_text().splitlines()[-2:]
    assert trailer[0] == f"# amb_fast {af.__version__}" and '"seed": 5' in trailer[1] and '"kd": 3.0' in trailer[1]


def test_paper_refuses_to_overwrite_its_outputs_before_running(capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "claims.md").write_text("last week's claims")
    status, out, err = run(capsys, "paper", "--out", "out", "--no-progress")
    assert status == 2 and "'out' already holds claims.md; pass --overwrite" in one_error_line(err)
    assert out == "" and sorted(p.name for p in (tmp_path / "out").iterdir()) == ["claims.md"]


CONTROLLER_FILE = """\
fs = 4000.0

[[block]]
type = "pid"
kp = 2400.0
ki = 20000.0
kd = 3.0
derivative_cutoff = 1000.0

[[block]]
type = "notch"
freq = 700.0
"""


def test_run_and_sweep_take_a_controller_file(capsys, tmp_path) -> None:
    """--controller FILE runs that controller: the same numbers as the Python API with load_controller."""
    path = tmp_path / "ctrl.toml"
    path.write_text(CONTROLLER_FILE)
    controller = af.PID.paper().to_controller() * af.notch(700.0)
    sphs = af.schroeder_multisine(f_max=50.0)
    est = af.run_experiment(af.Rig.paper(), controller, sphs, periods=3, seed=2026)
    assert cli.main(["run", "--controller", str(path), "--f-max", "50", "--periods", "3", "--at", "10",
                 "--save", str(tmp_path / "e.csv")]) == 0  # fmt: skip
    back = af.load_estimate(tmp_path / "e.csv")
    np.testing.assert_allclose(back.k, est.k, rtol=1e-12)
    capsys.readouterr()
    out = tmp_path / "s.nc"
    assert cli.main(["sweep", "--controller", str(path), "--kp", "2000,2400", "--f-max", "50", "--periods", "3",
                 "--out", str(out), "--no-progress"]) == 0  # fmt: skip
    swept = af.load_sweep(out)
    point = af.run_experiment(af.Rig.paper(), controller.with_params(kp=2000.0), sphs, periods=3,
                              seed=int(swept.seeds[0]))  # fmt: skip
    np.testing.assert_array_equal(swept.k[0], point.k)
    # Options that the file sets, and a missing file, are refused before any work.
    assert cli.main(["run", "--controller", str(path), "--kd", "4"]) == 2
    assert "--kd cannot go with --controller" in capsys.readouterr().err
    assert cli.main(["run", "--controller", str(tmp_path / "none.toml")]) == 2
    assert "is not a file" in capsys.readouterr().err
    (tmp_path / "bad.toml").write_text('[[block]]\ntype = "notch"\n')
    assert cli.main(["run", "--controller", str(tmp_path / "bad.toml")]) == 2
    assert "block 1" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["-1e4", "-2.5E+3", "-.5", "-7"])
def test_negative_numbers_in_any_notation_are_option_values(value) -> None:
    args = cli.build_parser().parse_args(cli._join_negative_values(["run", "--two-axis", "--kyx", value]))
    assert args.kyx == float(value)


def test_a_missing_value_is_still_a_usage_error(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["run", "--kyx", "--two-axis"])
    assert exit_info.value.code == 2
    assert "--kyx" in capsys.readouterr().err


def test_the_default_sweep_file_needs_no_extra(capsys, tmp_path, monkeypatch) -> None:
    """Without the xarray extra, `amb-fast sweep` with no --out failed ("--out .nc needs h5netcdf") although no
    option asked for NetCDF: the default is then sweep.npz."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "xarray" else real(name, *a))
    monkeypatch.chdir(tmp_path)
    status, out, _ = run(capsys, "sweep", "--kp", "2000", "--periods", "2", "--no-progress")
    assert status == 0 and "wrote sweep.npz" in out
    assert af.load_sweep(tmp_path / "sweep.npz").status.tolist() == ["ok"]
    assert not (tmp_path / "sweep.nc").exists()


@pytest.mark.parametrize(
    ("option", "shown"),
    [("--cross-kp", "--cross-kp must be a finite number (A/m), got nan"),
     ("--sensor-angle", "--sensor-angle must be a finite number (rad), got nan"),
     ("--kyx", "--kyx must be a finite number (N/m), got nan")],
)  # fmt: skip
def test_a_two_axis_nan_is_an_input_mistake_named_by_its_option(capsys, option, shown) -> None:
    """They were found in the run (exit status 1), and a NaN --cross-kp was reported as "--kp"."""
    status, _, err = run(capsys, "run", "--two-axis", "--periods", "2", option, "nan")
    assert status == 2 and one_error_line(err) == f"amb-fast: error: {shown}"


def test_the_default_design_band_follows_the_controllers_fs(capsys, tmp_path) -> None:
    """`design --fs 200` failed (exit status 1, the band's 131 frequencies printed): the default band 20-150 Hz
    reached above fs/2; it now ends at the last step below fs/2, and a band given above it is an input mistake."""
    out = tmp_path / "c.toml"
    status, printed, err = run(capsys, "design", "--stiffness", "6e4", "--fs", "200", "--out", str(out))
    assert status == 0, err
    assert af.load_controller(out).fs == 200.0 and "naive design" in printed
    status, _, err = run(capsys, "design", "--stiffness", "6e4", "--fs", "200", "--band", "20:150")
    assert status == 2
    assert one_error_line(err) == ("amb-fast: error: --band must lie below fs/2 = 100 Hz (the controller samples at "
                                   "200 Hz), got 20:150")  # fmt: skip
    status, _, err = run(capsys, "design", "--stiffness", "6e4", "--max-sensitivity", "-1")
    assert status == 2 and "--max-sensitivity must be a finite |S| peak > 1" in one_error_line(err)
