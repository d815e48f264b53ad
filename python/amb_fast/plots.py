"""Figures (matplotlib, the optional extra ``amb_fast[plot]``). Every function returns its Figure.

Frequencies in Hz on log axes, stiffness in kN/m, damping in N s/m, receptance in m/N on a log axis.
Standard errors are drawn as shaded bands of +-2 s.e. under the curves, never as bars over them.

Damping axes are linear, unless a few lines lie far outside the rest (an integral gain's ``-K_i k_i / w``
at the lowest lines: -21,700 N s/m at 1 Hz for the paper's rig, against +-100 N s/m around resonance): then
the axis is linear over the band the other lines span and logarithmic beyond (a symmetric-log axis whose
linear part takes most of the panel), so the damping around resonance stays readable and the lowest lines
stay in view; the panel says which lines lie in its logarithmic part.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ._validate import require

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ._experiment import Estimate
    from ._study import PaperStudy
    from ._sweep_result import SweepResult
    from .system import EstimateN

LABELS = {"kp": ("K_p", "A/m"), "ki": ("K_i", "A/(m s)"), "kd": ("K_d", "A s/m")}
FENCE = 3.0  # interquartile ranges beyond the quartiles where a damping value counts as far outside the rest
DECADE = 10.0  # how much larger than the rest the lowest lines must reach for a symmetric-log damping axis


def pyplot_module() -> Any:
    """matplotlib.pyplot, on the Agg backend unless one was chosen; a clear error without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError as error:
        raise ImportError("figures need matplotlib: pip install 'amb_fast[plot]'") from error
    return plt


def _figure(rows: int, height: float = 3.0) -> tuple[Figure, np.ndarray]:
    fig, axes = pyplot_module().subplots(rows, 1, figsize=(7.0, height * rows), sharex=True, squeeze=False)
    return fig, axes[:, 0]


def _tight_layout(fig: Figure) -> None:
    """``fig.tight_layout()``, measured once: it leaves a placeholder layout engine on the figure that makes every
    ``savefig`` draw the figure twice (a dry run for the layout, then the pixels); without it, one draw (same
    pixels)."""
    fig.tight_layout()
    fig.set_layout_engine(None)  # None (not "none", the placeholder) unless rcParams ask for an automatic layout


def _damping_scale(ax, freq: np.ndarray, curves: list[np.ndarray]) -> None:  # noqa: ANN001
    """Linear damping axis, or symmetric-log when the lowest lines lie more than ``FENCE`` interquartile ranges
    beyond the quartiles of all the panel's values (the integral term: see the module docstring); noisy lines
    elsewhere in the band do not count. ``curves`` at ``freq``."""
    table = np.vstack([np.asarray(c, dtype=float) for c in curves])
    values = table[np.isfinite(table)]
    if values.size < 8:
        return
    q1, q3 = np.percentile(values, [25.0, 75.0])
    spread = max(q3 - q1, 1e-12 * max(abs(q1), abs(q3), 1.0))
    with np.errstate(invalid="ignore"):
        far = ((table < q1 - FENCE * spread) | (table > q3 + FENCE * spread)).any(axis=0)
    lowest = int(np.argmin(far)) if not far.all() else far.size  # far lines from the lowest one on
    rest = table[:, lowest:]
    rest = rest[np.isfinite(rest)]
    if lowest == 0 or rest.size == 0:
        return
    threshold = 1.1 * float(np.max(np.abs(rest)))
    if np.nanmax(np.abs(table[:, :lowest])) <= DECADE * threshold:
        return  # on a linear axis the rest still spans a tenth of the panel or more
    from matplotlib.ticker import FixedLocator, FuncFormatter

    # the linear part (+-threshold) spans 3 decades per side: most of the panel for a decade or two beyond
    ax.set_yscale("symlog", linthresh=threshold, linscale=3.0)
    low, high = float(values.min()), float(values.max())
    pad = 0.05 * (min(high, threshold) - max(low, -threshold))
    ax.set_ylim(low - pad if low >= -threshold else low * 1.3, high + pad if high <= threshold else high * 1.3)
    step = _nice_above(threshold / 3.0)
    half = np.floor(threshold / step + 1e-9) * step
    linear = np.arange(-half, half + step / 2, step)
    decades = [s * 10.0**e for e in range(int(np.log10(2.5 * threshold)) + 1, 13) for s in (-1.0, 1.0)]
    ticks = [t for t in (*linear, *decades) if low - step <= t <= high + step]
    ax.yaxis.set_major_locator(FixedLocator(sorted(ticks)))
    ax.yaxis.set_minor_locator(FixedLocator([]))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}" if abs(v) >= 1 else f"{v:g}"))
    with np.errstate(invalid="ignore"):
        outside = (np.abs(table) > threshold).any(axis=0)
    if outside.any():
        f = freq[outside]
        where = f"{f.min():.4g} Hz" if f.size == 1 else f"{f.min():.4g}-{f.max():.4g} Hz"
        ax.text(0.99, 0.03, f"log scale beyond +-{threshold:,.0f} N s/m ({where})", transform=ax.transAxes,
                ha="right", va="bottom", fontsize=7, color="0.35")  # fmt: skip


