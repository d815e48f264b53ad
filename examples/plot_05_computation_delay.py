"""
What does one sample of computation delay cost?
===============================================

The paper's DS1103 computes its PID within microseconds of the sample (``PID.paper()`` has
``delay=0``). A slower controller applies its output one or more samples late (``PID.delay``). Each
sample at 4 kHz is 90 degrees of phase at 1 kHz and 18 degrees at 200 Hz: the figure shows the
damping it takes away and what it does to the stability margin.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig = replace(af.Rig.paper(), force_coupling_tau=None, mass_loading=0.0)  # the loop alone
freq = np.arange(1.0, 301.0)
w = 2 * np.pi * freq
fig, ax = plt.subplots(figsize=(7, 4))
for delay in (0, 1, 2):
    pid = replace(af.PID.paper(), delay=delay)
    margin = af.stability_margin(rig, pid, points=4000)
    H = 1 / af.predict(rig, pid, freq)
    ax.plot(freq, H.imag / w, label=f"delay {delay}: peak |S| {margin.peak:.2f} (zone {margin.zone})")
    print(f"delay {delay} samples: c(40 Hz) = {H.imag[39] / w[39]:.1f} N s/m, peak |S| = {margin.peak:.2f} "
          f"at {margin.frequency:.0f} Hz, zone {margin.zone}")  # fmt: skip
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("actual damping c (N s/m)")
ax.grid(True, alpha=0.3)
ax.legend()
fig.tight_layout()
