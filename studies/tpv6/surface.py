"""TPV6's surface stations: where the peak slip rate grows with the grid, and why (docs/studies/tpv6.md,
"The surface stations").

    python -m studies.tpv6.surface [--dx 400 200 100] [-o OUT] [--t-end 7.0]

Three TPV6 surface stations (faultst000dp000, faultst-120dp000, faultst120dp000) fail the
peak slip rate at 100 m, and their peak grows with every refinement. This study separates
the causes, with

1. **TPV6 near the surface**: ``scenes.tpv6`` (the law as the benchmark states it) at each
   grid spacing, recording the slip rate along strike at strike 0 and +-12 km at depths 0,
   the first node below the surface, 400 m and 800 m: the peak and the rupture time at
   each. A peak that grows at the surface node and not below it is a feature of the
   surface, not of the whole front.
2. **The same with a constant normal stress** (sigma_n = 120 MPa, the normal traction
   not followed): the growth without the normal-stress feedback of a bimaterial fault
   (the Adams instability) that a regularised normal stress addresses.
3. **A 2D analogue** (plane anti-plane problem, TPV6's friction and stresses, a 30 km
   periodic fault, nucleated at its centre): the two fronts meet at the cell's edge as
   the 3D front meets its mirror image at the free surface. The peak slip rate where they
   meet, at 200 m to 25 m, for TPV6's near rock on both sides, for the TPV6 pair, and for
   a pair of **one shear speed** with the far side's modulus (3.07 times smaller): in
   anti-plane that pair is exactly one material of the harmonic modulus (tested in
   tests/solver/test_bimaterial.py), so whatever its peak does is the elastodynamics of a
   softer medium, not the bimaterial machinery.

4. **A 2D in-plane analogue of the normal-stress feedback** (plane in-plane problem, the TPV6
   pair, the law following the normal traction, TPV6's stresses on a 60 km periodic fault
   nucleated at its centre): the peak slip rate and the range of the normal stress at 6 and
   12 km on either side, at 200 m to 25 m, with the law as stated and with the regularised
   normal stress at slip scales L* (``--slip-scales``, default 0.1 m and 0.4 m). Where the
   compliant side moves (+x1) the unregularised peak grows at every refinement (the
   bimaterial problem with Coulomb friction is ill-posed: Adams 1995); a slip scale makes it
   converge. This is what chooses the page's law setting.

Writes OUT/surface_results.json (default out/tpv6/surface), which studies/tpv6/run.py reads
(``--surface OUT``) for the page's section; ``--parts`` runs some parts only (3d, antiplane,
inplane) and keeps the other parts' results already in the file. The 3D runs stop at
``--t-end`` (7 s: every surface station has ruptured and peaked).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H
from studies.tpv6 import compare as C
from studies.tpv6.scene import DOMAIN

STRIKES_KM = (0, -12, 12)
SIGMA_N = 120.0e6          # Pa: TPV6's initial compression, held constant in the control
SAMPLE = 0.005             # s: the reference's sampling, on which the peak is read (as run.py)
PAIRS_2D = ("rock", "tpv6", "one_speed")
INPLANE_KM = (-12, -6, 6, 12)   # stations of the in-plane analogue, from the centre


def _stations(grid, xc):
    depths = (0.0, grid.dx3, 400.0, 800.0)
    return {f"st{s:+d}_z{d:g}": (xc + 1000.0 * s, d) for s in STRIKES_KM for d in depths}


def measure(t, v):
    """Peak and rupture time of a slip-rate series, read as run.py reads the stations: on the
    reference's 0.005 s samples (compare.resample, compare.peak, compare.rupture_time)."""
    ts, vs = C.resample(t, v, np.arange(0.0, t[-1] + SAMPLE, SAMPLE))
    return {"peak": C.peak(ts, vs)[0], "rupture_time": C.rupture_time(ts, vs, C.THRESHOLD)}