def _nice_above(value: float) -> float:
    """The smallest of 1, 2, 2.5, 5 x 10^n at or above ``value`` (> 0)."""
    exponent = np.floor(np.log10(value))
    for mantissa in (1.0, 2.0, 2.5, 5.0, 10.0):
        if mantissa * 10**exponent >= value * (1 - 1e-12):
            return float(mantissa * 10**exponent)
    return float(10 ** (exponent + 1))  # pragma: no cover


QUANTITIES = (("k", 1e3, "kN/m"), ("c", 1.0, "N s/m"))  # an estimate's field, its scale to the axis's unit, unit


def _frequency_axis(ax, scale: str = "log") -> None:  # noqa: ANN001
    ax.set_xscale(scale)
    ax.grid(True, which="both", alpha=0.3)


def _band(ax, freq: np.ndarray, raw: np.ndarray, std: np.ndarray, scale: float, **style: Any) -> None:  # noqa: ANN001
    """The raw estimate +-2 standard errors, shaded (in the axis's unit: divided by ``scale``)."""
    ax.fill_between(freq, (raw - 2 * std) / scale, (raw + 2 * std) / scale, lw=0, **style)


def _finish(fig: Figure, axes: np.ndarray, title: str, freq: np.ndarray, damping: list, scale: str = "log") -> Figure:
    """Labels with units, frequency axes (``scale``) with grids, the damping axis (see the module docstring),
    the title and the layout of a column of k, c (and |Y/F|) panels."""
    axes[0].set_ylabel("stiffness k (kN/m)")
    axes[1].set_ylabel("damping c (N s/m)")
    if len(axes) == 3:
        axes[2].set_ylabel("|Y/F| (m/N)")
        axes[2].set_yscale(scale)  # a log receptance over log frequencies; linear over a zoomed band
    axes[-1].set_xlabel("frequency (Hz)")
    for ax in axes:
        _frequency_axis(ax, scale)
    _damping_scale(axes[1], freq, damping)
    axes[0].set_title(title)
    _tight_layout(fig)
    return fig


def plot_coefficients(
    freq: np.ndarray, k: np.ndarray, c: np.ndarray, *, title: str, raw: tuple[np.ndarray, np.ndarray] | None = None
) -> Figure:
    """Stiffness and damping against frequency; ``raw`` adds the unfiltered estimates as dots."""
    fig, axes = _figure(2)
    for ax, (_, scale, _), values, dots in zip(axes, QUANTITIES, (k, c), raw or (None, None)):
        if dots is not None:
            ax.plot(freq, dots / scale, ".", ms=3, color="0.6", label="raw")
        ax.plot(freq, values / scale, lw=1.5, label=None if raw is None else "median filtered")
    if raw is not None:
        axes[0].legend()
    return _finish(fig, axes, title, freq, [c] if raw is None else [c, raw[1]])


