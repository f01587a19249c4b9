"""The cost of a step of product2 against the product scheme's, in one sitting.

    python studies/front_order/cost.py [--scene tpv3|tpv5] [--dx 100] [--steps 300] [--rounds 3]

Steps ``scenes.tpv3`` (or ``tpv5``) at 100 m and beta 0.125 with each scheme in turn (the
order reversed every other round), ``steps`` steps from t = 0 with the kernel fits of the
whole 12 s run, and takes the median of the second half's steps (the rupture has started
there, so the law's work is in it). Writes OUT/cost_<scene>.json.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCHEMES = ("product", "product2")


def scene_for(name, formulation, dx, beta):
    from cracklab import scenes
    from cracklab.model.scene import Numerics

    return getattr(scenes, name)(dx=dx, beta=beta, numerics=Numerics(formulation=formulation, engine="exponential",
                                                                    rupture_threshold=1e-3))


def step_times(scene, steps):
    from cracklab.model.record import Record
    from cracklab.solver.interfaces import for_scene
    from cracklab.solver.spectral import Transforms
    from cracklab.solver.stepper import Stepper

    short = scene.replace(t_end=steps * scene.dt, record=Record(fields=()))
    stepper = Stepper(short, for_scene(short, Transforms(short.grid), nsteps=scene.nsteps))
    times, t0 = [], time.perf_counter()
    for _ in stepper:
        times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
    return 1e3 * float(np.median(times[len(times) // 2:]))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scene", default="tpv3", choices=("tpv3", "tpv5"))
    p.add_argument("--dx", type=float, default=100.0)
    p.add_argument("--beta", type=float, default=0.125)
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("-o", "--out", default=str(ROOT / "out" / "front_order"))
    a = p.parse_args(argv)
    rows = []
    for r in range(a.rounds):
        row = {}
        for f in (SCHEMES if r % 2 == 0 else SCHEMES[::-1]):
            row[f] = step_times(scene_for(a.scene, f, a.dx, a.beta), a.steps)
            print(f"round {r + 1}: {f}: {row[f]:.1f} ms per step", flush=True)
        rows.append(row)
    ratios = [row["product2"] / row["product"] for row in rows]
    res = {"scene": a.scene, "dx": a.dx, "beta": a.beta, "steps": a.steps, "rounds": rows, "ratios": ratios}
    print(f"product2 / product per step: {min(ratios):.3f} - {max(ratios):.3f} (median {np.median(ratios):.3f})")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"cost_{a.scene}.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
