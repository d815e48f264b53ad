"""
ISO 14839-3 sensitivity of a rotor, measured and exact
======================================================

Commissioning grades each axis of a magnetic bearing by the peak of its sensitivity function, measured
with a test signal added to that axis' sensor signal before the controller (ISO 14839-3): zone A below
3 (9.5 dB), B below 4, C below 5, D above. Here the example rotor spins at 1000 rad/s; each axis in turn
gets a 1 um rms multisine, the probes' 20 nm of noise on, 10 periods. The measured ``|Gs|`` of each axis
(with its 95 % interval) lies on the exact sensitivity at the sensors of the sampled loop.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

import amb_fast as af

rig = af.RotorRig.example(speed=1000.0)
pid = af.RotorRig.example_controller()
test_signal = af.schroeder_multisine(f0=2.0, f_max=1000.0, rms=1e-6)  # m, added to each sensor's signal
measured = af.measure_sensitivity(rig, pid, test_signal, periods=10, seed=1)
print(measured.table())

# %%
# The exact sensitivity at the sensors, ``(I - P K)^-1`` of the sampled loop, at the same lines and on a
# fine grid for each axis' true peak (the lines are 2 Hz apart: the measured peak is at a line).
exact = af.sensitivity(rig, pid, measured.freq, at="sensors")
fine = np.geomspace(1.0, 1000.0, 3000)
diagonal = np.abs(np.diagonal(af.sensitivity(rig, pid, fine, at="sensors"), axis1=1, axis2=2))
for j, (name, peak) in enumerate(zip(measured.axes, measured.peak)):
    top = int(np.argmax(diagonal[:, j]))
    print(f"{name}: measured peak {peak:.3f}, exact {diagonal[top, j]:.3f} at {fine[top]:.1f} Hz")
t95 = stats.t.ppf(0.975, measured.periods - 1)
inside = np.abs(np.abs(measured.S) - np.abs(exact)) <= t95 * measured.S_std
print(f"95 % intervals covering the exact |Gs|: {inside.mean():.1%} of {inside.size} (lines x 16 entries)")

fig, ax = plt.subplots(figsize=(7.0, 4.5))
for limit, (zone, colour) in zip((3.0, 4.0, 5.0, 8.0), (("A", "#d8f0d8"), ("B", "#f7f3c8"), ("C", "#fbe0c4"),
                                                          ("D", "#f6cccc"))):  # fmt: skip
    ax.axhspan({3.0: 0.0, 4.0: 3.0, 5.0: 4.0, 8.0: 5.0}[limit], limit, color=colour, zorder=0)
    ax.text(2.2, limit - 0.1, f"zone {zone}", ha="left", va="top", fontsize="small")
for j, name in enumerate(measured.axes):
    ax.plot(measured.freq, np.abs(exact[:, j, j]), color=f"C{j}", lw=1)
    ax.errorbar(measured.freq[::4], np.abs(measured.S[::4, j, j]), yerr=t95 * measured.S_std[::4, j, j],
                fmt=".", color=f"C{j}", ms=3, label=f"{name} measured (every 4th line), exact: line")  # fmt: skip
ax.plot(measured.freq, measured.sigma_max, "k--", lw=1, label="largest singular value (measured)")
ax.set_xscale("log")
ax.set_xlim(2.0, 1000.0)
ax.set_ylim(0.0, 6.0)
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("|Gs|")
ax.set_title("ISO 14839-3 sensitivity of the rotor at 1000 rad/s")
ax.legend(loc="upper right", fontsize="x-small", bbox_to_anchor=(1.0, 0.9))
plt.show()
