"""
Is my excitation small enough for the linear model?
===================================================

The magnet pair's force is non-linear in position and current; the linear coefficients hold for small
motion. A *random-odd* multisine excites only odd lines and leaves out one in every three of them, so
whatever appears at the other harmonics is noise or distortion (``Estimate.unexcited``). Here the
paper rig with the non-linear force law (``force_law="nonlinear"``, noise off) is excited at 1 N and at
4 N rms: the level at the unexcited lines, and the change of ``k(f)`` against the linearised law,
show how far from linear each run is.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

linear = replace(af.Rig.paper(), sensor_noise=0.0, force_noise=0.0)
nonlinear = replace(linear, force_law="nonlinear")
pid = af.PID.paper()
fig, ax = plt.subplots(figsize=(7, 4))
for rms, colour in [(1.0, "C0"), (4.0, "C3")]:
    sphs = af.schroeder_multisine(f_max=200.0, rms=rms, lines="random-odd", seed=0)
    est = af.run_experiment(nonlinear, pid, sphs, seed=1)
    reference = af.run_experiment(linear, pid, sphs, seed=1)
    gaps = est.unexcited
    ax.semilogy(est.freq, np.abs(est.displacement) / rms, "o", ms=3, color=colour,
                label=f"{rms:g} N rms: excited lines")  # fmt: skip
    ax.semilogy(gaps.freq, gaps.displacement / rms, "x", ms=3, color=colour, alpha=0.6,
                label=f"{rms:g} N rms: unexcited lines")  # fmt: skip
    distortion = gaps.displacement.max() / np.abs(est.displacement).max()
    shift = np.median(np.abs(est.k_smooth - reference.k_smooth) / np.abs(reference.k_smooth))
    peak = np.abs(af.simulate(nonlinear, pid, np.tile(sphs.samples, 3)).displacement).max()
    print(f"{rms:g} N rms: peak motion {peak * 1e6:.0f} um of the {nonlinear.gap * 1e6:.0f} um gap; "
          f"largest unexcited / excited line {100 * distortion:.2f} %; k moved {100 * shift:.2f} %")  # fmt: skip
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("displacement amplitude / force rms (m/N)")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
