"""SCEC TPV5 with cracklab against the independent spectral BI code MDSBI (docs/studies/tpv5.md).

    python -m studies.tpv5.run [--dx 100 [50]] [-o OUT] [--quick] [--report-only] [--force]
                                [--beta B | --domain L1 L3 | --step-cost B1 B2 ...] [--formulation product]

Runs ``cracklab.scenes.tpv5`` (the free surface by mirror symmetry: the half plane below
it) at each grid spacing (default 100 m; ``--dx 100 50`` adds 50 m), streams each run to
OUT/tpv5_dx<dx>.zarr (station series every step, the rupture time of the half plane, the
slip at the end) with its wall time in OUT/tpv5_dx<dx>.json, compares the reference's five
stations (shared/reference/tpv5_mdsbi, or ``--reference DIR``: faultst000dp000 on the surface, faultst000dp030,
faultst000dp075 the hypocentre, faultst-075dp075 and faultst075dp075 the centres of the
78 MPa and 62 MPa patches) and writes

* OUT/tpv5_results.json         every number of the page, and the acceptance verdict,
* docs/figures/tpv5_*.png       station series against MDSBI, rupture-time contours,
* docs/studies/tpv5.md                  the page, written from these results.

The acceptance is the study's result (``compare.check_acceptance``, TPV3's): at 100 m, at
the five stations, rupture time within 0.05 s, final slip within 3 % and peak slip rate
within 15 % of MDSBI; at 50 m each difference within the same limit and no larger than at
100 m. The script prints PASS or FAIL and exits with status 1 when it does not hold (2
when it could not be checked: no 100 m run).

A run whose store is complete and whose scene matches is not repeated (``--force``
reruns); ``--report-only`` redraws from the stores. ``--quick`` runs 600 m and 400 m for
6 s into OUT/quick (a smoke test; no acceptance). ``--beta B`` (a time-step check) and
``--domain L1 L3`` (another periodic length along strike L1 and half-plane depth L3) run
the same problem into OUT/beta<B> or OUT/domain<L1>x<L3>km, together with the main cell's
run at the same dx if it is missing (its baseline), and write no page; the main page then
shows them next to the main runs. ``--formulation product`` (with ``--beta B`` or alone)
runs the same problem with the first-order product scheme (the law's slip path by the
rectangle rule, docs/reference/stability.md) into OUT/product[_beta<B>], shown next to the main runs
as well. ``--step-cost B1 B2`` measures the cost of a 100 m step at each beta in one
sitting (alternated rounds) into OUT/step_cost.json, which the page uses to say what a
smaller beta costs. Time stepping of the main runs: tpv5's own (product2, the product
scheme with the law at the step's mean velocity, second order in dt, at the builder's
beta) with the exponential history engine.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H
from studies.tpv5 import compare as C

HERE = Path(__file__).resolve().parent
ROOT = H.ROOT

REF_STATIONS = ("faultst000dp000", "faultst000dp030", "faultst000dp075", "faultst-075dp075", "faultst075dp075")
PRETTY = {"faultst000dp000": "faultst000dp000 (free surface above the hypocentre)",
          "faultst000dp030": "faultst000dp030 (3.0 km depth above the hypocentre)",
          "faultst000dp075": "faultst000dp075 (hypocentre, 7.5 km depth)",
          "faultst-075dp075": "faultst-075dp075 (centre of the 78 MPa patch)",
          "faultst075dp075": "faultst075dp075 (centre of the 62 MPa patch)"}
POSITION_KM = {"faultst000dp000": (0.0, 0.0), "faultst000dp030": (0.0, 3.0), "faultst000dp075": (0.0, 7.5),
               "faultst-075dp075": (-7.5, 7.5), "faultst075dp075": (7.5, 7.5)}
SURFACE = "faultst000dp000"
FORMULATION = "product2"  # the builder's default: the product scheme at second order in dt
ENGINE = "exponential"
DOMAIN = (48000.0, 24000.0)
BETA_SHOWN = 0.5          # a fitted beta beyond this lies past any builder's beta (at most 0.5): shown as "> 0.5"
SCATTER = 0.005           # s: the 1 mm/s crossing scatters by a few ms about its limit (docs/reference/stability.md)


def numerics(formulation=None):
    return H.numerics(formulation or FORMULATION, ENGINE)


def build_scene(dx, t_end, beta=None, domain=None, formulation=None):
    """``scenes.tpv5`` with its own stations, the rupture time of the half plane and the
    slip along strike at the end."""
    from cracklab.scenes import tpv5

    return H.build(tpv5, dx, t_end=t_end, domain=domain, beta=beta, numerics=numerics(formulation))


def store_path(out, dx):
    return H.store_path(out, f"tpv5_dx{dx:g}")


def run_one(dx, t_end, out, force=False, log=print, beta=None, domain=None, formulation=None):
    """Run (or reuse) one grid spacing; return its metadata dict."""
    scene = build_scene(dx, t_end, beta, domain, formulation)
    return H.run_scene(scene, store_path(out, dx), label=f"dx = {dx:g} m",
                       meta={"dx": dx, "shape": list(scene.grid.shape)}, force=force, log=log)


def step_cost(out, betas, dx=C.ACCEPT_DX, steps=300, rounds=3, log=print):
    """The cost of a step of ``tpv5`` at each beta, measured in one sitting: ``rounds``
    rounds, the betas alternated (reversed every other round), ``steps`` steps each from
    t = 0 with the kernel fits of the whole 12 s run (so each beta carries the terms of its
    real run), the median of the second half's steps. Writes OUT/step_cost.json:
    {"dx", "steps", "rounds": [{beta: ms per step}], "median_ms": {beta: median over rounds}}."""
    from cracklab.model.record import Record
    from cracklab.solver.interfaces import for_scene
    from cracklab.solver.spectral import Transforms
    from cracklab.solver.stepper import Stepper

    rows = []
    for r in range(rounds):
        row = {}
        for beta in (betas if r % 2 == 0 else betas[::-1]):
            full = build_scene(dx, 12.0, beta)
            scene = full.replace(t_end=steps * full.dt, record=Record(fields=()))
            stepper = Stepper(scene, for_scene(scene, Transforms(scene.grid), nsteps=full.nsteps))
            times, t0 = [], time.perf_counter()
            for _ in stepper:
                times.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
            row[f"{beta:g}"] = 1e3 * float(np.median(times[len(times) // 2:]))
            log(f"round {r + 1}: beta = {beta:g}: {row[f'{beta:g}']:.1f} ms per step", flush=True)
        rows.append(row)
    res = {"dx": dx, "steps": steps, "rounds": rows,
           "median_ms": {k: float(np.median([row[k] for row in rows])) for k in rows[0]}}
    Path(out).mkdir(parents=True, exist_ok=True)
    (Path(out) / "step_cost.json").write_text(json.dumps(res, indent=1))
    return res


# ------------------------------------------------------------------------------ analysis
def load_run(out, dx):
    return H.load_run(store_path(out, dx))


sim_series = H.strike_series
ref_series = H.reference_series


def compare_run(st, refs):
    """Every reference station of one run: compare.compare_station, the acceptance, the
    whole-series RMS differences, the node's position (strike from the hypocentre, depth)
    and the largest dip slip rate; for the surface station compare.surface_check."""
    out = {}
    xc = float(st.x1.sel(station="faultst000dp075"))
    for s in REF_STATIONS:
        cmp, sim, ref = H.compare_strike(st, s, refs[s])
        cmp["ref_max_abs_v3"] = float(np.max(np.abs(refs[s]["v_rate"])))
        cmp["position_km"] = [(float(st.x1.sel(station=s)) - xc) / 1e3, float(st.x3.sel(station=s)) / 1e3]
        if s == SURFACE:
            cmp["surface"] = C.surface_check(sim["t"], sim["rate"], sim["rate3"])
        out[s] = cmp
    return out


def analyse(out, dxs, ref_dir=None):
    refs = {s: C.load_reference(s, ref_dir) for s in REF_STATIONS}
    res = H.analyse_runs({f"{dx:g}": store_path(out, dx) for dx in dxs}, lambda st: compare_run(st, refs),
                         lambda st, rt, fault: {"surface_rupture_time": float(np.nanmax(rt[:, 0][fault[:, 0]]))})
    res["acceptance"] = C.check_acceptance(res["stations"])
    return res


def variants(out):
    """The time-step, cell and scheme checks found next to the main runs: {name: [dx, ...]}."""
    found = {}
    for d in sorted(Path(out).glob("beta*")) + sorted(Path(out).glob("domain*")) + sorted(Path(out).glob("product*")):
        done = sorted((float(p.stem.split("dx")[1]) for p in d.glob("tpv5_dx*.json")), reverse=True)
        if d.is_dir() and done:
            found[d.name] = done
    return found


def add_variants(res, main_out, ref_dir=None):
    """res["variants"] (each check's analysis), res["baselines"] (the main cell's analysis
    at each dx a check used), res["lag"] (compare.lag_fit per station from the beta checks
    at 100 m) and res["domain_change"] (compare.domain_change of each cell check)."""
    found = variants(main_out)
    if not found:
        return res
    res["variants"] = {name: analyse(main_out / name, done, ref_dir) for name, done in found.items()}
    need = sorted({dx for done in found.values() for dx in done}, reverse=True)
    have = [dx for dx in need if store_path(main_out, dx).with_suffix(".json").exists()]
    res["baselines"] = analyse(main_out, have, ref_dir) if have else {"runs": {}, "stations": {}}
    key = f"{C.ACCEPT_DX:g}"
    betas = {name: v for name, v in res["variants"].items() if name.startswith("beta") and key in v["runs"]}
    if betas and key in res["baselines"]["runs"]:
        from cracklab.solver.schemes import SCHEMES

        res["lag"] = {}
        base = res["baselines"]
        for s in REF_STATIONS:
            bs = [base["runs"][key]["beta"]] + [v["runs"][key]["beta"] for v in betas.values()]
            cs = [base["stations"][s][key]] + [v["stations"][s][key] for v in betas.values()]
            lags = [c["fine"]["rupture_time_interp"] - c["ref"]["rupture_time_interp"] for c in cs]
            fit = C.lag_fit(bs, lags, beta_now=base["runs"][key]["beta"],
                            order=SCHEMES[base["runs"][key]["formulation"]].front_order)
            fit["betas"], fit["lags"] = bs, lags
            fit["sampled"] = [c["diff"]["rupture_time"] for c in cs]
            res["lag"][s] = fit
    cost = Path(main_out) / "step_cost.json"
    if cost.exists():
        res["step_cost"] = json.loads(cost.read_text())
    res["domain_change"] = {}
    for name, v in res["variants"].items():
        if not name.startswith("domain"):
            continue
        for k in v["runs"]:
            if k in res["baselines"]["runs"]:
                main = {s: res["baselines"]["stations"][s][k] for s in REF_STATIONS}
                other = {s: v["stations"][s][k] for s in REF_STATIONS}
                res["domain_change"][f"{name}@{k}"] = {"dx": float(k), "cell": v["runs"][k]["domain"],
                                                       **C.domain_change(main, other)}
    return res


# ------------------------------------------------------------------------------ figures
COLOURS = {"100": "tab:red", "50": "tab:blue", "600": "tab:orange", "400": "tab:green", "200": "tab:purple"}


def fig_stations(out, dxs, figdir, ref_dir=None):
    plt = H.pyplot()
    paths = []
    runs = {f"{dx:g}": load_run(out, dx)[2] for dx in dxs}
    for s in REF_STATIONS:
        ref = C.load_reference(s, ref_dir)
        fig = H.station_figure(ref, runs, lambda st: sim_series(st, s), f"TPV5, {PRETTY[s]}: strike component",
                               ref_keys=("h_slip", "h_rate", "h_stress"), ref_label="MDSBI, 100 m", colours=COLOURS)
        paths.append(H.save(fig, Path(figdir) / f"tpv5_{s}.png", 100))
    # the rupture fronts: slip rate around the reference's rupture time, one panel per station
    fig, axes = plt.subplots(len(REF_STATIONS), 1, figsize=(7.5, 2.3 * len(REF_STATIONS)))
    for ax, s in zip(axes, REF_STATIONS):
        ref = C.load_reference(s, ref_dir)
        t_r = C.rupture_time(ref["t"], ref["h_rate"])
        ax.plot(ref["t"], ref["h_rate"], color="k", lw=2.2, alpha=0.55, label="MDSBI, 100 m")
        for name, st in runs.items():
            sim = sim_series(st, s)
            ax.plot(sim["t"], sim["rate"], color=COLOURS.get(name), lw=1.0, label=f"cracklab, {name} m")
        ax.set_xlim(t_r - 0.3, t_r + 1.2)
        ax.axvline(t_r, color="0.5", lw=0.5)
        ax.set_ylabel("slip rate (m/s)")
        ax.set_title(s, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time (s)")
    paths.append(H.save(fig, Path(figdir) / "tpv5_fronts.png", 100))
    return paths


def _decorate(ax, plt):
    from cracklab.scenes import TPV5_PATCHES

    for centre, _ in TPV5_PATCHES:
        ax.add_patch(plt.Rectangle((centre / 1e3 - 1.5, 6.0), 3, 3, fill=False, ls="--", color="0.4"))
    ax.add_patch(plt.Rectangle((-15, 0), 30, 15, fill=False, color="0.2", lw=0.8))
    for s, (px, pz) in POSITION_KM.items():
        ax.plot(px, pz, "k^", ms=6, clip_on=False)
        ax.annotate(s, (px, pz), textcoords="offset points", xytext=(4, 4 if pz > 0 else -11), fontsize=7)
    ax.set_xlim(-16, 16)
    ax.set_ylim(16, 0)
    ax.set_aspect("equal")
    ax.set_xlabel("along strike from the hypocentre (km)")
    ax.set_ylabel("depth (km)")


def fig_rupture(out, dxs, figdir):
    """cracklab's rupture-time contours on the half plane (the reference has no contour
    file for TPV5), and the difference of the two finest runs."""
    plt = H.pyplot()
    two = len(dxs) >= 2
    fig, axes = plt.subplots(2 if two else 1, 1, figsize=(9, 9.6 if two else 5.0), squeeze=False)
    axes = axes[:, 0]
    levels = np.arange(0.5, 12.01, 0.5)
    ax = axes[0]
    handles, finest = [], None
    for dx in dxs:
        ds, scene, _ = load_run(out, dx)
        g = scene.grid
        x = (ds.x1.values - g.x1[g.n1 // 2]) / 1e3
        z = ds.x3.values / 1e3
        rt = ds.rupture_time.values.T
        name = f"{dx:g}"
        cs = ax.contour(x, z, rt, levels=levels, colors=COLOURS.get(name), linewidths=0.9)
        handles.append(plt.Line2D([], [], color=COLOURS.get(name), label=f"cracklab, {name} m"))
        if finest is None or dx < finest[0]:
            finest = (dx, cs)
    ax.clabel(finest[1], levels[1::2], fontsize=7, fmt="%.0f s")
    _decorate(ax, plt)
    ax.set_title("TPV5 rupture time (slip rate > 1 mm/s), contours every 0.5 s; free surface at the top\n"
                 "(cracklab only: the MDSBI reference has no contour file for TPV5)", fontsize=9)
    ax.legend(handles=handles, loc="lower right", fontsize=8)
    if two:
        ax = axes[1]
        a, b = sorted(dxs)[1], sorted(dxs)[0]
        dsa, sca, _ = load_run(out, a)
        dsb, _, _ = load_run(out, b)
        ra = dsa.rupture_time.values
        rb = dsb.rupture_time.sel(x1=dsa.x1, x3=dsa.x3, method="nearest").values
        g = sca.grid
        im = ax.pcolormesh((dsa.x1.values - g.x1[g.n1 // 2]) / 1e3, dsa.x3.values / 1e3, (ra - rb).T,
                           cmap="RdBu_r", vmin=-0.1, vmax=0.1, shading="nearest")
        fig.colorbar(im, ax=ax, shrink=0.7, label="s")
        _decorate(ax, plt)
        ax.set_title(f"rupture time at {a:g} m minus at {b:g} m", fontsize=9)
    return [H.save(fig, Path(figdir) / "tpv5_rupture_time.png", 100)]


# ------------------------------------------------------------------------------ page
def verdict_lines(res, dxs):
    return H.verdict_lines(res, dxs, "the five stations")


def _fmt_runs(res, dxs):
    rows = []
    for dx in dxs:
        m = res["runs"][f"{dx:g}"]
        rows.append(f"| {dx:g} m | {m['shape'][0]} x {m['shape'][1]} | {m['domain'][0] / 1e3:g} km x "
                    f"{m['domain'][1] / 1e3:g} km | {m['beta']:.4f} | {m['dt'] * 1e3:.3f} ms | {m['nsteps']} | "
                    f"{m['t_end']:.2f} s | {m['wall_s'] / 60:.1f} min | {1e3 * m['s_per_step']:.0f} ms | "
                    f"{100 * m['ruptured_fraction']:.1f} % | {m['surface_rupture_time']:.2f} s |")
    return "\n".join(rows)


def _fmt_positions(res, dxs):
    rows = []
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            extra = ""
            if "surface" in c:
                sc = c["surface"]
                extra = f" (surface check: {'holds' if sc['pass'] else '**fails**'})"
            rows.append(f"| {s} | {dx:g} m | ({c['position_km'][0]:+.2f}, {c['position_km'][1]:.2f}) km | "
                        f"{c['max_abs_v3']:.1e}{extra} | {c['ref_max_abs_v3']:.1e} |")
    return "\n".join(rows)


def _describe(meta):
    L1, L3 = meta.get("domain", DOMAIN)
    return f"{meta['formulation']}, beta {meta['beta']:.4f}, {L1 / 1e3:g} km x {L3 / 1e3:g} km"


def variant_section(res):
    if not res.get("variants"):
        return ""
    rows = []
    base = res["baselines"]
    for name, vres in res["variants"].items():
        for key in sorted(vres["runs"], key=float, reverse=True):
            if key not in base["runs"]:
                continue
            mv, ma = vres["runs"][key], base["runs"][key]
            for s in REF_STATIONS:
                a, b = base["stations"][s][key], vres["stations"][s][key]
                rows.append(
                    f"| {s} | {float(key):g} m | {_describe(mv)} | "
                    f"{b['diff']['rupture_time']:+.3f} / {a['diff']['rupture_time']:+.3f} | "
                    f"{b['fine']['rupture_time_interp'] - b['ref']['rupture_time_interp']:+.4f} / "
                    f"{a['fine']['rupture_time_interp'] - a['ref']['rupture_time_interp']:+.4f} | "
                    f"{100 * b['rel']['final_slip']:+.1f} / {100 * a['rel']['final_slip']:+.1f} | "
                    f"{100 * b['rel']['peak_rate']:+.1f} / {100 * a['rel']['peak_rate']:+.1f} | "
                    f"{b['diff']['final_stress']:+.2f} / {a['diff']['final_stress']:+.2f} | "
                    f"{mv['nsteps']} / {ma['nsteps']} | {mv['wall_s'] / 60:.1f} / {ma['wall_s'] / 60:.1f} |")
    text = f"""## Time-step, scheme and cell checks