def run_3d(dx, t_end, constant_normal):
    """One TPV6 run near the surface: {station: {"x3", "peak", "rupture_time"}}."""
    import cracklab
    from cracklab import Record
    from cracklab.scenes import tpv6

    sc = tpv6(dx=dx, t_end=t_end, domain=DOMAIN)
    xc = sc.grid.x1[sc.grid.n1 // 2]
    sc = sc.replace(record=Record(fields=(), stations=_stations(sc.grid, xc)))
    if constant_normal:
        sc = sc.replace(law=dataclasses.replace(sc.law, sigma_n=SIGMA_N),
                        loading=dataclasses.replace(sc.loading, tau0_2=0.0))
    t0 = time.time()
    ds = cracklab.simulate(sc, progress=False)
    t = ds.t_station.values
    out = {}
    for s in ds.station.values:
        v = np.hypot(ds.station_v_1.sel(station=s).values, ds.station_v_3.sel(station=s).values)
        out[str(s)] = {"x3": float(ds.station_x3.sel(station=s)), **measure(t, v)}
    return out, time.time() - t0


def _plane_fault(L, dx):
    """The 2D analogues' plane grid of a periodic fault of length L and TPV6's shear
    traction on it: 70 MPa, 81.6 MPa on the 3 km nucleation patch at its centre."""
    from cracklab import Grid

    g = Grid(n1=int(round(L / dx)), n3=1, L1=L, L3=1.0)
    return g, np.where(np.abs(g.x1 - L / 2) <= 1500.0, 81.6e6, 70.0e6)[:, None]


def scene_2d(dx, pair, t_end=8.0):
    """The plane anti-plane analogue: TPV6's stresses and friction (constant sigma_n) on a
    30 km periodic fault, the 3 km nucleation patch at its centre."""
    from cracklab import Loading, Material, Numerics, Record, Scene
    from cracklab.laws import SlipWeakening
    from cracklab.scenes import TPV6_FAR, TPV6_NEAR

    L = 30000.0
    g, tau = _plane_fault(L, dx)
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, sigma_n=SIGMA_N)
    sides = {"rock": {"material": TPV6_NEAR},
             "tpv6": {"materials": (TPV6_FAR, TPV6_NEAR)},
             "one_speed": {"materials": (Material(mu=TPV6_FAR.mu, cs=TPV6_NEAR.cs, nu=0.25), TPV6_NEAR)}}[pair]
    return Scene(grid=g, law=law, loading=Loading(tau0_3=tau), t_end=t_end, beta=0.125,
                 record=Record(fields=(), stations={"meet": (0.0, 0.0), "quarter": (L / 4, 0.0)}),
                 numerics=Numerics(engine="exponential"), units={"length": "m", "time": "s", "stress": "Pa"},
                 **sides)


def run_2d(dx, pair):
    import cracklab

    ds = cracklab.simulate(scene_2d(dx, pair), progress=False)
    t = ds.t_station.values
    return {str(s): measure(t, np.abs(ds.station_v_3.sel(station=s).values)) for s in ds.station.values}


def scene_inplane(dx, slip_scale=None, t_end=6.0):
    """The plane in-plane analogue: the TPV6 pair, slip weakening on the current normal
    traction (regularised with ``slip_scale`` L* when given), 70 MPa shear and 120 MPa
    compression on a 60 km periodic fault, the 3 km nucleation patch (81.6 MPa) at its centre;
    the builder's time stepping (product2, beta 0.125)."""
    from cracklab import Loading, Numerics, Record, Scene
    from cracklab.laws import SlipWeakening
    from cracklab.scenes import TPV6_FAR, TPV6_NEAR

    L = 60000.0
    g, tau = _plane_fault(L, dx)
    extra = {} if slip_scale is None else {"normal_slip_scale": slip_scale}
    law = SlipWeakening(mu_s=0.677, mu_d=0.525, D_c=0.40, **extra)
    stations = {f"{s:+d}": (L / 2 + 1000.0 * s, 0.0) for s in INPLANE_KM}
    return Scene(materials=(TPV6_FAR, TPV6_NEAR), grid=g, law=law, loading=Loading(tau0_1=tau, tau0_2=-SIGMA_N),
                 t_end=t_end, beta=0.125, record=Record(fields=(), stations=stations),
                 numerics=Numerics(formulation="product2", engine="exponential"),
                 units={"length": "m", "time": "s", "stress": "Pa"})


