"""SCEC TPV3 with cracklab against the independent spectral BI code MDSBI (docs/studies/tpv3.md).

    python -m studies.tpv3.run [--dx 100 [50]] [-o OUT] [--quick] [--report-only] [--force]
                                [--beta B | --domain L1 L3 | --formulation product|displacement]

Runs ``cracklab.scenes.tpv3`` at each grid spacing (default 100 m; ``--dx 100 50`` adds
50 m, about seven times the cost), streams each run to OUT/tpv3_dx<dx>.zarr (station series
every step, rupture time of the whole fault, the slip field at the end) with its wall
time in OUT/tpv3_dx<dx>.json, compares the reference's two stations
(shared/reference/tpv3_mdsbi, or ``--reference DIR``: faultst075dp000, 7.5 km along strike, and
faultst000dp-030, 3.0 km along dip) and writes

* OUT/tpv3_results.json         every number of the page, and the acceptance verdict,
* docs/figures/tpv3_*.png       station series against MDSBI, rupture-time contours,
* docs/studies/tpv3.md                  the page, written from these results.

The TPV3 acceptance is the study's result: at 100 m, at both stations, rupture time
within 0.05 s, final slip within 3 % and peak slip rate within 15 % of MDSBI; at 50 m
each difference within the same limit and no larger than at 100 m
(``compare.check_acceptance``). The script prints PASS or FAIL and exits with status 1
when the acceptance does not hold (2 when it could not be checked: no 100 m run).

A run whose store is complete and whose scene matches is not repeated (``--force``
reruns); ``--report-only`` redraws from the stores. ``--quick`` runs 600 m and 400 m for
6 s into OUT/quick and writes its page and figures there (a smoke test: the acceptance
applies at 100 m and is not checked). ``--beta B`` (a time-step check),
``--domain L1 L3`` (a larger periodic cell: the replicas) and ``--formulation product``
(the first-order product scheme: the law's slip path by the rectangle rule) or
``--formulation displacement`` (the paper's displacement scheme) run the same problem into
OUT/beta<B>, OUT/domain<L1>x<L3>km or OUT/<formulation> and write no page; the main page
then shows them next to the main runs. Time stepping of the main runs: tpv3's own scheme
(formulation "product2": the product scheme with the law at the step's mean velocity,
second order in dt, at the builder's beta) with the exponential history engine (constant
cost and memory per step), default thread counts.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H
from studies.tpv3 import compare as C

HERE = Path(__file__).resolve().parent
ROOT = H.ROOT

REF_STATIONS = ("faultst075dp000", "faultst000dp-030")
PRETTY = {"faultst075dp000": "faultst075dp000 (7.5 km along strike, in-plane)",
          "faultst000dp-030": "faultst000dp-030 (3.0 km along dip, anti-plane)"}
OFFSET_KM = {"faultst075dp000": (7.5, 0.0), "faultst000dp-030": (0.0, -3.0)}
MIRROR = {"faultst000dp-030": "faultst000dp030"}   # the same distance on the other side of the hypocentre
LATE = 10.0               # s: the late slip after the arrivals from the fault edges (docs/studies/tpv3.md)
FORMULATION = "product2"  # the builder's default: the product scheme at second order in dt
ENGINE = "exponential"


def numerics(formulation=None):
    return H.numerics(formulation or FORMULATION, ENGINE)


def build_scene(dx, t_end, formulation=None, beta=None, domain=None):
    """``scenes.tpv3`` with its own stations (the reference's two among them), the
    rupture time of the whole fault and the slip field at the end."""
    from cracklab.scenes import tpv3

    return H.build(tpv3, dx, t_end=t_end, domain=domain, beta=beta, numerics=numerics(formulation))


def store_path(out, dx):
    return H.store_path(out, f"tpv3_dx{dx:g}")


def run_one(dx, t_end, out, force=False, log=print, formulation=None, beta=None, domain=None):
    """Run (or reuse) one grid spacing; return its metadata dict."""
    scene = build_scene(dx, t_end, formulation, beta, domain)
    return H.run_scene(scene, store_path(out, dx), label=f"dx = {dx:g} m", meta={"dx": dx}, force=force, log=log)


# ------------------------------------------------------------------------------ analysis
def load_run(out, dx):
    return H.load_run(store_path(out, dx))


sim_series = H.strike_series
ref_series = H.reference_series


def compare_run(st, refs):
    """Every reference station of one run: the comparison of compare.compare_station,
    the whole-series RMS differences, and the node the station sits on."""
    out = {}
    hypo = (float(st.x1.sel(station="faultst000dp000")), float(st.x3.sel(station="faultst000dp000")))
    for s in REF_STATIONS:
        cmp, sim, ref = H.compare_strike(st, s, refs[s])
        cmp["late_peak_rate"] = {"sim": float(np.max(sim["rate"][sim["t"] > LATE], initial=0.0)),
                                 "ref": float(np.max(ref["rate"][ref["t"] > LATE], initial=0.0))}
        cmp["offset_km"] = [(float(st.x1.sel(station=s)) - hypo[0]) / 1e3,
                            (float(st.x3.sel(station=s)) - hypo[1]) / 1e3]
        if s in MIRROR:
            other = sim_series(st, MIRROR[s])
            cmp["mirror"] = {"station": MIRROR[s],
                             "max_rate_diff": float(np.max(np.abs(other["rate"] - sim["rate"]))),
                             "max_slip_diff": float(np.max(np.abs(other["slip"] - sim["slip"])))}
        out[s] = cmp
    return out


def analyse(out, dxs, ref_dir=None):
    refs = {s: C.load_reference(s, ref_dir) for s in REF_STATIONS}
    res = H.analyse_runs({f"{dx:g}": store_path(out, dx) for dx in dxs}, lambda st: compare_run(st, refs))
    res["acceptance"] = C.check_acceptance(res["stations"])
    return res


def variants(out, dxs):
    """The time-step and scheme checks found next to the main runs (OUT/beta*, OUT/domain*,
    OUT/displacement, OUT/product2)."""
    found = {}
    for d in sorted(Path(out).glob("beta*")) + sorted(Path(out).glob("domain*")) + \
            [Path(out) / "product", Path(out) / "displacement"]:
        done = [x for x in dxs if store_path(d, x).with_suffix(".json").exists()]
        if d.is_dir() and done:
            found[d.name] = done
    return found


# ------------------------------------------------------------------------------ figures
COLOURS = {"MDSBI": "k", "100": "tab:red", "50": "tab:blue", "600": "tab:orange", "400": "tab:green",
           "300": "tab:olive", "200": "tab:purple"}


def fig_stations(out, dxs, figdir, ref_dir=None, cells=None):
    """Station series against MDSBI; ``cells``: {label: stations Dataset} of larger-cell
    runs, drawn dashed."""
    paths = []
    runs = {f"{dx:g}": load_run(out, dx)[2] for dx in dxs}
    cells = cells or {}
    for s in REF_STATIONS:
        ref = C.load_reference(s, ref_dir)
        fig = H.station_figure(ref, runs, lambda st: sim_series(st, s), f"TPV3, {PRETTY[s]}: strike component",
                               ref_keys=("h_slip", "h_rate", "h_stress"), ref_label="MDSBI, 100 m", colours=COLOURS,
                               extra={label: sim_series(st, s) for label, st in cells.items()})
        paths.append(H.save(fig, Path(figdir) / f"tpv3_{s}.png", 110))
        # zoom on the rupture front
        fig = H.front_figure(ref["t"], ref["h_rate"], C.rupture_time(ref["t"], ref["h_rate"]), runs,
                             lambda st: sim_series(st, s), f"{s}: slip rate around the rupture front",
                             ref_label="MDSBI, 100 m", colours=COLOURS, after=1.2, threshold=C.THRESHOLD)
        paths.append(H.save(fig, Path(figdir) / f"tpv3_{s}_front.png", 110))
    return paths


def fig_rupture(out, dxs, figdir):
    plt = H.pyplot()
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
        cs = ax.contour(x, z, rt, levels=levels, colors=COLOURS.get(name), linewidths=0.9)
        handles.append(plt.Line2D([], [], color=COLOURS.get(name), label=f"cracklab, {name} m"))
        if finest is None or dx < finest[0]:
            finest = (dx, x, z, rt, cs)
    ax.clabel(finest[4], levels[1::2], fontsize=7, fmt="%.0f s")
    for s, (px, pz) in OFFSET_KM.items():
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
    return [H.save(fig, Path(figdir) / "tpv3_rupture_time.png", 110)]


# ------------------------------------------------------------------------------ page
def _fmt_runs(res, dxs):
    rows = []
    for dx in dxs:
        m = res["runs"][f"{dx:g}"]
        rows.append(f"| {dx:g} m | {m['n1']} x {m['n3']} | {m['beta']:.4f} | {m['dt'] * 1e3:.3f} ms | "
                    f"{m['nsteps']} | {m['t_end']:.2f} s | {m['wall_s'] / 60:.1f} min | "
                    f"{1e3 * m['s_per_step']:.0f} ms | {100 * m['ruptured_fraction']:.1f} % |")
    return "\n".join(rows)


def _fmt_symmetry(res, dxs):
    rows = []
    for s in REF_STATIONS:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            mirror = c.get("mirror")
            mtxt = (f"{mirror['station']}: {mirror['max_rate_diff']:.1e} m/s, {mirror['max_slip_diff']:.1e} m"
                    if mirror else "n/a")
            rows.append(f"| {s} | {dx:g} m | ({c['offset_km'][0]:+.2f}, {c['offset_km'][1]:+.2f}) km | "
                        f"{c['max_abs_v3']:.1e} | {mtxt} |")
    return "\n".join(rows)


def verdict_lines(res, dxs):
    return H.verdict_lines(res, dxs, "both stations")


def _variant_section(res):
    if not res.get("variants"):
        return ""
    rows = []
    for name, vres in res["variants"].items():
        for key in sorted(vres["runs"], key=float, reverse=True):
            mv = vres["runs"][key]
            for s in REF_STATIONS:
                a = res["stations"][s].get(key)
                b = vres["stations"][s][key]
                if a is None:
                    continue
                ma = res["runs"][key]
                rows.append(
                    f"| {s} | {float(key):g} m | {_describe(mv)} | "
                    f"{b['diff']['rupture_time']:+.3f} / {a['diff']['rupture_time']:+.3f} | "
                    f"{100 * b['rel']['final_slip']:+.1f} / {100 * a['rel']['final_slip']:+.1f} | "
                    f"{100 * b['rel']['peak_rate']:+.1f} / {100 * a['rel']['peak_rate']:+.1f} | "
                    f"{b['diff']['final_stress']:+.2f} / {a['diff']['final_stress']:+.2f} | "
                    f"{mv['nsteps']} / {ma['nsteps']} | {mv['wall_s'] / 60:.1f} / {ma['wall_s'] / 60:.1f} |")
    return f"""## Time-step, scheme and cell checks

The same problem with another time step, scheme or periodic cell (`run.py --beta B`,
`--formulation product|displacement` or `--domain L1 L3`; stores in out/tpv3/beta*/,
out/tpv3/product/, out/tpv3/displacement/, out/tpv3/domain*/), next to the main run (variant / main
run; differences from MDSBI as in the acceptance table; the main runs use {FORMULATION},
beta {next(iter(res['runs'].values()))['beta']:.4f}, a 48 km x 24 km cell):

| station | dx | variant | rupture time (s) | final slip (%) | peak slip rate (%) | final stress (MPa) | steps | wall time (min) |
|---|---|---|---|---|---|---|---|---|
{chr(10).join(rows)}

"""


def _describe(meta):
    """A variant run in a few words: scheme, beta and the periodic cell."""
    L1, L3 = meta.get("domain", (48000.0, 24000.0))
    return f"{meta['formulation']}, beta {meta['beta']:.4f}, {L1 / 1e3:g} km x {L3 / 1e3:g} km"


def write_page(res, dxs, page, figrel, notes_path=None, command=None):
    """docs/studies/tpv3.md from the results; the discussion (``discussion.md`` next to this
    script, {placeholders} filled from the results) follows the tables."""
    cmd = command or "python -m studies.tpv3.run"
    text = f"""# SCEC TPV3 against MDSBI

*Written by `studies/tpv3/run.py` from its own output; this version by `{cmd}`.
Every number on this page comes from the runs in `out/tpv3/`: the main runs by this
command, the checks near the end by the `run.py` options named there.*

TPV3 (Harris et al. 2009; Day et al. 2005, Table 1) is the SCEC/USGS spontaneous rupture
benchmark in a homogeneous whole space: a 30 km x 15 km vertical fault with linear
slip-weakening friction (mu_s = 0.677, mu_d = 0.525, D_c = 0.4 m, 120 MPa normal stress),
70 MPa initial shear stress and 81.6 MPa on a 3 km x 3 km square around the hypocentre.
`cracklab.scenes.tpv3` builds it in a periodic 48 km x 24 km domain (the plane outside
the fault is bonded). The reference is two on-fault stations computed at 100 m with
MDSBI, E. M. Dunham's spectral boundary-integral code (its files, `tpv3_mdsbi`, are the
SCEC/USGS benchmark's results, scecdata.usc.edu/cvws, not in the repository):
faultst075dp000, 7.5 km along strike from the hypocentre (in-plane, mode II), and
faultst000dp-030, 3.0 km along dip (anti-plane, mode III). Both are stations of
`scenes.tpv3` under these names. All comparisons use the strike (h) components.

{verdict_lines(res, dxs)}

## Runs

| dx | grid | beta | dt | steps | t_end | wall time | per step | fault ruptured |
|---|---|---|---|---|---|---|---|---|
{_fmt_runs(res, dxs)}

Wall times on the project's 2-core machine shared with other jobs, at `nice 19`
(not a benchmark). Time stepping: `Numerics(formulation="{FORMULATION}", engine="{ENGINE}")`
(the product scheme with the law at the step's mean velocity, second order in dt: tpv3's
default) at the builder's beta, default thread counts.

## Acceptance

Both series are taken on the reference's samples (every 0.01 s; cracklab's series are
interpolated to those times) and measured with the same definitions: rupture time =
first sample with slip rate > 1 mm/s; final slip = slip at the common end time (12 s);
peak slip rate = largest sample. Each difference is followed by its limit and whether
it holds (at 50 m the limit is the smaller of the 100 m tolerance and the 100 m difference).

