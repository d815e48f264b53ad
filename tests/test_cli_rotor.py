"""amb-fast rotor: its three steps on the example rotor and on a rotor file; bad files and options are one
line with exit status 2."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
from cli_helpers import one_error_line, run


def test_campbell_sensitivity_and_unbalance_of_the_example(capsys, tmp_path) -> None:  # noqa: ANN001
    status, out, _ = run(capsys, "rotor", "campbell", "--speeds", "0:3000:4", "--figure", str(tmp_path / "c.png"))
    assert status == 0 and "stable at every speed given" in out and (tmp_path / "c.png").stat().st_size > 0
    expected = af.campbell(af.RotorRig.example(), af.RotorRig.example_controller(), [0.0])
    whirling = (expected.whirl[0] != 0) & (expected.damping[0] < 0.9)
    assert f"{min(np.round(expected.frequency[0][whirling], 1))} Hz" in out  # the parallel mode, 20.2 Hz
    status, out, _ = run(capsys, "rotor", "sensitivity", "--periods", "4")
    assert status == 0 and "A.x" in out and "zone" in out and out.count(" A\n") >= 4
    status, out, _ = run(capsys, "rotor", "unbalance", "--speeds", "10:600:60", "--unbalance", "1e-4,0.1,0")
    assert status == 0 and "A.x:" in out and "rev/min" in out


def test_a_rotor_file_changes_the_rotor(capsys, tmp_path) -> None:  # noqa: ANN001
    path = tmp_path / "rotor.toml"
    path.write_text("[rotor]\nmass = 12.0\nbearings = [-0.25, 0.25]\n[axes]\namp_bandwidth = 2500.0\n"
                    "[controller]\nkd = 12.0\n")  # fmt: skip
    rig, pid = af.system._file.load_rotor(path)
    assert rig.rotor.mass == 12.0 and rig.rotor.bearings == (-0.25, 0.25) and rig.axes[2].amp_bandwidth == 2500.0
    assert pid.kd == 12.0 and pid.kp == af.RotorRig.example_controller().kp
    status, out, _ = run(capsys, "rotor", "campbell", "--rotor", str(path), "--speeds", "0,1000")
    assert status == 0 and "Campbell" in out


@pytest.mark.parametrize(
    ("text", "message"),
    [("[rotor]\nmas = 3.0\n", "unknown key 'mas' in [rotor]"), ("[wheel]\n", "unknown section [wheel]"),
     ("[rotor]\npolar_inertia = 5.0\n", "polar_inertia must be within"), ("[rotor\n", "TOML syntax error")],
)  # fmt: skip
def test_bad_rotor_files_are_one_line_errors(capsys, tmp_path, text: str, message: str) -> None:  # noqa: ANN001
    path = tmp_path / "bad.toml"
    path.write_text(text)
    status, _, err = run(capsys, "rotor", "campbell", "--rotor", str(path))
    assert (
        status == 2 and message in err and err.startswith("amb-fast: error: rotor file") and len(err.splitlines()) <= 2
    )


def test_bad_options(capsys) -> None:  # noqa: ANN001
    status, _, err = run(capsys, "rotor", "unbalance", "--unbalance", "1e-4,0.1")
    assert status == 2 and "--unbalance must be 'm_e,z,phase'" in err
    status, _, err = run(capsys, "rotor", "sensitivity", "--figure", "s.png")
    assert status == 2 and "--figure goes with experiment, campbell and unbalance" in err


def test_the_experiment_step_prints_the_bearings_coefficients(capsys, tmp_path) -> None:  # noqa: ANN001
    """`amb-fast rotor experiment` (new): the shakers' actual coefficients or, with --exciter amb, the process, at
    the rotor's speed; the estimate saved and its figure written."""
    status, out, _ = run(capsys, "rotor", "experiment", "--periods", "4", "--speeds", "1000",
                         "--save", str(tmp_path / "e.npz"), "--figure", str(tmp_path / "e.png"))  # fmt: skip
    assert status == 0 and "excited by shakers at the bearing planes: 10 N rms" in out
    rig, pid = af.RotorRig.example(speed=1000.0), af.RotorRig.example_controller()
    expected = af.run_experiment(rig, pid, af.schroeder_multisine(rms=10.0), periods=4, seed=1)
    saved = af.load_estimate(tmp_path / "e.npz")
    np.testing.assert_array_equal(saved.k, expected.k)
    row = next(line for line in out.splitlines() if line.strip().startswith("40.0  A.x<B.x"))
    assert float(row.split()[2]) == pytest.approx(expected.k[39, 0, 2], rel=1e-5)
    assert (tmp_path / "e.png").stat().st_size > 0
    status, out, _ = run(capsys, "rotor", "experiment", "--periods", "4", "--exciter", "amb")
    assert status == 0 and "excited by the bearings (current commands): 1 A rms" in out and "process k" in out


@pytest.mark.parametrize(
    ("options", "message"),
    [(["campbell", "--exciter", "amb"], "--exciter goes with experiment, not campbell"),
     (["experiment", "--rms", "-1"], "--rms must be a finite amplitude > 0 (N rms), got -1"),
     (["experiment", "--save", "e.xlsx"], "--save must end in .nc, .npz, .csv, got 'e.xlsx'"),
     (["sensitivity", "--save", "e.npz"], "--save goes with experiment, not sensitivity")],
)  # fmt: skip
def test_the_experiment_steps_options_are_checked_first(capsys, options, message) -> None:  # noqa: ANN001
    status, _, err = run(capsys, "rotor", *options)
    assert status == 2 and message in err and "Traceback" not in err


def test_a_nan_unbalance_is_an_input_mistake(capsys) -> None:  # noqa: ANN001
    """It was found in the run (exit status 1) and named ``unbalance[0][1]``, not the option."""
    status, _, err = run(capsys, "rotor", "unbalance", "--unbalance", "1e-4,nan,0")
    assert status == 2
    assert one_error_line(err) == ("amb-fast: error: --unbalance must be finite numbers 'm_e,z,phase' (kg m, m, rad), "
                                   "got '1e-4,nan,0'")  # fmt: skip
