"""SCEC TPV3 with cracklab against the independent spectral BI code MDSBI (docs/tpv3.md).

    .venv/bin/python studies/tpv3/run.py [--quick] [-o OUT] [--dx 100 50] [--t-end-50 T]
                                         [--report-only] [--force]

Runs ``cracklab.scenes.tpv3`` at each grid spacing (default 100 m and 50 m), streams
each run to OUT/tpv3_dx<dx>.zarr (station series every step, rupture time of the whole
fault, the slip field at the end) with its wall time in OUT/tpv3_dx<dx>.json, then
compares the two MDSBI stations (shared/reference/tpv3_mdsbi) and writes

* OUT/tpv3_results.json         every number of the page,
* docs/figures/tpv3_*.png       station series against MDSBI, rupture-time contours,
* docs/tpv3.md                  the page, written from these results.

A run whose store is complete and whose scene matches is not repeated (``--force``
reruns). ``--quick`` runs 600 m and 400 m for 6 s into OUT/quick (about a minute) and
writes its page and figures there, not into docs/. ``--report-only`` redraws from the
stores. Time stepping: tpv3's own scheme (formulation "auto", i.e. the product scheme at
beta = 0.125) with the exponential history engine (constant cost and memory per step).
Runs with beta = 0.25 found in OUT/beta0.25 are shown as a time-step check.
``--formulation displacement`` runs the paper's displacement scheme (beta = 0.049) into
OUT/displacement; the page then shows it as a cross-check at 100 m (docs/tpv3.md).
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))

import compare as C  # noqa: E402

REF_STATIONS = ("faultst075dp000", "faultst000dp-045")
PRETTY = {"faultst075dp000": "faultst075dp000 (7.5 km along strike, in-plane)",
          "faultst000dp-045": "faultst000dp-045 (4.5 km along dip, anti-plane)"}
FORMULATION = "auto"      # tpv3's own choice: the product scheme (stable in mode II), beta = 0.125
ENGINE = "exponential"


def numerics(formulation=None):
    from cracklab.model.scene import Numerics

    return Numerics(formulation=formulation or FORMULATION, engine=ENGINE, rupture_threshold=C.THRESHOLD)


def build_scene(dx, t_end, formulation=None):
    from cracklab.model.record import Record
    from cracklab.scenes import tpv3

    base = tpv3(dx=dx, t_end=t_end, numerics=numerics(formulation))
    g = base.grid
    xc, zc = g.x1[g.n1 // 2], g.x3[g.n3 // 2]
    stations = dict(base.record.stations)
    for k in range(5, 151, 5):     # profiles along both axes every 0.5 km (docs/tpv3.md)
        stations[f"axis_x1_{k:03d}"] = (xc + 100.0 * k, zc)
        if k <= 75:
            stations[f"axis_x3_{k:03d}"] = (xc, zc - 100.0 * k)
    rec = Record(fields=("delta_1",), times=(base.nsteps * base.dt,), stations=stations)
    return base.replace(record=rec)


def store_path(out, dx):
    return Path(out) / f"tpv3_dx{dx:g}.zarr"


def _complete(store, scene):
    """The store holds a finished run of this very scene."""
    import xarray as xr

    from cracklab.output.simulate import scene_of

    if not Path(store).exists() or not Path(store).with_suffix(".json").exists():
        return False
    try:
        ds = xr.open_zarr(store, consolidated=False)
        old = scene_of(ds)
        return ("rupture_time" in ds and old.to_toml() == scene.to_toml())
    except Exception:
        return False


def run_one(dx, t_end, out, force=False, log=print, formulation=None):
    """Run (or reuse) one grid spacing; return its metadata dict."""
    from cracklab.output.simulate import simulate

    scene = build_scene(dx, t_end, formulation)
    store = store_path(out, dx)
    meta_path = store.with_suffix(".json")
    if not force and _complete(store, scene):
        meta = json.loads(meta_path.read_text())
        log(f"dx = {dx:g} m: reusing {store} (ran in {meta['wall_s']:.0f} s)")
        return meta
    if store.exists():
        import shutil

        shutil.rmtree(store)
    g = scene.grid
    log(f"dx = {dx:g} m: grid {g.n1} x {g.n3}, beta = {scene.beta:.4f}, dt = {scene.dt:.3e} s, "
        f"{scene.nsteps} steps to t = {t_end:g} s -> {store}")
    t0 = time.time()
    simulate(scene, store=str(store), progress=False)
    wall = time.time() - t0
    import cracklab

    meta = {"dx": dx, "t_end": scene.nsteps * scene.dt, "n1": g.n1, "n3": g.n3, "beta": scene.beta,
            "dt": scene.dt, "nsteps": scene.nsteps, "wall_s": wall, "s_per_step": wall / scene.nsteps,
            "formulation": scene.formulation, "engine": scene.numerics.engine,
            "cracklab_version": cracklab.__version__, "host": platform.node(),
            "finished": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}
    meta_path.write_text(json.dumps(meta, indent=1))
    log(f"dx = {dx:g} m: done in {wall:.0f} s ({1e3 * wall / scene.nsteps:.1f} ms/step)")
    return meta


# ------------------------------------------------------------------------------ analysis
def load_run(out, dx):
    import xarray as xr

    from cracklab.output.simulate import scene_of, stations

    ds = xr.open_zarr(store_path(out, dx), consolidated=False)
    scene = scene_of(ds)
    st = stations(ds).load()
    return ds, scene, st


def sim_series(st, station):
    s = st.sel(station=station)
    return {"t": st.t.values, "slip": s.delta_1.values, "rate": s.v_1.values,
            "stress": s.tau_1.values / 1e6, "rate3": s.v_3.values}


SCAN_AXIS = {"faultst075dp000": "axis_x1_", "faultst000dp-045": "axis_x3_"}


def position_scan(st, refs):
    """Each reference record against cracklab's series at every 0.5 km along the axis of
    its station (x1 for the in-plane station, x3 for the anti-plane one): which distance
    from the hypocentre fits the record best (docs/tpv3.md, "Where is faultst000dp-045?")."""
    out = {}
    names = [str(n) for n in st.station.values]
    for s, prefix in SCAN_AXIS.items():
        r = refs[s]
        ref = {"t": r["t"], "slip": r["h_slip"], "rate": r["h_rate"], "stress": r["h_stress"]}
        rows = []
        for n in names:
            if not n.startswith(prefix):
                continue
            axis = "x1" if prefix == "axis_x1_" else "x3"
            centre = float(st[axis].sel(station="faultst000dp000"))
            dist = round(abs(float(st[axis].sel(station=n)) - centre) / 1e3, 3)   # the node's distance
            if any(row["km"] == dist for row in rows):
                continue
            sim = sim_series(st, n)
            c = C.compare_station(sim, ref)
            e = C.series_errors(sim, ref)
            rows.append({"km": dist, "rupture_time": c["sim"]["rupture_time"], "final_slip": c["sim"]["final_slip"],
                         "peak_rate": c["sim"]["peak_rate"], "rms_rate": e["rate"], "rms_slip": e["slip"],
                         "rms_stress": e["stress"]})
        rows.sort(key=lambda row: row["km"])
        best = min(rows, key=lambda row: row["rms_rate"]) if rows else None
        out[s] = {"rows": rows, "best_km": best["km"] if best else None}
    return out


def analyse(out, dxs, ref_dir=None):
    res = {"runs": {}, "stations": {}}
    refs = {s: C.load_reference(s, ref_dir) for s in REF_STATIONS}
    for dx in dxs:
        meta = json.loads(store_path(out, dx).with_suffix(".json").read_text())
        ds, scene, st = load_run(out, dx)
        res["runs"][f"{dx:g}"] = meta
        for s in REF_STATIONS:
            ref = {"t": refs[s]["t"], "slip": refs[s]["h_slip"], "rate": refs[s]["h_rate"],
                   "stress": refs[s]["h_stress"]}
            sim = sim_series(st, s)
            cmp = C.compare_station(sim, ref)
            cmp["accept"] = C.acceptance(cmp)
            cmp["series_rms"] = C.series_errors(sim, ref)
            cmp["max_abs_v3"] = float(np.max(np.abs(sim["rate3"])))
            cmp["node"] = [float(st.x1.sel(station=s)), float(st.x3.sel(station=s))]
            res["stations"].setdefault(s, {})[f"{dx:g}"] = cmp
        res.setdefault("position_scan", {})[f"{dx:g}"] = position_scan(st, refs)
        rt = ds.rupture_time.values
        fault = ~np.asarray(scene.law.bonded)
        res["runs"][f"{dx:g}"]["ruptured_fraction"] = float(np.mean(np.isfinite(rt[fault])))
        res["runs"][f"{dx:g}"]["last_rupture_time"] = float(np.nanmax(rt))
    return res


# ------------------------------------------------------------------------------ figures
COLOURS = {"MDSBI": "k", "100": "tab:red", "50": "tab:blue", "600": "tab:orange", "400": "tab:green", "300": "tab:olive",
           "200": "tab:purple"}


def _colour(key):
    return COLOURS.get(key, None)


def fig_stations(out, dxs, figdir, ref_dir=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    runs = {f"{dx:g}": load_run(out, dx)[2] for dx in dxs}
    for s in REF_STATIONS:
        ref = C.load_reference(s, ref_dir)
        fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True)
        for ax, key, rkey, label in zip(axes, ("slip", "rate", "stress"), ("h_slip", "h_rate", "h_stress"),
                                        ("slip (m)", "slip rate (m/s)", "shear stress (MPa)")):
            ax.plot(ref["t"], ref[rkey], color="k", lw=2.2, alpha=0.55, label="MDSBI, 100 m")
            for name, st in runs.items():
                sim = sim_series(st, s)
                ax.plot(sim["t"], sim[key], color=_colour(name), lw=1.0, label=f"cracklab, {name} m")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[0].legend(loc="upper left", fontsize=8)
        axes[-1].set_xlabel("time (s)")
        axes[0].set_title(f"TPV3, {PRETTY[s]}: strike component", fontsize=10)
        fig.tight_layout()
        p = Path(figdir) / f"tpv3_{s}.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
        # zoom on the rupture front
        fig, ax = plt.subplots(figsize=(7.5, 3.6))
        t_r = C.rupture_time(ref["t"], ref["h_rate"])
        ax.plot(ref["t"], ref["h_rate"], color="k", lw=2.2, alpha=0.55, label="MDSBI, 100 m")
        for name, st in runs.items():
            sim = sim_series(st, s)
            ax.plot(sim["t"], sim["rate"], color=_colour(name), lw=1.0, label=f"cracklab, {name} m")
        ax.set_xlim(t_r - 0.3, t_r + 1.2)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("slip rate (m/s)")
        ax.axhline(C.THRESHOLD, color="0.5", lw=0.5)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{s}: slip rate around the rupture front", fontsize=10)
        fig.tight_layout()
        p = Path(figdir) / f"tpv3_{s}_front.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths


def fig_position(out, dx, res, figdir, ref_dir=None):
    """The anti-plane reference record against cracklab's series at its nominal position
    and at the position along the same axis that fits it best."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, _, st = load_run(out, dx)
    s = "faultst000dp-045"
    scan = res["position_scan"][f"{dx:g}"][s]
    best = scan["best_km"]
    centre = float(st.x3.sel(station="faultst000dp000"))
    names = [str(n) for n in st.station.values if str(n).startswith("axis_x3_")]
    best_name = min(names, key=lambda n: abs(abs(float(st.x3.sel(station=n)) - centre) / 1e3 - best))
    ref = C.load_reference(s, ref_dir)
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True)
    for ax, key, rkey, label in zip(axes, ("slip", "rate", "stress"), ("h_slip", "h_rate", "h_stress"),
                                    ("slip (m)", "slip rate (m/s)", "shear stress (MPa)")):
        ax.plot(ref["t"], ref[rkey], color="k", lw=2.2, alpha=0.55, label=f"MDSBI record '{s}'")
        sim = sim_series(st, s)
        ax.plot(sim["t"], sim[key], color="tab:red", lw=1.0, label=f"cracklab {dx:g} m, 4.5 km along dip")
        sim = sim_series(st, best_name)
        ax.plot(sim["t"], sim[key], color="tab:blue", lw=1.0, ls="--",
                label=f"cracklab {dx:g} m, {best:g} km along dip (best fit)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower right")
    axes[-1].set_xlabel("time (s)")
    axes[0].set_title("where along dip does the MDSBI record fit?", fontsize=10)
    fig.tight_layout()
    p = Path(figdir) / "tpv3_dp045_position.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p]


