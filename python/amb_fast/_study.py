"""The paper's study on the virtual rig: one SPHS experiment, effective coefficients, Ki/Kd/Kp families."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import claims as claim_checks
from ._equality import ArrayRecord
from ._excitation import Multisine, schroeder_multisine
from ._experiment import Estimate, run_experiment
from ._linear import effective_coefficients
from ._params import PID, Rig
from ._sweep import sweep
from ._sweep_result import SweepResult
from ._validate import real, require

GAINS = ("ki", "kd", "kp")  # the paper's order: sections 3.2.1, 3.2.2, 3.2.3


@dataclass(frozen=True, eq=False)
class PaperStudy(ArrayRecord):
    """Everything the paper's figures and observations are made of.

    Attributes
    ----------
    rig, pid, excitation
        What was run.
    estimate : Estimate
        The baseline experiment (actual k, c; Fig. 5).
    k_eff, c_eff : ndarray
        Effective stiffness (N/m) and damping (N s/m) from the theoretical PID (paper eq. 5; Fig. 4).
    families : dict of str to SweepResult
        For "ki", "kd", "kp": the baseline gain times each of ``scales`` (Figs. 6-10).
    scales : tuple of float
    """

    rig: Rig
    pid: PID
    excitation: Multisine
    estimate: Estimate
    k_eff: np.ndarray
    c_eff: np.ndarray
    families: dict[str, SweepResult]
    scales: tuple[float, ...]

    @property
    def freq(self) -> np.ndarray:
        return self.estimate.freq

    def family_data(self) -> dict[str, dict[str, np.ndarray]]:
        """Per gain: ``gains`` and, one row per gain, ``k``, ``c`` (median filtered) and ``H`` (F/Y)."""
        return {name: {"gains": r.points[name], "k": r.k_smooth, "c": r.c_smooth, "H": r.H}
                for name, r in self.families.items()}  # fmt: skip

    def claims(self) -> list[claim_checks.Claim]:
        """Every observation of the paper, checked on this study's data."""
        e = self.estimate
        return claim_checks.check_all(self.freq, e.k_smooth, e.c_smooth, self.k_eff, self.c_eff, self.family_data())


def paper_study(
    rig: Rig | None = None,
    pid: PID | None = None,
    excitation: Multisine | None = None,
    *,
    scales: Sequence[float] = (0.67, 1.0, 1.5),
    periods: int = 10,
    seed: int = 2026,
    progress: bool | None = None,
) -> PaperStudy:
    """Run the paper's study: defaults are :meth:`Rig.paper`, :meth:`PID.paper` and the paper's SPHS
    (1-200 Hz, 1 Hz fundamental, 4 kHz, 1 N rms)."""
    rig = rig or Rig.paper()
    pid = pid or PID.paper()
    excitation = excitation or schroeder_multisine(fs=pid.fs)
    scales = tuple(sorted(real("scales", s, "x baseline", positive=True) for s in scales))
    require(len(scales) >= 3, "scales", scales, "at least three gain multipliers")
    estimate = run_experiment(rig, pid, excitation, periods=periods, seed=seed)
    k_eff, c_eff = effective_coefficients(rig, pid, estimate.freq)
    families = {name: sweep(rig, pid, excitation, **{name: getattr(pid, name) * np.array(scales)}, periods=periods,
                            seed=seed + 1 + j, progress=progress)
                for j, name in enumerate(GAINS)}  # fmt: skip
    for name, result in families.items():
        bad = result.status != "ok"
        if bad.any():
            raise ValueError(f"{name} family: point(s) {result.points[name][bad]} are {set(result.status[bad])}")
    return PaperStudy(rig, pid, excitation, estimate, k_eff, c_eff, families, scales)
