"""
How many periods must I average?
================================

With probe and force-transducer noise, each period of the multisine gives a noisy estimate; averaging
``P`` periods shrinks the error like ``1/sqrt(P)``. ``Estimate.k_std`` and ``c_std`` come from the
period-to-period scatter of the same run, so one experiment tells you whether it was long enough.
Here the paper rig with ten times its noise, averaged over 2 to 64 periods, four runs each: the
reported standard error against the actual error from the exact answer (:func:`amb_fast.predict`).
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig = replace(af.Rig.paper(), sensor_noise=200e-9, force_noise=10e-3)
pid, sphs = af.PID.paper(), af.schroeder_multisine()
exact = 1 / af.predict(rig, pid, sphs.freq)
k_exact = rig.mass * (2 * np.pi * sphs.freq) ** 2 + exact.real
periods = np.array([2, 4, 8, 16, 32, 64])
reported, actual = [], []
for p in periods:
    runs = [af.run_experiment(rig, pid, sphs, periods=int(p), seed=seed) for seed in range(4)]
    k_std = np.mean([est.k_std for est in runs], axis=0)
    k_err = np.sqrt(np.mean([(est.k - k_exact) ** 2 for est in runs], axis=0))
    reported.append(100 * np.median(k_std / np.abs(k_exact)))
    actual.append(100 * np.median(k_err / np.abs(k_exact)))
    print(f"{p:3d} periods ({p * sphs.period_samples / pid.fs:3.0f} s): median k_std/|k| = {reported[-1]:.2f} %, "
          f"actual rms error {actual[-1]:.2f} %")  # fmt: skip

fig, ax = plt.subplots(figsize=(7, 4))
ax.loglog(periods, reported, "o-", label="reported standard error, k_std")
ax.loglog(periods, actual, "s-", label="actual rms error against predict")
ax.loglog(periods, actual[0] * np.sqrt(periods[0] / periods), "k:", label="1/sqrt(P)")
ax.set_xlabel("periods averaged P")
ax.set_ylabel("median over lines, % of |k|")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
