"""TPV6's fault at TPV7's contrast: the periodic cell's effect on final slip, and the
convergence of the +x side's final slip with and without the regularised normal stress
(docs/studies/tpv7_contrast.md).

    python -m studies.tpv6.contrast run -o OUT --dx 200 --domain 48 24 --domain 96 48 [--normal-slip-scale 0.1]
    python -m studies.tpv6.contrast report -o OUT [--page docs/studies/tpv7_contrast.md]

``run`` runs ``cracklab.scenes.tpv6`` with ``materials=(TPV7_FAR, TPV6_NEAR)`` (the far side's
c_s and c_p 1.2 times smaller than TPV3's rock, the same density; SCEC TPV7) for every
grid spacing and domain given (km, L1 x L3), into OUT/<tag>.zarr with its metadata in
OUT/<tag>.json (``--contrast tpv6`` runs TPV6's own pair instead). A complete store of the
same scene is reused. ``report`` reads every store in OUT and writes the page: final slip at
the stations against the largest domain of each spacing (the periodic images' effect), and
at a fixed domain against the grid spacing, as stated and with L*, with the Richardson
estimate of the limit where three spacings halve.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H

#: SCEC TPV7's far side: TPV3's rock (rho 2670 kg/m^3) with c_s and c_p 1.2 times smaller
#: (3464/1.2 and 6000/1.2 m/s, so nu stays 0.25)
CONTRAST = 1.2


def materials(contrast: str):
    """(top = far, bottom = near) of TPV7 ("tpv7") or TPV6 ("tpv6")."""
    from cracklab.model.material import Material
    from cracklab.scenes.scec import TPV6_FAR, TPV6_NEAR

    if contrast == "tpv6":
        return TPV6_FAR, TPV6_NEAR
    cs = TPV6_NEAR.cs / CONTRAST
    return Material(mu=2670.0 * cs**2, cs=cs, nu=0.25), TPV6_NEAR


def tag(contrast, dx, domain, L) -> str:
    law = f"L{L:g}" if L else "stated"
    return f"{contrast}_dx{dx:g}_{domain[0] / 1e3:g}x{domain[1] / 1e3:g}km_{law}"


def build(contrast, dx, domain, L=None, t_end=12.0):
    """The scene: the builder's with both materials, the domain (m), L* (None: the law as
    stated) and the final slip recorded."""
    import dataclasses

    from cracklab.scenes import tpv6

    s = H.build(tpv6, dx, t_end=t_end, domain=domain, fields=("delta_1",), materials=materials(contrast),
                numerics=H.numerics())
    return s if not L else s.replace(law=dataclasses.replace(s.law, normal_slip_scale=float(L)))


def run(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    domains = [tuple(1e3 * float(x) for x in d) for d in (args.domain or [(48, 24)])]
    for dx in args.dx:
        for dom in domains:
            scene = build(args.contrast, dx, dom, args.normal_slip_scale, args.t_end)
            name = tag(args.contrast, dx, dom, args.normal_slip_scale)
            H.run_scene(scene, H.store_path(out, name), label=name, force=args.force,
                        meta={"contrast": args.contrast, "dx": dx, "domain_km": [d / 1e3 for d in dom],
                              "normal_slip_scale": args.normal_slip_scale})
    return 0


# ------------------------------------------------------------------------------ analysis
def final_slips(store) -> dict:
    """{station: final strike slip (m)}, the mean final slip over the fault's nodes and the
    rupture time of the last station (s)."""
    ds, scene, st = H.load_run(store)
    slip = st.delta_1.isel(t=-1).values
    fault = ~np.asarray(scene.law.bonded)
    d1 = ds.delta_1.isel(t=-1).values
    return {"stations": {str(s): float(v) for s, v in zip(st.station.values, slip)},
            "mean_slip": float(d1[fault].mean()), "t_end": float(st.t.values[-1])}


def collect(out) -> list[dict]:
    rows = []
    for meta_path in sorted(Path(out).glob("*.json")):
        meta = json.loads(meta_path.read_text())
        if "contrast" not in meta or not meta_path.with_suffix(".zarr").exists():
            continue
        meta.update(final_slips(meta_path.with_suffix(".zarr")))
        meta["tag"] = meta_path.stem
        rows.append(meta)
    return rows


def domain_effect(rows) -> list[dict]:
    """Per (contrast, dx, L*): each domain's largest relative change of final slip at the
    stations, and of the mean slip, against the largest domain run."""
    groups = {}
    for r in rows:
        groups.setdefault((r["contrast"], r["dx"], r["normal_slip_scale"]), []).append(r)
    out = []
    for key, rs in sorted(groups.items(), key=lambda kv: (kv[0][0], -kv[0][1], kv[0][2] or 0)):
        ref = max(rs, key=lambda r: r["domain_km"][0] * r["domain_km"][1])
        for r in sorted(rs, key=lambda r: r["domain_km"][0]):
            if r is ref:
                continue
            rel = {s: (v - ref["stations"][s]) / ref["stations"][s] for s, v in r["stations"].items()
                   if ref["stations"][s] > 0}
            worst = max(rel, key=lambda s: abs(rel[s]))
            out.append({"contrast": key[0], "dx": key[1], "L": key[2], "domain": r["domain_km"],
                        "reference": ref["domain_km"], "worst_station": worst, "worst": rel[worst],
                        "per_station": rel, "mean": r["mean_slip"] / ref["mean_slip"] - 1.0})
    return out


def richardson(h, y):
    """(limit, observed order) from three values at spacings h, h/2, h/4 (None when the
    differences do not shrink monotonically)."""
    d1, d2 = y[0] - y[1], y[1] - y[2]
    if d1 == 0 or d2 == 0 or d1 * d2 < 0 or abs(d2) >= abs(d1):
        return None, None
    p = np.log2(d1 / d2)
    if p < 0.5:                 # the changes barely shrink: an extrapolation would mean nothing
        return None, None
    return y[2] - d2 / (2**p - 1), p


def fmt_domain(d) -> str:
    return f"{d[0]:g} x {d[1]:g} km"


PLUS_X = ("faultst120dp000", "faultst120dp075")   # the +x side: the compliant side's direction of motion
DEFAULT = [80.0, 40.0]                              # the builder's default cell (km)


def _effect(effects, contrast, domain):
    for e in effects:
        if e["contrast"] == contrast and e["domain"] == domain and e["dx"] == 200.0 and not e["L"]:
            return e
    return None


def page(rows, effects, domain, command="python -m studies.tpv6.contrast report") -> str:
    stations = list(rows[0]["stations"]) if rows else []
    lines = ["# TPV6's fault at TPV7's contrast: the periodic cell and the convergence of final slip", "",
             f"Written by `{command}` from the runs of `python -m studies.tpv6.contrast run` "
             "(studies/tpv6/contrast.py says which). The scene is `cracklab.scenes.tpv6(materials=(far, near))` "
             "with SCEC TPV7's far side: TPV3's rock with c_s and c_p 1.2 times smaller and the same density "
             "(TPV6's far side is 1.6 times slower and 1.2 times lighter). Final slip is the strike slip at "
             "t = 12 s. Against an independent code at 100 m on the old 48 km x 24 km cell, final slip was 4-7 % "
             "high at three of the five reference stations (issue 34); this page separates the cell's part "
             "from the grid's.", "",
             "## The periodic cell", "",
             "Each cell's largest relative change of final slip over the nine stations, and of the fault's mean "
             "final slip, against the largest cell run at the same spacing:", "",
             "| contrast | dx | L* | cell | against | largest change (station) | mean slip |",
             "|---|---|---|---|---|---|---|"]
    for e in effects:
        lines.append(f"| {e['contrast']} | {e['dx']:g} m | {e['L'] or 'as stated'} | {fmt_domain(e['domain'])} | "
                     f"{fmt_domain(e['reference'])} | {100 * e['worst']:+.2f} % ({e['worst_station']}) | "
                     f"{100 * e['mean']:+.2f} % |")
    found = [(c, _effect(effects, c, DEFAULT), _effect(effects, c, [48.0, 24.0])) for c in ("tpv6", "tpv7")]
    if all(d is not None and o is not None for _, d, o in found):
        lines += ["", f"The builder's default cell is now {fmt_domain(DEFAULT)}: its images change final slip by at "
                  "most " + " and ".join(f"{100 * abs(d['worst']):.2f} % ({c.upper()}'s contrast)" for c, d, _ in found)
                  + ", under the 0.5 % asked; the old 48 km x 24 km changed it by up to "
                  + " and ".join(f"{100 * abs(o['worst']):.1f} % ({o['worst_station']})" for _, _, o in found)
                  + f". At TPV7's contrast the old cell's excess is on the -x side; on the +x side ({', '.join(PLUS_X)}) "
                  f"it is at most {100 * max(abs(found[1][2]['per_station'][x]) for x in PLUS_X):.2f} %: the +x "
                  "side's excess over the independent code does not come from the cell."]
    lines += ["", "## Convergence with the grid", "",
              f"Final slip (m) at the stations on the {fmt_domain(domain)} cell (the cell's part is the same at "
              "every spacing, above), TPV7's contrast, with the change from one spacing to the next; the limit is "
              "Richardson's from the three finest spacings (its observed order in brackets) where their changes "
              "shrink monotonically.", ""]
    for L in sorted({r["normal_slip_scale"] or 0.0 for r in rows}):
        sel = sorted((r for r in rows if r["contrast"] == "tpv7" and (r["normal_slip_scale"] or 0.0) == L
                      and r["domain_km"] == list(domain)), key=lambda r: -r["dx"])
        if not sel:
            continue
        lines += [f"**{'The regularised normal stress, L* = %g m' % L if L else 'The law as stated'}**", "",
                  "| station | " + " | ".join(f"{r['dx']:g} m" for r in sel) + " | limit |",
                  "|---" * (len(sel) + 2) + "|"]
        for st in stations:
            y = [r["stations"][st] for r in sel]
            lim, p = richardson(None, y[-3:]) if len(y) >= 3 else (None, None)
            tail = f"{lim:.3f} ({p:.1f})" if lim is not None else "-"
            cells = [f"{y[0]:.3f}"] + [f"{v:.3f} ({100 * (v / u - 1):+.1f} %)" for u, v in zip(y, y[1:])]
            lines.append(f"| {st}{' (+x)' if st in PLUS_X else ''} | " + " | ".join(cells) + f" | {tail} |")
        lines.append("")
    lines += ["## What the convergence says", ""] + findings(rows, domain) + [""]
    return "\n".join(lines) + "\n"


def findings(rows, domain) -> list[str]:
    """Per law setting: the last change of final slip with the grid on each side of the
    hypocentre (the largest over the +x stations and over faultst-120dp000 and
    faultst-120dp075), and whether the changes shrink."""
    minus = ("faultst-120dp000", "faultst-120dp075")
    out = []
    for L in sorted({r["normal_slip_scale"] or 0.0 for r in rows}):
        sel = sorted((r for r in rows if r["contrast"] == "tpv7" and (r["normal_slip_scale"] or 0.0) == L
                      and r["domain_km"] == list(domain)), key=lambda r: -r["dx"])
        if len(sel) < 3:
            continue
        name = f"With L* = {L:g} m" if L else "With the law as stated"
        parts = []
        for side, group in (("-x", minus), ("+x", PLUS_X)):
            ch = [max(abs(b["stations"][st] / a["stations"][st] - 1) for st in group) for a, b in zip(sel, sel[1:])]
            trend = "shrink" if all(y < 0.7 * x for x, y in zip(ch, ch[1:])) else "do not shrink"
            parts.append(f"on the {side} side the changes from one spacing to the next are "
                         + ", ".join(f"{100 * c:.1f} %" for c in ch) + f" down to {sel[-1]['dx']:g} m ({trend})")
        out.append(f"- {name}: " + "; ".join(parts) + ".")
    out.append("- So the +x side's final slip (the direction the compliant side moves, where the peak slip rate grows "
               "to 45 m/s at 100 m, issue 34) does not converge at these spacings: it grows by several per cent at "
               "each halving down to the finest run, with the law as stated (Coulomb friction between different "
               "materials is ill-posed) and with L* = 0.1 m; with L* = 0.4 m its changes are smaller but not yet "
               "shrinking. Its limit cannot be given from these runs, and its excess over the independent code at "
               "100 m is of the size of these changes; the cell has no part in it (above). The -x side changes by "
               "about 1 % per halving once the normal stress is regularised.")
    return out


def figure(rows, domain, path) -> Path:
    """Final slip against the grid spacing at the +x stations and at faultst-120dp000, per
    law setting, on the ``domain`` cell at TPV7's contrast."""
    plt = H.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharey=False)
    for ax, st in zip(axes, PLUS_X + ("faultst-120dp000",)):
        for L in sorted({r["normal_slip_scale"] or 0.0 for r in rows}):
            sel = sorted((r for r in rows if r["contrast"] == "tpv7" and (r["normal_slip_scale"] or 0.0) == L
                          and r["domain_km"] == list(domain)), key=lambda r: -r["dx"])
            if sel:
                ax.plot([r["dx"] for r in sel], [r["stations"][st] for r in sel], "o-",
                        label="as stated" if not L else f"L* = {L:g} m")
        ax.set_xscale("log")
        dxs = sorted({r["dx"] for r in rows})
        ax.set_xticks(dxs, [f"{d:g}" for d in dxs])
        ax.minorticks_off()
        ax.invert_xaxis()
        ax.set(title=st + (" (+x)" if st in PLUS_X else ""), xlabel="dx (m)", ylabel="final slip (m)")
        ax.title.set_fontsize(9)
    axes[0].legend(fontsize=8)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return H.save(fig, path, 110)


