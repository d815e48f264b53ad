"""
Where do the closed-loop poles go as the derivative gain grows?
===============================================================

:func:`amb_fast.closed_loop_poles` gives the poles of the linearised sampled-data loop in the z-plane;
``log(z) fs`` maps them to equivalent continuous-time poles, here in Hz. The suspension mode (near
40 Hz on the paper rig) gains damping as ``kd`` grows until its two poles meet on the real axis and
split: the mode is then critically damped, and one of the two real poles slows down again. Too little
``kd`` leaves the mode with negative damping: the loop is unstable.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig, base = af.Rig.paper(), af.PID.paper()
kds = np.linspace(0.5, 12.0, 47)
fig, (ax_s, ax_r) = plt.subplots(1, 2, figsize=(9, 4))
zeta, stable = [], []
for kd in kds:
    z = af.closed_loop_poles(rig, replace(base, kd=kd))
    stable.append(bool(np.all(np.abs(z) < 1)))
    s = np.log(z.astype(complex)) * base.fs / (2 * np.pi)  # Hz
    slow = s[np.abs(s) < 150]
    ax_s.plot(slow.real, slow.imag, ".", ms=4, color=plt.cm.viridis(kd / kds.max()))
    mode = s[np.argmin(np.abs(np.abs(s) - 40.0))]  # the pole nearest 40 Hz
    zeta.append(-mode.real / abs(mode))
ax_s.axvline(0, color="k", lw=0.8)
ax_s.set_xlabel("Re s / 2 pi (Hz)")
ax_s.set_ylabel("Im s / 2 pi (Hz)")
ax_s.set_title("poles below 150 Hz, kd 0.5 (dark) to 12 A s/m", fontsize=10)
ax_s.grid(True, alpha=0.3)
ax_r.plot(kds, zeta)
ax_r.axhline(0, color="k", lw=0.8)
ax_r.axvline(base.kd, color="0.6", ls=":", label=f"PID.paper(): kd = {base.kd:g} A s/m")
ax_r.set_xlabel("kd (A s/m)")
ax_r.set_ylabel("damping ratio of the suspension mode")
ax_r.grid(True, alpha=0.3)
ax_r.legend(fontsize=8)
fig.tight_layout()

print(f"stable from kd = {kds[np.argmax(stable)]:.2f} A s/m (all |z| < 1)")
critical = kds[np.argmax(np.array(zeta) > 0.999)]
print(f"damping ratio {zeta[np.argmin(np.abs(kds - base.kd))]:.2f} at the baseline; critically damped from kd = "
      f"{critical:.1f} A s/m")  # fmt: skip
