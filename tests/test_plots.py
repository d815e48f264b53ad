"""Figures: damping axes linear over the band that matters, effective and actual overlaid with error bands,
insets where the paper zooms."""

from __future__ import annotations

import numpy as np
import pytest

import amb_fast as af

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def estimate() -> af.Estimate:
    rig = af.Rig(sensor_noise=1e-8, force_noise=1e-3)
    return af.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(f_max=100.0), periods=4, seed=2)


def test_damping_axes_are_linear_and_error_bands_lie_under_the_lines(estimate) -> None:
    from matplotlib.collections import PolyCollection

    above = estimate.freq >= 10.0  # the integral term's -K_i k_i / w dominates the lines below
    for fig in (af.plot_actual(estimate), af.plot_estimate(estimate)):
        ax = fig.axes[1]
        assert ax.get_ylabel() == "damping c (N s/m)" and ax.get_yscale() == "symlog"
        linear_part = ax.yaxis.get_transform().linthresh  # N s/m: the axis is linear inside +-this
        assert np.abs(estimate.c_smooth[above]).max() <= linear_part < 1000.0
    fig = af.plot_estimate(estimate)
    for ax in fig.axes[:2]:
        assert not ax.containers  # no error bars drawn over the curve
        bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
        assert len(bands) == 1 and bands[0].get_zorder() <= min(line.get_zorder() for line in ax.lines)


def test_effective_and_actual_in_one_figure(estimate) -> None:
    k_eff, c_eff = af.effective_coefficients(af.Rig(), af.PID.paper(), estimate.freq)
    fig = af.plot_overlay(estimate, k_eff, c_eff)
    for ax, effective in zip(fig.axes, (k_eff / 1e3, c_eff)):
        labels = [line.get_label() for line in ax.lines]
        assert labels == ["actual (median filtered)", "effective"]
        np.testing.assert_array_equal(ax.lines[1].get_ydata(), effective)
        assert len(ax.collections) == 1  # the +-2 s.e. band of the actual estimate


def test_family_figures_get_a_zoomed_inset() -> None:
    result = af.sweep(af.Rig(), af.PID.paper(), af.schroeder_multisine(f_max=100.0), kd=[2.0, 3.0], periods=2)
    plain = af.plot_family(result, "kd")
    zoomed = af.plot_family(result, "kd", inset=(30.0, 50.0))
    assert [len(ax.child_axes) for ax in zoomed.axes] == [1, 0, 1]  # stiffness and receptance panels
    assert [len(ax.child_axes) for ax in plain.axes] == [0, 0, 0]
    inset = zoomed.axes[0].child_axes[0]
    assert inset.get_title() == "30-50 Hz" and inset.get_xscale() == "linear"
    assert zoomed.axes[1].get_yscale() == "symlog"  # linear around resonance, log at the lowest lines


def test_without_matplotlib_every_figure_says_which_extra_to_install(estimate, monkeypatch) -> None:
    import sys

    import amb_fast.two_axis as ta

    est2 = ta.run_experiment(ta.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=100.0),
                             periods=2, seed=1)  # fmt: skip
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed: importing it raises ImportError
    for draw in (lambda: af.plot_estimate(estimate), lambda: af.plot_coefficients2(est2)):
        with pytest.raises(ImportError, match=r"pip install 'amb_fast\[plot\]'"):
            draw()


def test_plot_coefficients2_is_plot_coefficients_n_of_every_entry_in_one_row() -> None:
    """Before: plot_coefficients2 drew panels of its own (``kxy (N/m)``, +-1.96 s.e.); now it is the N-axis
    figure of every entry in one row: the same titles, units (kN/m) and lines as plot_coefficients_n."""
    import amb_fast.two_axis as ta

    est2 = ta.run_experiment(ta.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f0=20.0, f_max=100.0),
                             periods=2, seed=1)  # fmt: skip
    every = [("x", "x"), ("x", "y"), ("y", "x"), ("y", "y")]
    two, n = af.plot_coefficients2(est2, smoothed=True), af.plot_coefficients_n(est2, terms=every, smoothed=True)
    assert [ax.get_title() for ax in two.axes] == [ax.get_title() for ax in n.axes]
    assert [ax.get_title() for ax in two.axes[:2]] == ["k[x, x] (kN/m)", "k[x, y] (kN/m)"]
    for ours, theirs in zip(two.axes, n.axes):
        np.testing.assert_array_equal(ours.lines[0].get_ydata(), theirs.lines[0].get_ydata())
    np.testing.assert_array_equal(two.axes[1].lines[0].get_ydata(), est2.k_smooth[:, 0, 1] / 1e3)