def plot_coefficients2(estimate: EstimateN, *, smoothed: bool = False, effective: tuple | None = None) -> Figure:
    """Every stiffness and damping coefficient of an N-axis estimate over frequency: a 2 x N^2 grid of axes.

    Parameters
    ----------
    estimate : EstimateN
        An estimate of N axes (two: :func:`amb_fast.two_axis.run_experiment`, :func:`amb_fast.two_axis.identify`).
    smoothed : bool
        Plot the median-filtered ``k_smooth``, ``c_smooth`` instead of the raw ``k``, ``c``. The bands
        are always +-2 standard errors of the raw estimate.
    effective : (K_eff, C_eff), optional
        Effective matrices at ``estimate.freq`` (N/m, N s/m; shape (lines, N, N)), as
        :func:`amb_fast.two_axis.effective_coefficients` returns them: drawn as dashed lines.

    Returns
    -------
    matplotlib.figure.Figure
        :func:`plot_coefficients_n` of every entry in one row: top row ``k[x, x], k[x, y], k[y, x], k[y, y]``
        (kN/m), bottom row ``c[x, x] .. c[y, y]`` (N s/m) for two axes, against frequency (Hz). Needs
        matplotlib (the ``plot`` extra).

    Examples
    --------
    >>> rig = af.TwoAxisRig(x=af.Rig.paper(), y=af.Rig.paper(), kxy=1e4, kyx=-1e4)
    >>> est = af.two_axis.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(), seed=1)
    >>> fig = af.plot_coefficients2(est, effective=af.two_axis.effective_coefficients(rig, af.PID.paper(), est.freq))
    >>> [ax.get_title() for ax in fig.axes[4:]]
    ['c[x, x] (N s/m)', 'c[x, y] (N s/m)', 'c[y, x] (N s/m)', 'c[y, y] (N s/m)']
    """
    every = [(a, b) for a in estimate.axes for b in estimate.axes]
    return plot_coefficients_n(estimate, terms=every, effective=effective, smoothed=smoothed)


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
    for ax, (q, scale, _), effective in zip(axes, QUANTITIES, (k_eff, c_eff)):
        _band(ax, f, getattr(estimate, q), getattr(estimate, f"{q}_std"), scale, color="C0", alpha=0.2,
              label="actual, raw +-2 s.e.")  # fmt: skip
        ax.plot(f, getattr(estimate, f"{q}_smooth") / scale, color="C0", lw=1.5, label="actual (median filtered)")
        ax.plot(f, np.asarray(effective) / scale, color="C3", lw=1.5, ls="--", label="effective")
    axes[0].legend(fontsize=8)
    return _finish(fig, axes, title, f, [estimate.c_smooth, np.asarray(c_eff, dtype=float)])


def _inset(ax, freq: np.ndarray, curves: list[np.ndarray], zoom: tuple[float, float]) -> None:  # noqa: ANN001
    band = (freq >= zoom[0]) & (freq <= zoom[1])
    inner = ax.inset_axes((0.62, 0.08, 0.35, 0.45))
    for values in curves:
        inner.plot(freq[band], values[band], lw=1.0, label="")
    inner.tick_params(labelsize=6)
    inner.set_title(f"{zoom[0]:.0f}-{zoom[1]:.0f} Hz", fontsize=7)
    ax.indicate_inset_zoom(inner, edgecolor="0.5")


def _axis_label(name: str) -> tuple[str, str]:
    """(symbol, unit) of a sweep axis: the paper's symbols for the PID gains, else the parameter's own name."""
    from ._sweep_result import unit_of

    return LABELS.get(name, (name, unit_of(name)))


def _value_label(name: str, value: float) -> str:
    symbol, unit = _axis_label(name)
    return f"{symbol} = {value:.6g}" + (f" {unit}" if unit else "")


