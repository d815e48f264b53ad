"""
Campbell diagram of a rotor under the digital loop
==================================================

A 10 kg rigid rotor on two of the paper's magnet pairs, probes 30 mm outboard of the bearings, a PID
per axis at 4 kHz. The Campbell diagram is made of the closed-loop poles of the sampled loop (hold,
amplifier and eddy-current lags, the digital PID) at each speed: the conical mode splits into forward
and backward whirl as the gyroscopic coupling grows; the parallel mode does not move.
"""

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig = af.RotorRig.example()
pid = af.RotorRig.example_controller()
speeds = np.linspace(0.0, 6000.0, 121)  # rad/s, to about 57,000 rev/min
campbell = af.campbell(rig, pid, speeds)
print("unstable from", campbell.onset_speed, "rad/s" if campbell.onset_speed is not None else "(stable at every speed)")

# %%
# The whirling modes below 100 Hz at standstill and at the top speed: frequency, damping ratio, whirl.
for i in (0, -1):
    shown = (campbell.whirl[i] != 0) & (campbell.damping[i] < 0.9)
    rows = sorted({(round(f, 2), round(d, 3), int(w)) for f, d, w in zip(campbell.frequency[i][shown],
                   campbell.damping[i][shown], campbell.whirl[i][shown]) if f < 100})  # fmt: skip
    print(f"{speeds[i]:6.0f} rad/s:", ", ".join(f"{f} Hz (damping {d}, {'forward' if w > 0 else 'backward'})"
                                               for f, d, w in rows))  # fmt: skip

ax = campbell.plot(max_frequency=100.0)
plt.show()
