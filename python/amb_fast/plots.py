"""Figures (matplotlib, the optional extra ``amb_fast[plot]``). Every function returns its Figure.

Frequencies in Hz on log axes, stiffness in kN/m, damping in N s/m, receptance in m/N.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._experiment import Estimate
    from ._study import PaperStudy
    from ._sweep import SweepResult

LABELS = {"kp": ("K_p", "A/m"), "ki": ("K_i", "A/(m s)"), "kd": ("K_d", "A s/m")}


def _figure(rows: int, height: float = 3.0) -> tuple[Figure, np.ndarray]:
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError as error:
        raise ImportError("figures need matplotlib: pip install 'amb_fast[plot]'") from error
    fig, axes = plt.subplots(rows, 1, figsize=(7.0, height * rows), sharex=True, squeeze=False)
    return fig, axes[:, 0]


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
    axes[1].set_yscale("symlog", linthresh=100)
    if raw is not None:
        axes[0].legend()
    _coefficient_axes(axes)
    axes[0].set_title(title)
    fig.tight_layout()
    return fig


def plot_effective(study: PaperStudy) -> Figure:
    """Paper Fig. 4: effective stiffness and damping from the theoretical PID."""
    return plot_coefficients(study.freq, study.k_eff, study.c_eff, title="Effective stiffness and damping (eq. 5)")


def plot_actual(estimate: Estimate, *, title: str = "Actual stiffness and damping (eq. 9)") -> Figure:
    """Paper Fig. 5: actual stiffness and damping, raw and median filtered."""
    return plot_coefficients(estimate.freq, estimate.k_smooth, estimate.c_smooth, title=title,
                             raw=(estimate.k, estimate.c))  # fmt: skip


def plot_family(result: SweepResult, name: str, *, zoom: tuple[float, float] | None = None) -> Figure:
    """Paper Figs. 6-10: k, c and |Y/F| for one gain family; ``zoom`` (Hz) narrows to a band, linear axes."""
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
        axes[1].set_yscale("symlog", linthresh=100)
        axes[2].set_yscale("log")
    else:
        for ax in axes:
            ax.set_xscale("linear")
    axes[0].legend(fontsize=8)
    where = "" if zoom is None else f", {zoom[0]:.0f}-{zoom[1]:.0f} Hz"
    axes[0].set_title(f"Varying {symbol}{where}")
    fig.tight_layout()
    return fig


def plot_estimate(estimate: Estimate, *, title: str = "Identified stiffness, damping and receptance") -> Figure:
    """One estimate: k and c with their standard errors, and |Y/F|."""
    fig, axes = _figure(3, height=2.6)
    f = estimate.freq
    axes[0].errorbar(
        f, estimate.k / 1e3, yerr=2 * estimate.k_std / 1e3, fmt=".", ms=3, color="0.5", label="raw, 2 s.e."
    )
    axes[0].plot(f, estimate.k_smooth / 1e3, label="median filtered")
    axes[1].errorbar(f, estimate.c, yerr=2 * estimate.c_std, fmt=".", ms=3, color="0.5")
    axes[1].plot(f, estimate.c_smooth)
    axes[1].set_yscale("symlog", linthresh=100)
    axes[2].plot(f, np.abs(estimate.receptance))
    axes[2].set_yscale("log")
    axes[2].set_ylabel("|Y/F| (m/N)")
    _coefficient_axes(axes)
    axes[0].legend(fontsize=8)
    axes[0].set_title(title)
    fig.tight_layout()
    return fig