| station | dx | rupture time (s) | MDSBI | difference (limit: holds) | final slip (m) | MDSBI | difference (limit: holds) | peak slip rate (m/s) | MDSBI | difference (limit: holds) |
|---|---|---|---|---|---|---|---|---|---|---|
{H.station_rows(res, REF_STATIONS, dxs)}

The other measures (not part of the acceptance): the rupture time from the interpolated
1 mm/s crossing on cracklab's own steps (the reference's crossing interpolated between
its 0.01 s samples), the time of the peak slip rate on the common samples (difference
from MDSBI) and the peak on cracklab's own steps, the final shear stress, and the RMS
difference of the whole 0-12 s series (slip / slip rate / stress change, in % of the
reference's peak of each):

| station | dx | rupture time, interpolated (s) | MDSBI | time of peak (s) | MDSBI | peak on own steps (m/s) | final stress (MPa) | MDSBI | RMS difference (%) |
|---|---|---|---|---|---|---|---|---|---|
{H.measure_rows(res, REF_STATIONS, dxs, own_peak=True)}

Station positions and symmetry: each station's offset from the hypocentre (the node it
is recorded on), the largest dip component of the slip rate there (zero by symmetry on
the two axes), and the largest difference between faultst000dp-030 and its mirror image
3.0 km on the other side of the hypocentre (the same series by symmetry):

