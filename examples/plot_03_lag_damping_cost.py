"""
How much do the lags cost me in damping?
========================================

The controller's derivative term promises ``c_eff = Kiy Kd`` (filtered) of damping. Between the
controller and the platform sit the amplifier's current loop, the eddy-current lag of the force, the
probe's filter, and the sampling itself (a zero-order hold, half a sample of delay). Each adds phase
lag, and phase lag turns damping into stiffness. :func:`amb_fast.predict` gives the exact receptance
of the sampled-data loop, so the damping each lag costs is one line per case, with no noise.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

pid = af.PID.paper()
freq = np.arange(1.0, 401.0)
w = 2 * np.pi * freq
ideal = af.Rig()  # the paper's magnet pair with ideal amplifier, force and probe
cases = {
    "sampling only (ideal stages)": ideal,
    "+ amplifier 3 kHz": replace(ideal, amp_bandwidth=3000.0),
    "+ eddy currents 2 kHz": replace(ideal, amp_bandwidth=3000.0, eddy_bandwidth=2000.0),
    "+ probe 10 kHz (the paper rig's lags)": replace(
        ideal, amp_bandwidth=3000.0, eddy_bandwidth=2000.0, sensor_bandwidth=10_000.0
    ),
}
_, c_eff = af.effective_coefficients(ideal, pid, freq)

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(freq, c_eff, "k--", label="effective (no lags, continuous PID)")
for label, rig in cases.items():
    H = 1 / af.predict(rig, pid, freq)
    ax.plot(freq, H.imag / w, label=label)
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("damping c (N s/m)")
ax.set_ylim(-100, 250)
ax.grid(True, alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# At the natural frequency (about 40 Hz) and at 200 Hz, the damping left:
for f in (40.0, 200.0):
    j = int(f) - 1
    left = ", ".join(f"{(1 / af.predict(rig, pid, [f]))[0].imag / w[j]:.1f}" for rig in cases.values())
    print(f"{f:5.0f} Hz: effective {c_eff[j]:.1f} N s/m; actual, lag by lag: {left} N s/m")
