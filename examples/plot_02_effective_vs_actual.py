"""
When can I trust the effective coefficients?
============================================

The *effective* stiffness and damping (paper eq. 5) follow from the controller alone:
``k_eff = Kyy + Kiy Re G(jw)`` and ``c_eff = Kiy Im G(jw) / w``. They are what a designer computes.
The *actual* ones come out of an experiment on the closed loop. On the paper's rig they agree at low
frequency and part above about 100 Hz, where the lags, the sampling and the transducer's moving mass
matter. The figure shows where the shortcut holds and by how much it misses elsewhere.
"""

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig, pid = af.Rig.paper(), af.PID.paper()
sphs = af.schroeder_multisine()
est = af.run_experiment(rig, pid, sphs, seed=1)
k_eff, c_eff = af.effective_coefficients(rig, pid, est.freq)

fig, (ax_k, ax_c) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
ax_k.plot(est.freq, k_eff / 1e3, label="effective (eq. 5, theoretical PID)")
ax_k.plot(est.freq, est.k_smooth / 1e3, label="actual (eq. 9, experiment)")
ax_k.set_ylabel("stiffness (kN/m)")
ax_k.legend()
ax_c.plot(est.freq, c_eff)
ax_c.plot(est.freq, est.c_smooth)
ax_c.set_ylabel("damping (N s/m)")
ax_c.set_xlabel("frequency (Hz)")
ax_c.set_yscale("symlog", linthresh=100)
for ax in (ax_k, ax_c):
    ax.set_xscale("log")
    ax.grid(True, which="both", alpha=0.3)
fig.tight_layout()

# %%
# The relative stiffness error, band by band:
for lo, hi in [(1, 10), (10, 100), (100, 200)]:
    band = (est.freq >= lo) & (est.freq <= hi)
    error = np.median(np.abs(est.k_smooth[band] - k_eff[band]) / np.abs(k_eff[band]))
    print(f"{lo:3d}-{hi:3d} Hz: median |k - k_eff| / |k_eff| = {100 * error:5.1f} %")
