"""``amb-fast paper``: the paper's study on the virtual rig, written as figures, curves and a claims report."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import claims as claim_checks
from ._study import GAINS, PaperStudy, paper_study
from .io import atomic_path, atomic_text

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FIGURES = {  # file -> what it shows (the paper's figure)
    "fig4_effective.png": "effective k, c (Fig. 4)",
    "fig5_actual.png": "actual k, c (Fig. 5)",
    "fig5_overlay.png": "effective and actual k, c in one figure, +-2 s.e. bands (Figs. 4 and 5 together)",
    "fig6_ki.png": "Ki family (Fig. 6)",
    "fig7_ki_zoom.png": "Ki family around the natural frequency (Fig. 7)",
    "fig8_kd.png": "Kd family (Fig. 8)",
    "fig9_kd_zoom.png": "Kd family around the natural frequency (Fig. 9)",
    "fig10_kp.png": "Kp family (Fig. 10)",
}


def _say(progress: bool, text: str) -> None:
    if progress:
        print(text, file=sys.stderr, flush=True)


def _family_suffix() -> str:
    """``.nc`` where xarray and h5netcdf are installed (looked up, not imported: importing xarray takes ~0.4 s)."""
    from importlib.util import find_spec

    return ".nc" if find_spec("xarray") and find_spec("h5netcdf") else ".npz"


def output_names() -> list[str]:
    """Every file ``amb-fast paper`` writes into its folder."""
    families = [f"family_{g}{suffix}" for g in GAINS for suffix in (".csv", _family_suffix())]
    return [*FIGURES, "claims.md", "effective.csv", "actual.csv", *families]


def _write_csv(path: Path, columns: dict[str, np.ndarray], meta: dict | None = None) -> None:
    """A CSV with the column names in the first line and the metadata (version, rig, controller, seed) in
    trailing ``#`` lines."""
    from .io._results import trailer

    with atomic_path(path) as target, open(target, "w") as handle:
        np.savetxt(handle, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns),
                   comments="", fmt="%.10g")  # fmt: skip
        handle.write(trailer(meta or {}))


def write_curves(study: PaperStudy, out: Path) -> list[Path]:
    """Every curve as CSV (units in the column names), and each gain family as NetCDF (or .npz without xarray)."""
    e = study.estimate
    meta = {"rig": study.rig, "controller": study.pid, "seed": e.meta.get("seed")}
    written = [out / "effective.csv", out / "actual.csv"]
    _write_csv(written[0], {"freq_Hz": study.freq, "k_eff_N_per_m": study.k_eff, "c_eff_Ns_per_m": study.c_eff}, meta)
    _write_csv(written[1], {
        "freq_Hz": e.freq, "k_N_per_m": e.k, "c_Ns_per_m": e.c, "k_smooth_N_per_m": e.k_smooth,
        "c_smooth_Ns_per_m": e.c_smooth, "k_std_N_per_m": e.k_std, "c_std_Ns_per_m": e.c_std,
        "receptance_abs_m_per_N": np.abs(e.receptance), "receptance_phase_rad": np.angle(e.receptance),
    }, meta)  # fmt: skip
    suffix = _family_suffix()
    for name, result in study.families.items():
        columns = {"freq_Hz": result.freq}
        for j, gain in enumerate(result.points[name]):
            columns |= {f"k_smooth_N_per_m@{name}={gain:g}": result.k_smooth[j],
                        f"c_smooth_Ns_per_m@{name}={gain:g}": result.c_smooth[j],
                        f"receptance_abs_m_per_N@{name}={gain:g}": np.abs(1 / result.H[j])}  # fmt: skip
        path = out / f"family_{name}.csv"
        _write_csv(path, columns, {**meta, "seed": result.meta.get("seed"), "swept": name})
        result.save(out / f"family_{name}{suffix}")
        written += [path, out / f"family_{name}{suffix}"]
    return written


#: Resolution of the PNG figures (dots per inch).
DPI = 110