def plot_family(
    result: SweepResult,
    name: str | None = None,
    *,
    zoom: tuple[float, float] | None = None,
    inset: tuple[float, float] | None = None,
) -> Figure:
    """k, c and |Y/F| of every point of a sweep, one curve per point (paper Figs. 6-10: one gain family).

    Parameters
    ----------
    result : SweepResult
        Any sweep: over PID gains, a rig field (``amp_bandwidth``), a controller block's parameter
        (``notch_freq``), one axis or a grid of several.
    name : str, optional
        The swept parameter the figure is about: named first in every legend entry and in the title.
        Default: the sweep's first axis. Every swept parameter is in every legend entry (a kp x kd grid
        shows both gains), with its unit.
    zoom : (float, float), optional
        Narrows to that band (Hz), on linear axes.
    inset : (float, float), optional
        Adds a zoomed inset of that band (Hz) to the stiffness and receptance panels (where the paper
        zooms: Figs. 7 and 9).

    Returns
    -------
    matplotlib.figure.Figure
        Points that did not give an estimate (unstable, touchdown, ...) are listed in the legend with their
        status (their curves are NaN). The damping axis is linear, or symmetric-log when the lowest lines lie
        far outside the rest (see :mod:`amb_fast.plots`).
    """
    swept = list(result.points)
    if name is None:
        name = swept[0]
    if name not in result.points:
        raise ValueError(f"name must be one of the swept parameters {swept}, got {name!r}")
    names = [name, *(n for n in swept if n != name)]
    symbol = _axis_label(name)[0]
    fig, axes = _figure(3, height=2.6)
    freq = result.freq
    band = np.ones(freq.size, dtype=bool) if zoom is None else (freq >= zoom[0]) & (freq <= zoom[1])
    rows = range(len(result.status))
    with np.errstate(divide="ignore", invalid="ignore"):  # NaN rows of points without an estimate
        receptance = np.abs(1 / result.H)
    for row in rows:
        label = ", ".join(_value_label(n, float(result.points[n][row])) for n in names)
        if result.status[row] != "ok":
            label += f" ({result.status[row]})"
        axes[0].plot(freq[band], result.k_smooth[row, band] / 1e3, label=label)
        axes[1].plot(freq[band], result.c_smooth[row, band], label=label)
        axes[2].plot(freq[band], receptance[row, band], label=label)
    if inset is not None and zoom is None:
        _inset(axes[0], freq, [result.k_smooth[r] / 1e3 for r in rows], inset)
        _inset(axes[2], freq, [receptance[r] for r in rows], inset)
    axes[0].legend(fontsize=8 if len(names) == 1 else 7)
    where = "" if zoom is None else f", {zoom[0]:.0f}-{zoom[1]:.0f} Hz"
    others = [_axis_label(n)[0] for n in names[1:]]
    title = f"Varying {symbol}" + (f" and {', '.join(others)}" if others else "")
    damping = [result.c_smooth[row, band] for row in rows]
    return _finish(fig, axes, f"{title}{where}", freq[band], damping, "log" if zoom is None else "linear")


def plot_estimate(estimate: Estimate, *, title: str = "Identified stiffness, damping and receptance") -> Figure:
    """One estimate: k and c (raw dots over a +-2 s.e. band, the median-filtered line on top), and |Y/F|.
    Weak lines (``Estimate.weak``) are marked with a cross."""
    fig, axes = _figure(3, height=2.6)
    f = estimate.freq
    weak = estimate.weak if estimate.weak is not None and estimate.weak.any() else None
    for ax, (q, scale, _) in zip(axes, QUANTITIES):
        raw = getattr(estimate, q)
        _band(ax, f, raw, getattr(estimate, f"{q}_std"), scale, color="0.8", label="raw +-2 s.e.")
        ax.plot(f, raw / scale, ".", ms=3, color="0.45", label="raw")
        ax.plot(f, getattr(estimate, f"{q}_smooth") / scale, color="C0", lw=1.5, label="median filtered")
        if weak is not None:
            ax.plot(f[weak], raw[weak] / scale, "x", color="C3", ms=5, label="weak line")
    axes[2].plot(f, np.abs(estimate.receptance))
    axes[0].legend(fontsize=8)
    return _finish(fig, axes, title, f, [estimate.c_smooth, estimate.c])


