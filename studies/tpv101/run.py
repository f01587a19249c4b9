"""SCEC TPV101 and TPV103 (rate-and-state friction): convergence and, for TPV101, the
independent spectral BI code uguca (docs/studies/tpv101.md, docs/studies/tpv103.md).

    python -m studies.tpv101.run [--problem tpv101|tpv103] [--dx 200 100 50] [-o OUT]
                                  [--domain L1 L3] [--report-only] [--force] [--quick]

Runs ``cracklab.scenes.tpv101`` or ``scenes.tpv103`` at 200, 100 and 50 m (``--dx`` to choose)
one after the other, each streamed to OUT/<problem>_dx<dx>.zarr
(station series every step, the rupture time of the whole plane, the slip at the end)
with its wall time in the .json next to it; then

* TPV101: compares the 100 m run with uguca's at its three stations and over the
  rupture-time field (shared/reference/tpv101_uguca, or ``--reference DIR``), and every run with the next finer;
* TPV103: checks that the 100 m run reaches 12 s with finite values, and the
  convergence between 100 and 50 m;

and writes OUT/<problem>_results.json (every number of the page and the acceptance),
docs/figures/<problem>_*.png and docs/studies/<problem>.md. The acceptance (rs_compare.check_tpv101,
rs_compare.check_tpv103) is the study's result: the script prints PASS or FAIL and exits 1
when it fails, 2 when it could not be checked (a run missing).

A finished store of the same scene is reused (``--force`` reruns), a killed run resumes
from its checkpoint; ``--report-only`` redraws from the stores. ``--domain L1 L3`` runs the
same problem in another periodic cell into OUT/domain<L1>x<L3>km (no page; the main page
then shows its differences from the default cell). ``--quick``: 600 and 400 m for 4 s into
OUT/quick, page and figures there (a smoke test; the acceptance is not checked).
Time stepping: the builders' own (the product scheme, beta 0.25), default engine and threads.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H
from studies.tpv101 import rs_compare as C
from studies.tpv101 import rs_runs as R
from studies.tpv101.rs_page import write_page

ROOT = H.ROOT

DEFAULT_DX = {"tpv101": [200.0, 100.0, 50.0], "tpv103": [200.0, 100.0, 50.0]}
T_END = {"tpv101": 15.0, "tpv103": 12.0}
COLOURS = {"uguca": "k", "200": "tab:orange", "100": "tab:red", "50": "tab:blue", "600": "tab:olive",
           "400": "tab:green"}
NAMES = {"tpv101": "TPV101", "tpv103": "TPV103"}


# ------------------------------------------------------------------------------ analysis
def station_offsets(name):
    """(along strike, depth below the top of the fault) of a SCEC station name, in units of 100 m."""
    import re

    m = re.fullmatch(r"faultst(-?\d+)dp(-?\d+)", name)
    if m is None:
        raise ValueError(f"not a SCEC on-fault station name: {name!r}")
    return int(m.group(1)), int(m.group(2))


def series(st, station):
    """cracklab's strike components at one station (stress in MPa, as uguca's)."""
    s = st.sel(station=station)
    return {"t": st.t.values, "slip": s.delta_1.values, "rate": s.v_1.values, "stress": s.tau_1.values / 1e6,
            "rate3": s.v_3.values}


def offsets(ds, scene):
    """Coordinates of the rupture-time field as offsets from the hypocentre (m)."""
    g = scene.grid
    return ds.x1.values - g.x1[g.n1 // 2], ds.x3.values - g.x3[g.n3 // 2]


def analyse_run(ds, scene, st, meta):
    """One run: its station metrics, rupture-time field, box ruptured, finiteness."""
    t_end = float(st.t.values[-1])
    names = [str(s) for s in st.station.values]
    stations = {}
    finite = bool(np.all(np.isfinite(ds.delta_1.values)))
    for s in names:
        sim = series(st, s)
        finite &= bool(all(np.all(np.isfinite(sim[k])) for k in ("slip", "rate", "stress", "rate3")))
        m = C.station_metrics(sim["t"], sim["slip"], sim["rate"], at=t_end)
        m["max_abs_v3"] = float(np.max(np.abs(sim["rate3"])))
        stations[s] = m
    x, z = offsets(ds, scene)
    rt = ds.rupture_time.values
    inside = (np.abs(x)[:, None] <= C.BOX[0]) & (np.abs(z)[None, :] <= C.BOX[1])
    out = dict(meta)
    out.update({"stations": stations, "t_reached": t_end, "finite": finite,
                "box_ruptured": float(np.mean(np.isfinite(rt[inside]))),
                "last_rupture_in_box": float(np.nanmax(np.where(inside, rt, np.nan))),
                "ruptured_outside_box": float(np.isfinite(rt[~inside]).mean())})
    return out, (x, z, rt)


def analyse(problem, out, dxs, domain=None, ref_dir=None):
    res = {"problem": problem, "dxs": list(dxs), "runs": {}, "uguca": {}, "fields": {}}
    fields = {}
    for dx in dxs:
        ds, scene, st, meta = R.load_run(out, problem, dx, domain)
        key = f"{dx:g}"
        res["runs"][key], fields[dx] = analyse_run(ds, scene, st, meta)
        if problem == "tpv101":
            res["uguca"][key] = {s: C.compare_station(series(st, s), C.load_reference(s, ref_dir))
                                 for s in C.REF_STATIONS}
    stations = list(res["runs"][f"{dxs[0]:g}"]["stations"])
    runs = {s: {dx: res["runs"][f"{dx:g}"]["stations"][s] for dx in dxs} for s in stations}
    res["convergence"] = {s: {q: C.convergence({dx: runs[s][dx][q] for dx in dxs})
                              for q in ("rupture_time", "peak_rate", "final_slip")} for s in stations}
    pairs = {}
    for a, b in zip(dxs, dxs[1:]):
        pairs[(a, b)] = C.field_difference(*fields[a], *fields[b])
        res["fields"][f"{a:g}-{b:g}"] = pairs[(a, b)]
    if problem == "tpv101":
        ref_field = C.load_reference_field(ref_dir)
        res["uguca_field"] = {f"{dx:g}": C.field_difference(*fields[dx], *ref_field) for dx in dxs}
        key = f"{C.ACCEPT_DX:g}"
        res["acceptance"] = C.check_tpv101(res["uguca"].get(key, {}), res["uguca_field"].get(key), runs, pairs)
    else:
        run = res["runs"].get(f"{C.ACCEPT_DX:g}")
        stable = None if run is None else {"t_end": run["t_reached"], "finite": run["finite"]}
        res["acceptance"] = C.check_tpv103(stable, runs, pairs, t_end=T_END[problem])
    return res, fields


def domain_check(problem, out, dx, variant_out, domain, ref_dir=None):
    """The same grid spacing in two periodic cells: station metrics and rupture-time field."""
    a, fa = analyse_run(*R.load_run(out, problem, dx))
    b, fb = analyse_run(*R.load_run(variant_out, problem, dx, domain))
    rows = {s: {q: b["stations"][s][q] - a["stations"][s][q] for q in ("rupture_time", "peak_rate", "final_slip")}
            for s in a["stations"]}
    rel = {s: {q: b["stations"][s][q] / a["stations"][s][q] - 1 for q in ("peak_rate", "final_slip")}
           for s in a["stations"]}
    return {"dx": dx, "domain": list(domain), "diff": rows, "rel": rel,
            "field": C.field_difference(*fb, *fa), "wall_s": b["wall_s"], "s_per_step": b["s_per_step"]}


def exit_status(res) -> int:
    acc = res["acceptance"]
    if not acc["checked"]:
        return 2
    return 0 if acc["pass"] else 1


# ------------------------------------------------------------------------------ figures
def fig_reference_stations(problem, out, dxs, figdir, ref_dir=None):
    """TPV101 at uguca's stations: slip, slip rate, shear stress; and the slip rate around the front."""
    paths = []
    sts = {f"{dx:g}": R.load_run(out, problem, dx)[2] for dx in dxs}
    for s in C.REF_STATIONS:
        ref = C.load_reference(s, ref_dir)
        fig = H.station_figure(ref, sts, lambda st: series(st, s), f"TPV101, {s}: strike component",
                               ref_keys=("slip", "rate", "stress"), ref_label="uguca, 100 m", colours=COLOURS,
                               alpha=0.5)
        paths.append(H.save(fig, Path(figdir) / f"{problem}_{s}.png", 100))
        fig = H.front_figure(ref["t"], ref["rate"], C.rupture_time(ref["t"], ref["rate"]), sts,
                             lambda st: series(st, s), f"{s}: slip rate around the rupture front",
                             ref_label="uguca, 100 m", colours=COLOURS, after=1.5, alpha=0.5, height=3.4)
        paths.append(H.save(fig, Path(figdir) / f"{problem}_{s}_front.png", 100))
    return paths