def fig_rupture(out, dxs, figdir):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    two = len(dxs) >= 2
    fig, axes = plt.subplots(2 if two else 1, 1, figsize=(9, 8.4 if two else 4.6), squeeze=False)
    axes = axes[:, 0]
    levels = np.arange(0.5, 12.01, 0.5)
    ax = axes[0]
    handles = []
    finest = None
    for dx in dxs:
        ds, scene, _ = load_run(out, dx)
        g = scene.grid
        xc, zc = g.x1[g.n1 // 2], g.x3[g.n3 // 2]
        x = (ds.x1.values - xc) / 1e3
        z = (ds.x3.values - zc) / 1e3
        rt = ds.rupture_time.values.T
        name = f"{dx:g}"
        cs = ax.contour(x, z, rt, levels=levels, colors=_colour(name), linewidths=0.9)
        handles.append(plt.Line2D([], [], color=_colour(name), label=f"cracklab, {name} m"))
        if finest is None or dx < finest[0]:
            finest = (dx, x, z, rt, cs)
    ax.clabel(finest[4], levels[1::2], fontsize=7, fmt="%.0f s")
    for s, (px, pz) in {"faultst075dp000": (7.5, 0.0), "faultst000dp-045": (0.0, -4.5)}.items():
        ax.plot(px, pz, "k^", ms=7)
        ax.annotate(s, (px, pz), textcoords="offset points", xytext=(5, 5), fontsize=8)
    ax.add_patch(plt.Rectangle((-1.5, -1.5), 3, 3, fill=False, ls="--", color="0.4"))
    ax.set_xlim(-15.5, 15.5)
    ax.set_ylim(-8, 8)
    ax.set_aspect("equal")
    ax.set_xlabel("along strike (km)")
    ax.set_ylabel("along dip (km)")
    ax.set_title("rupture time (slip rate > 1 mm/s), contours every 0.5 s", fontsize=10)
    ax.legend(handles=handles, loc="upper right", fontsize=8)
    # the difference between the two finest runs, on the coarser grid
    if two:
        ax = axes[1]
        a, b = sorted(dxs)[1], sorted(dxs)[0]
        dsa, sca, _ = load_run(out, a)
        dsb, scb, _ = load_run(out, b)
        ra = dsa.rupture_time.values
        rb = dsb.rupture_time.sel(x1=dsa.x1, x3=dsa.x3, method="nearest").values
        g = sca.grid
        xc, zc = g.x1[g.n1 // 2], g.x3[g.n3 // 2]
        diff = (ra - rb).T
        im = ax.pcolormesh((dsa.x1.values - xc) / 1e3, (dsa.x3.values - zc) / 1e3, diff, cmap="RdBu_r",
                           vmin=-0.1, vmax=0.1, shading="nearest")
        fig.colorbar(im, ax=ax, shrink=0.8, label="s")
        ax.set_title(f"rupture time at {a:g} m minus at {b:g} m", fontsize=10)
        ax.set_xlim(-15.5, 15.5)
        ax.set_ylim(-8, 8)
        ax.set_aspect("equal")
        ax.set_xlabel("along strike (km)")
        ax.set_ylabel("along dip (km)")
    fig.tight_layout()
    p = Path(figdir) / "tpv3_rupture_time.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p]


# ------------------------------------------------------------------------------ page
def _fmt_station_rows(res, dxs):
    rows = []
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            a = c["accept"]
            ok = lambda b: "yes" if b else "**no**"  # noqa: E731
            rows.append(
                f"| {s} | {dx:g} m | {c['sim']['rupture_time']:.3f} | {c['ref']['rupture_time']:.3f} | "
                f"{c['diff']['rupture_time']:+.3f} ({ok(a['rupture_time'])}) | "
                f"{c['sim']['final_slip']:.3f} | {c['ref']['final_slip']:.3f} | "
                f"{100 * c['rel']['final_slip']:+.1f} % ({ok(a['final_slip'])}) | "
                f"{c['sim']['peak_rate']:.3f} | {c['ref']['peak_rate']:.3f} | "
                f"{100 * c['rel']['peak_rate']:+.1f} % ({ok(a['peak_rate'])}) | {c['t_end']:.2f} |")
    return "\n".join(rows)


def _fmt_extra_rows(res, dxs):
    rows = []
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            f = c["fine"]
            r = c["series_rms"]
            rows.append(
                f"| {s} | {dx:g} m | {f['rupture_time_interp']:.4f} | {c['ref']['rupture_time_interp']:.4f} | "
                f"{f['peak_rate']:.3f} at {f['peak_time']:.3f} s | {c['ref']['peak_rate']:.3f} at "
                f"{c['ref']['peak_time']:.2f} s | {c['sim']['final_stress']:.2f} | {c['ref']['final_stress']:.2f} | "
                f"{100 * r['slip']:.1f} / {100 * r['rate']:.1f} / {100 * r['stress']:.1f} |")
    return "\n".join(rows)


def _fmt_runs(res, dxs):
    rows = []
    for dx in dxs:
        m = res["runs"][f"{dx:g}"]
        rows.append(f"| {dx:g} m | {m['n1']} x {m['n3']} | {m['beta']:.4f} | {m['dt'] * 1e3:.3f} ms | "
                    f"{m['nsteps']} | {m['t_end']:.2f} s | {m['wall_s'] / 60:.1f} min | "
                    f"{1e3 * m['s_per_step']:.0f} ms | {100 * m['ruptured_fraction']:.1f} % |")
    return "\n".join(rows)


def _fmt_scan(res, dx, station, kmax=8.0):
    scan = res["position_scan"][f"{dx:g}"][station]
    rows = []
    for r in scan["rows"]:
        if r["km"] > kmax:
            continue
        mark = " **(best)**" if r["km"] == scan["best_km"] else ""
        rows.append(f"| {r['km']:.1f}{mark} | {r['rupture_time']:.2f} | {r['final_slip']:.2f} | "
                    f"{r['peak_rate']:.2f} | {100 * r['rms_rate']:.1f} | {100 * r['rms_slip']:.1f} |")
    return "\n".join(rows)


def write_page(res, dxs, page, figrel, notes_path=None, command=None):
    """docs/tpv3.md from the results; the discussion (a file next to this script,
    ``discussion.md``, with {placeholders} filled from the results) follows the tables."""
    d = {}
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            key = f"{s.replace('-', 'm')}_{dx:g}"
            d[f"rt_{key}"] = f"{c['sim']['rupture_time']:.3f}"
            d[f"drt_{key}"] = f"{c['diff']['rupture_time']:+.3f}"
            d[f"slip_{key}"] = f"{100 * c['rel']['final_slip']:+.1f} %"
            d[f"peak_{key}"] = f"{100 * c['rel']['peak_rate']:+.1f} %"
    dxa = min(dxs, key=lambda x: abs(x - 100.0))
    for s in REF_STATIONS:
        key = s.replace("-", "m")
        c = res["stations"][s][f"{dxa:g}"]
        d[f"rms_rate_{key}"] = f"{100 * c['series_rms']['rate']:.1f} %"
        d[f"rms_slip_{key}"] = f"{100 * c['series_rms']['slip']:.1f} %"
        d[f"v3_{key}"] = f"{c['max_abs_v3']:.1e}"
        scan = res.get("position_scan", {}).get(f"{dxa:g}", {}).get(s)
        if scan:
            best = min(scan["rows"], key=lambda r: r["rms_rate"])
            d[f"best_km_{key}"] = f"{best['km']:g}"
            d[f"best_rt_{key}"] = f"{best['rupture_time']:.2f}"
            d[f"best_slip_{key}"] = f"{best['final_slip']:.2f}"
            d[f"best_peak_{key}"] = f"{best['peak_rate']:.2f}"
            d[f"best_rms_{key}"] = f"{100 * best['rms_rate']:.1f} %"
            d[f"best_rms_slip_{key}"] = f"{100 * best['rms_slip']:.1f} %"
    if "cross_check" in res:
        for s in REF_STATIONS:
            key = s.replace("-", "m")
            c = res["cross_check"]["stations"][s]["100"]
            d[f"x_rt_{key}"] = f"{c['sim']['rupture_time']:.3f}"
            d[f"x_drt_{key}"] = f"{c['diff']['rupture_time']:+.3f}"
            d[f"x_slip_{key}"] = f"{100 * c['rel']['final_slip']:+.1f} %"
            d[f"x_peak_{key}"] = f"{100 * c['rel']['peak_rate']:+.1f} %"
            d[f"x_rms_rate_{key}"] = f"{100 * c['series_rms']['rate']:.1f} %"
            d[f"x_rms_slip_{key}"] = f"{100 * c['series_rms']['slip']:.1f} %"
        d["x_wall_min"] = f"{res['cross_check']['runs']['100']['wall_s'] / 60:.0f}"
    for x in dxs:
        m = res["runs"][f"{x:g}"]
        d[f"wall_min_{x:g}"] = f"{m['wall_s'] / 60:.0f}"
        d[f"ms_step_{x:g}"] = f"{1e3 * m['s_per_step']:.0f}"
        d[f"steps_{x:g}"] = f"{m['nsteps']}"
        d[f"t_end_{x:g}"] = f"{m['t_end']:.1f}"
    fine = [x for x in dxs if x < dxa]
    if fine:
        lines = []
        for s in REF_STATIONS:
            a = res["stations"][s][f"{dxa:g}"]
            b = res["stations"][s][f"{min(fine):g}"]
            lines.append(f"{s}: rupture time {a['diff']['rupture_time']:+.3f} s at {dxa:g} m, "
                         f"{b['diff']['rupture_time']:+.3f} s at {min(fine):g} m; peak slip rate "
                         f"{100 * a['rel']['peak_rate']:+.1f} % and {100 * b['rel']['peak_rate']:+.1f} % "
                         f"(slip at {b['t_end']:.1f} s: {100 * b['rel']['final_slip']:+.1f} %).")
        scan_lines = []
        ref45 = C.load_reference("faultst000dp-045")
        m45 = C.metrics(ref45["t"], ref45["h_slip"], ref45["h_rate"])
        for x in (dxa, min(fine)):
            sc = res.get("position_scan", {}).get(f"{x:g}", {}).get("faultst000dp-045")
            if sc:
                b = min(sc["rows"], key=lambda r: r["rms_rate"])
                scan_lines.append(f"{b['rupture_time']:.2f} s and {b['peak_rate']:.2f} m/s "
                                  f"({100 * (b['peak_rate'] / m45['peak_rate'] - 1):+.1f} %) at {x:g} m")
        extra = ""
        if len(scan_lines) == 2:
            extra = (f" At the position where the anti-plane record fits (3 km along dip, below): rupture time and "
                     f"peak slip rate {scan_lines[0]}, {scan_lines[1]} (MDSBI 1.30 s, {m45['peak_rate']:.2f} m/s).")
        d["convergence"] = "Against MDSBI, " + " ".join(lines) + extra
    else:
        d["convergence"] = ("The 50 m run is not in this version of the page (see \"What is left\"): "
                            "the convergence from 100 m to 50 m is not shown yet.")
    cmd = "studies/tpv3/run.py"
    short = [f"{x:g} m" for x in dxs if res["runs"][f"{x:g}"]["t_end"] < 11.9]
    short_note = (f"The {', '.join(short)} run ends before the slip does: its \"final slip\" is the slip at "
                  f"its last common sample, which at faultst075dp000 (ruptured 0.5 s before) measures the "
                  f"lag of the front rather than the final slip; the acceptance applies at 100 m.\n\n"
                  if short else "")
    text = f"""# SCEC TPV3 against MDSBI

*Written by `{cmd}` from its own output.
This version: `{command or cmd}` (runs reused from `out/tpv3/`; the 100 m cross-check of the
displacement scheme from `.venv/bin/python {cmd} --formulation displacement --dx 100`).
`nice -n 10 .venv/bin/python {cmd}` alone runs what is missing (both runs: about an hour on
the shared 2-core machine) and redraws.*

TPV3 (Harris et al. 2009; Day et al. 2005, Table 1) is the SCEC/USGS spontaneous rupture
benchmark in a homogeneous whole space: a 30 km x 15 km vertical fault with linear
slip-weakening friction (mu_s = 0.677, mu_d = 0.525, D_c = 0.4 m, 120 MPa normal stress),
70 MPa initial shear stress and 81.6 MPa on a 3 km x 3 km square around the hypocentre.
`cracklab.scenes.tpv3` builds it in a periodic 48 km x 24 km domain (the plane outside
the fault is bonded). The reference is two on-fault stations computed at 100 m with
MDSBI, E. M. Dunham's spectral boundary-integral code (`shared/reference/tpv3_mdsbi`).
All comparisons use the strike (h) components.

## Runs

| dx | grid | beta | dt | steps | t_end | wall time | per step | fault ruptured |
|---|---|---|---|---|---|---|---|---|
{_fmt_runs(res, dxs)}

Wall times on the project's 2-core machine shared with other jobs, at `nice 10`
(not a benchmark). Time stepping: `Numerics(formulation="{FORMULATION}", engine="{ENGINE}")`
(the product scheme, tpv3's default) at the builder's beta (see "Numerics" below).

## Acceptance (issue 5): rupture time within 0.05 s, final slip within 3 %, peak slip rate within 15 % at 100 m

Both series are taken on the reference's samples (every 0.01 s; cracklab's series are
interpolated to those times) and measured with the same definitions: rupture time =
first sample with slip rate > 1 mm/s; final slip = slip at the common end time
(12 s, or the end of a shorter run); peak slip rate = largest sample.

| station | dx | rupture time (s) | MDSBI | difference (pass) | final slip (m) | MDSBI | difference (pass) | peak slip rate (m/s) | MDSBI | difference (pass) | end (s) |
|---|---|---|---|---|---|---|---|---|---|---|---|
{_fmt_station_rows(res, dxs)}

{short_note}On cracklab's own time steps (no resampling), with the rupture time from the
interpolated 1 mm/s crossing (the reference's crossing interpolated between its
0.01 s samples), the final shear stress, and the RMS difference of the whole series
(slip / slip rate / stress change, in % of the reference's peak):

| station | dx | rupture time, interpolated (s) | MDSBI | peak slip rate | MDSBI | final stress (MPa) | MDSBI | RMS difference (%) |
|---|---|---|---|---|---|---|---|---|
{_fmt_extra_rows(res, dxs)}

## Figures

![faultst075dp000]({figrel}/tpv3_faultst075dp000.png)

![faultst075dp000, front]({figrel}/tpv3_faultst075dp000_front.png)

![faultst000dp-045]({figrel}/tpv3_faultst000dp-045.png)

![faultst000dp-045, front]({figrel}/tpv3_faultst000dp-045_front.png)

![rupture time]({figrel}/tpv3_rupture_time.png)

"""
    dxa = min(dxs, key=lambda x: abs(x - 100.0))
    if "position_scan" in res and f"{dxa:g}" in res["position_scan"]:
        refs = {st: C.load_reference(st) for st in REF_STATIONS}
        rm = {st: C.metrics(r["t"], r["h_slip"], r["h_rate"], r["h_stress"]) for st, r in refs.items()}
        text += f"""## Where is faultst000dp-045? Both records against cracklab along their axes ({dxa:g} m)

Each MDSBI record compared with cracklab's series at every node 0.5 km apart along the
axis of its station (strike for faultst075dp000, dip for faultst000dp-045); RMS of the
slip-rate and slip differences over 0-12 s in % of the record's peak. The in-plane record
is the control: it should fit best at its own position, 7.5 km.

faultst075dp000 (MDSBI: rupture {rm['faultst075dp000']['rupture_time']:.2f} s, final slip
{rm['faultst075dp000']['final_slip']:.2f} m, peak {rm['faultst075dp000']['peak_rate']:.2f} m/s), along strike:

| km from hypocentre | rupture time (s) | final slip (m) | peak rate (m/s) | RMS rate (%) | RMS slip (%) |
|---|---|---|---|---|---|
{_fmt_scan(res, dxa, "faultst075dp000", 9.0)}

faultst000dp-045 (MDSBI: rupture {rm['faultst000dp-045']['rupture_time']:.2f} s, final slip
{rm['faultst000dp-045']['final_slip']:.2f} m, peak {rm['faultst000dp-045']['peak_rate']:.2f} m/s), along dip:

| km from hypocentre | rupture time (s) | final slip (m) | peak rate (m/s) | RMS rate (%) | RMS slip (%) |
|---|---|---|---|---|---|
{_fmt_scan(res, dxa, "faultst000dp-045", 7.5)}

![dp-045 position]({figrel}/tpv3_dp045_position.png)

"""
    if "cross_check" in res:
        cc = res["cross_check"]
        m = cc["runs"]["100"]
        rows = []
        for st_name in REF_STATIONS:
            a = res["stations"][st_name].get("100")
            b = cc["stations"][st_name]["100"]
            if a is None:
                continue
            rows.append(f"| {st_name} | {a['sim']['rupture_time']:.3f} | {b['sim']['rupture_time']:.3f} | "
                        f"{a['ref']['rupture_time']:.3f} | {a['sim']['final_slip']:.3f} | {b['sim']['final_slip']:.3f} | "
                        f"{a['ref']['final_slip']:.3f} | {a['sim']['peak_rate']:.3f} | {b['sim']['peak_rate']:.3f} | "
                        f"{a['ref']['peak_rate']:.3f} | {100 * a['series_rms']['rate']:.1f} / "
                        f"{100 * b['series_rms']['rate']:.1f} |")
        rows = "\n".join(rows)
        text += f"""## Cross-check at 100 m: the product scheme against the displacement scheme

The same 100 m problem with the paper's displacement scheme (`--formulation displacement`,
beta = {m['beta']:.4f}, {m['nsteps']} steps, {m['wall_s'] / 60:.0f} min on the shared machine;
store `out/tpv3/displacement/`), next to the product scheme of the main runs and MDSBI
(same definitions as above; last column: RMS slip-rate difference from MDSBI, % of its peak):

| station | rupture time, product | displacement | MDSBI | final slip, product | displacement | MDSBI | peak rate, product | displacement | MDSBI | RMS rate (%), product / displacement |
|---|---|---|---|---|---|---|---|---|---|---|
{rows}

"""
    if "dt_check" in res:
        dc = res["dt_check"]
        rows = []
        for key in sorted(dc["runs"], key=float, reverse=True):
            for st_name in REF_STATIONS:
                a = res["stations"][st_name].get(key)
                b = dc["stations"][st_name][key]
                if a is None:
                    continue
                ma, mb = res["runs"][key], dc["runs"][key]
                rows.append(f"| {st_name} | {float(key):g} m | {b['sim']['rupture_time']:.3f} ({b['diff']['rupture_time']:+.3f}) | "
                            f"{a['sim']['rupture_time']:.3f} ({a['diff']['rupture_time']:+.3f}) | "
                            f"{a['ref']['rupture_time']:.3f} | {100 * b['rel']['peak_rate']:+.1f} / "
                            f"{100 * a['rel']['peak_rate']:+.1f} | {mb['beta']:.3f} / {ma['beta']:.3f} | "
                            f"{mb['t_end']:.1f} / {ma['t_end']:.1f} |")
        rows = "\n".join(rows)
        text += f"""## Time step: beta = 0.25 against tpv3's default

The same runs with twice the time step (`tpv3(..., beta=0.25)`; stores
`out/tpv3/beta0.25/`), next to the main runs. Rupture time
in s (difference from MDSBI), peak slip rate difference from MDSBI (beta 0.25 / main run):

| station | dx | rupture time, beta 0.25 | main run | MDSBI | peak rate (%) | beta | t_end (s) |
|---|---|---|---|---|---|---|---|
{rows}

"""
    notes = Path(notes_path or HERE / "discussion.md")
    if notes.exists():
        body = notes.read_text()
        try:
            body = body.format(**d)
        except (KeyError, IndexError, ValueError) as exc:
            print(f"warning: {notes}: placeholder {exc} not filled", file=sys.stderr)
        text += body
    Path(page).write_text(text)
    return page


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default=str(ROOT / "out" / "tpv3"))
    p.add_argument("--dx", type=float, nargs="+", default=None, help="grid spacings in m (default 100 50)")
    p.add_argument("--t-end", type=float, default=12.0, help="simulated time of the runs (s)")
    p.add_argument("--t-end-50", type=float, default=None,
                   help="simulated time of runs with dx <= 50 m (default: --t-end)")
    p.add_argument("--quick", action="store_true", help="600 m and 400 m, 6 s, into OUT/quick")
    p.add_argument("--report-only", action="store_true", help="only redraw figures and page from the stores")
    p.add_argument("--force", action="store_true", help="rerun even if a complete store exists")
    p.add_argument("--figures", default=None, help="figure directory (default docs/figures)")
    p.add_argument("--page", default=None, help="page to write (default docs/tpv3.md)")
    p.add_argument("--reference", default=None, help="directory of the MDSBI station files")
    p.add_argument("--formulation", default=FORMULATION, choices=("auto", "displacement"),
                   help="time stepping (default auto: tpv3's product scheme); 'displacement' runs the "
                        "cross-check of docs/tpv3.md into OUT/displacement and writes no page")
    args = p.parse_args(argv)

    out = Path(args.out)
    if args.formulation != FORMULATION:
        out = out / args.formulation
        args.page = args.page or str(out / "tpv3.md")
        args.figures = args.figures or str(out)
    if args.quick:
        out = out / "quick"
        dxs = args.dx or [600.0, 400.0]
        t_end = 6.0
        figdir = Path(args.figures or out)
        page = Path(args.page or out / "tpv3.md")
    else:
        dxs = args.dx or [100.0, 50.0]
        t_end = args.t_end
        figdir = Path(args.figures or ROOT / "docs" / "figures")
        page = Path(args.page or ROOT / "docs" / "tpv3.md")
    out.mkdir(parents=True, exist_ok=True)
    figdir.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        for dx in dxs:
            te = args.t_end_50 if (args.t_end_50 is not None and dx <= 50.0) else t_end
            run_one(dx, te, out, force=args.force, formulation=args.formulation)
    res = analyse(out, dxs, args.reference)
    cross = Path(args.out) / "displacement"
    if args.formulation == FORMULATION and not args.quick and store_path(cross, 100.0).with_suffix(".json").exists():
        res["cross_check"] = analyse(cross, [100.0], args.reference)
    coarse_dt = Path(args.out) / "beta0.25"
    done = [x for x in dxs if store_path(coarse_dt, x).with_suffix(".json").exists()]
    if args.formulation == FORMULATION and not args.quick and done:
        res["dt_check"] = analyse(coarse_dt, done, args.reference)
    (out / "tpv3_results.json").write_text(json.dumps(res, indent=1))
    fig_stations(out, dxs, figdir, args.reference)
    fig_rupture(out, dxs, figdir)
    fig_position(out, min(dxs, key=lambda x: abs(x - 100.0)), res, figdir, args.reference)
    try:
        figrel = Path(figdir).resolve().relative_to(Path(page).resolve().parent)
    except ValueError:
        figrel = Path(figdir).resolve()
    argv_used = sys.argv[1:] if argv is None else list(argv)
    write_page(res, dxs, page, figrel.as_posix(),
               command=" ".join([".venv/bin/python", "studies/tpv3/run.py"] + argv_used))
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            print(f"{s:18s} {dx:5g} m  rupture {c['sim']['rupture_time']:.3f} vs {c['ref']['rupture_time']:.3f} "
                  f"({c['diff']['rupture_time']:+.3f} s)  final slip {c['sim']['final_slip']:.3f} vs "
                  f"{c['ref']['final_slip']:.3f} ({100 * c['rel']['final_slip']:+.1f} %)  peak rate "
                  f"{c['sim']['peak_rate']:.3f} vs {c['ref']['peak_rate']:.3f} ({100 * c['rel']['peak_rate']:+.1f} %)"
                  f"  accept {c['accept']}")
    print(f"wrote {page}, figures in {figdir}, results in {out / 'tpv3_results.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