def report(args) -> int:
    rows = collect(args.out)
    effects = domain_effect(rows)
    Path(args.out, "contrast_results.json").write_text(json.dumps({"runs": rows, "domain": effects}, indent=1))
    fixed = [float(x) for x in args.fixed_domain]
    text = page(rows, effects, fixed, command="python -m studies.tpv6.contrast report " + " ".join(sys.argv[2:]))
    if args.page:
        fig = figure(rows, fixed, Path(args.page).resolve().parents[1] / "figures" / "tpv7_contrast_convergence.png")
        text += f"\n![final slip against the grid spacing](../figures/{fig.name})\n"
    if args.page:
        Path(args.page).write_text(text)
    print(text)
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("what", choices=("run", "report"))
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--dx", type=float, nargs="+", default=[200.0])
    p.add_argument("--domain", type=float, nargs=2, action="append", metavar=("L1_KM", "L3_KM"))
    p.add_argument("--fixed-domain", type=float, nargs=2, default=[48.0, 24.0], metavar=("L1_KM", "L3_KM"),
                   help="the domain of the convergence tables (km)")
    p.add_argument("--contrast", choices=("tpv7", "tpv6"), default="tpv7")
    p.add_argument("--normal-slip-scale", type=float, default=None, help="L* (m); default: the law as stated")
    p.add_argument("--t-end", type=float, default=12.0)
    p.add_argument("--force", action="store_true")
    p.add_argument("--page", default=None)
    args = p.parse_args(argv)
    return run(args) if args.what == "run" else report(args)


if __name__ == "__main__":
    sys.exit(main())
