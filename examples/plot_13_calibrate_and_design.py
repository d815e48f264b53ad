"""
How do I calibrate the virtual rig, predict untried gains and design for the actual k, c?
=========================================================================================

A rig whose lags we do not know is recorded under two gain sets. We fit the virtual rig to the two
estimates (:func:`amb_fast.calibration.fit_rig`), predict what a third, untried gain set will give with
error bars, choose gains for a target *actual* stiffness and damping
(:func:`amb_fast.calibration.design_controller`), and check the design by simulating it on the rig.
"""

# %%
# The "real" rig: hidden lags
# ---------------------------
# The paper's rig, but with a slower amplifier, a 70 us dead time and other magnets than the nominal
# values. We pretend not to know any of this: we only see its recordings.
from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

import amb_fast as af
from amb_fast.calibration import design_controller, fit_rig

hidden = replace(af.Rig.paper(), kyy=-51e3, kiy=46.5, amp_bandwidth=1800.0, dead_time=70e-6, mass_loading=0.07,
                 force_coupling_tau=1.3)  # fmt: skip
sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
baseline, second = af.PID.paper(), replace(af.PID.paper(), kp=3000.0, kd=2.2)


def record(pid: af.PID, seed: int) -> af.Estimate:
    """45 s from rest; the first 25 periods let the transducer's coupling settle, 20 are averaged."""
    trace = af.simulate(hidden, pid, np.tile(sphs.samples, 45), seed=seed)
    return af.identify(trace.force, trace.displacement, fs=4000.0, f0=1.0, mass=0.92, f_max=200.0,
                       settle_periods=25)  # fmt: skip


measured = [record(baseline, 1), record(second, 2)]

# %%
# Calibrate
# ---------
# Start from the nominal rig (the paper's values, no dead time) and fit the magnets, the amplifier,
# the dead time, the mass loading and the transducer's time constant to both estimates at once.
nominal = af.Rig.paper()
fit = fit_rig(measured, nominal, [baseline, second],
              free=["kyy", "kiy", "amp_bandwidth", "dead_time", "mass_loading", "force_coupling_tau"])  # fmt: skip
print(fit.report())

# %%
# The report names the amplifier bandwidth and the dead time as not separately identifiable: on
# 1-200 Hz both are a phase lag growing with frequency. Their combination is well determined, and so is
# everything predicted from it, as the error bands below show.
#
# Predict an untried gain set
# ---------------------------
untried = replace(baseline, kp=2000.0, ki=10000.0, kd=4.0)
freq = measured[0].freq
k_pred, c_pred, k_std, c_std = fit.coefficients(untried, freq)
check = af.run_experiment(hidden, untried, sphs, periods=20, seed=3)
combined = np.hypot(check.k_std, k_std)
t = stats.t.ppf(0.975, check.blocks - 1)  # k_std has blocks - 1 degrees of freedom: Student's t, not 1.96
print(f"untried gains: {np.mean(np.abs(check.k - k_pred) <= t * combined):.1%} of lines within the 95 % band (k)")

# %%
# Design for the actual stiffness and damping
# -------------------------------------------
# Target 60 kN/m and 150 N s/m on 20-150 Hz, with the sensitivity peak in ISO zone A (``|S| < 3``), starting
# from a well-damped controller inside that zone. The naive design matches the effective coefficients
# (paper eq. 5) instead, as if there were no lags.
band = np.arange(20.0, 151.0)
start = replace(baseline, kd=6.0)
print(f"start: peak |S| = {af.stability_margin(fit.rig, start).peak:.2f}")
design = design_controller(fit.rig, start, freq=band, stiffness=6e4, damping=150.0, max_sensitivity=3.0)
naive = design_controller(fit.rig, start, freq=band, stiffness=6e4, damping=150.0, max_sensitivity=3.0,
                          basis="effective")  # fmt: skip
print(design.report())
print("naive gains:", {n: round(v, 4) for n, v in naive.params.items()})
verify = af.run_experiment(hidden, design.controller, sphs, periods=20, seed=4)
naive_run = af.run_experiment(hidden, naive.controller, sphs, periods=20, seed=5)

# %%
# The figure
# ----------
fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True, constrained_layout=True)
for est, pid, colour in zip(measured, (baseline, second), ("C0", "C1")):
    k, c, ks, cs = fit.coefficients(pid, freq)
    k_eff, c_eff = af.effective_coefficients(fit.rig, pid, freq)
    axes[0, 0].plot(freq, est.k, ".", ms=2, color=colour, label=f"measured kp={pid.kp:g}, kd={pid.kd:g}")
    axes[0, 0].fill_between(freq, k - 1.96 * ks, k + 1.96 * ks, color=colour, alpha=0.3)
    axes[0, 0].plot(freq, k, color=colour, lw=1, label="calibrated (95 % band)")
    axes[0, 0].plot(freq, k_eff, "--", color=colour, lw=1, label="effective (eq. 5)")
    axes[0, 1].plot(freq, est.c, ".", ms=2, color=colour)
    axes[0, 1].fill_between(freq, c - 1.96 * cs, c + 1.96 * cs, color=colour, alpha=0.3)
    axes[0, 1].plot(freq, c, color=colour, lw=1)
    axes[0, 1].plot(freq, c_eff, "--", color=colour, lw=1)
axes[0, 0].set(title="Calibration: stiffness", ylabel="k (N/m)")
axes[0, 1].set(
    title="Calibration: damping (the 95 % bands are narrower than the lines)", ylabel="c (N s/m)", ylim=(-200, 400)
)
axes[0, 0].legend(fontsize=7)

ax = axes[1, 0]
ax.plot(freq, check.k, ".", ms=2, color="C2", label="untried gains, simulated on the rig")
ax.fill_between(freq, k_pred - 1.96 * k_std, k_pred + 1.96 * k_std, color="C2", alpha=0.3)
ax.plot(freq, k_pred, color="C2", lw=1, label="predicted from the calibration (95 % band)")
ax.plot(freq, af.effective_coefficients(fit.rig, untried, freq)[0], "--", color="C2", lw=1, label="effective")
ax.set(title="Prediction at kp=2000, ki=10000, kd=4", xlabel="f (Hz)", ylabel="k (N/m)")
ax.legend(fontsize=7)

ax = axes[1, 1]
ax.axhline(150.0, color="k", lw=0.8, label="target")
ax.plot(band, design.c, color="C3", label="design: predicted actual c")
ax.plot(verify.freq, verify.c, ".", ms=2, color="C3", label="design: simulated on the rig")
ax.plot(naive_run.freq, naive_run.c, ".", ms=2, color="C7", label="naive design: simulated")
ax.set(title="Designed for c = 150 N s/m on 20-150 Hz", xlabel="f (Hz)", ylabel="c (N s/m)", ylim=(-100, 400))
ax.legend(fontsize=7)
plt.show()
