"""Every file the command writes loads back with the library; input mistakes that only the library used to
catch (after the run had started: exit status 1) are refused before any work, exit status 2, in one line
naming the option."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import amb_fast as af
from amb_fast import cli
from amb_fast import two_axis as ta
from cli_helpers import one_error_line, run

# -- every output loads back ----------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".csv", ".nc", ".npz"])
def test_run_two_axis_saves_the_n_axis_estimate_that_load_estimate_reads(capsys, tmp_path, suffix) -> None:
    """Was: ``save_estimate2``'s wide table (freq_Hz, kxx_N_per_m, ...): load_estimate refused the .npz and
    could not read the .csv; .nc was refused by the command."""
    if suffix == ".nc":
        pytest.importorskip("h5netcdf")
    path = tmp_path / f"two{suffix}"
    status, out, err = run(capsys, "run", "--two-axis", "--kxy=1e4", "--f-max", "20", "--periods", "2", "--seed",
                           "3", "--save", str(path))  # fmt: skip
    assert status == 0, err
    assert f"wrote {path}" in out
    rig = ta.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=1e4)
    pid = af.PID.paper()
    expected = ta.run_experiment(rig, [[pid, None], [None, pid]], af.schroeder_multisine(f_max=20.0), periods=2,
                                 seed=3)  # fmt: skip
    assert af.load_estimate(path) == expected


@pytest.mark.parametrize(
    ("args", "name", "load"),
    [
        (["run", "--save"], "e.csv", af.load_estimate),
        (["run", "--save"], "e.nc", af.load_estimate),
        (["rotor", "experiment", "--save"], "r.csv", af.load_estimate),
        (["rotor", "experiment", "--save"], "r.nc", af.load_estimate),
        (["rotor", "experiment", "--save"], "r.npz", af.load_estimate),
        (["sweep", "--kp", "2000,2400", "--no-progress", "--out"], "s.nc", af.load_sweep),
        (["sweep", "--kp", "2000,2400", "--no-progress", "--out"], "s.npz", af.load_sweep),
    ],
)  # fmt: skip
def test_every_saved_result_loads_back_with_the_library(capsys, tmp_path, args, name, load) -> None:
    if name.endswith(".nc"):
        pytest.importorskip("h5netcdf")
        pytest.importorskip("xarray")
    path = tmp_path / name
    status, _, err = run(capsys, *args, str(path), "--periods", "2", "--seed", "5")
    assert status == 0, err
    loaded = load(path)
    assert loaded.freq.size > 0 and np.all(np.isfinite(loaded.k))


def test_fit_and_design_files_load_back(capsys, tmp_path) -> None:
    estimate = tmp_path / "e.csv"
    assert run(capsys, "run", "--periods", "4", "--f-max", "50", "--save", str(estimate))[0] == 0
    status, _, err = run(capsys, "fit", str(estimate), "--free", "kyy,kiy", "--out", str(tmp_path / "rig.toml"))
    assert status == 0, err
    assert af.load_rig(tmp_path / "rig.toml").kiy > 0
    status, _, err = run(capsys, "design", "--stiffness", "6e4", "--out", str(tmp_path / "c.toml"))
    assert status == 0, err
    assert af.load_controller(tmp_path / "c.toml").fs == 4000.0


# -- design and fit: input mistakes before the work -----------------------------------------------------------


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--stiffness", "6e4", "--max-sensitivity", "-1"],
         "--max-sensitivity must be a finite |S| peak > 1 (3: ISO 14839-3 zone A), got -1"),
        (["--stiffness", "6e4", "--max-sensitivity", "nan"], "--max-sensitivity must be a finite |S| peak > 1"),
        (["--stiffness", "nan"], "--stiffness must be a finite number (N/m), got nan"),
        (["--damping", "inf"], "--damping must be a finite number (N s/m), got inf"),
        (["--stiffness", "6e4", "--free", "kq"],
         "--free: 'kq' is not a parameter of the controller; one of kp, ki, kd, derivative_cutoff"),
        (["--stiffness", "6e4", "--free", "kp,kp"], "--free must name one or more distinct parameters, got 'kp,kp'"),
        (["--stiffness", "6e4", "--free", "kyy"], "--free: 'kyy' is a rig field; design chooses controller parameters"),
    ],
)  # fmt: skip
def test_design_mistakes_the_library_found_after_the_start_are_exit_status_2(capsys, options, message) -> None:
    """Were exit status 1 (a failed run), and ``--free kq`` was named ``free:``."""
    status, _, err = run(capsys, "design", *options)
    assert status == 2 and message in one_error_line(err)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--stiffness", "6e4", "--step", "nan"], "--step must be a finite number > 0 (Hz), got nan"),
        (["--stiffness", "6e4", "--step", "1e-9"], "--step 1e-09 gives 1.3e+11 frequencies in 20:150 Hz"),
        (["--stiffness", "6e4", "--band", "20:inf"], "--band must be finite frequencies 0 < low < high (Hz), got "
         "20:inf"),
        (["--stiffness", "6e4", "--kp", "nan"], "--kp must be a finite number (A/m), got nan"),
        (["--stiffness", "6e4", "--set", "mass=nan"], "--set: mass must be a finite number > 0 (kg), got nan"),
        (["--stiffness", "6e4", "--set", "substeps=2.5"], "--set substeps must be a whole number >= 1, got 2.5"),
    ],
)  # fmt: skip
def test_design_messages_name_the_option(capsys, options, message) -> None:
    """Were "arange: cannot compute length", "Maximum allowed size exceeded", "kp must ...", "mass must ..."; and
    ``--set substeps=2.5`` ran with 2 substeps."""
    status, _, err = run(capsys, "design", *options)
    assert status == 2 and message in one_error_line(err)


@pytest.fixture(scope="module")
def estimates(tmp_path_factory) -> dict[str, str]:
    """Estimate files: ``plain`` (4 periods), ``noiseless`` (no noise: no weights), ``three`` (3 periods),
    ``slow`` (fs 2000 Hz)."""
    folder = tmp_path_factory.mktemp("estimates")
    options = {"plain": [], "noiseless": ["--sensor-noise", "0", "--force-noise", "0"], "slow": ["--fs", "2000"]}
    paths = {}
    for name, extra in options.items():
        paths[name] = str(folder / f"{name}.csv")
        assert cli.main(["run", "--periods", "4", "--f-max", "50", "--save", paths[name], *extra]) == 0
    paths["three"] = str(folder / "three.csv")
    assert cli.main(["run", "--periods", "3", "--f-max", "50", "--save", paths["three"]]) == 0
    return paths


@pytest.mark.parametrize(
    ("files", "options", "message"),
    [
        (["plain"], ["--free", "kq"], "--free: 'kq' is not a rig field the fit can choose; one of mass, kyy"),
        (["plain"], ["--free", "kyy,kyy"], "--free must name one or more distinct parameters, got 'kyy,kyy'"),
        (["plain"], ["--free", "sensor_bandwidth", "--set", "sensor_bandwidth=none"],
         "--free sensor_bandwidth: the rig's sensor_bandwidth is 'none' (its stage is off), so the fit has no start "
         "value; give one with --set sensor_bandwidth=X"),
        (["noiseless"], [], "noiseless.csv' has standard errors k_std, c_std that are not all finite and > 0"),
        (["three"], [], "three.csv' averages 3 periods; a fit needs >= 4"),
        (["plain", "slow"], [], "the estimates' controllers run at different fs [2000.0, 4000.0] Hz"),
    ],
)  # fmt: skip
def test_fit_mistakes_the_library_found_after_the_start_are_exit_status_2(capsys, estimates, files, options,
                                                                          message) -> None:  # fmt: skip
    """Were exit status 1, named ``free:``, ``estimates[0]:`` or ``controllers:``."""
    capsys.readouterr()
    status, _, err = run(capsys, "fit", *[estimates[f] for f in files], *options)
    assert status == 2 and message in one_error_line(err)


# -- sweep, rotor and run --two-axis: input mistakes before the work ------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sweep", "--kp", "2000,nan"], "--kp must be finite values, got [nan]"),
        (["sweep", "--vary", "amp_bandwidth=nan"], "--vary amp_bandwidth must be finite values, got [nan]"),
        (["sweep", "--vary", "mass=-1,1"], "--vary mass -1: mass must be a finite number > 0 (kg), got -1.0"),
        (["sweep", "--kp", "2400", "--settle-periods", "-1"], "--settle-periods must be a whole number >= 0, got -1"),
        (["run", "--two-axis", "--kp", "300"], "the two-axis closed loop is unstable"),
        (["run", "--two-axis", "--force-law", "nonlinear"],
         "--two-axis models the linear force law only; the rig's is 'nonlinear' (--force-law or --rig)"),
        (["rotor", "experiment", "--seed", "-1"], "--seed must be a whole number >= 0, got -1"),
        (["paper", "--seed", "-1", "--no-progress"], "--seed must be a whole number >= 0, got -1"),
        (["rotor", "sensitivity", "--speeds", "50000"], "the closed loop at speed 50000 rad/s is unstable"),
        (["rotor", "unbalance", "--speeds", "0,50000"],
         "--speeds must be below the Nyquist rate pi fs = 12566.4 rad/s for unbalance (the controller samples at "
         "4000 Hz), got up to 50000"),
    ],
)  # fmt: skip
def test_mistakes_found_in_the_run_are_now_found_before_it(capsys, tmp_path, monkeypatch, args, message) -> None:
    """Were exit status 1 after the start ("seed must be ...", "x.force_law must be 'linear'", "speeds must be
    below ...", an unstable loop that ``run`` without --two-axis refuses with status 2)."""
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, *args, *([] if args[0] == "paper" else ["--periods", "2"]))  # paper has no periods
    assert status == 2 and message in one_error_line(err)
    assert list(tmp_path.iterdir()) == []