The same problem with another time step, scheme or periodic cell (`run.py --beta B`,
`--formulation product [--beta B]` or `--domain L1 L3`; stores in out/tpv5/beta*/,
out/tpv5/product*/ and out/tpv5/domain*/), next to the main cell's run at the same dx with
the builder's scheme ({FORMULATION}) and beta (variant / main; differences from MDSBI as in the
acceptance table, the rupture time also as the interpolated 1 mm/s crossing):

| station | dx | variant | rupture time (s) | interpolated (s) | final slip (%) | peak slip rate (%) | final stress (MPa) | steps | wall time (min) |
|---|---|---|---|---|---|---|---|---|---|
{chr(10).join(rows)}
"""
    if res.get("domain_change"):
        drows = []
        for name, d in res["domain_change"].items():
            m = d["max"]
            drows.append(f"| {d['dx']:g} m | {DOMAIN[0] / 1e3:g} km x {DOMAIN[1] / 1e3:g} km -> "
                         f"{d['cell'][0] / 1e3:g} km x {d['cell'][1] / 1e3:g} km | {m['rupture_time']:.3f} s | "
                         f"{100 * m['final_slip']:.2f} % | {100 * m['peak_rate']:.2f} % | "
                         f"{m['final_stress']:.2f} MPa |")
        text += f"""
