"""
A scene written in TOML
=======================

A scene is data: the same Kostrov problem as in docs/guide/getting_started.md, a plane
mode III crack forced to grow at 0.7 c_s from a line, written as TOML text, read
with ``cracklab.Scene.from_toml`` and run. The slip at the centre grows as Kostrov's
self-similar solution (``cracklab.analysis.exact.kostrov_slip``).
"""
import matplotlib.pyplot as plt

import cracklab
from cracklab.analysis.exact import kostrov_slip

TOML = """
name = "kostrov"
t_end = 0.2
beta = 0.5

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 256
n3 = 1
L1 = 1.0
L3 = 1.0

[law]
kind = "prescribed_rupture"
speed = 0.7
origin = [0.5, 0.0]
residual = 0.0
weakening_time = 0.01

[loading]
tau0_3 = 1.0

[record]
fields = ["delta_3"]
every = 10
stations = { centre = [0.5, 0.0] }
"""

scene = cracklab.Scene.from_toml(TOML)
ds = cracklab.simulate(scene)
centre = cracklab.stations(ds).sel(station="centre")
exact = kostrov_slip(0.0, centre.t.values, 0.7, 1.0, 1.0)
print(scene.formulation, scene.nsteps, "steps")
print(f"centre slip at t = {centre.t[-1].item():.3f}: {centre.delta_3[-1].item():.4f}, "
      f"Kostrov {exact[-1]:.4f}")

fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
ax.plot(centre.t, centre.delta_3, label="cracklab, 256 nodes")
ax.plot(centre.t, exact, "k--", label="Kostrov (self-similar)")
ax.set_xlabel("t")
ax.set_ylabel("slip delta_3 at the centre")
ax.legend()
plt.show()