def fig_all_stations(problem, out, dxs, figdir, key="rate"):
    """Every SCEC station's slip rate (or slip) at each grid spacing."""
    plt = H.pyplot()
    sts = {f"{dx:g}": R.load_run(out, problem, dx)[2] for dx in dxs}
    names = [str(s) for s in next(iter(sts.values())).station.values]
    order = sorted(names, key=lambda n: tuple(reversed(station_offsets(n))))
    fig, axes = plt.subplots(3, 3, figsize=(11, 8), sharex=True, sharey=True)
    for ax, s in zip(axes.ravel(), order):
        for name, st in sts.items():
            sim = series(st, s)
            ax.plot(sim["t"], sim[key], color=COLOURS.get(name), lw=0.9, label=f"{name} m")
        ax.set_title(s, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    for ax in axes[:, 0]:
        ax.set_ylabel("slip rate (m/s)" if key == "rate" else "slip (m)")
    fig.suptitle(f"{NAMES.get(problem, problem)}: strike slip {'rate ' if key == 'rate' else ''}at SCEC's "
                 f"stations, cracklab at {', '.join(sts)} m", fontsize=10)
    return H.save(fig, Path(figdir) / f"{problem}_stations_{key}.png", 90)


def fig_rupture(problem, fields, dxs, figdir, ref_dir=None, levels=None):
    """Rupture-time contours of every run (and uguca's), and the differences 100 - 50 m and
    100 m - uguca."""
    plt = H.pyplot()
    levels = np.arange(1.0, 12.01, 1.0) if levels is None else levels
    panels = [("contours", None)]
    fine = sorted(dxs)
    if len(dxs) >= 2:
        panels.append(("diff", (fine[1], fine[0])))
    ref = C.load_reference_field(ref_dir) if problem == "tpv101" else None
    if ref is not None and C.ACCEPT_DX in dxs:
        panels.append(("uguca", C.ACCEPT_DX))
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 4.2 * len(panels)), squeeze=False)
    for ax, (kind, arg) in zip(axes[:, 0], panels):
        if kind == "contours":
            handles = []
            if ref is not None:
                x, z, rt = ref
                ax.contour(x / 1e3, z / 1e3, rt.T, levels=levels, colors="k", linewidths=2.0, alpha=0.4)
                handles.append(plt.Line2D([], [], color="k", lw=2, alpha=0.4, label="uguca, 100 m"))
            for dx in dxs:
                x, z, rt = fields[dx]
                cs = ax.contour(x / 1e3, z / 1e3, rt.T, levels=levels, colors=COLOURS.get(f"{dx:g}"),
                                linewidths=0.9)
                handles.append(plt.Line2D([], [], color=COLOURS.get(f"{dx:g}"), label=f"cracklab, {dx:g} m"))
            ax.clabel(cs, levels[::2], fontsize=7, fmt="%.0f s")
            ax.legend(handles=handles, loc="upper right", fontsize=8)
            ax.set_title(f"{NAMES.get(problem, problem)}: rupture time (slip rate > 1 mm/s), contours every "
                         f"{levels[1] - levels[0]:g} s", fontsize=10)
        else:
            if kind == "diff":
                a, b = arg
                xa, za, ra = fields[a]
                xb, zb, rb = fields[b]
                title = f"rupture time at {a:g} m minus at {b:g} m"
            else:
                xa, za, ra = fields[arg]
                xb, zb, rb = ref
                title = f"rupture time, cracklab at {arg:g} m minus uguca at 100 m"
            ia, ib = C.match_nodes(xa, xb)
            ka, kb = C.match_nodes(za, zb)
            d = ra[np.ix_(ia, ka)] - rb[np.ix_(ib, kb)]
            im = ax.pcolormesh(xa[ia] / 1e3, za[ka] / 1e3, d.T, cmap="RdBu_r", vmin=-0.1, vmax=0.1,
                               shading="nearest")
            plt.colorbar(im, ax=ax, shrink=0.85, label="s")
            ax.set_title(title, fontsize=10)
        ax.add_patch(plt.Rectangle((-C.BOX[0] / 1e3, -C.BOX[1] / 1e3), 2 * C.BOX[0] / 1e3, 2 * C.BOX[1] / 1e3,
                                   fill=False, ls="--", color="0.4"))
        ax.set_xlim(-20, 20)
        ax.set_ylim(11, -11)
        ax.set_aspect("equal")
        ax.set_xlabel("along strike from the hypocentre (km)")
        ax.set_ylabel("depth below the hypocentre (km)")
    return H.save(fig, Path(figdir) / f"{problem}_rupture_time.png", 100)