def plot_coefficients_n(
    estimate: EstimateN,
    *,
    terms: str | list[tuple[str, str]] = "all",
    effective: tuple[np.ndarray, np.ndarray] | None = None,
    smoothed: bool = False,
) -> Figure:
    """Stiffness and damping matrices of N axes over frequency: per entry a k panel over a c panel.

    Parameters
    ----------
    estimate : EstimateN
        An estimate of N axes (:func:`amb_fast.run_experiment` of a :class:`~amb_fast.RotorRig`,
        :func:`amb_fast.system.identify`).
    terms : {"all", "direct", "cross"} or list of (str, str)
        Which entries ``[i, j]`` (force of axis i from displacement of axis j): ``"all"`` the N x N grid (16
        entries, 32 panels for a rotor), ``"direct"`` the N diagonal ones in one row, ``"cross"`` the grid
        without its diagonal, or a list of ``(out, in)`` axis names (``[("A.x", "B.x")]``) in one row.
    effective : (K_eff, C_eff), optional
        Effective matrices at ``estimate.freq`` (N/m, N s/m; shape (lines, N, N)), as
        :func:`amb_fast.effective_coefficients` returns them: drawn dashed.
    smoothed : bool
        Draw the median-filtered ``k_smooth``, ``c_smooth`` instead of the raw ``k``, ``c``; the band is the
        raw estimate +-2 s.e. either way.

    Returns
    -------
    matplotlib.figure.Figure
        Stiffness in kN/m and damping in N s/m against frequency (Hz, log axis); each panel's first line is
        the estimate, the next the effective coefficient. Panels titled ``k[A.x, B.x] (kN/m)``.
    """
    names = list(estimate.axes)
    N = len(names)
    grid = terms in ("all", "cross")
    if grid:
        entries = [(i, j) for i in range(N) for j in range(N) if terms == "all" or i != j]
    elif terms == "direct":
        entries = [(i, i) for i in range(N)]
    else:
        pairs = terms if isinstance(terms, list) else []
        ok = bool(pairs) and all(isinstance(t, tuple) and len(t) == 2 and set(t) <= set(names) for t in pairs)
        require(ok, "terms", terms, f"'all', 'direct', 'cross' or a list of (out, in) pairs of the axes {names}")
        entries = [(names.index(a), names.index(b)) for a, b in pairs]
    if effective is not None:
        shapes = [np.shape(m) for m in effective] if isinstance(effective, (tuple, list)) else []
        require(shapes == [estimate.k.shape] * 2, "effective", shapes or type(effective).__name__,
                f"(K_eff, C_eff), each of shape {estimate.k.shape} (lines, N, N) at estimate.freq")  # fmt: skip
    columns, rows = (N, 2 * N) if grid else (len(entries), 2)
    fig, axes = pyplot_module().subplots(rows, columns, figsize=(3.2 * columns, 2.0 * rows), sharex=True, squeeze=False)
    for cell in axes.ravel():
        cell.set_visible(False)
    f = estimate.freq
    for n, (i, j) in enumerate(entries):
        top, column = (2 * i, j) if grid else (0, n)
        for row, (q, scale, unit) in enumerate(QUANTITIES):
            ax = axes[top + row, column]
            ax.set_visible(True)
            curves = [getattr(estimate, f"{q}_smooth" if smoothed else q)[:, i, j]]
            ax.plot(f, curves[0] / scale, color="C0", lw=1.2, label="actual")
            if effective is not None:
                curves.append(effective[row][:, i, j])
                ax.plot(f, curves[1] / scale, color="C3", lw=1.2, ls="--", label="effective")
            raw, std = getattr(estimate, q)[:, i, j], getattr(estimate, f"{q}_std")[:, i, j]
            _band(ax, f, raw, std, scale, color="C0", alpha=0.2, label="+-2 s.e.")
            ax.set_title(f"{q}[{names[i]}, {names[j]}] ({unit})", fontsize=8)
            _frequency_axis(ax)
            ax.tick_params(labelsize=7)
            ax.xaxis.set_tick_params(labelbottom=True)
            if row == 1:
                _damping_scale(ax, f, curves)
                ax.set_xlabel("frequency (Hz)", fontsize=7)
    axes[0, entries[0][1] if grid else 0].legend(fontsize=7)
    _tight_layout(fig)
    return fig
