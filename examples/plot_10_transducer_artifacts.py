"""
Why does my measured stiffness fall at high frequency and rise at low frequency?
================================================================================

Two properties of the force measurement, not of the bearing, bend the actual stiffness of eq. 9:

* **mass loading**: the part of the force transducer and stinger between its sensing element and
  the platform moves with the platform, but eq. 9 subtracts only the known mass, so ``k(f)`` shows
  ``-dm w^2`` (``Rig.mass_loading``);
* **AC coupling**: a piezoelectric transducer forgets its DC level with a time constant ``tau``; at the
  lowest lines it leads the force, and the integral action turns that into apparent stiffness
  (``Rig.force_coupling_tau``).

:func:`amb_fast.predict` includes both exactly, so each can be switched off to see its share.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

pid = af.PID.paper()
freq = np.arange(1.0, 201.0)
w = 2 * np.pi * freq
paper = af.Rig.paper()
cases = {
    "paper rig (60 g loading, tau = 1 s)": paper,
    "no mass loading": replace(paper, mass_loading=0.0),
    "DC-coupled transducer": replace(paper, force_coupling_tau=None),
    "neither": replace(paper, mass_loading=0.0, force_coupling_tau=None),
}
k_eff, _ = af.effective_coefficients(paper, pid, freq)
fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(freq, k_eff / 1e3, "k--", label="effective (eq. 5)")
for label, rig in cases.items():
    H = 1 / af.predict(rig, pid, freq)
    ax.plot(freq, (paper.mass * w**2 + H.real) / 1e3, label=label)
ax.set_xscale("log")
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("actual stiffness k (kN/m)")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()

print(f"-dm w^2 at 200 Hz: {-0.06 * w[-1] ** 2 / 1e3:.1f} kN/m")
