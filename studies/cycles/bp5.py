"""SEAS BP5-QD with cracklab (docs/studies/bp5.md): a sequence of earthquakes on a 3D
strike-slip fault below a free surface, at several grid spacings.

    python -m studies.cycles.bp5 [-o OUT] [--dx 2000 1000 500] [--years 1800] [--report-only]

Runs ``cracklab.scenes.bp5`` at each spacing into OUT/bp5_dx<dx>.zarr (a complete store of
the same scene is reused, a killed one resumed), recording the slip and slip rate along
strike (``delta_1``, ``v_1``) on the rate-and-state fault at the benchmark's cadence and the
default stations, with the wall time in OUT/bp5_dx<dx>.json, and writes

* OUT/bp5_results.json          every number of the page,
* docs/figures/bp5_*.png        largest slip rate against time, slip profiles, slip maps,
* docs/studies/bp5.md           the page, written from these results.
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
from studies.cycles.run import YEAR, earthquakes

ROOT = Path(__file__).resolve().parents[2]
#: an earthquake's peak slip rate is above this (m/s); slower events are slow slip
BIG = 0.1
FIELDS = ("delta_1", "v_1")


def store_of(out, dx) -> Path:
    return Path(out) / f"bp5_dx{dx:g}.zarr"


def scene_of(dx, years):
    """BP5-QD at ``dx`` recording the slip and slip rate along strike only."""
    from cracklab.scenes import bp5

    scene = bp5(dx=dx, years=years)
    return scene.replace(record=dataclasses.replace(scene.record, fields=FIELDS))


def run_one(out, dx, years, force=False, log=print) -> dict:
    import xarray as xr

    from cracklab import simulate
    from cracklab.model.scene_io import scene_to_json

    scene = scene_of(dx, years)
    store = store_of(out, dx)
    meta_path = store.with_suffix(".json")
    text, _ = scene_to_json(scene)
    if not force and store.exists() and meta_path.exists():
        old = xr.open_zarr(store)
        if old.attrs.get("scene") == text and old.attrs.get("cracklab_status") == "complete":
            log(f"dx = {dx:g} m: reusing {store}")
            return json.loads(meta_path.read_text())
    log(f"dx = {dx:g} m: {scene.grid.n1} x {scene.grid.n3} nodes, {years:g} years -> {store}", flush=True)
    t0 = time.time()
    ds = simulate(scene, store=str(store), resume=True)       # a killed run goes on from its checkpoint
    wall = time.time() - t0
    meta = {"dx": dx, "years": years, "wall_s": wall, "nodes": [scene.grid.n1, scene.grid.n3],
            "resumed_from": None if ds.attrs.get("cracklab_resumed_from") is None else
            int(ds.attrs["cracklab_resumed_from"]),
            **{k: ds.attrs.get(k) for k in ("accepted_steps", "smallest_step", "largest_step",
                                            "wall_time_in_events", "wall_time_between_events")}}
    meta_path.write_text(json.dumps(meta, indent=1))
    log(f"dx = {dx:g} m: done in {wall:.0f} s, {meta['accepted_steps']} steps", flush=True)
    return meta


def centre(ds) -> float:
    """x1 of the fault's centre (x2 = 0): the middle of the recorded region."""
    x1 = ds.x1.values
    return float(x1[len(x1) // 2])


def analyse(out, dxs) -> dict:
    import xarray as xr

    from cracklab import analysis

    res = {"runs": {}}
    for dx in dxs:
        ds = xr.open_zarr(store_of(out, dx))
        ev = analysis.events(ds).load()
        meta = json.loads(store_of(out, dx).with_suffix(".json").read_text())
        xc = centre(ds)
        big = ev.peak_slip_rate.values > BIG
        quakes = earthquakes(ev.t_start.values[big])
        t, V = ds.t_station.values, ds.max_slip_rate.values
        fast = V >= ds.attrs["event_threshold"]
        dt = np.diff(t, prepend=t[0])
        meta.update({
            "events": {k: ev[k].values.tolist() for k in ev.data_vars},
            "x2_centre": xc,
            "earthquakes_yr": (np.array(quakes) / YEAR).tolist(),
            "recurrence_yr": (np.diff(quakes) / YEAR).tolist(),
            "time_in_events_s": float(np.sum(dt[fast])),
            "steps_in_events": int(np.sum(fast)),
        })
        res["runs"][f"{dx:g}"] = meta
    return res


def fig_max_rate(out, dxs, figdir):
    import xarray as xr

    plt = H.pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for dx in dxs:
        ds = xr.open_zarr(store_of(out, dx))
        ax.semilogy(ds.t_station.values / YEAR, ds.max_slip_rate.values, lw=0.8, label=f"dx = {dx:g} m")
    ax.set(xlabel="time (years)", ylabel="largest slip rate (m/s)", title="BP5-QD: largest slip rate on the fault")
    ax.legend(fontsize=8)
    return H.save(fig, Path(figdir) / "bp5_max_slip_rate.png", 110)


def fig_profiles(out, dx, figdir):
    """Cumulative slip along strike at 10 km depth and along depth at the centre: every 5
    years between events (blue) and every second during them (red)."""
    import xarray as xr

    plt = H.pyplot()
    ds = xr.open_zarr(store_of(out, dx))
    xc = centre(ds)
    kind = ds.snapshot_kind.values
    slow = kind == 0                                    # snapshot_kind: 0 is the slow cadence
    along = ds.delta_1.sel(x3=10e3, method="nearest").load().values
    down = ds.delta_1.sel(x1=xc, method="nearest").load().values
    x2, z = (ds.x1.values - xc) / 1e3, ds.x3.values / 1e3
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for i in range(len(kind)):
        colour, lw = ("tab:blue", 0.5) if slow[i] else ("tab:red", 0.3)
        ax[0].plot(x2, along[i], color=colour, lw=lw)
        ax[1].plot(down[i], z, color=colour, lw=lw)
    ax[0].set(xlabel="distance along strike from the centre (km)", ylabel="cumulative slip (m)",
              title=f"at 10 km depth")
    ax[1].invert_yaxis()
    ax[1].set(xlabel="cumulative slip (m)", ylabel="depth (km)", title="at the centre (x2 = 0)")
    fig.suptitle(f"BP5-QD, dx = {dx:g} m: slip every 5 years (blue) and every second during events (red)",
                 fontsize=9)
    for a in ax:
        a.title.set_fontsize(9)
    return H.save(fig, Path(figdir) / f"bp5_profiles_dx{dx:g}.png", 110)


def fig_event_slip(out, dx, figdir, res):
    """The slip of each of the first earthquakes over the fault (the end snapshot minus the
    start snapshot), with its hypocentre."""
    import xarray as xr

    plt = H.pyplot()
    ds = xr.open_zarr(store_of(out, dx))
    r = res["runs"][f"{dx:g}"]
    ev = r["events"]
    xc = centre(ds)
    big = [i for i, p in enumerate(ev["peak_slip_rate"]) if p > BIG][:4]
    t = ds.t.values
    fig, axes = plt.subplots(1, max(len(big), 1), figsize=(4.4 * max(len(big), 1), 2.9), squeeze=False)
    for ax, i in zip(axes[0], big):
        a = int(np.searchsorted(t, ev["t_start"][i]))
        b = int(np.searchsorted(t, ev["t_end"][i]))
        b = min(b, len(t) - 1)
        slip = (ds.delta_1.isel(t=b) - ds.delta_1.isel(t=a)).load().values
        im = ax.pcolormesh((ds.x1.values - xc) / 1e3, ds.x3.values / 1e3, slip.T, shading="auto", cmap="viridis")
        ax.plot((ev["hypocentre_x1"][i] - xc) / 1e3, ev["hypocentre_x3"][i] / 1e3, "r*", ms=9)
        ax.invert_yaxis()
        ax.set_aspect("equal")
        ax.set(xlabel="along strike (km)", ylabel="depth (km)", title=f"{ev['t_start'][i] / YEAR:.1f} yr")
        ax.title.set_fontsize(9)
        fig.colorbar(im, ax=ax, shrink=0.7, label="slip (m)")
    return H.save(fig, Path(figdir) / f"bp5_event_slip_dx{dx:g}.png", 110)


def write_page(res, dxs, page, figs, command):
    runs = res["runs"]
    lines = ["# Sequences in 3D: SEAS BP5-QD", "",
             f"Written by `{command}` (studies/cycles/bp5.py) from its runs; every number below is in "
             "OUT/bp5_results.json.", "",
             "SEAS BP5-QD (Jiang et al. 2022, J. Geophys. Res. 127): a vertical strike-slip fault below a free "
             "surface in 3D, rate-and-state friction with the ageing law on a fault 100 km along strike and 40 km "
             "deep, a velocity-weakening patch 60 km x 12 km from 4 to 16 km depth, a nucleation zone of 12 km x "
             "12 km at its end (x2 from -30 to -18 km) sliding at 0.03 m/s at t = 0, the plane around the fault "
             "creeping at 1e-9 m/s. `cracklab.scenes.bp5` builds it (docs/reference/scenes.md: the parameters and "
             "where each comes from); the response is quasi-dynamic, the step adaptive (Dormand-Prince 5(4), "
             "tolerance 1e-7); the runs record the slip and slip rate along strike at the benchmark's cadence and "
             "the stations. An event lasts while the largest slip rate exceeds 1 mm/s; an earthquake is an event "
             f"whose peak exceeds {BIG:g} m/s. x2 is the distance along strike from the fault's centre.", "",
             "## Cost", "",
             "| dx | nodes (x1 x depth) | years | wall time | accepted steps | smallest step | largest step | "
             "steps in events | wall time in events / between |", "|---|---|---|---|---|---|---|---|---|"]
    for dx in dxs:
        r = runs[f"{dx:g}"]
        fast, slow = r.get("wall_time_in_events"), r.get("wall_time_between_events")
        phases = "-" if fast is None or slow is None else f"{fast:.0f} s / {slow:.0f} s"
        wall = f"{r['wall_s']:.0f} s" + (" (resumed)" if r.get("resumed_from") is not None else "")
        lines.append(f"| {dx:g} m | {r['nodes'][0]} x {r['nodes'][1]} | {r['years']:g} | {wall} | "
                     f"{r['accepted_steps']} | {r['smallest_step']:.2g} s | {r['largest_step'] / YEAR:.2g} yr | "
                     f"{r['steps_in_events']} | {phases} |")
    finest = runs[f"{dxs[-1]:g}"]
    lines += ["", "Wall times on a shared 2-core host (one core per run, other jobs running), not a benchmark. "
              f"The finest grid run here, {dxs[-1]:g} m, took {finest['wall_s'] / 60:.0f} min for "
              f"{finest['years']:g} years: "
              + ("within" if finest["wall_s"] <= 3600 else "over") + " the hour the issue allows.", "",
              "## Earthquakes", ""]
    for dx in dxs:
        r = runs[f"{dx:g}"]
        ev, xc = r["events"], r["x2_centre"]
        rec = r["recurrence_yr"]
        lines += [f"**dx = {dx:g} m**: {len(r['earthquakes_yr'])} earthquakes, starting at (years) "
                  + ", ".join(f"{x:.2f}" for x in r["earthquakes_yr"])
                  + ("; recurrence intervals (years): " + ", ".join(f"{x:.2f}" for x in rec) if rec else ""), "",
                  "| event | start (yr) | duration (s) | hypocentre x2 (km) | hypocentre depth (km) | "
                  "peak slip rate (m/s) | mean slip (m) | rupture area (km^2) | moment (N m) | Mw |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for i in range(len(ev["t_start"])):
            if not ev["peak_slip_rate"][i] > BIG:
                continue
            m0 = ev["moment"][i]
            mw = 2.0 / 3.0 * (np.log10(m0) - 9.1) if m0 > 0 else float("nan")
            lines.append(f"| {i} | {ev['t_start'][i] / YEAR:.3f} | {ev['duration'][i]:.1f} | "
                         f"{(ev['hypocentre_x1'][i] - xc) / 1e3:.1f} | {ev['hypocentre_x3'][i] / 1e3:.1f} | "
                         f"{ev['peak_slip_rate'][i]:.3f} | {ev['mean_slip'][i]:.3f} | "
                         f"{ev['rupture_area'][i] / 1e6:.0f} | {m0:.3g} | {mw:.2f} |")
        slow = [i for i, p in enumerate(ev["peak_slip_rate"]) if not p > BIG]
        if slow:
            lines += ["", f"{len(slow)} slower events (peak at most {BIG:g} m/s) are left out of the table."]
        lines.append("")
    if len(dxs) >= 2:
        lines += ["## Self-convergence", ""]
        for a, b in zip(dxs[:-1], dxs[1:]):
            qa, qb = runs[f"{a:g}"]["earthquakes_yr"], runs[f"{b:g}"]["earthquakes_yr"]
            n = min(len(qa), len(qb))
            d = np.array(qb[:n]) - np.array(qa[:n])
            ra, rb = runs[f"{a:g}"]["recurrence_yr"], runs[f"{b:g}"]["recurrence_yr"]
            pa = max(runs[f"{a:g}"]["events"]["peak_slip_rate"])
            pb = max(runs[f"{b:g}"]["events"]["peak_slip_rate"])
            lines.append(f"- {a:g} m against {b:g} m: {len(qa)} and {len(qb)} earthquakes; the first {n} start "
                         + ", ".join(f"{x:+.2f}" for x in d) + " years apart; mean recurrence "
                         + (f"{np.mean(ra[1:]):.2f} and {np.mean(rb[1:]):.2f} years (after the first interval, "
                            "which the nucleation zone's start sets)" if len(ra) > 1 and len(rb) > 1 else "-")
                         + f"; largest slip rate {pa:.2f} and {pb:.2f} m/s.")
        lines.append("")
    lines += ["## Figures", ""]
    for f in figs:
        lines += [f"![{f.stem}]({f.as_posix()})", ""]
    Path(page).write_text("\n".join(lines))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default="out/bp5")
    p.add_argument("--dx", type=float, nargs="+", default=[2000.0, 1000.0, 500.0])
    p.add_argument("--years", type=float, default=1800.0)
    p.add_argument("--report-only", action="store_true")
    p.add_argument("--force", action="store_true")
    p.add_argument("--page", default=str(ROOT / "docs" / "studies" / "bp5.md"))
    p.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        for dx in args.dx:
            run_one(out, dx, args.years, force=args.force)
    res = analyse(out, args.dx)
    (out / "bp5_results.json").write_text(json.dumps(res, indent=1))
    figdir = Path(args.figures)
    figdir.mkdir(parents=True, exist_ok=True)
    figs = [fig_max_rate(out, args.dx, figdir), fig_profiles(out, args.dx[-1], figdir),
            fig_event_slip(out, args.dx[-1], figdir, res)]
    rel = [Path("..") / "figures" / f.name for f in figs]
    write_page(res, args.dx, args.page, rel, "python -m studies.cycles.bp5 " + " ".join(argv or sys.argv[1:]))
    print(f"wrote {args.page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
