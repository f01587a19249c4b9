"""Section 4 of Geubelle & Rice (1995), Figs. 12-13: a mode I crack front through a row
of tough asperities, with the steady speed and the cohesive zone against Freund's
equation of motion and a Palmer-Rice estimate.

    nice -n 10 .venv/bin/python studies/asperity_front/run.py [-o out/asperity_front]
        [--force] [--analyse-only]

One command: runs the 512 x 256 problem with and without the asperities and four
plane (n3 = 1) diagnostics of the crack speed into Zarr stores under OUT (finished
runs are reused unless --force), measures the fronts into OUT/fronts.zarr, draws
docs/figures/asperity_front_*.png and writes docs/studies/paper_asperities.md from the
numbers (OUT/numbers.json).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))

import runs  # noqa: E402
import theory  # noqa: E402

CR = theory.rayleigh_speed(0.25)
GC_RATIO = 1.25
PAPER_SPEED = 0.56
PAPER_ZONE = 0.06


def interaction_times(ds, tip, scene):
    """Event times of the front-asperity interaction, from the opening snapshots:
    touch (the tip at the asperities' x3 reaches their near edge), wrap (the tip midway
    between them passes their far edge), ring_closed (every node of a ring just outside
    the asperities is broken), half (half of the asperity area broken) and broken (all
    of it). Also the broken fraction of the asperity area over time."""
    from cracklab.scenes import asperity_mask

    grid = scene.grid
    d = 0.125
    centres = [(0.578, 0.25), (0.578, 0.75)]
    inside = asperity_mask(grid, centres, d)
    ring = asperity_mask(grid, centres, d + 6 * grid.dx1) & ~asperity_mask(grid, centres, d + 2 * grid.dx1)
    dc = scene.law.delta_c
    op = ds["delta_2"].transpose("t", "x1", "x3").values
    broken = np.maximum.accumulate(op >= dc, axis=0)
    frac = broken[:, inside].mean(axis=1)
    ring_done = broken[:, ring].all(axis=1)
    t = ds["t"].values
    k = int(np.argmin(np.abs(tip["x3"].values - 0.25)))
    near = 0.578 - d / 2
    touch = t[np.argmax(tip.values[:, k] >= near - 0.01)]
    # wrap-around: the tip midway between the asperities (x3 = 0 and Z/2) passes their far edge
    kk = [int(np.argmin(np.abs(tip["x3"].values - x))) for x in (0.0, 0.5)]
    past = (tip.values[:, kk] >= 0.578 + d / 2).all(axis=1)
    wrap = t[np.argmax(past)] if past.any() else np.nan
    closed = t[np.argmax(ring_done)] if ring_done.any() else np.nan
    half = t[np.argmax(frac >= 0.5)] if (frac >= 0.5).any() else np.nan
    full = t[np.argmax(frac >= 1.0)] if (frac >= 1.0).any() else np.nan
    return {"touch": float(touch), "wrap": float(wrap), "ring_closed": float(closed), "half": float(half),
            "broken": float(full), "frac_at_wrap": float(frac[np.argmin(np.abs(t - wrap))])}, frac


def key_numbers(asp_store, uni_store):
    """The headline numbers of one grid: speed and zone before the asperities, the
    interaction times, the smallest mean speed and the delay at 0.8 Z."""
    from cracklab import analysis, scene_of

    out = {}
    d = {}
    for name, store in (("asp", asp_store), ("uni", uni_store)):
        ds = runs.open_run(store)
        tip = analysis.front_position(ds, method="opening")
        L = analysis.mean_crack_length(tip)
        d[name] = (ds, tip, L, analysis.front_speed(L, window=0.125), scene_of(ds))
    ds, tip, L, v, scene = d["asp"]
    ev, _ = interaction_times(ds, tip, scene)
    t = ds["t"].values
    Lu = d["uni"][2].values
    dx = scene.grid.dx1
    t_init = float(t[np.argmax(Lu > 0.25 + dx)])
    win = (t_init + 0.15, ev["touch"] - 0.03)
    m = (t >= win[0]) & (t <= win[1])
    zone = analysis.cohesive_zone(d["uni"][0])
    mm = (t >= ev["touch"]) & (t <= ev["broken"] + 0.2)

    def reach(LL, x):
        return float(t[np.argmax(LL >= x)]) if (LL >= x).any() else float("nan")
    out.update(ev)
    out.update({"dx": dx, "t_init": t_init, "v_uniform": theory.steady_speed(t, Lu, *win)[0],
                "v_uniform_t1_2": theory.steady_speed(t, Lu, 1.0, 2.0)[0],
                "zone": float(np.nanmean(zone.values[m])), "zone_cells": float(np.nanmean(zone.values[m])) / dx,
                "min_mean_speed": float(np.nanmin(v.values[mm])),
                "delay_0.8": reach(L.values, 0.8) - reach(Lu, 0.8),
                "max_front_std": float(np.nanmax(tip.std("x3").values))})
    return out


def pick_times(ev, t):
    """Six snapshot times like Fig. 12 (a)-(f)."""
    want = [ev["touch"], 0.5 * (ev["touch"] + ev["wrap"]), ev["wrap"], ev["half"],
            ev["broken"] + 0.12, ev["broken"] + 0.35]
    return [float(t[np.argmin(np.abs(t - w))]) for w in want]


def analyse(out, figdir, info):
    import xarray as xr

    from cracklab import analysis, scene_of

    res = {}
    data = {}
    for name in ("asperity", "uniform"):
        ds = runs.open_run(out / f"{name}_512x256.zarr")
        scene = scene_of(ds)
        tip = analysis.front_position(ds, method="opening")
        length = analysis.mean_crack_length(tip)
        speed = analysis.front_speed(length, window=0.125)
        tf = np.arange(0.0, float(ds["t"][-1]) + 1e-9, 0.005)
        lead = analysis.front_position(ds[["rupture_time"]].load(), times=tf, start=analysis.initial_front(scene))
        zone = analysis.cohesive_zone(ds)
        data[name] = dict(ds=ds, scene=scene, tip=tip, length=length, speed=speed, lead=lead,
                          lead_len=analysis.mean_crack_length(lead), zone=zone)
    A, U = data["asperity"], data["uniform"]
    scene = U["scene"]
    t = U["ds"]["t"].values
    dx = scene.grid.dx1
    l0 = 0.25
    ev, frac = interaction_times(A["ds"], A["tip"], A["scene"])
    res["events"] = ev
    # initiation and the steady window before the asperities
    Lu = U["length"].values
    t_init = float(t[np.argmax(Lu > l0 + dx)])
    win = (t_init + 0.15, ev["touch"] - 0.03)
    v_asp, r_asp = theory.steady_speed(t, A["length"].values, *win)
    v_uni, r_uni = theory.steady_speed(t, Lu, *win)
    v_late, _ = theory.steady_speed(t, Lu, 1.0, 2.0)
    m = (t >= win[0]) & (t <= win[1])
    l_mid = float(np.mean(Lu[m])) + l0          # full crack length (the back half is l0)
    G_iso = GC_RATIO
    G_per = float(theory.static_G_ratio(l_mid, g0_ratio=GC_RATIO))
    zone_win = float(np.nanmean(U["zone"].values[m]))
    zone_win_asp = float(np.nanmean(A["zone"].values[m]))
    mat = scene.material
    Gc = 0.5 * float(np.min(A["scene"].law.tau_c)) * scene.law.delta_c
    R0 = float(theory.palmer_rice_zone(mu=mat.mu, nu=mat.nu, Gc=Gc, tau_c=1.0))
    res["steady"] = {
        "t_init": t_init, "window": list(win), "v_asperity_run": v_asp, "v_uniform_run": v_uni,
        "fit_rms": r_asp, "v_uniform_t1_2": v_late, "crack_length_mid": l_mid,
        "G_static_isolated": G_iso, "G_static_periodic": G_per,
        "v_freund_isolated": float(theory.freund_speed(G_iso, CR)),
        "v_freund_periodic": float(theory.freund_speed(G_per, CR)),
        "G_needed": float(1.0 / theory.freund_g(v_uni, CR)),
        "zone_uniform": zone_win, "zone_asperity_run": zone_win_asp, "zone_cells": zone_win / dx,
        "R0": R0, "R_at_v_measured": float(theory.palmer_rice_zone(mu=mat.mu, nu=mat.nu, Gc=Gc, tau_c=1.0, v=v_uni)),
        "R_at_v_freund": float(theory.palmer_rice_zone(mu=mat.mu, nu=mat.nu, Gc=Gc, tau_c=1.0,
                                                        v=theory.freund_speed(G_per, CR))),
        "R_at_paper_speed": float(theory.palmer_rice_zone(mu=mat.mu, nu=mat.nu, Gc=Gc, tau_c=1.0, v=PAPER_SPEED)),
        "A_I_measured": float(theory.A_I(v_uni, mat.nu)), "dx": dx, "cR": CR, "delta_c": scene.law.delta_c,
        "tau0": float(scene.loading.tau0_2),
    }
    # effect of the asperities
    def reach(L, x):
        return float(t[np.argmax(L >= x)]) if (L >= x).any() else float("nan")
    spa = A["speed"].values
    mm = (t >= ev["touch"]) & (t <= ev["broken"] + 0.2)
    res["asperities"] = {
        "t_reach_0.8_asp": reach(A["length"].values, 0.8), "t_reach_0.8_uni": reach(Lu, 0.8),
        "t_reach_1.2_asp": reach(A["length"].values, 1.2), "t_reach_1.2_uni": reach(Lu, 1.2),
        "min_mean_speed": float(np.nanmin(spa[mm])), "t_min_mean_speed": float(t[mm][np.nanargmin(spa[mm])]),
        "max_front_std": float(np.nanmax(A["tip"].std("x3").values)),
        "min_tip_speed_at_asperity": float(np.nanmin(analysis.front_speed(A["tip"], window=0.125).sel(
            x3=0.25, method="nearest").values[mm])),
    }
    # plane diagnostics
    diag = {}
    for case in {**runs.PLANE_CASES, **runs.ZONE_CASES}:
        ds = runs.open_run(out / f"{case}.zarr")
        tip = analysis.front_position(ds, method="opening")
        L = analysis.mean_crack_length(tip)
        v = analysis.front_speed(L, window=0.125)
        const = "constK" in case
        rows = []
        for x in (0.4, 0.6, 0.8, 1.0, 1.2):
            i = int(np.argmax(L.values >= x)) if (L.values >= x).any() else None
            if i is None:
                continue
            full = x + l0
            G = float(theory.static_G_ratio(full, g0_ratio=GC_RATIO)) * (1.0 if const else full / (2 * l0))
            rows.append({"tip": x, "t": float(ds["t"][i]), "v": float(v.values[i]), "G_static": G,
                         "v_freund": float(theory.freund_speed(G, CR))})
        from cracklab import scene_of as _scene
        from cracklab.scenes import cohesive_zone_size

        sc_case = _scene(ds)
        diag[case] = {"rows": rows, "elapsed_s": info.get(case, {}).get("elapsed_s"),
                      "length": L, "speed": v, "n1": sc_case.grid.n1, "beta": sc_case.beta,
                      "zone": float(cohesive_zone_size(sc_case.material, float(np.max(sc_case.law.tau_c)),
                                                              sc_case.law.delta_c))}
    res["plane"] = {k: {kk: d[kk] for kk in ("rows", "elapsed_s", "n1", "beta", "zone")} for k, d in diag.items()}
    # where the ramped constant-K crack starts: G_static at that moment (load factor squared)
    from cracklab import scene_of as _so

    rds = runs.open_run(out / "plane_ramp_constK.zarr")
    L = diag["plane_ramp_constK"]["length"].values
    i0 = int(np.argmax(L > l0 + dx))
    t0 = float(rds["t"][i0])
    fac = _so(rds).loading.factor(t0)          # the ramp factor (no length scaling: l = l_ref)
    res["plane"]["plane_ramp_constK"]["t_start"] = t0
    res["plane"]["plane_ramp_constK"]["G_static_at_start"] = float(fac**2 * theory.static_G_ratio(2 * l0))
    res["runs"] = {k: {kk: vv for kk, vv in v.items() if kk != "skipped"} for k, v in info.items()}
    res["grid_check"] = {"512x256": key_numbers(out / "asperity_512x256.zarr", out / "uniform_512x256.zarr"),
                         "256x128": key_numbers(out / "asperity_256x128.zarr", out / "uniform_256x128.zarr")}
    times6 = pick_times(ev, A["ds"]["t"].values)
    res["fig12_times"] = times6

    # derived store
    fr = xr.Dataset({
        "tip_asperity": A["tip"], "tip_uniform": U["tip"],
        "length_asperity": A["length"], "length_uniform": U["length"],
        "speed_asperity": A["speed"], "speed_uniform": U["speed"],
        "zone_uniform": U["zone"], "zone_asperity": A["zone"],
        "asperity_broken_fraction": (("t",), frac, {"long_name": "broken fraction of the asperity area"}),
    })
    fr = fr.drop_vars([v for v in fr.coords if v not in ("t", "x3")], errors="ignore")
    fr.attrs = {"description": "crack fronts of the asperity-front study (studies/asperity_front); tip = opening "
                               "reaches delta_c"}
    fr.to_zarr(out / "fronts.zarr", mode="w", consolidated=False)

    figures(data, diag, ev, frac, times6, res, figdir)
    return res


def figures(data, diag, ev, frac, times6, res, figdir):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figdir.mkdir(parents=True, exist_ok=True)
    A, U = data["asperity"], data["uniform"]
    dc = A["scene"].law.delta_c
    t = A["ds"]["t"].values
    letters = "abcdef"

    # Fig. 12: 3D views
    fig = plt.figure(figsize=(14, 8.5))
    ds = A["ds"]
    sub = ds["delta_2"].sel(x1=slice(0.3, 1.05)).isel(x1=slice(None, None, 2), x3=slice(None, None, 2))
    X1, X3 = np.meshgrid(sub["x1"].values, sub["x3"].values, indexing="ij")
    zmax = float(np.nanmax(sub.sel(t=times6[-1], method="nearest").values)) / dc
    for j, tt in enumerate(times6):
        ax = fig.add_subplot(2, 3, j + 1, projection="3d")
        Z = sub.sel(t=tt, method="nearest").transpose("x1", "x3").values / dc
        ax.plot_surface(X1, X3, np.minimum(Z, 1.5 * zmax), cmap="viridis", vmin=0, vmax=zmax,
                        rstride=1, cstride=1, linewidth=0, antialiased=False)
        for c3 in (0.25, 0.75):
            th = np.linspace(0, 2 * np.pi, 60)
            ax.plot(0.578 + 0.0625 * np.cos(th), c3 + 0.0625 * np.sin(th), 0 * th, color="r", lw=0.8)
        ax.set_zlim(0, zmax)
        ax.view_init(elev=35, azim=-120)
        ax.set_xlabel("x1 / Z", fontsize=8)
        ax.set_ylabel("x3 / Z", fontsize=8)
        ax.set_zlabel("opening / delta_c", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(f"({letters[j]}) t = {tt:.3f} Z/c_s", fontsize=10)
    fig.suptitle("Fig. 12: opening as the front meets, bows around and breaks the asperities (red circles); "
                 "512 x 256, x1 in [0.3, 1.05] Z", fontsize=11)
    fig.tight_layout()
    p = figdir / "asperity_front_3d.png"
    fig.savefig(p, dpi=100)
    plt.close(fig)

    # fronts in plan view: the contour opening = delta_c (it shows the front closing behind the asperities)
    fig, ax = plt.subplots(figsize=(9, 5))
    op = A["ds"]["delta_2"].sel(x1=slice(0.2, 1.5))
    x1p, x3p = op["x1"].values, op["x3"].values
    for i in range(0, len(t), 2):
        ax.contour(x1p, x3p, op.isel(t=i).values.T / dc, levels=[1.0], colors="0.7", linewidths=0.5)
    for j, tt in enumerate(times6):
        i = int(np.argmin(np.abs(t - tt)))
        ax.contour(x1p, x3p, op.isel(t=i).values.T / dc, levels=[1.0], colors=[f"C{j}"], linewidths=1.5)
        ax.plot([], [], color=f"C{j}", label=f"({letters[j]}) t = {tt:.3f}")
    for c3 in (0.25, 0.75):
        ax.add_patch(plt.Circle((0.578, c3), 0.0625, fill=False, color="r", ls="--"))
    ax.set_xlim(0.2, 1.5)
    ax.set_ylim(0, 1)
    ax.set_aspect("equal")
    ax.set_xlabel("x1 / Z")
    ax.set_ylabel("x3 / Z")
    ax.set_title("crack tip (contour opening = delta_c) every 0.0625 Z/c_s (grey) and at the times of Fig. 12",
                 fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(figdir / "asperity_front_plan.png", dpi=110)
    plt.close(fig)

    # Fig. 13: mean crack length
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    ax = axes[0]
    ax.plot(t, U["length"].values, "k-", label="uniform (tip)")
    ax.plot(t, A["length"].values, "k:", lw=2, label="asperities (tip)")
    ax.plot(U["lead_len"]["t"], U["lead_len"].values, "C0-", lw=0.8, label="uniform (leading edge of zone)")
    ax.plot(A["lead_len"]["t"], A["lead_len"].values, "C1:", lw=1.2, label="asperities (leading edge of zone)")
    Lmax = float(A["length"].values.max())
    for j, tt in enumerate(times6):
        y = float(np.interp(tt, t, A["length"].values))
        ax.annotate(f"{letters[j]}", xy=(tt, y), xytext=(tt - 0.15, y + 0.18), fontsize=9,
                    arrowprops=dict(arrowstyle="->", lw=0.8))
    ax.axhspan(0.578 - 0.0625, 0.578 + 0.0625, color="r", alpha=0.1, label="asperity x1 range")
    ax.set_xlabel("t (Z / c_s)")
    ax.set_ylabel("mean crack length (Z), from x1 = 0")
    ax.set_ylim(0.2, Lmax + 0.1)
    ax.set_title("Fig. 13: mean crack length")
    ax.legend(fontsize=8, loc="upper left")
    ax = axes[1]
    ax.plot(t, U["speed"].values, "k-", label="uniform")
    ax.plot(t, A["speed"].values, "k:", lw=2, label="asperities")
    ax.plot(t, frac, "r-", lw=0.8, label="broken fraction of asperity area")
    s = res["steady"]
    lens = U["length"].values + 0.25
    vf = theory.freund_speed(theory.static_G_ratio(lens, g0_ratio=GC_RATIO), CR)
    moving = U["length"].values > 0.26
    ax.plot(t[moving], vf[moving], "C2--", label="Freund, G_static of the periodic crack at l(t)")
    ax.axhline(s["v_freund_isolated"], color="C2", ls=":", label=f"Freund, G0 = 1.25 Gc: {s['v_freund_isolated']:.3f}")
    ax.axhline(PAPER_SPEED, color="C3", ls="-.", lw=0.8, label="paper: 0.56")
    ax.axhline(CR, color="0.5", lw=0.6)
    ax.text(0.05, CR + 0.01, "c_R", fontsize=8)
    ax.axvspan(*s["window"], color="C0", alpha=0.1, label="window of the steady speed")
    ax.set_xlabel("t (Z / c_s)")
    ax.set_ylabel("speed of the mean tip (c_s)")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title("mean front speed")
    fig.tight_layout()
    fig.savefig(figdir / "asperity_front_length.png", dpi=110)
    plt.close(fig)

    # cohesive zone and the plane diagnostics
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    ax = axes[0]
    z = U["zone"].mean("x3")
    ax.plot(t, z.values, "k-", label="uniform run, measured (x3 mean)")
    za = A["zone"].mean("x3")
    ax.plot(t, za.values, "k:", label="asperity run, measured (x3 mean)")
    v = np.clip(U["speed"].values, 0, None)
    R = theory.palmer_rice_zone(mu=1.0, nu=0.25, Gc=0.5 * dc, tau_c=1.0, v=v)
    ax.plot(t, R, "C2--", label="Palmer-Rice R0 / A_I(v), v measured")
    ax.axhline(s["R0"], color="C2", ls=":", label=f"static R0 = {s['R0']:.3f}")
    ax.axhline(PAPER_ZONE, color="C3", ls="-.", lw=0.8, label="paper: 0.06 Z")
    ax.set_ylim(0, 0.14)
    ax.set_xlabel("t (Z / c_s)")
    ax.set_ylabel("cohesive zone along x1 (Z)")
    ax.legend(fontsize=8)
    ax.set_title("cohesive-zone length")
    ax = axes[1]
    styles = {"plane_sudden_constK": ("k", "-"), "plane_ramp_constK": ("C0", "-"),
              "plane_sudden_fixed": ("C1", "-"), "plane_ramp_fixed": ("C3", "-")}
    for case, d in diag.items():
        if case not in styles:
            continue
        c, ls = styles[case]
        L = d["length"].values
        vv = d["speed"].values
        ok = (L > 0.27) & (L < 1.45)
        ax.plot(L[ok], vv[ok], color=c, ls=ls, label=case.replace("plane_", "") + " (run)")
        full = L[ok] + 0.25
        G = theory.static_G_ratio(full, g0_ratio=GC_RATIO) * (1.0 if "constK" in case else full / 0.5)
        ax.plot(L[ok], theory.freund_speed(G, CR), color=c, ls="--", lw=0.8,
                label=case.replace("plane_", "") + " (Freund)")
    ax.axhline(CR, color="0.5", lw=0.6)
    ax.set_xlabel("crack tip x1 (Z)")
    ax.set_ylabel("speed (c_s)")
    ax.set_ylim(0, 1.0)
    ax.set_title("plane diagnostics: sudden / slow ramp load, constant K / fixed load")
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    fig.tight_layout()
    fig.savefig(figdir / "asperity_front_speed_zone.png", dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default=str(ROOT / "out" / "asperity_front"))
    ap.add_argument("--force", action="store_true", help="rerun finished runs")
    ap.add_argument("--analyse-only", action="store_true")
    ap.add_argument("--docs", default=str(ROOT / "docs"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    info = {}
    todo = [("asperity", runs.scene_3d(True)), ("uniform", runs.scene_3d(False))]
    todo += [(k, runs.scene_plane(**v)) for k, v in {**runs.PLANE_CASES, **runs.ZONE_CASES}.items()]
    # grid check: the same problem at half the resolution
    todo += [("asperity_256x128", runs.scene_3d(True, n1=256, n3=128, every=8)),
             ("uniform_256x128", runs.scene_3d(False, n1=256, n3=128, every=8))]
    for name, scene in todo:
        store = out / (f"{name}_512x256.zarr" if name in ("asperity", "uniform") else f"{name}.zarr")
        if args.analyse_only:
            info[name] = json.loads(store.with_suffix(".json").read_text())
        else:
            info[name] = runs.run_one(scene, store, force=args.force)
        print(name, info[name], flush=True)
    res = analyse(out, Path(args.docs) / "figures", info)
    (out / "numbers.json").write_text(json.dumps(res, indent=1, default=float))
    import page

    page.write(res, Path(args.docs) / "studies" / "paper_asperities.md", out)
    print(json.dumps({k: res[k] for k in ("steady", "asperities", "events")}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
