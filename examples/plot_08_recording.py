"""
From my rig's recording to k(f), c(f)
=====================================

A recording is a force channel (N) and a displacement channel (m) sampled at ``fs``. Here a simulated
run of the paper rig stands in for the real one: it is written as a CSV file the way a data logger
would, read back by channel name with :func:`amb_fast.load_recording`, and identified with
:func:`amb_fast.identify`, which needs only the sampling frequency, the multisine's fundamental and the
known mass. The first 25 periods, while the loop and the transducer settle, are skipped.
"""

import tempfile
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig, pid = af.Rig.paper(), af.PID.paper()
sphs = af.schroeder_multisine(f0=1.0, f_max=200.0)
run = af.simulate(rig, pid, np.tile(sphs.samples, 35), seed=3)  # 35 s at 4 kHz

folder = Path(tempfile.mkdtemp())
af.save_recording(folder / "rig.csv", force=run.force, displacement=run.displacement, fs=run.fs)
print((folder / "rig.csv").read_text()[:120])

rec = af.load_recording(folder / "rig.csv", force="force", displacement="displacement")
print(f"fs = {rec.fs:g} Hz (from the time column), {rec.force.size} samples")
est = af.identify(rec.force, rec.displacement, fs=rec.fs, f0=1.0, mass=0.92, settle_periods=25)
print(f"{est.freq.size} excited lines found from the force itself: {est.freq[0]:g}-{est.freq[-1]:g} Hz")

# %%
# A record cut mid-period is not an error: the incomplete period is dropped with a warning that says
# how many samples went.
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    af.identify(rec.force[:-1234], rec.displacement[:-1234], fs=rec.fs, f0=1.0, mass=0.92, settle_periods=25)
print("warning:", caught[0].message)

# %%
# The estimate against the exact receptance of the model the recording came from:
exact = 1 / af.predict(rig, pid, est.freq)
w = 2 * np.pi * est.freq
fig = af.plot_estimate(est, title="Identified from rig.csv")
fig.axes[0].plot(est.freq, (0.92 * w**2 + exact.real) / 1e3, "k:", label="exact (predict)")
fig.axes[1].plot(est.freq, exact.imag / w, "k:")
fig.axes[0].legend(fontsize=8)
plt.show()