def write_figures(study: PaperStudy, out: Path) -> list[Path]:
    import matplotlib
    import matplotlib.pyplot as plt

    from .io import figure_metadata
    from .plots import plot_actual, plot_effective, plot_family, plot_overlay

    fn = claim_checks.natural_frequency(study.freq, study.estimate.H)
    zoom = (max(1.0, fn - 15.0), fn + 15.0)
    draws: list[Callable[[], Figure]] = [  # in the order of FIGURES
        lambda: plot_effective(study),
        lambda: plot_actual(study.estimate),
        lambda: plot_overlay(study.estimate, study.k_eff, study.c_eff),
        lambda: plot_family(study.families["ki"], "ki", inset=zoom),
        lambda: plot_family(study.families["ki"], "ki", zoom=zoom),
        lambda: plot_family(study.families["kd"], "kd", inset=zoom),
        lambda: plot_family(study.families["kd"], "kd", zoom=zoom),
        lambda: plot_family(study.families["kp"], "kp"),
    ]
    stamp = figure_metadata({"rig": study.rig, "controller": study.pid, "seed": study.estimate.meta.get("seed")})
    for name, draw in zip(FIGURES, draws):  # one at a time: drawn, saved, closed
        # Laid out at the resolution it is saved at: the layout measures the text with the renderer that savefig
        # then draws with, so savefig finds every text size (on log axes, mathtext) measured already.
        with matplotlib.rc_context({"figure.dpi": DPI}):
            fig = draw()
        with atomic_path(out / name) as target:
            fig.savefig(target, dpi=DPI, format="png", metadata=stamp)
        plt.close(fig)
    return [out / name for name in FIGURES]


def report(study: PaperStudy, table: str) -> str:
    rig, pid, ex = study.rig, study.pid, study.excitation
    stages = ("amp_bandwidth", "eddy_bandwidth", "sensor_bandwidth")
    lags = ", ".join(f"{n.replace('_', ' ')} {getattr(rig, n):g} Hz" for n in stages if getattr(rig, n))
    scales = ", ".join(f"{s:g}" for s in study.scales)
    rms = np.sqrt(np.mean(ex.samples**2))
    from . import __version__

    return f"""# Claims of the paper, checked on the virtual rig

amb_fast {__version__}; noise seed {study.estimate.meta.get("seed")} (families: seed + 1, + 2, + 3).

Rig: m = {rig.mass} kg (+ {rig.mass_loading} kg mass loading), Kyy = {rig.kyy} N/m, Kiy = {rig.kiy} N/A; {lags};
force transducer AC coupled with tau = {rig.force_coupling_tau} s; noise {rig.sensor_noise} m rms (probe),
{rig.force_noise} N rms (force); {rig.force_law} force law.
Controller: kp = {pid.kp} A/m, ki = {pid.ki} A/(m s), kd = {pid.kd} A s/m,
derivative filter {pid.derivative_cutoff} Hz, fs = {pid.fs} Hz, delay {pid.delay} samples.
Experiment: Schroeder multisine {ex.freq[0]:g}-{ex.freq[-1]:g} Hz, f0 = {ex.f0:g} Hz, {rms:.3g} N rms,
{study.estimate.periods} periods averaged, median filter over 5 lines. Gain families: each gain times {scales}.

{table}"""


def write_paper(out: Path, *, seed: int = 2026, progress: bool = True) -> list[claim_checks.Claim]:
    """Run the study and write figures, curves, ``claims.md``; print the claims table."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _say(progress, "[1/4] SPHS experiment on the paper rig, then the Ki, Kd and Kp families ...")
    study = paper_study(seed=seed, progress=False)
    _say(progress, f"[2/4] writing curves to {out} ...")
    write_curves(study, out)
    _say(progress, f"[3/4] drawing {len(FIGURES)} figures ...")
    write_figures(study, out)
    _say(progress, "[4/4] checking the paper's observations ...")
    claims = study.claims()
    table = claim_checks.markdown(claims)
    atomic_text(out / "claims.md", report(study, table))
    print(table)
    print(f"wrote {out}/: {', '.join(FIGURES)}, claims.md, effective.csv, actual.csv, "
          + ", ".join(f"family_{g}.csv/{_family_suffix()}" for g in GAINS))  # fmt: skip
    return claims