How far the cell moves the stations: the largest change over the five stations of each
quantity between the builder's cell and the other one (cracklab against cracklab):

| dx | cell | rupture time | final slip | peak slip rate | final stress |
|---|---|---|---|---|---|
{chr(10).join(drows)}
"""
    if res.get("lag"):
        lrows = []
        beta_now = res["baselines"]["runs"][f"{C.ACCEPT_DX:g}"]["beta"]
        p = next(iter(res["lag"].values()))["order"]
        bp = "beta" if p == 1 else f"beta^{p}"
        scheme = ("the product scheme is first order in dt" if p == 1 else
                  f"{res['baselines']['runs'][f'{C.ACCEPT_DX:g}']['formulation']} is second order in dt")
        for s, f in res["lag"].items():
            pairs = ", ".join(f"{b:.4f}: {1e3 * x:+.1f} ms" for b, x in zip(f["betas"], f["lags"]))
            within = ("any beta" if f["beta_within"] == float("inf") else
                      "none" if f["beta_within"] == 0 else
                      f"> {BETA_SHOWN:g}" if f["beta_within"] > BETA_SHOWN else f"{f['beta_within']:.3f}")
            lrows.append(f"| {s} | {pairs} | {1e3 * f['a']:+.1f} ms | {1e3 * f['b'] * beta_now ** p:+.1f} ms | "
                         f"{within} |")
        text += f"""