def test_a_rotor_with_a_slow_controller_tabulates_lines_within_its_band(capsys, tmp_path) -> None:
    """Was: rows at 10, 40, 100 and 200 Hz whatever the band: with fs 300 Hz (lines 1-149 Hz) 200 Hz showed the
    149 Hz line; now the table follows the band as ``run``'s does."""
    path = tmp_path / "slow.toml"
    path.write_text("[controller]\nfs = 300.0\n")
    status, out, err = run(capsys, "rotor", "experiment", "--rotor", str(path), "--periods", "2")
    assert status == 0, err
    rows = [line.split()[0] for line in out.splitlines() if "A.x<A.x" in line]
    assert rows == ["1.0", "5.0", "28.0", "149.0"]
    status, out, err = run(capsys, "rotor", "campbell", "--rotor", str(path), "--speeds", "0,10")
    assert status == 0 and "whirling modes below 150 Hz" in out  # was "below 200 Hz": fs/2 is 150 Hz


def test_the_default_run_up_stays_below_the_nyquist_rate_of_a_slow_controller(capsys, tmp_path) -> None:
    """Was: exit 1, "speeds must be below the Nyquist rate pi fs = 502.655 rad/s, got array([10., ..., 600.])"
    (120 numbers) for a 160 Hz controller and no --speeds: the default 10-600 rad/s did not follow fs."""
    path = tmp_path / "slow.toml"
    path.write_text("[controller]\nfs = 160.0\nkp = 1234.0\nki = 0.0\nkd = 7.29\n")
    status, out, err = run(capsys, "rotor", "unbalance", "--rotor", str(path))
    assert status == 0, err
    assert "120 speeds 10-452.389 rad/s" in out  # 90 % of pi * 160 Hz
    status, out, _ = run(capsys, "rotor", "unbalance", "--speeds", "10:600:3")
    assert status == 0 and "3 speeds 10-600 rad/s" in out  # a fast controller keeps the paper's run-up