| station | dx | offset (strike, dip) | max abs v_3 (m/s) | mirror station: max difference of slip rate, slip |
|---|---|---|---|---|
{_fmt_symmetry(res, dxs)}

## Figures

![faultst075dp000]({figrel}/tpv3_faultst075dp000.png)

![faultst075dp000, front]({figrel}/tpv3_faultst075dp000_front.png)

![faultst000dp-030]({figrel}/tpv3_faultst000dp-030.png)

![faultst000dp-030, front]({figrel}/tpv3_faultst000dp-030_front.png)

![rupture time]({figrel}/tpv3_rupture_time.png)

{_variant_section(res)}"""
    if f"{C.ACCEPT_DX:g}" not in res["runs"]:
        text += f"*The discussion (`studies/tpv3/discussion.md`) needs the {C.ACCEPT_DX:g} m run.*\n"
    else:
        text += H.fill_notes(notes_path or HERE / "discussion.md", page_numbers(res, dxs))
    Path(page).write_text(text)
    return page


def page_numbers(res, dxs):
    """The {placeholders} of discussion.md: numbers of the 100 m run (keys ``..._100``),
    the reference's, and two sentences, the 100 m summary and the convergence."""
    key100 = f"{C.ACCEPT_DX:g}"
    d = {}
    for s in REF_STATIONS:
        key = s.replace("-", "m")
        c = res["stations"][s][key100]
        k = f"{key}_{key100}"
        d[f"rt_{k}"] = f"{c['sim']['rupture_time']:.2f}"
        d[f"drt_{k}"] = f"{c['diff']['rupture_time']:+.2f}"
        d[f"slip_{k}"] = f"{100 * c['rel']['final_slip']:+.1f} %"
        d[f"peak_{k}"] = f"{100 * c['rel']['peak_rate']:+.1f} %"
        d[f"dstress_{k}"] = f"{c['diff']['final_stress']:+.2f}"
        d[f"rms_rate_{k}"] = f"{100 * c['series_rms']['rate']:.1f} %"
        d[f"rms_slip_{k}"] = f"{100 * c['series_rms']['slip']:.1f} %"
        d[f"ref_rt_{key}"] = f"{c['ref']['rupture_time']:.2f}"
        d[f"ref_stress_{key}"] = f"{c['ref']['final_stress']:.2f}"
    rows = [r for r in res["acceptance"]["checks"] if r["dx"] == C.ACCEPT_DX]
    bad = [r for r in rows if not r["pass"]]
    parts = [f"{s}: {d[f'drt_{s.replace(chr(45), chr(109))}_{key100}']} s, "
             f"{d[f'slip_{s.replace(chr(45), chr(109))}_{key100}']} and "
             f"{d[f'peak_{s.replace(chr(45), chr(109))}_{key100}']}" for s in REF_STATIONS]
    lead = (f"At {key100} m both stations meet all three acceptance numbers" if not bad else
            f"At {key100} m {len(bad)} of the {len(rows)} acceptance numbers do not hold "
            f"({'; '.join(C.QUANTITY[r['quantity']] + ' at ' + r['station'] for r in bad)})")
    d["summary"] = (f"{lead}. The differences from MDSBI (rupture time, final slip, peak slip rate) "
                    f"are {'; '.join(parts)}.")
    fine = sorted((float(k) for k in res["runs"] if float(k) < C.ACCEPT_DX), reverse=True)
    if not fine:
        d["convergence"] = (f"No run finer than {key100} m is in this version of the page, so whether the "
                            f"differences shrink with the grid is not shown (`run.py --dx 100 50`).")
    else:
        sent = []
        for s in REF_STATIONS:
            a = res["stations"][s][key100]
            steps = [a] + [res["stations"][s][f"{x:g}"] for x in fine]
            dxs_txt = " -> ".join(f"{x:g} m" for x in [C.ACCEPT_DX] + fine)
            sent.append(f"at {s} ({dxs_txt}) the rupture time differs by "
                        + " -> ".join(f"{c['diff']['rupture_time']:+.2f}" for c in steps)
                        + " s, the final slip by " + " -> ".join(f"{100 * c['rel']['final_slip']:+.1f}" for c in steps)
                        + " % and the peak slip rate by "
                        + " -> ".join(f"{100 * c['rel']['peak_rate']:+.1f}" for c in steps) + " %")
        grown = [r for r in res["acceptance"]["checks"] if r["dx"] < C.ACCEPT_DX and not r["pass"]]
        verdict = ("every difference is no larger than at 100 m" if not grown else
                   "; ".join(f"{C.QUANTITY[r['quantity']]} at {r['station']} ({r['dx']:g} m)" for r in grown)
                   + (" differs more than at 100 m" if len(grown) == 1 else " differ more than at 100 m"))
        d["convergence"] = f"Refining the grid, {'; '.join(sent)}: {verdict}."
        if grown:
            own = []
            for r in grown:
                a = res["stations"][r["station"]][key100]
                b = res["stations"][r["station"]][f"{r['dx']:g}"]
                q = r["quantity"]
                unit = " s" if q == "rupture_time" else (" m" if q == "final_slip" else " m/s")
                own.append(f"{C.QUANTITY[q]} at {r['station']}: {a['sim'][q]:.3f}{unit} at {key100} m, "
                           f"{b['sim'][q]:.3f}{unit} at {r['dx']:g} m, MDSBI {a['ref'][q]:.3f}{unit}")
            d["convergence"] += (
                " cracklab's own values, against MDSBI's: " + "; ".join(own) + ". MDSBI's record is itself a "
                f"{key100} m solution, so a difference from it can grow while cracklab converges: whether "
                f"cracklab at {fine[-1]:g} m is nearer the converged answer than both {key100} m runs "
                f"cannot be told from a {key100} m reference.")
            cells = [v for n, v in res.get("variants", {}).items() if n.startswith("domain") and key100 in v["runs"]]
            for r in grown:
                if r["quantity"] != "final_slip" or not cells:
                    continue
                v = cells[0]
                L1, L3 = v["runs"][key100]["domain"]
                big = v["stations"][r["station"]][key100]["rel"]["final_slip"]
                main = res["stations"][r["station"]][key100]["rel"]["final_slip"]
                d["convergence"] += (
                    f" At {key100} m the final-slip difference at {r['station']} is {100 * main:+.1f} % in the "
                    f"48 km x 24 km cell and {100 * big:+.1f} % in a {L1 / 1e3:g} km x {L3 / 1e3:g} km cell "
                    f"(\"After the slip stops\", below): "
                    + ("most of it is the periodic replicas', which refining the grid does not remove."
                       if abs(big) < 0.5 * abs(main) else "the replicas do not explain it."))
    d["replicas"], d["timestep"] = _variant_sentences(res)
    d["scheme"] = _scheme_sentence(res)
    for s in REF_STATIONS:
        d[f"lag_{s.replace('-', 'm')}_{key100}"] = f"{lag(res['stations'][s][key100]):+.4f}"
    return d