The rupture-time lag (interpolated crossing, cracklab minus MDSBI) against beta at 100 m,
fitted as lag = a + b {bp} ({scheme}; `compare.lag_fit`):
a is what is left at dt -> 0 (the grid's share and the reference's own error), b x {beta_now:g}{'' if p == 1 else f'^{p}'}
the time step's share at the builder's beta, and the last column the largest beta whose
fitted lag is within {C.TOL_RUPTURE_TIME:g} s:

| station | lag at beta | a (dt -> 0) | b x {beta_now:g}{'' if p == 1 else f'^{p}'} | beta within {C.TOL_RUPTURE_TIME:g} s |
|---|---|---|---|---|
{chr(10).join(lrows)}
"""
    return text + "\n"


def _main_command(dxs):
    return "python -m studies.tpv5.run --dx " + " ".join(f"{x:g}" for x in dxs)


def _check_commands(res):
    """The run.py commands of the checks the results hold (none: 'none in this version')."""
    cmds = []
    for name, v in res.get("variants", {}).items():
        for key in sorted(v["runs"], key=float, reverse=True):
            m = v["runs"][key]
            opt = (f"--beta {m['beta']:g}" if name.startswith("beta") else
                   f"--formulation {m['formulation']}" + (f" --beta {m['beta']:g}" if "_beta" in name else "")
                   if name.startswith("product") else f"--domain {m['domain'][0]:g} {m['domain'][1]:g}")
            cmds.append(f"`run.py --dx {key} {opt}`")
    if res.get("step_cost"):
        cmds.append("`run.py --step-cost " + " ".join(res["step_cost"]["median_ms"]) + "`")
    return ", ".join(cmds) if cmds else "no check in this version"


def write_page(res, dxs, page, figrel, notes_path=None, command=None):
    """docs/studies/tpv5.md from the results; the discussion (``discussion.md`` next to this
    script, {placeholders} filled from the results) follows the tables."""
    cmd = command or "python -m studies.tpv5.run"
    L1, L3 = res["runs"][f"{dxs[0]:g}"]["domain"]
    figs = "\n\n".join(f"![{s}]({figrel}/tpv5_{s}.png)" for s in REF_STATIONS)
    text = f"""# SCEC TPV5 against MDSBI

