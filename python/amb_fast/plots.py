"""Figures (matplotlib, the optional extra ``amb_fast[plot]``). Every function returns its Figure.

Frequencies in Hz on log axes, stiffness in kN/m, damping in N s/m on a linear axis (a symmetric-log
axis would bend the curves at +-its threshold), receptance in m/N on a log axis. Standard errors are
drawn as shaded bands of +-2 s.e. under the curves, never as bars over them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._experiment import Estimate
    from ._study import PaperStudy
    from ._sweep_result import SweepResult

LABELS = {"kp": ("K_p", "A/m"), "ki": ("K_i", "A/(m s)"), "kd": ("K_d", "A s/m")}


def _pyplot() -> Any:
    """matplotlib.pyplot, on the Agg backend unless one was chosen; a clear error without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError as error:
        raise ImportError("figures need matplotlib: pip install 'amb_fast[plot]'") from error
    return plt


def _figure(rows: int, height: float = 3.0) -> tuple[Figure, np.ndarray]:
    fig, axes = _pyplot().subplots(rows, 1, figsize=(7.0, height * rows), sharex=True, squeeze=False)
    return fig, axes[:, 0]


def _tight_layout(fig: Figure) -> None:
    """``fig.tight_layout()``, measured once: it leaves a placeholder layout engine on the figure that makes every
    ``savefig`` draw the figure twice (a dry run for the layout, then the pixels); without it, one draw (same
    pixels)."""
    fig.tight_layout()
    fig.set_layout_engine(None)  # None (not "none", the placeholder) unless rcParams ask for an automatic layout


def _coefficient_axes(axes: np.ndarray, freq_unit: str = "Hz") -> None:
    axes[0].set_ylabel("stiffness k (kN/m)")
    axes[1].set_ylabel("damping c (N s/m)")
    axes[-1].set_xlabel(f"frequency ({freq_unit})")
    for ax in axes:
        ax.set_xscale("log")
        ax.grid(True, which="both", alpha=0.3)


def plot_coefficients(
    freq: np.ndarray, k: np.ndarray, c: np.ndarray, *, title: str, raw: tuple[np.ndarray, np.ndarray] | None = None
) -> Figure:
    """Stiffness and damping against frequency; ``raw`` adds the unfiltered estimates as dots."""
    fig, axes = _figure(2)
    if raw is not None:
        axes[0].plot(freq, raw[0] / 1e3, ".", ms=3, color="0.6", label="raw")
        axes[1].plot(freq, raw[1], ".", ms=3, color="0.6", label="raw")
    axes[0].plot(freq, k / 1e3, lw=1.5, label="median filtered" if raw is not None else None)
    axes[1].plot(freq, c, lw=1.5)
    if raw is not None:
        axes[0].legend()
    _coefficient_axes(axes)
    axes[0].set_title(title)
    _tight_layout(fig)
    return fig


def plot_effective(study: PaperStudy) -> Figure:
    """Paper Fig. 4: effective stiffness and damping from the theoretical PID."""
    return plot_coefficients(study.freq, study.k_eff, study.c_eff, title="Effective stiffness and damping (eq. 5)")


def plot_actual(estimate: Estimate, *, title: str = "Actual stiffness and damping (eq. 9)") -> Figure:
    """Paper Fig. 5: actual stiffness and damping, raw and median filtered."""
    return plot_coefficients(estimate.freq, estimate.k_smooth, estimate.c_smooth, title=title,
                             raw=(estimate.k, estimate.c))  # fmt: skip


def plot_overlay(
    estimate: Estimate, k_eff: np.ndarray, c_eff: np.ndarray, *, title: str = "Effective (eq. 5) and actual (eq. 9)"
) -> Figure:
    """Effective and actual stiffness and damping in one figure: the actual ones median filtered, over a
    +-2 s.e. band of the raw estimate; ``k_eff``, ``c_eff`` at ``estimate.freq`` (N/m, N s/m)."""
    fig, axes = _figure(2)
    f = estimate.freq
    for ax, actual, std, effective, scale in ((axes[0], estimate.k_smooth, estimate.k_std, k_eff, 1e3),
                                              (axes[1], estimate.c_smooth, estimate.c_std, c_eff, 1.0)):  # fmt: skip
        raw = estimate.k if scale == 1e3 else estimate.c
        ax.fill_between(f, (raw - 2 * std) / scale, (raw + 2 * std) / scale, color="C0", alpha=0.2, lw=0,
                        label="actual, raw +-2 s.e.")  # fmt: skip
        ax.plot(f, actual / scale, color="C0", lw=1.5, label="actual (median filtered)")
        ax.plot(f, np.asarray(effective) / scale, color="C3", lw=1.5, ls="--", label="effective")
    axes[0].legend(fontsize=8)
    _coefficient_axes(axes)
    axes[0].set_title(title)
    _tight_layout(fig)
    return fig