def _variant_sentences(res):
    """What the cell and time-step checks, when present, say (two sentences for discussion.md)."""
    key100 = f"{C.ACCEPT_DX:g}"
    cell = step = None
    for name, v in res.get("variants", {}).items():
        if key100 not in v["runs"]:
            continue
        meta = v["runs"][key100]
        if name.startswith("domain") and cell is None:
            cell = (meta, v)
        elif name.startswith("beta") and step is None:
            step = (meta, v)
    if cell:
        meta, v = cell
        L1, L3 = meta["domain"]
        cs = [v["stations"][s][key100] for s in REF_STATIONS]
        ms = [res["stations"][s][key100] for s in REF_STATIONS]
        d_rt = max(abs(c["sim"]["rupture_time"] - m["sim"]["rupture_time"]) for c, m in zip(cs, ms))
        d_pk = max(abs(c["sim"]["peak_rate"] / m["sim"]["peak_rate"] - 1) for c, m in zip(cs, ms))
        shrinks = all(abs(c["diff"]["final_stress"]) < 0.5 * abs(m["diff"]["final_stress"]) for c, m in zip(cs, ms))
        late = cs[1]["late_peak_rate"], ms[1]["late_peak_rate"]
        replicas = (f"With a {L1 / 1e3:g} km x {L3 / 1e3:g} km cell (table \"Time-step, scheme and cell checks\", "
                    f"dashed in the figures) the final shear stress differs from MDSBI's by "
                    f"{cs[0]['diff']['final_stress']:+.2f} and {cs[1]['diff']['final_stress']:+.2f} MPa and the "
                    f"final slip by {100 * cs[0]['rel']['final_slip']:+.1f} % and "
                    f"{100 * cs[1]['rel']['final_slip']:+.1f} % (faultst075dp000, faultst000dp-030), and the "
                    f"slip at faultst000dp-030 after {LATE:g} s peaks at {late[0]['sim']:.3f} m/s (MDSBI "
                    f"{late[0]['ref']:.3f} m/s, the 48 km x 24 km run {late[1]['sim']:.3f} m/s); the rupture times "
                    f"change by at most {d_rt:.3f} s and the peak slip rates by {100 * d_pk:.1f} %. "
                    + ("The late and final-state differences of the 48 km x 24 km runs are the replicas'."
                       if shrinks else "The replicas do not explain the final-state differences."))
    else:
        replicas = ("A larger cell (`run.py --domain 96000 48000`) would test this reading; it is not in this "
                    "version of the page.")
    if step:
        meta, v = step
        cs = [v["stations"][s][key100] for s in REF_STATIONS]
        timestep = (f"With beta = {meta['beta']:g} at {key100} m the rupture time differs from MDSBI's by "
                    f"{cs[0]['diff']['rupture_time']:+.2f} s and {cs[1]['diff']['rupture_time']:+.2f} s and the "
                    f"peak slip rate by {100 * cs[0]['rel']['peak_rate']:+.1f} % and "
                    f"{100 * cs[1]['rel']['peak_rate']:+.1f} % (table \"Time-step, scheme and cell checks\").")
    else:
        timestep = "`run.py --beta B` runs the same problem at another time step and adds it to this page."
    return replicas, timestep


