"""The paper's study: defaults, claim checks that can fail, and the amb-fast command end to end."""

from __future__ import annotations

import struct
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

import amb_fast as af
from amb_fast import claims
from amb_fast._study import paper_study


@pytest.fixture(scope="module")
def study():
    return paper_study()


@pytest.fixture(scope="module")
def noise_free_study():
    return paper_study(rig=replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0))


# Observation 3.2.1-f is a 0.01 % change of k near resonance across the Ki family, about the standard
# error the noise leaves there: it holds on the noise-free rig and on 17 of 20 noise seeds (2026-2045,
# the current noise streams and the steady start; 2026 among them, 14 of 20 when settling from rest).
# Requiring it on a chosen seed would only hide that it is noise-sensitive.
NOISE_SENSITIVE = {"3.2.1-f"}


def test_paper_baseline_is_stable_for_each_gain_from_two_thirds_to_one_and_a_half() -> None:
    rig, pid = af.Rig.paper(), af.PID.paper()
    for name in ("kp", "ki", "kd"):
        values = getattr(pid, name) * np.linspace(0.67, 1.5, 84)
        assert af._linear.spectral_radius(rig, pid, **{name: values}).max() < 1, name
    assert rig.kiy * pid.kp * 0.67 + rig.kyy > 0  # positive net stiffness at the softest kp


def test_every_claim_holds_on_the_noise_free_paper_study(noise_free_study) -> None:
    results = noise_free_study.claims()
    assert len(results) == 14
    assert [c.id for c in results if not c.reproduced] == []


def test_every_claim_but_the_noise_sensitive_one_holds_on_the_paper_study(study) -> None:
    results = study.claims()
    assert len(results) == 14
    assert {c.id for c in results if not c.reproduced} <= NOISE_SENSITIVE


def reversed_family(data: dict) -> dict:
    return {key: value[::-1] for key, value in data.items()}


FAMILY_CHECKS = {
    "ki_raises_resonance_peak": ("ki", lambda d: (d["gains"], 1 / d["H"])),
    "ki_lowers_low_frequency_damping": ("ki", lambda d: (d["gains"], d["c"])),
    "ki_attenuates_low_frequency_response": ("ki", lambda d: (d["gains"], 1 / d["H"])),
    "ki_raises_low_frequency_stiffness": ("ki", lambda d: (d["gains"], d["k"])),
    "ki_raises_stiffness_near_resonance_marginally": ("ki", lambda d: (d["gains"], d["k"], d["H"])),
    "kd_reduces_resonance_peak": ("kd", lambda d: (d["gains"], d["c"], d["H"])),
    "kp_raises_stiffness_and_natural_frequency": ("kp", lambda d: (d["gains"], d["k"], d["H"])),
    "kp_raises_low_frequency_damping": ("kp", lambda d: (d["gains"], d["c"], d["H"])),
}


@pytest.mark.parametrize("check", sorted(FAMILY_CHECKS))
def test_family_checks_fail_when_the_trend_is_reversed(study, noise_free_study, check) -> None:
    if check == "ki_raises_stiffness_near_resonance_marginally":  # 3.2.1-f: see NOISE_SENSITIVE
        study = noise_free_study
    family, arguments = FAMILY_CHECKS[check]
    data = study.family_data()[family]
    function = getattr(claims, check)
    assert function(study.freq, *arguments(data)).reproduced
    assert not function(study.freq, *arguments(reversed_family(data))).reproduced


