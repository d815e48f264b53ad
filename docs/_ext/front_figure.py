"""The start page's figure: the actual stiffness of the paper's rig against the effective one.

The documentation build draws it on ``index.md`` (the plot directive runs this file); the README shows
a copy, ``docs/images/actual_vs_effective.png``, written by::

    python -c "import runpy, matplotlib; matplotlib.use('Agg'); runpy.run_path('docs/_ext/front_figure.py');
    import matplotlib.pyplot as plt; plt.savefig('docs/images/actual_vs_effective.png', dpi=100)"
"""

from __future__ import annotations

import matplotlib.pyplot as plt

import amb_fast as af

rig, pid = af.Rig.paper(), af.PID.paper()
est = af.run_experiment(rig, pid, af.schroeder_multisine(f0=1.0, f_max=200.0), periods=10, seed=1)
k_eff, _ = af.effective_coefficients(rig, pid, est.freq)
fig, ax = plt.subplots(figsize=(8, 3.4))
ax.plot(est.freq, k_eff / 1e3, lw=2, label="effective (eq. 5: the PID alone)")
ax.plot(est.freq, est.k / 1e3, ".", ms=3, color="0.6", label="actual, each line (eq. 9: the experiment)")
ax.plot(est.freq, est.k_smooth / 1e3, lw=2, label="actual, median filtered")
ax.set(xscale="log", xlabel="frequency (Hz)", ylabel="stiffness (kN/m)")
ax.set_title("The paper's rig: actual against effective stiffness")
ax.grid(True, which="both", alpha=0.3)
ax.legend(loc="upper left")
fig.tight_layout()
