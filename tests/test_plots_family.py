"""plot_family for any sweep axis and grid, damping axes that show the band that matters, log frequency
axes and units on every figure (issue 25, case 14)."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af
import amb_fast.two_axis as ta

pytest.importorskip("matplotlib")

SPHS = af.schroeder_multisine()


@pytest.fixture(autouse=True)
def close_figures():  # noqa: ANN201 - pyplot keeps every figure open (and warns past 20) until closed
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


def labels(ax) -> list[str]:  # noqa: ANN001
    return [text.get_text() for text in ax.get_legend().get_texts()]


@pytest.fixture(scope="module")
def notch_sweep() -> af.SweepResult:
    controller = af.PID.paper().to_controller() * af.notch(700.0)
    return af.sweep(af.Rig.paper(), controller, SPHS, notch_freq=[600.0, 700.0, 800.0], periods=2, seed=1,
                    progress=False)  # fmt: skip


@pytest.fixture(scope="module")
def kd_family() -> af.SweepResult:
    return af.sweep(af.Rig.paper(), af.PID.paper(), SPHS, kd=[1.5, 2.0, 3.0], periods=2, seed=1, progress=False)


def test_family_of_a_controller_block_parameter(notch_sweep) -> None:
    fig = af.plot_family(notch_sweep, "notch_freq")
    assert labels(fig.axes[0]) == ["notch_freq = 600 Hz", "notch_freq = 700 Hz", "notch_freq = 800 Hz"]
    assert fig.axes[0].get_title() == "Varying notch_freq"
    assert af.plot_family(notch_sweep).axes[0].get_title() == "Varying notch_freq"  # the only axis by default


def test_family_of_a_rig_field() -> None:
    result = af.sweep(af.Rig.paper(), af.PID.paper(), SPHS, amp_bandwidth=[1500.0, 3000.0], periods=2, seed=1,
                      progress=False)  # fmt: skip
    fig = af.plot_family(result, "amp_bandwidth")
    assert labels(fig.axes[0]) == ["amp_bandwidth = 1500 Hz", "amp_bandwidth = 3000 Hz"]
    assert [ax.get_xscale() for ax in fig.axes] == ["log"] * 3


def test_a_grid_names_every_swept_gain_in_every_legend_entry() -> None:
    result = af.sweep(af.Rig.paper(), af.PID.paper(), SPHS, kp=[2000.0, 2400.0], kd=[2.0, 3.0], periods=2, seed=1,
                      progress=False)  # fmt: skip
    assert labels(af.plot_family(result, "kp").axes[0]) == [
        "K_p = 2000 A/m, K_d = 2 A s/m", "K_p = 2000 A/m, K_d = 3 A s/m",
        "K_p = 2400 A/m, K_d = 2 A s/m", "K_p = 2400 A/m, K_d = 3 A s/m",
    ]  # fmt: skip
    fig = af.plot_family(result, "kd")  # the named one first
    assert labels(fig.axes[0])[1] == "K_d = 3 A s/m, K_p = 2000 A/m"
    assert fig.axes[0].get_title() == "Varying K_d and K_p"


def test_a_name_that_was_not_swept_is_refused(kd_family) -> None:
    with pytest.raises(ValueError, match=r"name must be one of the swept parameters \['kd'\], got 'kp'"):
        af.plot_family(kd_family, "kp")


def test_unstable_points_are_labelled_with_their_status() -> None:
    result = af.sweep(af.Rig.paper(), af.PID.paper(), SPHS, kd=[0.0, 2.0], periods=2, seed=1, progress=False)
    assert list(result.status) == ["unstable", "ok"]
    assert labels(af.plot_family(result, "kd").axes[0]) == ["K_d = 0 A s/m (unstable)", "K_d = 2 A s/m"]


def test_a_kd_family_shows_its_damping_around_resonance(kd_family) -> None:
    """The integral term puts c(1 Hz) at -21,700 N s/m; the Kd family differs by ~20-70 N s/m around 40 Hz.
    On a linear axis over the whole range those differences were < 0.3 % of the panel."""
    ax = af.plot_family(kd_family, "kd").axes[1]
    assert ax.get_yscale() == "symlog"
    linear_part = ax.yaxis.get_transform().linthresh
    above = kd_family.freq >= 10.0
    assert np.abs(kd_family.c_smooth[:, above]).max() <= linear_part < 1000.0  # c(1 Hz) = -21,700 N s/m
    low, high = ax.get_ylim()
    assert low <= kd_family.c_smooth.min() and high >= kd_family.c_smooth.max()  # nothing cut off
    # the spread at resonance, as a fraction of the panel's height in display units
    transform = ax.transData
    at = np.argmin(np.abs(kd_family.freq - 40.0))
    y = [transform.transform((40.0, v))[1] for v in kd_family.c_smooth[:, at]]
    panel = transform.transform((40.0, high))[1] - transform.transform((40.0, low))[1]
    assert (max(y) - min(y)) / panel > 0.05  # 0.003 on a linear axis over the whole range
    assert any("log scale beyond" in text.get_text() for text in ax.texts)


def test_damping_axes_stay_linear_without_far_lines() -> None:
    result = af.sweep(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=200.0), kd=[2.0, 3.0],
                      periods=2, seed=1, progress=False)  # fmt: skip
    ax = af.plot_family(result, "kd").axes[1]
    assert ax.get_yscale() == "linear" and not ax.texts


def test_every_figure_has_log_frequency_axes_and_units_on_every_label(kd_family) -> None:
    estimate = af.run_experiment(af.Rig.paper(), af.PID.paper(), SPHS, periods=2, seed=1)
    k_eff, c_eff = af.effective_coefficients(af.Rig.paper(), af.PID.paper(), estimate.freq)
    est2 = ta.run_experiment(ta.TwoAxisRig.paper(), af.PID.paper(), SPHS, periods=2, seed=1)
    figures = {
        "plot_actual": af.plot_actual(estimate),
        "plot_coefficients": af.plot_coefficients(estimate.freq, estimate.k, estimate.c, title="t"),
        "plot_effective": af.plot_coefficients(estimate.freq, k_eff, c_eff, title="t"),
        "plot_estimate": af.plot_estimate(estimate),
        "plot_family": af.plot_family(kd_family),
        "plot_overlay": af.plot_overlay(estimate, k_eff, c_eff),
        "plot_coefficients2": af.plot_coefficients2(est2),
    }
    for name, fig in figures.items():
        axes = [ax for ax in fig.axes if ax.get_xlabel() or ax.get_ylabel() or ax.get_title()]
        assert [ax.get_xscale() for ax in axes] == ["log"] * len(axes), name
        for ax in axes:
            for text in (ax.get_xlabel(), ax.get_ylabel() or ax.get_title()):
                assert text == "" or text.endswith(")") and "(" in text, (name, text)  # "(unit)"
            assert ax.get_ylabel() or ax.get_title(), name
    two = figures["plot_coefficients2"].axes
    assert [ax.get_yscale() for ax in two[4:]] == ["symlog", "linear", "linear", "symlog"]  # cxx, cyy: -K_i k_i / w