def lag(c):
    """cracklab's interpolated 1 mm/s crossing minus MDSBI's (s)."""
    return c["fine"]["rupture_time_interp"] - c["ref"]["rupture_time_interp"]


def _scheme_sentence(res):
    """What the first-order product scheme (the check OUT/product) gives at 100 m next to
    the main runs' product2 (a sentence for discussion.md)."""
    key100 = f"{C.ACCEPT_DX:g}"
    v = res.get("variants", {}).get("product")
    if not v or key100 not in v["runs"]:
        return ("The first-order product scheme (`run.py --formulation product`) is not in this version of "
                "the page.")
    meta, main = v["runs"][key100], res["runs"][key100]
    cs = [v["stations"][s][key100] for s in REF_STATIONS]
    ms = [res["stations"][s][key100] for s in REF_STATIONS]
    missed = [f for f in v["acceptance"]["failures"] if f" at {key100} m" in f.split(":")[0]]
    n = sum(1 for r in v["acceptance"]["checks"] if r["dx"] == C.ACCEPT_DX)
    return (f"With the first-order product scheme at beta = {meta['beta']:g} (`run.py --formulation product`; "
            f"table \"Time-step, scheme and cell checks\") the interpolated crossings lag MDSBI's by "
            f"{lag(cs[0]):+.4f} s and {lag(cs[1]):+.4f} s, against {lag(ms[0]):+.4f} s and {lag(ms[1]):+.4f} s "
            f"with {main['formulation']} at beta = {main['beta']:g}; it "
            + (f"meets all {n} acceptance numbers at {key100} m." if not missed else
               f"misses {len(missed)} of the {n} acceptance numbers at {key100} m."))


