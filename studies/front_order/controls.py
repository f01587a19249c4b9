"""Controlled experiments on the source of the product scheme's first-order front
(docs/reference/stability.md, "The order of a rupture front"): change one thing, measure the order.

    python studies/front_order/controls.py [--dx 200] [-o OUT]

On the 2D fault of run.py (mode II), at beta 0.2, 0.1, 0.05, 0.025, the rupture time
(slip rate crossing 1 m/s, interpolated) at 3 and 6 km for:

* product            the product scheme (law updated with v_{n-1}: S_n = S_{n-1} + dt |v_{n-1}|)
* product, trial     the same with its predictor on a copy of the law state (the path it
                     takes for a law that reads the slip): the predictor machinery alone
* product2           the law at the step's mean velocity: S_n = S_{n-1} + dt |v_{n-1} + v*_n|/2
* product2, right    the same machinery with the law at the predicted velocity: S_n = S_{n-1} + dt |v*_n|
                     (the rectangle rule at the step's end: first order again, early)

The onset of sliding, the start-up weight E_0, the end-of-step traction of the law's solve
and the detection are the same in all four, so the two that are second order (product2)
show that none of them is first order.

Writes OUT/controls.json and prints the orders.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import run as R  # noqa: E402

BETAS = (0.2, 0.1, 0.05, 0.025)


def times(formulation, beta, dx):
    t, v, d, cpu, sc = R.run("II", beta, formulation, dx=dx, t_end=2.4)
    return [R.crossing(t, v[:, j], 1.0) for j in (0, 1)]


def variant(name, dx):
    from cracklab.solver import stepper
    from cracklab.solver.schemes import product2

    saved_reads, saved_mean = stepper.reads_slip, product2.plus_mean
    try:
        if name == "product, trial":
            stepper.reads_slip = lambda law, comps: True
        if name == "product2, right":
            # the law's update velocity (v_{n-1} + v*_n)/2 -> v*_n; the trial slip unchanged
            def right(y, a, x1, x2, out=None):
                if out is None and not np.any(y):       # the mean velocity of the step
                    return np.array(x2, dtype=float)
                return saved_mean(y, a, x1, x2, out=out)
            product2.plus_mean = right
        form = "product2" if name.startswith("product2") else "product"
        return np.array([times(form, b, dx) for b in BETAS])
    finally:
        stepper.reads_slip, product2.plus_mean = saved_reads, saved_mean


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dx", type=float, default=200.0)
    p.add_argument("-o", "--out", default=str(R.ROOT / "out" / "front_order"))
    a = p.parse_args(argv)
    res = {"dx": a.dx, "betas": BETAS, "stations_km": [3.0, 6.0], "runs": {}}
    for name in ("product", "product, trial", "product2", "product2, right"):
        t = variant(name, a.dx)
        d = np.diff(t, axis=0)
        orders = np.log2(d[:-1] / d[1:])
        res["runs"][name] = {"times": t.tolist(), "orders": orders.tolist()}
        print(f"{name:18s} t(beta) at 3 km " + " ".join(f"{x:.5f}" for x in t[:, 0]) + " | 6 km "
              + " ".join(f"{x:.5f}" for x in t[:, 1]) + " | orders " + " ".join(f"{o:.2f}" for o in orders.ravel()),
              flush=True)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "controls.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
