"""
Actual and effective bearing coefficients of a spinning rotor
=============================================================

The example rotor (10 kg, magnets at +-0.2 m, probes 30 mm outboard) spins at 1000 rad/s; four shakers
excite it through the bearing planes with Hadamard signs, and ``H = F Y^-1`` per line gives the 4x4
actual coefficients at the bearing planes with the rotor's own inertia and gyroscopics removed (the
paper's eq. 9). The effective coefficients come from the controllers' transfer functions (paper eq. 5
per entry): the direct terms part from the actual ones with frequency as on the paper's platform (the
amplifier's and eddy currents' lags, the hold), and the cross-bearing terms (A.x from B.x) are not zero,
because each bearing's controller reads a probe that sees both bearings' motion.
"""

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig = af.RotorRig.example(speed=1000.0)
pid = af.RotorRig.example_controller()
est = af.run_experiment(rig, pid, af.schroeder_multisine(f0=1.0, f_max=200.0), periods=10, seed=1)
k_eff, c_eff = af.effective_coefficients(rig, pid, est.freq)

# %%
# Bearing A's x axis at a few lines: actual (with its standard error) against effective.
for f in (10.0, 50.0, 100.0, 200.0):
    j = int(np.argmin(np.abs(est.freq - f)))
    print(f"{est.freq[j]:5.0f} Hz  k[A.x, A.x] {est.k[j, 0, 0] / 1e3:7.1f} +- {est.k_std[j, 0, 0] / 1e3:.1f} kN/m "
          f"(effective {k_eff[j, 0, 0] / 1e3:7.1f})   c[A.x, A.x] {est.c[j, 0, 0]:6.1f} N s/m "
          f"(effective {c_eff[j, 0, 0]:6.1f})   k[A.x, B.x] {est.k[j, 0, 2] / 1e3:6.1f} kN/m "
          f"(effective {k_eff[j, 0, 2] / 1e3:6.1f})")  # fmt: skip

# %%
# The direct terms and the x-plane cross terms between the bearings, actual (solid, +-2 s.e.) and
# effective (dashed).
fig = est.plot(terms=[("A.x", "A.x"), ("B.x", "B.x"), ("A.x", "B.x"), ("B.x", "A.x")], effective=(k_eff, c_eff))
plt.show()
