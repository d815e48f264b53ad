"""
Unbalance run-up through the first critical speed
=================================================

The example rotor (10 kg, bearings at +-0.2 m, probes 30 mm outboard) carries an unbalance of 100 g mm
(1e-4 kg m, about balance grade G2.5 at 3000 rev/min) 0.1 m from its centre of mass. Run up from
10 to 600 rad/s, the synchronous (1X) response of the sampled loop, exact at every speed: amplitude and
phase at the probes and the magnets' force on the rotor at each bearing. The phase turns through the
critical speeds as the amplitude peaks. Then one speed as a field record: the loop simulated from rest
with the rotating force (and the probes' noise), its 1X read back from the record as a tracking filter
does, against the exact response.
"""

import matplotlib.pyplot as plt
import numpy as np

import amb_fast as af

rig = af.RotorRig.example()
pid = af.RotorRig.example_controller()
unbalance = [(1e-4, 0.1, 0.0)]  # (m_e kg m, z m, phase rad)
speeds = np.linspace(10.0, 600.0, 300)  # rad/s
runup = af.unbalance_response(rig, pid, speeds, unbalance)
for name, speed, amplitude in runup.peaks:
    print(f"{name}: peak {1e6 * amplitude:.1f} um at {speed:.0f} rad/s ({speed * 60 / (2 * np.pi):.0f} rev/min)")

# %%
# A record at the first critical speed: 12 s from rest (the integrators settle within about 11 s), the
# 1X amplitude and phase fitted to the last 4 s (least squares on cos and sin of the spin angle).
first = runup.peaks[0][1]
trace = af.simulate(rig.at_speed(first), pid, np.zeros((48_000, 4)), unbalance=unbalance, seed=1)
k = np.arange(32_000, 48_000)
basis = np.c_[np.cos(first * k / trace.fs), -np.sin(first * k / trace.fs)]
re, im = np.linalg.lstsq(basis, trace.displacement[k], rcond=None)[0]
exact = af.unbalance_response(rig, pid, [first], unbalance).probes[0]
for j, name in enumerate(trace.axes):
    print(f"{name} at {first:.0f} rad/s: record {1e6 * abs(re[j] + 1j * im[j]):.3f} um "
          f"{np.degrees(np.angle(re[j] + 1j * im[j])):7.2f} deg, exact {1e6 * abs(exact[j]):.3f} um "
          f"{np.degrees(np.angle(exact[j])):7.2f} deg")  # fmt: skip

fig, ax = plt.subplots(4, 1, figsize=(7.0, 10.0))
rpm = speeds * 60 / (2 * np.pi)
for j, name in enumerate(("A.x", "B.x")):
    column = runup.probes[:, 2 * j]
    ax[0].plot(rpm, 1e6 * np.abs(column), color=f"C{j}", label=f"probe {name}")
    ax[1].plot(rpm, np.degrees(np.unwrap(np.angle(column))), color=f"C{j}", label=f"probe {name}")
    ax[2].plot(rpm, np.abs(runup.forces[:, 2 * j]), color=f"C{j}", label=f"bearing {name[0]}")
ax[2].plot(rpm, 1e-4 * speeds**2, "k:", label="unbalance force m_e W^2")
ax[0].axvline(first * 60 / (2 * np.pi), color="grey", lw=0.8)
ax[0].set_ylabel("1X amplitude (um)")
ax[1].set_ylabel("1X phase (deg)")
ax[2].set_ylabel("magnet force (N)")
ax[2].set_xlabel("speed (rev/min)")
for a in ax[:3]:
    a.legend(fontsize="small")
ax[0].set_title("Unbalance run-up of the sampled loop (y axes alike)")
t = trace.time[-800:]
ax[3].plot(t, 1e6 * trace.displacement[-800:, 0], ".", ms=2, color="C0", label="simulated record A.x")
ax[3].plot(t, 1e6 * np.real(exact[0] * np.exp(1j * first * np.arange(48_000)[-800:] / trace.fs)), "k-", lw=0.8,
           label="exact 1X")  # fmt: skip
ax[3].set_xlabel("time (s)")
ax[3].set_ylabel("probe A.x (um)")
ax[3].set_title(f"A record at {first:.0f} rad/s (last 0.2 s of 12 s, probe noise on)")
ax[3].legend(fontsize="small", loc="upper right")
fig.tight_layout()
plt.show()