def _inset(ax, freq: np.ndarray, curves: list[tuple[np.ndarray, str]], zoom: tuple[float, float]) -> None:  # noqa: ANN001
    band = (freq >= zoom[0]) & (freq <= zoom[1])
    inner = ax.inset_axes((0.62, 0.08, 0.35, 0.45))
    for values, label in curves:
        inner.plot(freq[band], values[band], lw=1.0, label=label)
    inner.tick_params(labelsize=6)
    inner.set_title(f"{zoom[0]:.0f}-{zoom[1]:.0f} Hz", fontsize=7)
    ax.indicate_inset_zoom(inner, edgecolor="0.5")


def plot_family(
    result: SweepResult,
    name: str,
    *,
    zoom: tuple[float, float] | None = None,
    inset: tuple[float, float] | None = None,
) -> Figure:
    """Paper Figs. 6-10: k, c and |Y/F| for one gain family; ``zoom`` (Hz) narrows to a band, linear axes;
    ``inset`` (Hz) adds a zoomed inset of that band to the stiffness and receptance panels (where the paper
    zooms: Figs. 7 and 9)."""
    symbol, unit = LABELS[name]
    fig, axes = _figure(3, height=2.6)
    freq = result.freq
    band = np.ones(freq.size, dtype=bool) if zoom is None else (freq >= zoom[0]) & (freq <= zoom[1])
    for row, value in enumerate(result.points[name]):
        label = f"{symbol} = {value:.4g} {unit}"
        axes[0].plot(freq[band], result.k_smooth[row, band] / 1e3, label=label)
        axes[1].plot(freq[band], result.c_smooth[row, band], label=label)
        axes[2].plot(freq[band], np.abs(1 / result.H[row, band]), label=label)
    axes[2].set_ylabel("|Y/F| (m/N)")
    _coefficient_axes(axes)
    if zoom is None:
        axes[2].set_yscale("log")
    else:
        for ax in axes:
            ax.set_xscale("linear")
    if inset is not None and zoom is None:
        rows = range(len(result.points[name]))
        _inset(axes[0], freq, [(result.k_smooth[r] / 1e3, "") for r in rows], inset)
        _inset(axes[2], freq, [(np.abs(1 / result.H[r]), "") for r in rows], inset)
    axes[0].legend(fontsize=8)
    where = "" if zoom is None else f", {zoom[0]:.0f}-{zoom[1]:.0f} Hz"
    axes[0].set_title(f"Varying {symbol}{where}")
    _tight_layout(fig)
    return fig


def plot_estimate(estimate: Estimate, *, title: str = "Identified stiffness, damping and receptance") -> Figure:
    """One estimate: k and c (raw dots over a +-2 s.e. band, the median-filtered line on top), and |Y/F|.
    Weak lines (``Estimate.weak``) are marked with a cross."""
    fig, axes = _figure(3, height=2.6)
    f = estimate.freq
    for ax, raw, std, smooth, scale in ((axes[0], estimate.k, estimate.k_std, estimate.k_smooth, 1e3),
                                        (axes[1], estimate.c, estimate.c_std, estimate.c_smooth, 1.0)):  # fmt: skip
        ax.fill_between(f, (raw - 2 * std) / scale, (raw + 2 * std) / scale, color="0.8", lw=0, label="raw +-2 s.e.")
        ax.plot(f, raw / scale, ".", ms=3, color="0.45", label="raw")
        ax.plot(f, smooth / scale, color="C0", lw=1.5, label="median filtered")
        if estimate.weak is not None and estimate.weak.any():
            ax.plot(f[estimate.weak], raw[estimate.weak] / scale, "x", color="C3", ms=5, label="weak line")
    axes[2].plot(f, np.abs(estimate.receptance))
    axes[2].set_yscale("log")
    axes[2].set_ylabel("|Y/F| (m/N)")
    _coefficient_axes(axes)
    axes[0].legend(fontsize=8)
    axes[0].set_title(title)
    _tight_layout(fig)
    return fig
