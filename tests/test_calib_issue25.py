"""Issue 25, cases 1, 10, 12 and the file parts of 15: the fit uses what each estimate file records, the
design finds a feasible start itself, a PID composes like any controller, fitted rigs and designed
controllers go to files that the commands chain through, and file errors name the file."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import amb_fast as af
from amb_fast.cli import main


def load_rig(path: Path) -> af.Rig:
    from amb_fast._toml import load_rig

    return load_rig(path)


def save_rig(rig: af.Rig, path: Path) -> Path:
    from amb_fast._toml import save_rig

    return save_rig(rig, path)


def save_controller(controller: object, path: Path) -> Path:
    from amb_fast.controllers import save_controller

    return save_controller(controller, path)


DOCS = Path(__file__).resolve().parents[1] / "docs"
PID_B = replace(af.PID.paper(), kp=3000.0, kd=2.2)  # the second gain set of the issue: --kp 3000 --kd 2.2
FREE = ["kyy", "kiy", "amp_bandwidth", "mass_loading"]  # amb-fast fit's default
BAND = np.arange(20.0, 151.0, 1.0)


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Two estimates as `amb-fast run --save a.csv` and `amb-fast run --kp 3000 --kd 2.2 --save b.csv` write them."""
    folder = tmp_path_factory.mktemp("estimates")
    a, b = folder / "a.csv", folder / "b.csv"
    assert main(["run", "--save", str(a)]) == 0
    assert main(["run", "--kp", "3000", "--kd", "2.2", "--save", str(b)]) == 0
    return a, b


# ------------------------------------------------------------------------------------------- case 1: fit
def test_fit_rig_takes_the_controllers_the_estimates_record(saved: tuple[Path, Path]) -> None:
    estimates = [af.load_estimate(p) for p in saved]
    fit = af.fit_rig(estimates, af.Rig.paper(), free=FREE)  # no controllers: the recorded ones
    assert fit.fits and fit.chi2 / fit.dof < 1.3
    truth = af.Rig.paper()
    assert abs(fit.values["amp_bandwidth"] - truth.amp_bandwidth) < 4 * fit.std["amp_bandwidth"]
    assert "PID(kp=3000.0" in fit.inputs[1] and "recorded in the estimate" in fit.inputs[1]
    assert "recorded in the estimate" in fit.report()
    # The same controllers given explicitly (a PID or its Controller) agree with the records: the same fit.
    given = af.fit_rig(estimates, af.Rig.paper(), [af.PID.paper().to_controller(), PID_B], free=FREE)
    assert given.values == pytest.approx(fit.values, rel=1e-9)
    # A controller that contradicts an estimate's record is an error naming both.
    with pytest.raises(
        ValueError, match=r"controllers\[1\] is PID\(kp=2400.0.*estimates\[1\] was measured with PID\(kp=3000"
    ):
        af.fit_rig(estimates, af.Rig.paper(), [af.PID.paper(), af.PID.paper()], free=FREE)


def test_fit_rig_without_a_record_needs_the_controllers() -> None:
    estimate = af.run_experiment(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=100.0), seed=3)
    plain = replace(estimate, meta={})  # as identified from a recording: no controller recorded
    with pytest.raises(ValueError, match=r"estimates\[0\] record no controller.*give controllers="):
        af.fit_rig(plain, af.Rig.paper(), free=["kyy"])
    fit = af.fit_rig(plain, af.Rig.paper(), af.PID.paper(), free=["kyy"])
    assert "given (the estimate records none)" in fit.inputs[0]