def fig_convergence(res, figdir):
    """The differences between successive grid spacings against the finer spacing."""
    plt = H.pyplot()
    problem = res["problem"]
    fig, ax = plt.subplots(figsize=(6.5, 4.4))
    pairs = [tuple(float(x) for x in k.split("-")) for k in res["fields"]]
    h = [b for _, b in pairs]
    ax.loglog(h, [res["fields"][k]["rms"] for k in res["fields"]], "ko-", lw=1.6,
              label="rupture-time field, RMS in the box")
    for s in C.REF_STATIONS:
        d = [abs(p[2]) for p in res["convergence"][s]["rupture_time"]["pairs"]]
        ax.loglog(h, np.maximum(d, 1e-5), "s--", ms=4, lw=0.9, label=f"{s}: rupture time")
    if len(h) >= 2:
        ref = res["fields"][next(iter(res["fields"]))]["rms"]
        ax.loglog(h, [ref * (x / h[0]) for x in h], color="0.6", lw=0.8, label="first order")
        ax.loglog(h, [ref * (x / h[0]) ** 2 for x in h], color="0.6", lw=0.8, ls=":", label="second order")
    ax.axhline(C.TOL_CONVERGENCE, color="tab:red", lw=0.6)
    ax.set_xlabel("finer grid spacing of the pair (m)")
    ax.set_ylabel("difference from the next coarser run (s)")
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.set_xticks(h)
    ax.set_xticklabels([f"{a:g}-{b:g}" for a, b in pairs])
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax.set_title(f"{NAMES.get(problem, problem)}: differences between successive grid spacings", fontsize=10)
    return H.save(fig, Path(figdir) / f"{problem}_convergence.png", 100)


