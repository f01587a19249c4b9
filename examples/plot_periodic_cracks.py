"""
A periodic row of mode III cracks
=================================

The plane (2D, ``n3 = 1``) problem: a row of cracks of half length 0.25 in the unit
period, slipping under an anti-plane shear load that is raised smoothly over 1.5 time
units and then held. Once the waves have left, the slip settles on the exact static
solution of the periodic row (``cracklab.analysis.exact.periodic_row_opening``).
"""
import matplotlib.pyplot as plt
import numpy as np

import cracklab
from cracklab import Loading, Record
from cracklab.analysis.exact import periodic_row_opening

t_end = 2.5
scene = cracklab.scenes.periodic_cracks(n=128, c=0.25, mode="III", t_end=t_end,
                                        record=Record(fields=("delta_3",), times=(1.0, 1.5, t_end)))
load = Loading(tau0_3=scene.loading.tau0_3, time="smooth", ramp_time=1.5)
ds = cracklab.simulate(scene.replace(loading=load))

x = scene.grid.x1 - 0.5
c_grid = np.count_nonzero(np.abs(x) <= 0.25) / 2 * scene.grid.dx1  # the crack as the grid sees it
exact = periodic_row_opening(x, c_grid, 1.0, 1.0, 1.0, 0.25, "III")
slip = ds.delta_3.isel(x3=0)
print(f"{scene.nsteps} steps; centre slip at t = {t_end}: {slip.isel(t=-1)[64].item():.4f}, "
      f"exact static {exact[64]:.4f}")

fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
for t in slip.t.values:
    ax.plot(scene.grid.x1, slip.sel(t=t), label=f"t = {t:g}")
ax.plot(scene.grid.x1, exact, "k--", label="exact, static")
ax.set_xlabel("x1")
ax.set_ylabel("slip delta_3")
ax.set_title("Periodic row of mode III cracks, 128 nodes per period")
ax.legend()
plt.show()
