"""
What does one identification experiment give me?
================================================

One call simulates the paper's experiment: a Schroeder-phased multisine (1-200 Hz, 1 N rms) drives the
platform of the suspended rig, the force and displacement are averaged over ten periods after the loop
has settled, and the dynamic stiffness ``H = F/Y`` at every excited line gives the *actual* stiffness
``k(f) = m w^2 + Re H`` and damping ``c(f) = Im H / w`` (paper eq. 9), each with its standard error.
"""

import amb_fast as af

rig, pid = af.Rig.paper(), af.PID.paper()
sphs = af.schroeder_multisine(f0=1.0, f_max=200.0, rms=1.0)
est = af.run_experiment(rig, pid, sphs, periods=10, seed=1)

print(f"{est.freq.size} lines, {est.periods} periods averaged, crest factor {sphs.crest_factor:.2f}")
for f in (1.0, 40.0, 200.0):
    j = int(f / sphs.f0) - 1
    print(f"{f:5.0f} Hz: k = {est.k[j] / 1e3:7.2f} +/- {est.k_std[j] / 1e3:.2f} kN/m, "
          f"c = {est.c[j]:8.1f} +/- {est.c_std[j]:.1f} N s/m")  # fmt: skip

# %%
# Raw estimates (grey, two standard errors) and the median-filtered curves, with the receptance
# ``|Y/F|``: its peak is the suspension's natural frequency, near 40 Hz.
fig = af.plot_estimate(est, title="Paper rig, one SPHS experiment (10 periods)")