def test_frequency_band_checks_fail_without_their_pattern(study) -> None:
    f, data = study.freq, study.family_data()
    ki, kd = data["ki"], data["kd"]
    # Ki acting at high frequency too.
    receptance = np.abs(1 / ki["H"]) * np.array([1.0, 1.1, 1.2])[:, None]
    assert claims.ki_acts_at_low_frequency_only(f, ki["gains"], np.abs(1 / ki["H"])).reproduced
    assert not claims.ki_acts_at_low_frequency_only(f, ki["gains"], receptance).reproduced
    # Kd moving the low-frequency stiffness as much as the high.
    assert claims.kd_changes_stiffness_at_high_frequency_only(f, kd["gains"], kd["k"]).reproduced
    shifted = kd["k"] * np.array([0.8, 1.0, 1.2])[:, None]
    assert not claims.kd_changes_stiffness_at_high_frequency_only(f, kd["gains"], shifted).reproduced
    # A gain that moves nothing.
    still = {n: (np.repeat(d["k"][1:2], 3, 0), np.repeat(d["c"][1:2], 3, 0)) for n, d in data.items()}
    assert not claims.every_gain_moves_stiffness_and_damping(still).reproduced


def test_section_3_1_checks_fail_on_data_that_contradict_them(study) -> None:
    f, e = study.freq, study.estimate
    assert not claims.effective_frequency_dependent_and_smooth(f, np.full(f.size, 6e4), study.c_eff).reproduced
    rough = study.k_eff * (1 + 0.05 * (-1) ** np.arange(f.size))
    assert not claims.effective_frequency_dependent_and_smooth(f, rough, study.c_eff).reproduced
    assert not claims.damping_actual_matches_effective(f, 1.5 * study.c_eff, study.c_eff).reproduced
    assert not claims.stiffness_agrees_low_diverges_high(f, study.k_eff, study.k_eff).reproduced  # no divergence
    assert not claims.stiffness_agrees_low_diverges_high(f, 1.3 * e.k_smooth, study.k_eff).reproduced  # no agreement


def test_natural_frequency_of_a_single_degree_of_freedom() -> None:
    f = np.arange(1.0, 101.0)
    w = 2 * np.pi * f
    m, k, c = 1.0, (2 * np.pi * 37.3) ** 2, 20.0
    assert claims.natural_frequency(f, k - m * w**2 + 1j * c * w) == pytest.approx(37.3, rel=1e-9)


