"""BP1-QD against uguca, a second spectral boundary-integral code run on this machine
(issue 35, verification 4; docs/studies/cycles.md, "Against uguca").

    python -m studies.cycles.uguca --uguca DIR [-o OUT] [--dz 100 50]

DIR holds uguca's event catalogues, one CSV per run (columns start_yr, duration_s,
hypo_depth_km, peak_slip_rate_m_per_s, depth_of_peak_km, time_of_peak_yr; an event is the
largest slip rate over 0-40 km above 1 mm/s; its year is 3.1536e7 s), as its README there
says how they were made: uguca's BP1-QD driver of the public fork kura-okubo/4mNonSelfSim_UGUCA
(branch 35-benchmark-2d-antiplane, commit fc0840d), with its state update and its mirror
fixed, on uguca's geometry: a periodic line of 100 km, the surface at its middle, the fault
to 50 km and creep below 40 km. cracklab runs the same geometry, ``scenes.bp1(depth=50e3)``,
at each ``--dz`` into OUT/bp1_depth50km_dz<dz>.zarr (a complete store is reused), and both
catalogues go to OUT/uguca_bp1.json, which the page reads.
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

import numpy as np

UGUCA_YEAR = 3.1536e7
#: uguca's runs compared: (file stem, dz in m, its step factor S on Lapusta's bound)
UGUCA_RUNS = (("bp1qd_N1000_xi0.0625", 100.0, 0.0625), ("bp1qd_N2000_xi0.5", 50.0, 0.5),
              ("bp1qd_N4000_xi0.5", 25.0, 0.5))
BIG = 0.1       # an earthquake's peak slip rate is above this (m/s)


def read_uguca(path) -> dict:
    """The catalogue of one uguca run: lists per column."""
    rows = [r for r in csv.reader(line for line in Path(path).read_text().splitlines() if not line.startswith("#"))]
    cols = np.array(rows, dtype=float).T
    names = ("start_yr", "duration_s", "hypo_depth_km", "peak_slip_rate", "depth_of_peak_km", "time_of_peak_yr")
    return {n: c.tolist() for n, c in zip(names, cols)}


def run_cracklab(out, dz, log=print) -> dict:
    import xarray as xr

    from cracklab import Record, analysis, simulate
    from cracklab.scenes import bp1

    store = Path(out) / f"bp1_depth50km_dz{dz:g}.zarr"
    sc = bp1(dz=dz, years=1500.0, depth=50e3, tolerance=1e-7, pair="dormand_prince",
             record=Record(fields=("v_3",), region={"x1": (0.0, 50e3)}, stations={}))
    t0 = time.time()
    if store.exists() and xr.open_zarr(store).attrs.get("cracklab_status") == "complete":
        ds, wall = xr.open_zarr(store), None
    else:
        log(f"cracklab bp1(depth=50 km) at dz = {dz:g} m -> {store}", flush=True)
        ds = simulate(sc, store=str(store), resume=True)
        wall = time.time() - t0
    ev = analysis.events(ds).load()
    return {"dz": dz, "wall_s": wall, "accepted_steps": int(ds.attrs["accepted_steps"]),
            "start_yr": (ev.t_start.values / UGUCA_YEAR).tolist(), "duration_s": ev.duration.values.tolist(),
            "hypo_depth_km": (ev.hypocentre_x1.values / 1e3).tolist(),
            "peak_slip_rate": ev.peak_slip_rate.values.tolist()}


def earthquakes(cat) -> list:
    """(start year, peak slip rate, hypocentre depth) of the events whose peak is above BIG."""
    return [(t, v, h) for t, v, h in zip(cat["start_yr"], cat["peak_slip_rate"], cat["hypo_depth_km"]) if v > BIG]


def section(res) -> list:
    """The page's lines: the earthquakes of both codes side by side at each spacing."""
    ug, ck = res["uguca"], res["cracklab"]
    lines = ["## Against uguca", "",
             "uguca (Kammer et al. 2021, SoftwareX 15) built here from the public fork kura-okubo/4mNonSelfSim_UGUCA "
             "(branch 35-benchmark-2d-antiplane, commit fc0840d, its BP1 drivers marked \"still not working "
             "correctly\" upstream). Its BP1-QD driver gives no event in 1500 years as it stands: its state update "
             "ignores the step multiplier, its mirror is odd and its creep slides at 2 V_p. With those three fixed "
             "in the driver only, it steps forward Euler with Lapusta et al.'s bound on the step (times a factor S) "
             "and no error control. Its BP1-FD is a fixed step over 1500 years, about 200 CPU-years at 100 m here, "
             "and cannot be run. Its geometry is a periodic line of 100 km with the surface in the middle: "
             "cracklab's `bp1(depth=50e3)`. Earthquakes (peak slip rate above 0.1 m/s; years of 3.1536e7 s, "
             "uguca's):", ""]
    for key in sorted(ck, key=float, reverse=True):
        c = earthquakes(ck[key])
        u = next((r for r in ug.values() if r["dz"] == float(key)), None)
        lines += [f"**dz = {float(key):g} m** (cracklab tolerance 1e-7"
                  + (f"; uguca S = {u['S']:g}" if u else "") + ")", "",
                  "| # | cracklab start (yr) | peak (m/s) | hypocentre (km) | uguca start (yr) | peak (m/s) | "
                  "hypocentre (km) |", "|---|---|---|---|---|---|---|"]
        uq = earthquakes(u["catalogue"]) if u else []
        for i in range(max(len(c), len(uq))):
            a = c[i] if i < len(c) else None
            b = uq[i] if i < len(uq) else None
            lines.append(f"| {i} | " + (f"{a[0]:.2f} | {a[1]:.2f} | {a[2]:.1f}" if a else "- | - | -") + " | "
                         + (f"{b[0]:.2f} | {b[1]:.2f} | {b[2]:.1f}" if b else "- | - | -") + " |")
        lines.append("")
    u100 = earthquakes(ug["bp1qd_N1000_xi0.0625"]["catalogue"])
    c100 = earthquakes(ck["100"]) if "100" in ck else []
    if c100:
        n = min(len(c100), len(u100))
        gaps = [a[0] - b[0] for a, b in zip(c100[:n], u100[:n])]
        ratio = [a[1] / b[1] for a, b in zip(c100[:n], u100[:n])]
        whole = sum(a[2] > 5.0 for a in c100)
        lines += [f"At 100 m, {len(c100)} earthquakes here and {len(u100)} in uguca over 1500 years; "
                  f"{whole} of cracklab's nucleate at depth (10-15 km) and run to the surface, as all of uguca's "
                  f"do. Their starts differ by {min(gaps):+.2f} to {max(gaps):+.2f} years (uguca's own first event "
                  "moves by 0.2 years per halving of its step factor there, and its runs are not bit-reproducible: "
                  "0.01 years between two identical runs); the largest slip rates are "
                  f"{min(ratio):.3f}-{max(ratio):.3f} times uguca's. Mean recurrence: "
                  f"{np.mean(np.diff([a[0] for a in c100])):.2f} years here, "
                  f"{np.mean(np.diff([b[0] for b in u100])):.2f} in uguca.", ""]
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--uguca", required=True, help="the directory of uguca's event catalogues (CSV)")
    p.add_argument("-o", "--out", default="out/cycles")
    p.add_argument("--dz", type=float, nargs="+", default=[100.0, 50.0])
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ug = {}
    for stem, dz, S in UGUCA_RUNS:
        path = Path(args.uguca) / f"{stem}_events.csv"
        if path.exists():
            ug[stem] = {"dz": dz, "S": S, "catalogue": read_uguca(path)}
    if "bp1qd_N1000_xi0.0625" not in ug:
        p.error(f"{args.uguca}: no bp1qd_N1000_xi0.0625_events.csv (uguca's run at 100 m, S = 0.0625)")
    res = {"uguca": ug, "cracklab": {f"{dz:g}": run_cracklab(out, dz) for dz in args.dz}}
    (out / "uguca_bp1.json").write_text(json.dumps(res, indent=1))
    print(f"wrote {out / 'uguca_bp1.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
