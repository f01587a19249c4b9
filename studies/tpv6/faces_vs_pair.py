"""TPV6's scene with the near side's rock on both sides, through the pair's kernels
(Identical) and through the two faces (the top's mu 1e-6 larger, so the scene runs the
bimaterial path): each station's peak slip rate and final slip, side by side.

    python studies/tpv6/faces_vs_pair.py DX [T_END]

docs/studies/tpv6.md ("Discussion") quotes its output at 400, 200 and 100 m: it tells whether the
faces' machinery or the contrast of materials makes the peak slip rate grow with the grid.
"""
from __future__ import annotations

import sys
import time

import cracklab
from cracklab import scenes
from cracklab.model.material import Material
from cracklab.solver.interfaces import for_scene

from studies.tpv6.scene import DOMAIN


def main(dx, t_end=12.0):
    base = scenes.tpv6(dx=dx, t_end=t_end, domain=DOMAIN)
    near = base.materials[1]
    nearly = Material(mu=near.mu * (1 + 1e-6), cs=near.cs, nu=near.nu)
    out = {}
    for name, mats in (("pair", (near, near)), ("faces", (nearly, near))):
        sc = base.replace(materials=mats)
        t0 = time.time()
        ds = cracklab.simulate(sc)
        out[name] = (ds["station_v_1"].max("t_station").values, ds["station_delta_1"].isel(t_station=-1).values,
                     [str(s) for s in ds["station"].values])
        print(f"{name}: {type(for_scene(sc)).__name__}, {time.time() - t0:.0f} s", flush=True)
    print("station | peak slip rate, pair / faces (m/s) | final slip, pair / faces (m)")
    for i, st in enumerate(out["pair"][2]):
        print(f"{st} | {out['pair'][0][i]:.3f} / {out['faces'][0][i]:.3f} | "
              f"{out['pair'][1][i]:.3f} / {out['faces'][1][i]:.3f}")


if __name__ == "__main__":
    main(float(sys.argv[1]), *(float(x) for x in sys.argv[2:3]))
