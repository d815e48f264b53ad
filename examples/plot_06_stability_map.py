"""
Which gains are stable, and in which ISO 14839-3 zone?
======================================================

Before running any experiment, :func:`amb_fast.stability_margin` gives the peak of the sensitivity
function ``|S| = 1/|1 + L|`` of the sampled-data loop and its ISO 14839-3 zone (A below 3, B below 4,
C below 5, D above or unstable). Mapped over proportional and derivative gains, it shows how much
room the paper's baseline gains (the cross) have.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig, base = af.Rig.paper(), af.PID.paper()
kps = np.linspace(1200.0, 4800.0, 13)
kds = np.linspace(0.5, 8.0, 11)
peak = np.array([[af.stability_margin(rig, replace(base, kp=kp, kd=kd), points=1000).peak for kp in kps]
                 for kd in kds])  # fmt: skip

fig, ax = plt.subplots(figsize=(7, 4.5))
mesh = ax.pcolormesh(kps, kds, np.clip(peak, 1, 6), shading="nearest", cmap="viridis_r")
contours = ax.contour(kps, kds, np.clip(peak, 1, 10), levels=[3, 4, 5], colors="w", linewidths=1)
ax.clabel(contours, fmt={3: "A|B", 4: "B|C", 5: "C|D"}, fontsize=8)
ax.plot(base.kp, base.kd, "rx", ms=10, mew=2)
fig.colorbar(mesh, label="peak |S| (clipped at 6; unstable = 6)")
ax.set_xlabel("kp (A/m)")
ax.set_ylabel("kd (A s/m)")
ax.set_title("Peak sensitivity of the paper rig's loop")
fig.tight_layout()

print("baseline:", af.stability_margin(rig, base))
print(f"unstable below kp = {-rig.kyy / rig.kiy:.0f} A/m (Kiy kp > -Kyy), and where the lags win")
