"""
How does each gain move the stiffness and the damping?
======================================================

:func:`amb_fast.sweep` runs the experiment for many gain sets at once in the compiled core (on all
cores), bit for bit what :func:`amb_fast.run_experiment` gives for each. Here the derivative gain at
0.5x, 1x, 1.5x and 2x the paper's baseline: the damping at resonance grows with ``kd``, the stiffness
barely moves at low frequency and a lot at the top of the band.
"""

import numpy as np

import amb_fast as af

rig, pid = af.Rig.paper(), af.PID.paper()
sphs = af.schroeder_multisine()
family = af.sweep(rig, pid, sphs, kd=pid.kd * np.array([0.5, 1.0, 1.5, 2.0]), seed=1, progress=False)
print("status:", family.status)
peak = np.abs(1 / family.H).max(axis=1)
for kd, p in zip(family.points["kd"], peak):
    print(f"kd = {kd:4.1f} A s/m: peak |Y/F| = {p:.3e} m/N")

fig = af.plot_family(family, "kd")