def report(res):
    for row in res["acceptance"]["rows"]:
        print(f"{'ok  ' if row['pass'] else 'FAIL'} {row['check']}: {C.fmt_value(row['value'], row['unit'])} "
              f"({row['rule']} {C.fmt_value(row['limit'], row['unit'])})")
    acc = res["acceptance"]
    print(f"acceptance: {'NOT CHECKED' if not acc['checked'] else 'PASS' if acc['pass'] else 'FAIL'}")


def main(argv=None) -> int:
    p = H.parser(__doc__, "tpv101", dx_help="grid spacings in m (default 200 100 50)",
                 quick_help="600 m and 400 m, 4 s, into OUT/quick (acceptance not checked)",
                 reference_help="directory of the uguca reference", t_end=None,
                 t_end_help="simulated time (default 15 s, 12 s for tpv103)", page="docs/<problem>.md",
                 first=[(("--problem",), {"choices": ("tpv101", "tpv103"), "default": "tpv101"})])
    p.add_argument("--domain", type=float, nargs=2, default=None, metavar=("L1", "L3"),
                   help="periodic cell in m instead of 72000 36000: a cell check into OUT/domain<L1>x<L3>km, no page")
    args = p.parse_args(argv)

    problem = args.problem
    out, dxs, t_end = H.spacings(args, quick=[600.0, 400.0], quick_t_end=4.0, default=DEFAULT_DX[problem])
    main_out = out
    if t_end is not None and not args.quick and abs(t_end - T_END[problem]) > 1e-9:
        p.error(f"--t-end other than {T_END[problem]:g} s is only for --quick")
    domain = tuple(args.domain) if args.domain else None
    if domain is not None:
        out = main_out / f"domain{domain[0] / 1e3:g}x{domain[1] / 1e3:g}km"
    out.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        for dx in dxs:
            R.run_one(problem, dx, out, t_end=t_end, domain=domain, force=args.force)
    if domain is not None:
        checks = {f"{dx:g}": domain_check(problem, main_out, dx, out, domain, args.reference) for dx in dxs
                  if R.store_path(main_out, problem, dx).with_suffix(".json").exists()}
        (out / f"{problem}_domain.json").write_text(json.dumps(checks, indent=1))
        for key, c in checks.items():
            worst = {q: max(abs(c["diff"][s][q]) for s in c["diff"]) for q in ("rupture_time",)}
            print(f"{problem} {key} m, {domain[0] / 1e3:g} km x {domain[1] / 1e3:g} km against the default cell: "
                  f"station rupture times within {worst['rupture_time']:.4f} s, rupture-time field RMS "
                  f"{c['field']['rms']:.4f} s (largest {c['field']['max_abs']:.4f} s)")
        print(f"results in {out / f'{problem}_domain.json'}; the main page shows them when redrawn")
        return 0
    res, fields = analyse(problem, out, dxs, None, args.reference)
    found = sorted(main_out.glob(f"domain*/{problem}_domain.json"))
    if found and not args.quick:
        res["domain_checks"] = {f.parent.name: json.loads(f.read_text()) for f in found}
    (out / f"{problem}_results.json").write_text(json.dumps(res, indent=1, default=float))
    report(res)
    figdir, page = H.page_paths(args, out, problem, args.quick)
    figs = []
    if problem == "tpv101":
        figs += fig_reference_stations(problem, out, dxs, figdir, args.reference)
    figs.append(fig_all_stations(problem, out, dxs, figdir, "rate"))
    figs.append(fig_all_stations(problem, out, dxs, figdir, "slip"))
    figs.append(fig_rupture(problem, fields, dxs, figdir, args.reference))
    if len(dxs) >= 2:
        figs.append(fig_convergence(res, figdir))
    write_page(res, page, H.figure_link(figdir, page), [f.name for f in figs],
               command=H.command_line("studies.tpv101.run", argv))
    print(f"wrote {page}, figures in {figdir}, results in {out / f'{problem}_results.json'}")
    return exit_status(res) if not args.quick else 0


if __name__ == "__main__":
    sys.exit(main())