def test_the_two_axis_figure_records_what_drew_it(capsys, tmp_path) -> None:
    """As the one-axis figure does (version, rig, controller, seed in the PNG's text); it recorded nothing."""
    pytest.importorskip("matplotlib")
    path = tmp_path / "two.png"
    status, _, err = run(capsys, "run", "--two-axis", "--kxy=1e4", "--f-max", "20", "--periods", "2", "--seed", "17",
                         "--figure", str(path))  # fmt: skip
    assert status == 0, err
    png = path.read_bytes()
    assert f"amb_fast {af.__version__}".encode() in png and b'"seed": 17' in png and b'"kxy": 10000.0' in png


# -- outputs that cannot be written are refused before the work -------------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "--save", "afile/e.csv"], "--save: 'afile' is not a directory"),
        (["paper", "--out", "afile/out"], "--out: 'afile' is not a directory"),
        (["run", "--save", "readonly/e.csv"], "--save: the directory 'readonly' is not writable"),
        (["sweep", "--kp", "2000", "--out", "readonly/s.npz"], "--out: the directory 'readonly' is not writable"),
        (["paper", "--out", "readonly"], "--out: the directory 'readonly' is not writable"),
        (["identify", "rec.csv", "--mass", "1", "--out", "taken"], "--out: 'taken/estimate.csv' is a directory, where "
         "a file goes"),
        (["identify", "rec.csv", "--mass", "1", "--out", "taken", "--overwrite"], "--out: 'taken/estimate.csv' is a "
         "directory"),
        (["identify", "estimate.csv", "--mass", "1", "--out", ".", "--overwrite"], "--out: 'estimate.csv' is the "
         "recording itself; choose another --out"),
    ],
)  # fmt: skip
def test_outputs_that_cannot_be_written_are_refused_first(capsys, tmp_path, monkeypatch, args, message) -> None:
    """Were: "the directory 'afile' does not exist" (it is a file); a read-only directory failed at the write after
    the run (exit status 1); a directory in the way of identify's estimate.csv was "overwritten" (exit 1)."""
    import os

    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("a file")
    (tmp_path / "readonly").mkdir()
    (tmp_path / "taken" / "estimate.csv").mkdir(parents=True)
    (tmp_path / "rec.csv").write_text("time,force,displacement\n")
    (tmp_path / "estimate.csv").write_text("time,force,displacement\n")  # a recording that --out . would replace
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path).name != "readonly" and real_access(path, mode))
    before = sorted(tmp_path.rglob("*"))
    status, _, err = run(capsys, *args)
    assert status == 2 and message in one_error_line(err)
    assert sorted(tmp_path.rglob("*")) == before