def run_inplane(dx, slip_scale=None):
    """{station: {"peak", "rupture_time", "normal": [min, max] (MPa)}}, or {"error": ...} when
    the solver stops the run."""
    import cracklab
    from cracklab.errors import SimulationError

    try:
        ds = cracklab.simulate(scene_inplane(dx, slip_scale), progress=False)
    except SimulationError as exc:
        return {"error": str(exc)}
    t = ds.t_station.values
    out = {}
    for s in ds.station.values:
        n = ds.station_tau_2.sel(station=s).values / 1e6
        out[str(s)] = {**measure(t, np.abs(ds.station_v_1.sel(station=s).values)),
                       "normal": [float(n.min()), float(n.max())]}
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default=str(H.ROOT / "out" / "tpv6" / "surface"))
    p.add_argument("--dx", type=float, nargs="+", default=[400.0, 200.0, 100.0], help="3D grid spacings (m)")
    p.add_argument("--dx-2d", type=float, nargs="+", default=[200.0, 100.0, 50.0, 25.0], help="2D spacings (m)")
    p.add_argument("--t-end", type=float, default=7.0, help="simulated time of the 3D runs (s)")
    p.add_argument("--slip-scales", type=float, nargs="+", default=[0.1, 0.4],
                   help="slip scales L* (m) of the in-plane analogue's regularised runs")
    p.add_argument("--parts", nargs="+", default=["3d", "antiplane", "inplane"],
                   choices=("3d", "antiplane", "inplane"), help="the parts to run (the others are kept)")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "surface_results.json"
    res = json.loads(path.read_text()) if path.exists() else {}
    res.setdefault("wall_s", {})
    if "3d" in args.parts:
        res["t_end"], res["runs"] = args.t_end, {}
    for dx in sorted(args.dx, reverse=True) if "3d" in args.parts else ():
        for label, const in (("law", False), ("constant_normal", True)):
            r, wall = run_3d(dx, args.t_end, const)
            res["runs"].setdefault(label, {})[f"{dx:g}"] = r
            res["wall_s"][f"{label}_{dx:g}"] = wall
            z0 = r["st+0_z0"]
            print(f"3D {label:15s} dx {dx:5g} m: strike 0 surface peak {z0['peak']:.2f} m/s, "
                  f"rupture {z0['rupture_time']:.3f} s ({wall:.0f} s)", flush=True)
    if "antiplane" in args.parts:
        res["analogue"] = {}
    for pair in PAIRS_2D if "antiplane" in args.parts else ():
        for dx in sorted(args.dx_2d, reverse=True):
            r = run_2d(dx, pair)
            res["analogue"].setdefault(pair, {})[f"{dx:g}"] = r
            print(f"2D {pair:10s} dx {dx:5g} m: peak where the fronts meet {r['meet']['peak']:.2f} m/s, "
                  f"at a quarter {r['quarter']['peak']:.2f} m/s", flush=True)
    if "inplane" in args.parts:
        res["inplane"] = {}
        for scale in [None] + list(args.slip_scales):
            key = "as stated" if scale is None else f"{scale:g}"
            for dx in sorted(args.dx_2d, reverse=True):
                r = run_inplane(dx, scale)
                res["inplane"].setdefault(key, {})[f"{dx:g}"] = r
                print(f"2D in-plane L* {key:9s} dx {dx:5g} m: " + ("stopped" if "error" in r else " | ".join(
                    f"{s} km peak {c['peak']:.2f}" for s, c in r.items())), flush=True)
    path.write_text(json.dumps(res, indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