def main(argv=None) -> int:
    p = H.parser(__doc__, "tpv3", dx_help="grid spacings in m (default 100; '--dx 100 50' adds 50 m)",
                 quick_help="600 m and 400 m, 6 s, into OUT/quick (acceptance not checked)",
                 reference_help="directory of the MDSBI station files")
    p.add_argument("--formulation", default=FORMULATION, choices=(FORMULATION, "product", "displacement"),
                   help=f"time stepping (default {FORMULATION}: tpv3's own, second order in dt); 'product' "
                        "(first order: the law's slip path by the rectangle rule) or 'displacement' runs the "
                        "scheme check into OUT/<formulation> and writes no page")
    p.add_argument("--beta", type=float, default=None,
                   help="time-step factor instead of the builder's: a time-step check into OUT/beta<B>, no page")
    p.add_argument("--domain", type=float, nargs=2, default=None, metavar=("L1", "L3"),
                   help="periodic cell in m instead of 48000 24000: a replica check into OUT/domain<L1>x<L3>km, no page")
    args = p.parse_args(argv)

    variant = None
    if args.formulation != FORMULATION:
        variant = args.formulation
    elif args.beta is not None:
        variant = f"beta{args.beta:g}"
    elif args.domain is not None:
        variant = f"domain{args.domain[0] / 1e3:g}x{args.domain[1] / 1e3:g}km"
    if sum(x is not None for x in (args.beta, args.domain)) + (args.formulation != FORMULATION) > 1:
        p.error("give one of --beta, --domain, --formulation product|displacement at a time")
    out, dxs, t_end = H.spacings(args, quick=[600.0, 400.0], quick_t_end=6.0, default=[C.ACCEPT_DX],
                                 accept_dx=C.ACCEPT_DX)
    main_out = out
    if variant:
        out = out / variant
    out.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        for dx in dxs:
            run_one(dx, t_end, out, force=args.force, formulation=args.formulation, beta=args.beta,
                    domain=args.domain)
    res = analyse(out, dxs, args.reference)
    (out / "tpv3_results.json").write_text(json.dumps(res, indent=1))
    report(res, dxs)
    if variant:
        print(f"results in {out / 'tpv3_results.json'}; the main page shows this run when it is redrawn "
              f"(python -m studies.tpv3.run --report-only with the same --dx)")
        return exit_status(res)
    found = variants(main_out, dxs) if not args.quick else {}
    if found:
        res["variants"] = {name: analyse(main_out / name, done, args.reference) for name, done in found.items()}
        (out / "tpv3_results.json").write_text(json.dumps(res, indent=1))
    figdir, page = H.page_paths(args, out, "tpv3", args.quick)
    cells = {}
    for name in found:
        if name.startswith("domain") and C.ACCEPT_DX in found[name]:
            meta = res["variants"][name]["runs"][f"{C.ACCEPT_DX:g}"]
            cells[f"{C.ACCEPT_DX:g} m, {meta['domain'][0] / 1e3:g} km x {meta['domain'][1] / 1e3:g} km cell"] = \
                load_run(main_out / name, C.ACCEPT_DX)[2]
    fig_stations(out, dxs, figdir, args.reference, cells)
    fig_rupture(out, dxs, figdir)
    write_page(res, dxs, page, H.figure_link(figdir, page), command=H.command_line("studies.tpv3.run", argv))
    print(f"wrote {page}, figures in {figdir}, results in {out / 'tpv3_results.json'}")
    return exit_status(res)


def report(res, dxs):
    H.report(res, REF_STATIONS, dxs)


def exit_status(res) -> int:
    return H.exit_status(res)


if __name__ == "__main__":
    sys.exit(main())