# -- defaults that follow the options given ---------------------------------------------------------------------


def test_the_default_design_step_follows_a_narrow_band(capsys) -> None:
    """Was: ``--band 0.5:0.9`` with the 1 Hz default step designed on one frequency (0.5 Hz) without a word."""
    status, out, err = run(capsys, "design", "--stiffness", "6e4", "--band", "0.5:0.9")
    assert status == 0, err
    assert "on 0.5-0.9 Hz (21 frequencies)" in out
    status, out, _ = run(capsys, "design", "--stiffness", "6e4")
    assert status == 0 and "on 20-150 Hz (131 frequencies)" in out  # a wide band keeps its 1 Hz step


def test_a_default_band_above_nyquist_is_not_blamed_on_band(capsys) -> None:
    """Was: "--band must lie below fs/2 = 15 Hz ..., got 20:150" for ``design --fs 30``: no --band was given."""
    status, _, err = run(capsys, "design", "--stiffness", "6e4", "--fs", "30")
    assert status == 2
    assert one_error_line(err) == ("amb-fast: error: the default band 20:150 Hz lies above fs/2 = 15 Hz (the "
                                   "controller samples at 30 Hz): give a --band below it")  # fmt: skip


def test_a_sweeps_csv_says_the_library_does_not_read_it(capsys, tmp_path) -> None:
    """The one output the library cannot read back (a table for other tools, as documented): the command says so
    where it writes it, and ``load_sweep`` refuses it with a clear error."""
    path = tmp_path / "s.csv"
    status, out, err = run(capsys, "sweep", "--kp", "2000", "--f-max", "20", "--periods", "2", "--no-progress", "--out",
                           str(path))  # fmt: skip
    assert status == 0, err
    assert f"wrote {path} (a table for other tools: amb_fast.load_sweep reads .nc and .npz)" in out
    with pytest.raises(ValueError, match=r"a sweep's \.csv is for other tools"):
        af.load_sweep(path)