def run_cli(*args: str, cwd) -> subprocess.CompletedProcess:  # noqa: ANN001
    return subprocess.run([sys.executable, "-m", "amb_fast", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300)  # fmt: skip


def png_size(path) -> tuple[int, int]:  # noqa: ANN001
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    return struct.unpack(">II", data[16:24])


def test_paper_command_end_to_end(tmp_path) -> None:
    done = run_cli("paper", "--out", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "out"
    for name in (
        "fig4_effective.png", "fig5_actual.png", "fig6_ki.png", "fig7_ki_zoom.png", "fig8_kd.png",
        "fig9_kd_zoom.png", "fig10_kp.png",
    ):  # fmt: skip
        width, height = png_size(out / name)
        assert width >= 600 and height >= 500 and (out / name).stat().st_size > 20_000, name
    report = (out / "claims.md").read_text()
    results = paper_study().claims()
    for claim in results:
        assert f"| {claim.id} |" in report
    reproduced = sum(c.reproduced for c in results)
    assert reproduced >= 14 - len(NOISE_SENSITIVE)
    assert f"{reproduced} of 14 observations reproduced" in report
    assert f"{reproduced} of 14 observations reproduced" in done.stdout
    actual = np.loadtxt(out / "actual.csv", delimiter=",", skiprows=1)
    assert actual.shape == (200, 9)
    for gain in ("ki", "kd", "kp"):
        assert (out / f"family_{gain}.csv").exists()
        assert af.load_sweep(next(out.glob(f"family_{gain}.n*"))).status.tolist() == ["ok"] * 3
    assert "[4/4]" in done.stderr


def test_run_sweep_and_identify_commands(tmp_path) -> None:
    done = run_cli("run", "--kp", "2600", "--amp-bandwidth", "none", "--periods", "4", "--save", "est.csv",
                   "--figure", "est.png", cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "ISO 14839-3 zone" in done.stdout and "natural frequency" in done.stdout
    saved = af.load_estimate(tmp_path / "est.csv")
    assert saved.freq.size == 200 and saved.meta["controller"]["kp"] == 2600.0 and saved.meta["seed"] == 2026
    png_size(tmp_path / "est.png")

    done = run_cli("sweep", "--kp", "2000:2800:3", "--kd", "2,4", "--periods", "3", "--out", "s.npz", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "6 points: 6 ok" in done.stdout
    assert af.load_sweep(tmp_path / "s.npz").shape == (3, 2)

    rig, pid = af.Rig.paper(), af.PID.paper()
    ms = af.schroeder_multisine(f_max=100.0)
    af.simulate(replace(rig, force_coupling_tau=None), pid, np.tile(ms.samples, 6), seed=3).save(tmp_path / "rec.csv")
    done = run_cli("identify", "rec.csv", "--settle-periods", "2", "--out", "ident", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "100 lines from 1 to 100 Hz" in done.stdout
    saved = af.load_estimate(tmp_path / "ident" / "estimate.csv")
    assert saved.freq.size == 100 and saved.meta["source"] == "identify" and saved.meta["settle_periods"] == 2
    png_size(tmp_path / "ident" / "estimate.png")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "--mass", "-1"], "mass must be a finite number > 0"),
        (["run", "--kp", "300"], "closed loop is unstable"),
        (["run", "--f0", "3"], "--fs/--f0 must be a whole number"),
        (["identify", "missing.csv"], "the recording 'missing.csv' does not exist"),
        (["sweep", "--periods", "3"], "give at least one of --kp, --ki, --kd"),
        (["sweep", "--kp", "2000", "--out", "x.txt"], "--out must end in .nc, .npz, .csv, got 'x.txt'"),
    ],
)
def test_user_mistakes_get_one_line_errors(tmp_path, args, message) -> None:
    done = run_cli(*args, cwd=tmp_path)
    assert done.returncode == 2
    assert message in done.stderr
    assert "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_bad_option_values_are_refused_by_the_parser(tmp_path) -> None:
    done = run_cli("run", "--kp", "fast", cwd=tmp_path)
    assert done.returncode == 2 and "expected a number or 'none'" in done.stderr and "Traceback" not in done.stderr
    help_text = run_cli("run", "--help", cwd=tmp_path).stdout
    for unit in ("A/m", "A/(m s)", "A s/m", "Hz", "kg", "m rms"):
        assert unit in help_text


def test_figures_are_reachable_from_the_package(study) -> None:
    pytest.importorskip("matplotlib")
    fig = af.plot_actual(study.estimate)
    assert [ax.get_ylabel() for ax in fig.axes] == ["stiffness k (kN/m)", "damping c (N s/m)"]
    assert fig.axes[-1].get_xlabel() == "frequency (Hz)" and fig.axes[0].get_xscale() == "log"
    fig = af.plot_family(study.families["kd"], "kd")
    assert len(fig.axes[0].get_legend().get_texts()) == 3
    with pytest.raises(AttributeError):
        af.plot_nothing  # noqa: B018


@pytest.mark.parametrize("suffix", [".nc", ".npz"])
def test_paper_names_the_family_files_it_writes(tmp_path, capsys, monkeypatch, suffix) -> None:
    """Without xarray the families are written as .npz; the closing line said ".csv/.nc" all the same."""
    from types import SimpleNamespace

    from amb_fast import paper

    claim = claims.Claim("4", "4", "statement", "metric", "measured", True)
    monkeypatch.setattr(paper, "paper_study", lambda **kw: SimpleNamespace(claims=lambda: [claim]))
    monkeypatch.setattr(paper, "write_curves", lambda study, out: [])
    monkeypatch.setattr(paper, "write_figures", lambda study, out: [])
    monkeypatch.setattr(paper, "report", lambda study, table: table)
    monkeypatch.setattr(paper, "_family_suffix", lambda: suffix)
    paper.write_paper(tmp_path, progress=False)
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.endswith("family_ki.csv/" + suffix + ", family_kd.csv/" + suffix + ", family_kp.csv/" + suffix)
    assert set(paper.output_names()) >= {f"family_{g}{suffix}" for g in ("ki", "kd", "kp")}