*Written by `studies/tpv5/run.py` from its own output; this version by `{cmd}`.
Every number on this page comes from the runs in the output directory (`out/tpv5/` by
default): the main runs by `{_main_command(dxs)}`, the checks near the end by
{_check_commands(res)}.*

TPV5 (Harris et al. 2009) is TPV3's 30 km x 15 km vertical strike-slip fault reaching a
free surface, with two more stress patches: linear slip weakening (mu_s = 0.677, mu_d =
0.525, D_c = 0.4 m, 120 MPa normal stress), 70 MPa initial shear stress along strike, and
three 3 km x 3 km squares centred at 7.5 km depth: 81.6 MPa at the hypocentre (it starts
above the static strength, 81.24 MPa), 78.0 MPa at -7.5 km and 62.0 MPa at +7.5 km along
strike. `cracklab.scenes.tpv5` builds it with the free surface by mirror symmetry
(`Grid(free_surface=True)`): the run covers the half plane below the surface, {L1 / 1e3:g} km
along strike (periodic) by {L3 / 1e3:g} km deep, and stands for the whole space with the fault
and its loads mirrored about the surface, as MDSBI (and every spectral BI code) models
TPV5. The reference is five on-fault stations computed at 100 m with MDSBI, E. M. Dunham's
spectral boundary-integral code (its files, `tpv5_mdsbi`, are the SCEC/USGS benchmark's
results, scecdata.usc.edu/cvws, not in the repository); `scenes.tpv5` records them
under the same names (`st`: strike from the hypocentre, `dp`: depth below the surface,
in units of 100 m). All comparisons use the strike (h) components.

{verdict_lines(res, dxs)}

## Runs

| dx | half plane (nodes) | cell | beta | dt | steps | t_end | wall time | per step | fault ruptured | surface ruptured by |
|---|---|---|---|---|---|---|---|---|---|---|
{_fmt_runs(res, dxs)}

Wall times on the project's 2-core machine shared with other jobs (not a
benchmark). Time stepping: `Numerics(formulation="{FORMULATION}", engine="{ENGINE}")` (the
product scheme with the law at the step's mean velocity, second order in dt: tpv5's
default) at the builder's beta, default thread counts.

## Acceptance

Both series are taken on the reference's samples (every 0.01 s; cracklab's series are
interpolated to those times) and measured with the same definitions: rupture time =
first sample with slip rate > 1 mm/s; final slip = slip at the common end time (12 s);
peak slip rate = largest sample. Each difference is followed by its limit and whether it
holds (at 50 m the limit is the smaller of the 100 m tolerance and the 100 m difference).

| station | dx | rupture time (s) | MDSBI | difference (limit: holds) | final slip (m) | MDSBI | difference (limit: holds) | peak slip rate (m/s) | MDSBI | difference (limit: holds) |
|---|---|---|---|---|---|---|---|---|---|---|
{H.station_rows(res, REF_STATIONS, dxs)}