def test_cli_fit_uses_each_file_s_controller_and_periods(saved: tuple[Path, Path], tmp_path: Path, capsys) -> None:  # noqa: ANN001
    # Before: PID.paper() for both files, chi2/dof 74 and amp_bandwidth 542 Hz (truth 3000), a MISFIT.
    out_file = tmp_path / "fit.toml"
    assert main(["fit", *map(str, saved), "--out", str(out_file)]) == 0
    out = capsys.readouterr().out
    assert out.count("controller recorded in the file; 10 periods averaged (recorded in the file)") == 2
    ratio = float(re.search(r"chi2/dof = ([0-9.]+)", out).group(1))  # type: ignore[union-attr]
    assert ratio < 1.3 and "consistent with the data" in out
    rig = load_rig(out_file)
    assert rig.amp_bandwidth == pytest.approx(3000.0, rel=0.01)


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (["--periods", "20"], ["--periods 20", "a.csv", "10 periods"]),
        (["--kp", "2400"], ["--kp 2400", "b.csv", "kp = 3000"]),
        (["--kd", "3,2.5"], ["--kd 2.5", "b.csv", "kd = 2.2"]),
        (["--fs", "5000"], ["--fs 5000", "a.csv", "fs = 4000"]),
    ],
)
def test_cli_fit_option_that_contradicts_a_file_is_an_error(
    saved: tuple[Path, Path],
    capsys,
    options: list[str],
    expected: list[str],  # noqa: ANN001
) -> None:
    assert main(["fit", *map(str, saved), *options]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amb-fast: error:") and len(err.splitlines()) == 1
    for text in expected:
        assert text in err


def test_cli_fit_accepts_options_that_agree_with_the_files(saved: tuple[Path, Path], capsys) -> None:  # noqa: ANN001
    assert main(["fit", *map(str, saved), "--kp", "2400,3000", "--kd", "3,2.2", "--free", "kyy,amp_bandwidth"]) == 0
    assert "consistent with the data" in capsys.readouterr().out


def test_cli_fit_controller_file_that_contradicts_a_file(saved: tuple[Path, Path], tmp_path: Path, capsys) -> None:  # noqa: ANN001
    path = save_controller(af.PID.paper() * af.notch(700.0), tmp_path / "c.toml")
    assert main(["fit", *map(str, saved), "--controller", str(path)]) == 2
    err = capsys.readouterr().err
    assert "--controller" in err and "c.toml" in err and "a.csv" in err and "notch" in err


# ---------------------------------------------------------------------------------------- case 10: design
def test_design_below_the_start_s_sensitivity_peak_finds_a_feasible_start(monkeypatch: pytest.MonkeyPatch) -> None:
    from amb_fast.calibration import _design

    calls = []  # sensitivity evaluations of the search
    monkeypatch.setattr(_design, "sensitivity", lambda *a, **k: calls.append(1) or af.sensitivity(*a, **k))
    start = af.PID.paper()
    assert af.stability_margin(af.Rig.paper(), start).peak == pytest.approx(4.84, abs=0.01)
    # Before: 203 to 2,615 sensitivity evaluations (0.3-6 s) as the rig's mass changed at 1e-15, SLSQP never
    # converging on the peak's kinks. The same design, in a bounded work, for each of these masses.
    designs = []
    for seed in (0, 1, 2):
        mass = af.Rig.paper().mass * (1 + 1e-15 * np.random.default_rng(seed).standard_normal())
        calls.clear()
        d = af.design_controller(replace(af.Rig.paper(), mass=mass), start, freq=BAND, stiffness=6e4, damping=150.0,
                                 max_sensitivity=2.3)  # fmt: skip
        assert len(calls) <= 300
        assert d.feasible and d.stable and d.constrained
        assert d.peak_sensitivity <= 2.3
        assert d.start_peak == pytest.approx(4.84, abs=0.01)
        assert np.isfinite(d.k_miss) and np.isfinite(d.c_miss)
        text = d.report()
        assert re.search(r"start controller's sensitivity peak 4\.8\d+ is over the limit", text)
        assert "best feasible design" in text
        designs.append(d)
    for d in designs[1:]:
        assert d.params == pytest.approx(designs[0].params, rel=1e-6)


def test_design_with_no_feasible_point_says_so_with_the_best_peak() -> None:
    with pytest.warns(UserWarning, match=r"no values of kp, kd make the loop stable with \|S\| <= 1.1; the lowest"):
        d = af.design_controller(af.Rig.paper(), af.PID.paper(), freq=BAND, stiffness=6e4, max_sensitivity=1.1)
    assert not d.feasible and d.stable and d.peak_sensitivity > 1.1
    assert "NO FEASIBLE DESIGN" in d.report() and f"{d.peak_sensitivity:.3f}" in d.report()


def test_design_keeps_a_free_block_frequency_below_nyquist() -> None:
    # Before: ValueError "freq must be below the Nyquist frequency 2000.0 Hz, got 8799.6".
    start = af.PID.paper() * af.notch(700.0)
    d = af.design_controller(af.Rig.paper(), start, freq=BAND, stiffness=6e4, damping=150.0,
                             free=["kp", "kd", "notch_freq"])  # fmt: skip
    assert 0 < d.params["notch_freq"] < 2000.0
    assert d.stable


def test_design_with_one_target_prints_no_nan(capsys) -> None:  # noqa: ANN001
    d = af.design_controller(af.Rig.paper(), af.PID.paper(), freq=BAND, stiffness=6e4)
    assert "nan" not in d.report().lower() and "damping" not in d.misses_text()
    assert "nan" not in str(d).lower() and "stiffness misses by" in repr(d) and len(repr(d)) < 300
    assert main(["design", "--stiffness", "6e4"]) == 0
    assert "nan" not in capsys.readouterr().out.lower()


# --------------------------------------------------------------------------------- case 12: composition
def test_pid_composes_like_any_controller() -> None:
    pid, n = af.PID.paper(), af.notch(700.0)
    f = np.geomspace(1.0, 1999.0, 200)
    reference = (pid.to_controller() * n).response(f)
    for c in (pid * n, n * pid, af.series(pid, n), af.series(n, pid)):
        assert isinstance(c, af.Controller)
        np.testing.assert_allclose(c.response(f), reference, rtol=1e-12, atol=0)
    parallel = (pid.to_controller() + n).response(f)
    for c in (pid + n, n + pid, af.parallel(pid, n)):
        np.testing.assert_allclose(c.response(f), parallel, rtol=1e-12, atol=0)
    np.testing.assert_allclose((2.0 * pid).response(f), 2.0 * pid.to_controller().response(f), rtol=1e-15, atol=0)
    np.testing.assert_allclose((pid * pid).response(f), pid.to_controller().response(f) ** 2, rtol=1e-12, atol=0)
    assert (pid * n).params["kp"] == 2400.0 and (pid * n).params["notch_freq"] == 700.0
    with pytest.raises(ValueError, match="blocks must be Controllers or PIDs"):
        af.series(pid, "notch")


# ----------------------------------------------------------------------------------------- case 12: files
@pytest.mark.parametrize(
    "controller",
    [
        af.PID.paper(),
        af.PID(kp=2000.0, ki=1e4, kd=2.0),  # no derivative filter, one sample of delay
        af.PID.paper().to_controller() * af.notch(700.0) * af.low_pass(1500.0, order=2) * af.lead_lag() * af.gain(1.5),
        af.PID.paper().to_controller() + af.notch(700.0),  # no named blocks: written as one transfer function
        af.second_order(100.0, 200.0) * af.Controller.from_tf([0.5, 0.2], [1.0, -0.3], fs=4000.0),
    ],
)
def test_saved_controller_loads_to_the_same_response(controller: object, tmp_path: Path) -> None:
    path = save_controller(controller, tmp_path / "c.toml")
    back = af.load_controller(path)
    c = controller if isinstance(controller, af.Controller) else controller.to_controller()  # type: ignore[attr-defined]
    f = np.geomspace(1.0, 1999.0, 100)
    np.testing.assert_allclose(back.response(f), c.response(f), rtol=1e-9, atol=0)
    assert back.delay == c.delay and back.fs == c.fs


def test_rig_file_round_trip_and_errors(tmp_path: Path) -> None:
    rig = replace(af.Rig.paper(), kyy=-51234.5, eddy_bandwidth=None, dead_time=1e-4)
    path = save_rig(rig, tmp_path / "rig.toml")
    assert load_rig(path) == rig
    partial = tmp_path / "partial.toml"
    partial.write_text("kyy = -50000.0\n")
    assert load_rig(partial) == replace(af.Rig.paper(), kyy=-50000.0)
    (tmp_path / "typo.toml").write_text("kyy = -5e4\nmas = 1.0\n")
    with pytest.raises(ValueError, match=r"rig file '.*typo.toml': unknown key\(s\) mas"):
        load_rig(tmp_path / "typo.toml")
    (tmp_path / "neg.toml").write_text("mass = -1.0\n")
    with pytest.raises(ValueError, match=r"rig file '.*neg.toml': mass"):
        load_rig(tmp_path / "neg.toml")


def test_fit_design_run_chain_through_files(saved: tuple[Path, Path], tmp_path: Path, capsys) -> None:  # noqa: ANN001
    fit_file, ctrl_file = tmp_path / "fit.toml", tmp_path / "ctrl.toml"
    assert main(["fit", *map(str, saved), "--out", str(fit_file)]) == 0
    assert main(["design", "--rig", str(fit_file), "--stiffness", "6e4", "--damping", "150",
                 "--out", str(ctrl_file)]) == 0  # fmt: skip
    capsys.readouterr()
    designed = af.load_controller(ctrl_file)
    fitted = load_rig(fit_file)
    expected = af.design_controller(fitted, af.PID.paper(), freq=BAND, stiffness=6e4, damping=150.0)
    np.testing.assert_allclose(designed.response(BAND), expected.controller.to_controller().response(BAND), rtol=1e-12)
    assert main(["run", "--rig", str(fit_file), "--controller", str(ctrl_file)]) == 0
    assert "stability margin" in capsys.readouterr().out
    # design --controller FILE starts from the file's controller
    assert main(["design", "--controller", str(ctrl_file), "--stiffness", "6e4"]) == 0
    assert "kp" in capsys.readouterr().out


def test_design_save_is_loadable(tmp_path: Path) -> None:
    d = af.design_controller(af.Rig.paper(), af.PID.paper() * af.notch(700.0), freq=BAND, stiffness=6e4, damping=150.0)
    back = af.load_controller(d.save(tmp_path / "d.toml"))
    np.testing.assert_allclose(back.response(BAND), d.controller.response(BAND), rtol=1e-12, atol=0)
    assert back.params["notch_freq"] == 700.0


# --------------------------------------------------------------------------------- case 15: file errors
@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_file_syntax_errors_name_the_file(tmp_path: Path, suffix: str, capsys) -> None:  # noqa: ANN001
    bad = tmp_path / f"bad{suffix}"
    bad.write_text("fs = [\n" if suffix == ".toml" else '{"fs": 4000,')
    with pytest.raises(ValueError, match=rf"controller file '.*bad{suffix}': {suffix[1:].upper()} syntax error"):
        af.load_controller(bad)
    with pytest.raises(ValueError, match=rf"rig file '.*bad{suffix}': {suffix[1:].upper()} syntax error"):
        load_rig(bad)
    for option in ("--controller", "--rig"):
        assert main(["run", option, str(bad)]) == 2
        err = capsys.readouterr().err
        assert f"bad{suffix}" in err and "syntax error" in err and len(err.strip().splitlines()) == 1


def test_missing_files_are_named(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"controller file '.*none.toml' does not exist"):
        af.load_controller(tmp_path / "none.toml")
    with pytest.raises(ValueError, match=r"rig file '.*none.toml' does not exist"):
        load_rig(tmp_path / "none.toml")


def test_the_full_controller_file_of_the_docs_is_stable_on_the_paper_rig(tmp_path: Path) -> None:
    page = (DOCS / "controllers.md").read_text()
    shown = re.search(r"```toml\n(fs = 4000.0 .*?)```", page, re.S).group(1)  # type: ignore[union-attr]
    tested = re.search(r'```\{testsetup\}.*?write_text\("""\\\n(.*?)"""\)', page, re.S).group(1)  # type: ignore[union-attr]
    assert tested == shown  # the page's doctest loads the file it shows
    path = tmp_path / "full.toml"
    path.write_text(shown)
    c = af.load_controller(path)
    assert c.order == 9
    margin = af.stability_margin(af.Rig.paper(), c)
    assert margin.stable and margin.peak < 4.0
    assert np.max(np.abs(af.closed_loop_poles(af.Rig.paper(), c))) < 1.0


def test_fit_without_degrees_of_freedom_prints_no_nan_and_no_misfit() -> None:
    # Before: "chi2/dof = nan), p = nan" and "MISFIT", with a misfit warning, for a fit that cannot be tested.
    one_line = af.run_experiment(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f_max=1.0), seed=1)
    fit = af.fit_rig(one_line, af.Rig.paper(), free=["kyy", "kiy"])
    assert fit.dof == 0
    text = fit.report()
    assert "nan" not in text and "MISFIT" not in text and "not testable" in text
