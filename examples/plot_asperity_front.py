"""
A crack front meeting tough asperities
======================================

The section 4 problem of Geubelle & Rice (1995) on a coarse grid (128 x 64): a mode I
crack under a constant stress intensity runs into a row of circular asperities three
times as tough as the rest of the plane (``cracklab.scenes.asperity_row``). The front
is held back where it meets them and bows out between them.
``cracklab.analysis.front_position`` finds the front from the rupture time, and
``cracklab.plots.rupture_contours`` draws the rupture time over the toughness.
"""
import matplotlib.pyplot as plt

import cracklab
import cracklab.plots
from cracklab.analysis import front_position, mean_crack_length

scene = cracklab.scenes.asperity_row(n1=128, n3=64, t_end=3.0)
ds = cracklab.simulate(scene)

# %%
# The front x1_f(t, x3) from the rupture time (when each point first failed),
# and its mean over x3.
front = front_position(ds)
length = mean_crack_length(front)
print(f"{scene.nsteps} steps on {scene.grid.n1} x {scene.grid.n3}; {ds.sizes['t']} snapshots")
print(f"mean crack length {length[0].item():.3f} -> {length[-1].item():.3f}")

# %%
# The front every fourth snapshot: held back by the two asperities, ahead between them.
fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
for t in front.t.values[::4]:
    ax.plot(front.x3, front.sel(t=t), color=plt.cm.viridis(t / scene.t_end))
ax.set_xlabel("x3")
ax.set_ylabel("front position x1_f")
ax.set_title("The front every 4 snapshots (colour: time)")

# %%
# The rupture time over the toughness (greys: tau_c, the asperities darker).
cracklab.plots.rupture_contours(ds, levels=8)
plt.show()
