"""
Bearing coefficients of a spinning rotor, the bearings as exciters
==================================================================

A seal 0.1 m from the centre of the example rotor (10 kg, bearings at +-0.2 m) couples x and y:
``kxy = -kyx = 20 kN/m``, ``cxy = -cyx = 20 N s/m``; at bearing B that is 11.25 kN/m and 11.25 N s/m. The
rotor spins at 2000 rad/s. Nobody bolts a shaker to a spinning shaft: the magnetic bearings excite it
themselves (``exciter="amb"``: 1 A rms added to each axis' current command after the controller) and the
force on the rotor is estimated from each coil's current and probe, ``F = -kyy d - kiy i``.

The raw ``k`` of that estimate is far off at 200 Hz: the coil current at the sample instants stands for
the force held over the sample, half a sample late, and the rotor's gyroscopic coupling at this speed is
large. ``est.process`` removes the hold and the known lags, and gives the seal back to its noise (the
error bars: 95 % of ``est.k``'s standard errors; the correction scales them by about 1). The shaker
experiment (47 N rms, the force the magnets put in) measures the bearings' coefficients with the magnets:
their cross-coupled entry carries the sampled loop's effect on the gyroscopic coupling too (-26 kN/m at
200 Hz, exactly what ``af.predict`` gives, against 8.6 kN/m at standstill).

Every axis has the paper's chain, its 2 kHz eddy-current lag included: the force follows the coil current
through that lag, which the raw estimate cannot see and ``est.process`` removes as the model knows it.
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

seal = (0.1, 2e4, -2e4, 20.0, -20.0)  # z (m), kxy, kyx (N/m), cxy, cyx (N s/m)
rotor = replace(af.RotorRig.example().rotor, speed=2000.0, process=(seal,))
rig = af.RotorRig(rotor, af.Rig.paper())
pid = af.RotorRig.example_controller()

amb = af.run_experiment(rig, pid, af.schroeder_multisine(f0=5.0, f_max=200.0, rms=1.0), exciter="amb",
                        periods=40, seed=1)  # fmt: skip
shaker = af.run_experiment(rig, pid, af.schroeder_multisine(f0=5.0, f_max=200.0, rms=47.0), periods=40, seed=1)

# %%
# The true process at the bearing planes, and B.x <- B.y (index 2, 3) from each estimate.
mech = rig.mechanics()
f = amb.freq
w = 2 * np.pi * f
true = mech.at_bearings(mech.stiffness)[2, 3], mech.at_bearings(mech.damping)[2, 3]
process = amb.process[:, 2, 3]
for j in (9, 19, 39):
    print(
        f"{f[j]:5.0f} Hz  kxy: true {true[0]:.0f}, est.process {process[j].real:.0f} +- "
        f"{amb.k_std[j, 2, 3]:.0f}, raw AMB {amb.k[j, 2, 3]:.0f}, shaker {shaker.k[j, 2, 3]:.0f} N/m"
    )

fig, (ax_k, ax_c) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
for ax, value, unit in ((ax_k, 0, "N/m"), (ax_c, 1, "N s/m")):
    pick = (lambda x: x.real) if value == 0 else (lambda x: x.imag / w)
    ax.axhline(true[value], color="k", lw=1, label="true process")
    ax.errorbar(f, pick(process), yerr=1.96 * (amb.k_std if value == 0 else amb.c_std)[:, 2, 3], fmt="o", ms=3,
                label="bearings as exciters: est.process")  # fmt: skip
    ax.plot(f, (amb.k if value == 0 else amb.c)[:, 2, 3], "--", label="bearings as exciters: raw k, c")
    ax.plot(f, (shaker.k if value == 0 else shaker.c)[:, 2, 3], ":", label="shakers: k, c")
    ax.set_ylabel(f"B: {'k' if value == 0 else 'c'}xy ({unit})")
ax_c.set_xlabel("frequency (Hz)")
ax_k.legend(fontsize=8)
ax_k.set_title("Cross-coupled coefficients at bearing B, 2000 rad/s")
plt.show()
