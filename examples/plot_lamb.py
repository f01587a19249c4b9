"""
Lamb's problem against Pekeris
==============================

A unit step point load on a traction-free plane (section 3.2 of Geubelle & Rice 1995),
on a 64 x 64 grid of the unit square. The opening at a station 8 cells from the load
is compared with the exact solution of Pekeris (1955): the P, S and Rayleigh arrivals
are at ``c_s t / r`` = 0.577, 1 and 1.088.
"""
import matplotlib.pyplot as plt
import numpy as np

import cracklab
from cracklab import Record
from cracklab.analysis.exact import lamb_arrivals, lamb_opening

r = 0.125  # 8 cells of 1/64 from the load at (0.5, 0.5)
scene = cracklab.scenes.lamb(n=64, t_end=0.3,
                             record=Record(fields=("delta_2",), every=16,
                                           stations={"A": (0.5 + r, 0.5)}))
ds = cracklab.simulate(scene)
a = cracklab.stations(ds).sel(station="A")

t = a.t.values
exact = np.array([lamb_opening(r, ti) if ti > 0 else 0.0 for ti in t])
print(f"{scene.nsteps} steps of dt = {scene.dt:.5f}")
print(f"opening at t = {t[-1]:.3f}: {a.delta_2[-1].item():.3f}, Pekeris {exact[-1]:.3f}")

fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
ax.plot(t / r, a.delta_2, label="cracklab, 64 x 64")
ax.plot(t / r, exact, "k--", label="Pekeris (1955)")
for tau, name in zip(lamb_arrivals(), "PSR"):
    ax.axvline(tau, color="0.6", lw=0.8, ls=":")
    ax.text(tau, 0.02, f" {name}", transform=ax.get_xaxis_transform(), color="0.4")
ax.set_xlabel("c_s t / r")
ax.set_ylabel("opening 2w (P / (mu r) units)")
ax.legend()
plt.show()