The other measures (not part of the acceptance): the rupture time from the interpolated
1 mm/s crossing on cracklab's own steps (the reference's crossing interpolated between its
0.01 s samples), the time of the peak slip rate on the common samples (difference from
MDSBI), the final shear stress, and the RMS difference of the whole 0-12 s series (slip /
slip rate / stress change, in % of the reference's peak of each):

| station | dx | rupture time, interpolated (s) | MDSBI | time of peak (s) | MDSBI | final stress (MPa) | MDSBI | RMS difference (%) |
|---|---|---|---|---|---|---|---|---|
{H.measure_rows(res, REF_STATIONS, dxs)}

Station positions: the node each station is recorded on (strike from the hypocentre,
depth), and the largest dip component of the slip rate there, cracklab's and MDSBI's. On
the free surface (faultst000dp000) the dip slip is odd about the surface and must vanish
exactly; the surface check asks that, and that the station ruptures:

| station | dx | node (strike, depth) | max abs v_3 (m/s) | MDSBI |
|---|---|---|---|---|
{_fmt_positions(res, dxs)}

## Figures

Station series (strike component) against MDSBI:

{figs}

The rupture fronts (slip rate around MDSBI's rupture time, grey line):

![fronts]({figrel}/tpv5_fronts.png)

Rupture-time contours on the half plane. The reference has no contour file for TPV5, so
these are cracklab's only (patches dashed, the fault outlined, the reference's stations
marked):

![rupture time]({figrel}/tpv5_rupture_time.png)

{variant_section(res)}"""
    if f"{C.ACCEPT_DX:g}" not in res["runs"]:
        text += f"*The discussion (`studies/tpv5/discussion.md`) needs the {C.ACCEPT_DX:g} m run.*\n"
    else:
        text += H.fill_notes(notes_path or HERE / "discussion.md", page_numbers(res, dxs))
    Path(page).write_text(text)
    return page


def _key(s):
    return s.replace("-", "m")


def page_numbers(res, dxs):
    """The {placeholders} of discussion.md: numbers of the 100 m run (``<quantity>_<station>``
    with '-' written 'm'), and sentences: the summary, the convergence, the cell and the
    time step."""
    key100 = f"{C.ACCEPT_DX:g}"
    d = {}
    for s in REF_STATIONS:
        c = res["stations"][s][key100]
        k = _key(s)
        d[f"drt_{k}"] = f"{c['diff']['rupture_time']:+.2f}"
        d[f"lag_{k}"] = f"{c['fine']['rupture_time_interp'] - c['ref']['rupture_time_interp']:+.3f}"
        d[f"slip_{k}"] = f"{100 * c['rel']['final_slip']:+.1f} %"
        d[f"peak_{k}"] = f"{100 * c['rel']['peak_rate']:+.1f} %"
        d[f"dstress_{k}"] = f"{c['diff']['final_stress']:+.2f}"
        d[f"rms_rate_{k}"] = f"{100 * c['series_rms']['rate']:.1f} %"
        d[f"rms_slip_{k}"] = f"{100 * c['series_rms']['slip']:.1f} %"
        d[f"ref_rt_{k}"] = f"{c['ref']['rupture_time']:.2f}"
    at100 = {s: res["stations"][s][key100] for s in REF_STATIONS}
    dstress = [c["diff"]["final_stress"] for c in at100.values()]
    d["dstress_min"], d["dstress_max"] = f"{min(dstress):+.2f}", f"{max(dstress):+.2f}"
    d["rms_slip_max"] = f"{100 * max(c['series_rms']['slip'] for c in at100.values()):.1f} %"
    d["ref_v3_surface"] = f"{at100[SURFACE]['ref_max_abs_v3']:.0e}"
    d["v3_surface"] = f"{at100[SURFACE]['max_abs_v3']:g}"
    d["ref_peak_surface"] = f"{at100[SURFACE]['ref']['peak_rate']:.1f}"
    later = [s for s, c in at100.items() if abs(c["diff"]["peak_time"]) > 1.0]
    if later:
        shifts = ", ".join(f"{at100[s]['diff']['peak_time']:+.2f}" for s in later)
        d["two_peaks"] = (
            f"At {' and '.join(later)} the slip rate has two peaks of nearly the same height, at the front "
            f"and at a later arrival (figures); the larger is not the same one in the two records, so the time of "
            f"the peak differs by {shifts} s (second table) while the peak values agree as the acceptance table "
            f"shows.")
    else:
        d["two_peaks"] = "The time of the peak slip rate agrees within the rupture-time lag (second table)."
    rows = [r for r in res["acceptance"]["checks"] if r["dx"] == C.ACCEPT_DX]
    bad = [r for r in rows if not r["pass"]]
    parts = [f"{s}: {d['drt_' + _key(s)]} s, {d['slip_' + _key(s)]}, {d['peak_' + _key(s)]}" for s in REF_STATIONS]
    lead = (f"At {key100} m the five stations meet all three acceptance numbers" if not bad else
            f"At {key100} m {len(bad)} of the {len(rows)} acceptance numbers do not hold "
            f"({'; '.join(C.QUANTITY[r['quantity']] + ' at ' + r['station'] for r in bad)})")
    d["summary"] = (f"{lead}. The differences from MDSBI (rupture time, final slip, peak slip rate) are "
                    f"{'; '.join(parts)}.")
    worst = max(abs(res["stations"][s][key100]["diff"]["rupture_time"]) for s in REF_STATIONS)
    d["worst_rt"] = f"{worst:.2f}"
    d["rt_verdict"] = (f"within the {C.TOL_RUPTURE_TIME:g} s limit" if worst <= C.TOL_RUPTURE_TIME + 1e-9 else
                       f"over the {C.TOL_RUPTURE_TIME:g} s limit by {worst - C.TOL_RUPTURE_TIME:.2f} s")
    fine = sorted((float(k) for k in res["runs"] if float(k) < C.ACCEPT_DX), reverse=True)
    if not fine:
        d["convergence"] = (f"No run finer than {key100} m is in this version of the page, so whether the "
                            f"differences shrink with the grid is not shown (`run.py --dx 100 50`).")
    else:
        sent = []
        for s in REF_STATIONS:
            steps = [res["stations"][s][f"{x:g}"] for x in [C.ACCEPT_DX] + fine]
            sent.append(f"{s} " + " -> ".join(f"{c['diff']['rupture_time']:+.2f}" for c in steps) + " s, "
                        + " -> ".join(f"{100 * c['rel']['final_slip']:+.1f}" for c in steps) + " %, "
                        + " -> ".join(f"{100 * c['rel']['peak_rate']:+.1f}" for c in steps) + " %")
        grown = [r for r in res["acceptance"]["checks"] if r["dx"] < C.ACCEPT_DX and not r["pass"]]
        if not grown:
            verdict = "every difference is no larger than at 100 m"
        else:
            groups = {}
            for r in grown:
                groups.setdefault((r["quantity"], r["dx"]), []).append(r["station"])
            verdict = "; ".join(
                f"the {C.QUANTITY[q]} at " + ("all five stations" if len(st) == len(REF_STATIONS) else ", ".join(st))
                + f" ({dx:g} m)" for (q, dx), st in groups.items()) + " differs more than at 100 m"
        dxs_txt = " -> ".join(f"{x:g} m" for x in [C.ACCEPT_DX] + fine)
        d["convergence"] = (f"Refining the grid ({dxs_txt}; rupture time, final slip, peak slip rate): "
                            f"{'; '.join(sent)}: {verdict}.")
        if grown:
            d["convergence"] += (f" MDSBI's record is itself a {key100} m solution, so a difference from it can "
                                 f"grow while cracklab converges; which of the two is nearer the converged "
                                 f"answer cannot be told from a {key100} m reference.")
            cells = [v for n, v in res.get("variants", {}).items() if n.startswith("domain") and key100 in v["runs"]]
            if any(r["quantity"] == "final_slip" for r in grown) and cells:
                v = cells[0]
                L1, L3 = v["runs"][key100]["domain"]
                main = [100 * res["stations"][s][key100]["rel"]["final_slip"] for s in REF_STATIONS]
                big = [100 * v["stations"][s][key100]["rel"]["final_slip"] for s in REF_STATIONS]
                d["convergence"] += (
                    f" The final slip differs from MDSBI's by {min(main):+.1f} to {max(main):+.1f} % at {key100} m in "
                    f"the builder's {DOMAIN[0] / 1e3:g} km x {DOMAIN[1] / 1e3:g} km cell and by {min(big):+.1f} to "
                    f"{max(big):+.1f} % in a {L1 / 1e3:g} km x {L3 / 1e3:g} km cell"
                    + (": the offset is the periodic replicas', which refining the grid does not remove."
                       if max(abs(x) for x in big) < 0.5 * max(abs(x) for x in main) else
                       ": the replicas do not explain it."))
    d["cell"], d["timestep"] = _variant_sentences(res)
    d["scheme"] = scheme_sentence(res)
    return d


def _variant_sentences(res):
    """What the cell and time-step checks, when present, say (two sentences for discussion.md)."""
    changes = res.get("domain_change") or {}
    if changes:
        parts = []
        for d in changes.values():
            m = d["max"]
            parts.append(f"at {d['dx']:g} m a {d['cell'][0] / 1e3:g} km x {d['cell'][1] / 1e3:g} km cell moves "
                         f"the rupture times by at most {m['rupture_time']:.3f} s, the final slip by "
                         f"{100 * m['final_slip']:.2f} %, the peak slip rate by {100 * m['peak_rate']:.2f} % and "
                         f"the final stress by {m['final_stress']:.2f} MPa")
        cell = "Against the builder's cell, " + "; ".join(parts) + " (tables in \"Time-step, scheme and cell checks\")."
        for name, v in res.get("variants", {}).items():
            key100 = f"{C.ACCEPT_DX:g}"
            if name.startswith("domain") and key100 in v["runs"]:
                L1, L3 = v["runs"][key100]["domain"]
                fs = max(abs(v["stations"][s][key100]["diff"]["final_stress"]) for s in REF_STATIONS)
                sl = max(abs(v["stations"][s][key100]["rel"]["final_slip"]) for s in REF_STATIONS)
                cell += (f" In the {L1 / 1e3:g} km x {L3 / 1e3:g} km cell at {key100} m the final stress is within "
                         f"{fs:.2f} MPa and the final slip within {100 * sl:.1f} % of MDSBI's at every station.")
                break
    else:
        cell = "A larger cell (`run.py --domain L1 L3`) would test this; it is not in this version of the page."
    lag = res.get("lag")
    if lag:
        key100 = f"{C.ACCEPT_DX:g}"
        others = [v["runs"][key100] for name, v in res["variants"].items()
                  if name.startswith("beta") and key100 in v["runs"]]
        a = max(abs(f["a"]) for f in lag.values())
        share = max(abs(f["b"]) * f["beta_now"] ** f["order"] for f in lag.values())
        within = min(f["beta_within"] for f in lag.values())
        base_meta = res["baselines"]["runs"][key100]
        order = next(iter(lag.values()))["order"]
        timestep = ((f"{base_meta['formulation']} is second order in dt. Fitted over beta^2" if order == 2 else
                     f"{base_meta['formulation']} is first order in dt. Fitted over beta")
                    + f", the lag left at dt -> 0 is at "
                    f"most {1e3 * a:.0f} ms and the time step's share at the builder's beta = {base_meta['beta']:g} "
                    f"at most {1e3 * share:.0f} ms (table \"Time-step, scheme and cell checks\")"
                    + (": the lag is the time step's." if a < 0.2 * share else "."))
        if a < SCATTER and share < SCATTER:
            timestep += (f" Both are within the {1e3 * SCATTER:.0f} ms by which the 1 mm/s crossing scatters about "
                         f"its limit (docs/reference/stability.md, \"The order of a rupture front\"): the fit resolves "
                         f"neither, and its largest beta within 0.05 s is an extrapolation.")
        if within == float("inf") or within >= base_meta["beta"]:
            timestep += " The builder's beta already holds the 0.05 s limit at every station."
        elif within == 0:
            timestep += (" No beta brings every station within 0.05 s: the lag left at dt -> 0 exceeds it, so "
                         "a smaller time step does not fix it.")
        else:
            factor = base_meta["beta"] / within
            timestep += (f" On the interpolated crossings, beta = {within:.3f} would bring every station within "
                         f"0.05 s: {factor:.2f} times the steps of the builder's beta.")
        for m in others:
            accepted = [v for n, v in res["variants"].items() if n.startswith("beta") and key100 in v["runs"] and
                        v["runs"][key100]["beta"] == m["beta"]][0]["acceptance"]
            missed = [f for f in accepted["failures"] if f.split(":")[0].endswith(f" at {key100} m")]
            timestep += (f" The run at beta = {m['beta']:g} ({m['nsteps']} steps, "
                         f"{m['nsteps'] / base_meta['nsteps']:.2f} times the builder's) "
                         + ("meets all 15 acceptance numbers at 100 m." if not missed else
                            f"misses {len(missed)} of the 15 acceptance numbers at 100 m."))
        cost = res.get("step_cost")
        if cost:
            med = cost["median_ms"]
            ref_key = f"{base_meta['beta']:g}"
            parts = [f"{med[k]:.0f} ms at beta = {k}" for k in med]
            timestep += (f" Measured in one sitting (`run.py --step-cost`, {len(cost['rounds'])} alternated rounds "
                         f"of {cost['steps']} steps at {cost['dx']:g} m), a step costs " + ", ".join(parts))
            if ref_key in med:
                ratios = [f"{med[k] / med[ref_key]:.2f}" for k in med if k != ref_key]
                timestep += f" ({', '.join(ratios)} times the builder's per step)"
                whole = [f"beta = {k}: {base_meta['beta'] / float(k) * med[k] / med[ref_key]:.1f} times the "
                         f"builder's run" for k in med if k != ref_key]
                timestep += ", so a whole run costs " + "; ".join(whole)
            timestep += "."
        else:
            timestep += (" The wall times of these runs, taken under different loads of the shared host, do not "
                         "measure the cost of a step (`run.py --step-cost` does).")
    else:
        timestep = ("`run.py --beta B` runs the same problem at another time step and adds it to this page (the "
                    "lag's fit over beta).")
    return cell, timestep


def lag(c):
    """cracklab's interpolated 1 mm/s crossing minus MDSBI's (s)."""
    return c["fine"]["rupture_time_interp"] - c["ref"]["rupture_time_interp"]


def scheme_sentence(res):
    """What the first-order product scheme (the checks OUT/product*) gives at 100 m next to
    the main runs' scheme (a sentence for discussion.md)."""
    key100 = f"{C.ACCEPT_DX:g}"
    checks = [(n, v) for n, v in res.get("variants", {}).items() if n.startswith("product") and key100 in v["runs"]]
    main = res["runs"][key100]
    if not checks:
        return ("The first-order product scheme (`run.py --formulation product [--beta B]`) is not in this version "
                "of the page.")
    worst_main = max(lag(res["stations"][s][key100]) for s in REF_STATIONS)
    parts = []
    for _, v in sorted(checks, key=lambda nv: -nv[1]["runs"][key100]["beta"]):
        meta = v["runs"][key100]
        lags = [lag(v["stations"][s][key100]) for s in REF_STATIONS]
        missed = [f for f in v["acceptance"]["failures"] if f" at {key100} m" in f.split(":")[0]]
        n = sum(1 for r in v["acceptance"]["checks"] if r["dx"] == C.ACCEPT_DX)
        parts.append(f"at beta = {meta['beta']:g} ({meta['nsteps']} steps) the interpolated crossings lag by up "
                     f"to {max(lags):+.4f} s and the run "
                     + (f"meets all {n} acceptance numbers" if not missed else
                        f"misses {len(missed)} of the {n} acceptance numbers"))
    return (f"With the first-order product scheme (`run.py --formulation product`, table \"Time-step, scheme and "
            f"cell checks\"), " + "; ".join(parts) + f"; with {main['formulation']} at beta = {main['beta']:g} "
            f"({main['nsteps']} steps) the largest lag is {worst_main:+.4f} s.")


def report(res, dxs):
    H.report(res, REF_STATIONS, dxs)


def exit_status(res) -> int:
    return H.exit_status(res)


def main(argv=None) -> int:
    p = H.parser(__doc__, "tpv5", dx_help="grid spacings in m (default 100; '--dx 100 50' adds 50 m)",
                 quick_help="600 m and 400 m, 6 s, into OUT/quick (no acceptance)",
                 reference_help="directory of the MDSBI station files")
    p.add_argument("--beta", type=float, default=None,
                   help="time-step factor instead of the builder's: a check into OUT/beta<B>, no page")
    p.add_argument("--domain", type=float, nargs=2, default=None, metavar=("L1", "L3"),
                   help="periodic length along strike and half-plane depth in m instead of 48000 24000: "
                        "a check into OUT/domain<L1>x<L3>km, no page")
    p.add_argument("--formulation", default=None, choices=("product",),
                   help=f"time stepping instead of tpv5's {FORMULATION}: 'product' (first order: the law's slip path "
                        "by the rectangle rule), with --beta or at the builder's, a check into "
                        "OUT/product[_beta<B>], no page")
    p.add_argument("--step-cost", type=float, nargs="+", default=None, metavar="BETA",
                   help="measure the cost of a 100 m step at these betas in one sitting (alternated) into "
                        "OUT/step_cost.json, no page")
    args = p.parse_args(argv)
    if args.step_cost:
        step_cost(Path(args.out), args.step_cost)
        return 0
    if args.beta is not None and args.domain is not None:
        p.error("give one of --beta, --domain at a time")
    variant = (f"beta{args.beta:g}" if args.beta is not None else
               f"domain{args.domain[0] / 1e3:g}x{args.domain[1] / 1e3:g}km" if args.domain is not None else None)
    if args.formulation:
        variant = args.formulation + (f"_{variant}" if variant else "")
    out, dxs, t_end = H.spacings(args, quick=[600.0, 400.0], quick_t_end=6.0, default=[C.ACCEPT_DX],
                                 accept_dx=None if variant else C.ACCEPT_DX)
    main_out = out
    out.mkdir(parents=True, exist_ok=True)
    if variant:
        if not args.report_only:
            for dx in dxs:              # the baseline first: the main cell at the builder's beta
                run_one(dx, t_end, main_out, force=False)
                run_one(dx, t_end, main_out / variant, force=args.force, beta=args.beta, domain=args.domain,
                        formulation=args.formulation)
        res = analyse(main_out / variant, dxs, args.reference)
        (main_out / variant / "tpv5_results.json").write_text(json.dumps(res, indent=1))
        report(res, dxs)
        print(f"results in {main_out / variant / 'tpv5_results.json'}; the main page shows this check when it is "
              f"redrawn (python -m studies.tpv5.run --report-only with the page's --dx)")
        return exit_status(res)
    if not args.report_only:
        for dx in dxs:
            run_one(dx, t_end, out, force=args.force)
    res = analyse(out, dxs, args.reference)
    report(res, dxs)
    if not args.quick:
        add_variants(res, main_out, args.reference)
    (out / "tpv5_results.json").write_text(json.dumps(res, indent=1))
    figdir, page = H.page_paths(args, out, "tpv5", args.quick)
    fig_stations(out, dxs, figdir, args.reference)
    fig_rupture(out, dxs, figdir)
    write_page(res, dxs, page, H.figure_link(figdir, page), command=H.command_line("studies.tpv5.run", argv))
    print(f"wrote {page}, figures in {figdir}, results in {out / 'tpv5_results.json'}")
    return exit_status(res)


if __name__ == "__main__":
    sys.exit(main())
