"""The order in dt of a slip-weakening rupture front on the grid (docs/reference/stability.md,
"The order of a rupture front").

    python studies/front_order/run.py [--mode II III] [--betas 0.25 0.125 ...] [--formulation product ...]
                                      [-o OUT] [--dx 100]

A plane (2D) problem with TPV3's friction, stresses and material (Harris et al. 2009):
a 30 km fault in a periodic 48 km cell, bonded outside it, linear slip weakening
(mu_s 0.677, mu_d 0.525, D_c 0.4 m, sigma_n 120 MPa), 70 MPa of shear stress and 81.6 MPa
on the 3 km nucleation patch (placed by cell fraction as scenes.tpv3 does), in-plane (mode
II, tau0_1) or anti-plane (mode III, tau0_3). The run is stepped to t_end at each beta with
dx fixed (dt -> 0 converges to the space-discrete solution), and at stations 3, 6, 9 and
12 km from the hypocentre the time of the slip rate's crossing of several thresholds
(1 mm/s, 0.1 m/s, 1 m/s) and of the slip's crossing of 1 mm and 0.2 m is found by
interpolation between the steps (linear, and the cubic through the four samples around
the crossing: if the two agree, the detection is not what is first order). The order
is the base-2 logarithm of the ratio of successive differences between the betas, which
halve. Writes OUT/front_order_<mode>_<formulation>.json.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
STATIONS_KM = (3.0, 6.0, 9.0, 12.0)
V_THRESHOLDS = (1e-3, 0.1, 1.0)     # m/s
D_THRESHOLDS = (1e-3, 0.2)          # m


def cell_fraction(x, dx, half):
    lo, hi = np.maximum(x - 0.5 * dx, -half), np.minimum(x + 0.5 * dx, half)
    return np.clip((hi - lo) / dx, 0.0, 1.0)


def build(mode, beta, formulation="product", dx=100.0, t_end=5.0, L1=48000.0, engine="exponential"):
    from cracklab import Grid, Loading, Material, Record, Scene, SlipWeakening
    from cracklab.model.scene import Numerics

    n1 = int(round(L1 / dx))
    g = Grid(n1=n1, n3=1, L1=n1 * dx, L3=dx)
    mat = Material(mu=2670.0 * 3464.0**2, cs=3464.0, nu=0.25)
    xc = g.x1[n1 // 2]
    patch = cell_fraction(g.x1 - xc, dx, 1500.0)[:, None]
    fault = cell_fraction(g.x1 - xc, dx, 15000.0)[:, None] >= 1 - 1e-9
    tau0 = 70.0e6 + 11.6e6 * patch
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, sigma_n=120.0e6, bonded=~fault)
    comp = 1 if mode == "II" else 3
    return Scene(material=mat, grid=g, law=law, loading=Loading(**{f"tau0_{comp}": tau0}), t_end=t_end,
                 beta=beta, record=Record(fields=()), numerics=Numerics(formulation=formulation, engine=engine),
                 units={"length": "m", "time": "s", "stress": "Pa"}, name=f"front_order_{mode}"), comp, xc


def run(mode, beta, formulation="product", dx=100.0, t_end=5.0):
    """Station series (t, v, delta) of one run, every step."""
    from cracklab.solver.stepper import steps

    sc, comp, xc = build(mode, beta, formulation, dx, t_end)
    nodes = [int(round((xc + 1000.0 * s) / dx)) for s in STATIONS_KM]
    t, v, d = [], [], []
    t0 = time.process_time()
    for st in steps(sc):
        t.append(st.t)
        v.append(st.v[comp][nodes, 0].copy())
        d.append(st.delta[comp][nodes, 0].copy())
    cpu = time.process_time() - t0
    return np.array(t), np.abs(np.array(v)), np.abs(np.array(d)), cpu, sc


def crossing(t, y, level, cubic=False):
    """First time y crosses level upward, interpolated between the samples (linear, or the
    cubic through the two samples either side of the crossing)."""
    above = np.nonzero(y >= level)[0]
    if above.size == 0 or above[0] == 0:
        return float("nan")
    k = above[0]
    if not cubic or k < 2 or k + 1 >= y.size:
        return float(t[k - 1] + (level - y[k - 1]) * (t[k] - t[k - 1]) / (y[k] - y[k - 1]))
    tt, yy = t[k - 2:k + 2], y[k - 2:k + 2]
    c = np.polyfit(tt - tt[1], yy - level, 3)
    roots = np.roots(c)
    h = tt[2] - tt[1]
    real = [r.real for r in roots if abs(r.imag) < 1e-9 * h and -1e-9 * h <= r.real <= h * (1 + 1e-9)]
    return float(tt[1] + min(real)) if real else float(crossing(t, y, level))


def measures(t, v, d):
    out = {}
    for j, s in enumerate(STATIONS_KM):
        for lv in V_THRESHOLDS:
            out[f"{s:g}km v>{lv:g}"] = crossing(t, v[:, j], lv)
            out[f"{s:g}km v>{lv:g} cubic"] = crossing(t, v[:, j], lv, cubic=True)
        for ld in D_THRESHOLDS:
            out[f"{s:g}km d>{ld:g}"] = crossing(t, d[:, j], ld)
        out[f"{s:g}km peak v"] = float(v[:, j].max())
        out[f"{s:g}km final d"] = float(d[-1, j])
    return out


def orders(betas, values):
    """log2 of the ratio of successive differences (betas halving)."""
    x = np.asarray(values, dtype=float)
    diff = np.diff(x)
    with np.errstate(divide="ignore", invalid="ignore"):
        return list(np.log2(diff[:-1] / diff[1:]))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--mode", nargs="+", default=["II", "III"])
    p.add_argument("--betas", type=float, nargs="+", default=[0.25, 0.125, 0.0625, 0.03125, 0.015625])
    p.add_argument("--formulation", nargs="+", default=["product"])
    p.add_argument("--dx", type=float, default=100.0)
    p.add_argument("--t-end", type=float, default=5.0)
    p.add_argument("-o", "--out", default=str(ROOT / "out" / "front_order"))
    a = p.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    for form in a.formulation:
        for mode in a.mode:
            res = {"mode": mode, "formulation": form, "dx": a.dx, "betas": a.betas, "runs": []}
            for b in a.betas:
                t, v, d, cpu, sc = run(mode, b, form, a.dx, a.t_end)
                m = measures(t, v, d)
                res["runs"].append({"beta": b, "dt": sc.dt, "nsteps": sc.nsteps, "cpu_s": cpu, "measures": m})
                print(f"{form} mode {mode} beta {b:g}: {sc.nsteps} steps, {cpu:.1f} s cpu", flush=True)
            keys = list(res["runs"][0]["measures"])
            res["orders"] = {k: orders(a.betas, [r["measures"][k] for r in res["runs"]]) for k in keys}
            path = out / f"front_order_{mode}_{form}.json"
            path.write_text(json.dumps(res, indent=1))
            for k in keys:
                vals = [r["measures"][k] for r in res["runs"]]
                print(f"  {k:22s} " + " ".join(f"{x:.5f}" for x in vals) + "  orders "
                      + " ".join(f"{o:.2f}" for o in res["orders"][k]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
