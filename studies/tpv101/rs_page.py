"""docs/studies/tpv101.md and docs/studies/tpv103.md, written from the study's results (run.py)."""
from __future__ import annotations

import math
from pathlib import Path

from studies.tpv101 import rs_compare as C

NAMES = {"tpv101": "TPV101", "tpv103": "TPV103"}


def _f(x, fmt="{:.3f}"):
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else fmt.format(x)


def _pct(x):
    return _f(None if x is None else 100 * x, "{:+.1f} %")


def _dxs(res):
    return [float(x) for x in res["dxs"]]


def verdict(res):
    acc = res["acceptance"]
    n_ok = sum(r["pass"] for r in acc["rows"])
    if not acc["checked"]:
        head = (f"**Acceptance: NOT CHECKED** ({n_ok} of {len(acc['rows'])} checks hold; it needs the "
                f"{C.ACCEPT_DX:g} m and {C.FINE_DX:g} m runs)")
    else:
        head = f"**Acceptance: {'PASS' if acc['pass'] else 'FAIL'}** ({n_ok} of {len(acc['rows'])} checks hold)"
    if acc["failures"]:
        head += ". These do not hold:\n\n" + "\n".join(f"* {f}" for f in acc["failures"])
    return head


def acceptance_table(res):
    lines = ["| check | value | limit | holds |", "|---|---|---|---|"]
    for r in res["acceptance"]["rows"]:
        rule = "<" if r["rule"] == "below" else "<="
        lines.append(f"| {r['check']} | {C.fmt_value(r['value'], r['unit'])} | {rule} "
                     f"{C.fmt_value(r['limit'], r['unit'])} | {'yes' if r['pass'] else '**no**'} |")
    return "\n".join(lines)


def runs_table(res):
    lines = ["| dx | grid | dt | steps | t_end | wall time | per step | box ruptured | last rupture in the box |",
             "|---|---|---|---|---|---|---|---|---|"]
    for dx in _dxs(res):
        m = res["runs"][f"{dx:g}"]
        lines.append(f"| {dx:g} m | {m['n1']} x {m['n3']} | {1e3 * m['dt']:.3f} ms | {m['nsteps']} | "
                     f"{m['t_reached']:.2f} s | {m['wall_s'] / 60:.1f} min | {1e3 * m['s_per_step']:.0f} ms | "
                     f"{100 * m['box_ruptured']:.1f} % | {m['last_rupture_in_box']:.2f} s |")
    return "\n".join(lines)


def uguca_table(res):
    lines = ["| station | cracklab dx | rupture time (s) | uguca | difference | peak slip rate (m/s) | uguca | "
             "difference | final slip (m) | uguca | difference |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in C.REF_STATIONS:
        for dx in _dxs(res):
            c = res["uguca"][f"{dx:g}"][s]
            lines.append(f"| {s} | {dx:g} m | {c['sim']['rupture_time']:.3f} | {c['ref']['rupture_time']:.3f} | "
                         f"{c['diff']['rupture_time']:+.3f} s | {c['sim']['peak_rate']:.3f} | "
                         f"{c['ref']['peak_rate']:.3f} | {_pct(c['rel']['peak_rate'])} | "
                         f"{c['sim']['final_slip']:.3f} | {c['ref']['final_slip']:.3f} | "
                         f"{_pct(c['rel']['final_slip'])} |")
    return "\n".join(lines)


def field_table(res):
    lines = ["| fields | RMS (s) | mean (s) | largest (s) | nodes where both ruptured | ruptured in one only |",
             "|---|---|---|---|---|---|"]
    for key, d in res["fields"].items():
        a, b = key.split("-")
        lines.append(f"| cracklab {a} m minus {b} m | {d['rms']:.4f} | {d['mean']:+.4f} | {d['max_abs']:.4f} | "
                     f"{d['n_both']} | {d['only_a'] + d['only_b']} |")
    for key, d in res.get("uguca_field", {}).items():
        lines.append(f"| cracklab {key} m minus uguca 100 m | {d['rms']:.4f} | {d['mean']:+.4f} | "
                     f"{d['max_abs']:.4f} | {d['n_both']} | {d['only_a'] + d['only_b']} |")
    return "\n".join(lines)


def _distinct(name):
    """The stations that the symmetry of the whole-space problem about the two axes through
    the hypocentre does not repeat: along strike >= 0, at most as deep as the hypocentre."""
    st, dp = _station_key(name)[::-1]
    return st >= 0 and dp <= 75


def mirror(name):
    """The stations a whole-space station's series equals by symmetry."""
    from cracklab.scenes import tpv3_station_name

    st, dp = _station_key(name)[::-1]
    return {tpv3_station_name(a, b) for a in (st, -st) for b in (dp, 150 - dp)} - {name}


def symmetry(res):
    """Largest difference, over the stations and runs, between a station's numbers and its
    mirror images' (zero up to round-off in a whole space)."""
    worst = {q: 0.0 for q in ("rupture_time", "peak_rate", "final_slip")}
    for run in res["runs"].values():
        st = run["stations"]
        for name in st:
            for other in mirror(name) & set(st):
                for q in worst:
                    worst[q] = max(worst[q], abs(st[name][q] - st[other][q]))
    return worst


def convergence_table(res, quantities=("rupture_time", "peak_rate", "final_slip"), distinct=False):
    dxs = _dxs(res)
    head = ["station", "quantity"] + [f"{dx:g} m" for dx in dxs] + \
        [f"{a:g} - {b:g} m" for a, b in zip(dxs, dxs[1:])] + (["ratio"] if len(dxs) >= 3 else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    label = {"rupture_time": "rupture time (s)", "peak_rate": "peak slip rate (m/s)", "final_slip": "final slip (m)"}
    fmt = {"rupture_time": "{:.4f}", "peak_rate": "{:.3f}", "final_slip": "{:.4f}"}
    dfmt = {"rupture_time": "{:+.4f}", "peak_rate": "{:+.3f}", "final_slip": "{:+.4f}"}
    for s in sorted(res["convergence"], key=_station_key):
        if distinct and not _distinct(s):
            continue
        for q in quantities:
            vals = [res["runs"][f"{dx:g}"]["stations"][s][q] for dx in dxs]
            conv = res["convergence"][s][q]
            row = [s, label[q]] + [_f(v, fmt[q]) for v in vals] + [_f(p[2], dfmt[q]) for p in conv["pairs"]]
            if len(dxs) >= 3:
                row.append(", ".join(_f(r, "{:.1f}") for r in conv["ratios"]))
            lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def _station_key(name):
    import re

    m = re.fullmatch(r"faultst(-?\d+)dp(-?\d+)", name)
    return (int(m.group(2)), int(m.group(1))) if m else (0, 0)


def domain_table(res):
    checks = res.get("domain_checks")
    if not checks:
        return None
    lines = ["| cell | dx | station rupture times: largest change | peak slip rate: largest change | "
             "final slip: largest change | rupture-time field: RMS / largest change | wall time |",
             "|---|---|---|---|---|---|---|"]
    for name, by_dx in checks.items():
        for key, c in by_dx.items():
            drt = max(abs(v["rupture_time"]) for v in c["diff"].values())
            dpk = max(abs(v["peak_rate"]) for v in c["rel"].values())
            dsl = max(abs(v["final_slip"]) for v in c["rel"].values())
            lines.append(f"| {c['domain'][0] / 1e3:g} km x {c['domain'][1] / 1e3:g} km | {key} m | {drt:.4f} s | "
                         f"{100 * dpk:.2f} % | {100 * dsl:.2f} % | {c['field']['rms']:.4f} / "
                         f"{c['field']['max_abs']:.4f} s | {c['wall_s'] / 60:.1f} min |")
    return "\n".join(lines)


def which_converges(res):
    """Where cracklab at 100 m and uguca differ: which is nearer cracklab's 50 m run."""
    if "uguca" not in res or not {f"{C.ACCEPT_DX:g}", f"{C.FINE_DX:g}"} <= set(res["uguca"]):
        return (f"(The {C.FINE_DX:g} m run is needed to tell which of the two {C.ACCEPT_DX:g} m results lies "
                f"nearer the converged one.)")
    a, b = f"{C.ACCEPT_DX:g}", f"{C.FINE_DX:g}"
    lines = ["| station | quantity | cracklab 100 m | uguca 100 m | cracklab 50 m | cracklab 100 m minus 50 m | "
             "uguca minus cracklab 50 m | nearer the 50 m run |", "|---|---|---|---|---|---|---|---|"]
    nearer = {"cracklab": 0, "uguca": 0}
    for s in C.REF_STATIONS:
        for q, unit in (("rupture_time", "s"), ("peak_rate", "rel"), ("final_slip", "rel")):
            c100, c50 = res["uguca"][a][s]["sim"][q], res["uguca"][b][s]["sim"][q]
            u = res["uguca"][a][s]["ref"][q]
            if unit == "s":
                d_c, d_u = c100 - c50, u - c50
                txt = (f"{d_c:+.4f} s", f"{d_u:+.4f} s")
            else:
                d_c, d_u = c100 / c50 - 1, u / c50 - 1
                txt = (_pct(d_c), _pct(d_u))
            who = "cracklab" if abs(d_c) < abs(d_u) else "uguca"
            conv = res["convergence"][s][q]["pairs"]
            if len(conv) >= 2 and abs(conv[-1][2]) >= abs(conv[-2][2]):
                who = "undecided (cracklab's own 100 -> 50 m change is not the smaller)"
                nearer.setdefault("undecided", 0)
            nearer[who.split(" ")[0]] += 1
            fmt = "{:.4f}" if q != "peak_rate" else "{:.3f}"
            lines.append(f"| {s} | {q.replace('_', ' ')} | {fmt.format(c100)} | {fmt.format(u)} | {fmt.format(c50)} | "
                         f"{txt[0]} | {txt[1]} | {who} |")
    fa, fu = res["fields"].get(f"{a}-{b}"), res["uguca_field"].get(b)
    tail = ""
    if fa and fu:
        tail = (f"\n\nOver the rupture-time field in the box, cracklab's {a} m run differs from its {b} m run by "
                f"{fa['rms']:.4f} s RMS (mean {fa['mean']:+.4f} s) and uguca's {a} m field from cracklab's {b} m "
                f"by {fu['rms']:.4f} s RMS (mean {fu['mean']:+.4f} s): "
                + ("cracklab's 100 m field is the nearer." if fa["rms"] < fu["rms"] else
                   "uguca's 100 m field is the nearer."))
    undecided = nearer.get("undecided", 0)
    return ("\n".join(lines) + f"\n\nOf these {sum(nearer.values())} numbers, cracklab's 100 m value is nearer "
            f"its 50 m value in {nearer['cracklab']}, uguca's in {nearer['uguca']}"
            + (f"; {undecided} cannot be told, since cracklab's own value changes more from 100 to 50 m than from "
               f"200 to 100 m (the 50 m value is no converged reference there)" if undecided else "") + "." + tail)


def unconverged(res):
    """Sentences on the station quantities whose 100 -> 50 m change is not smaller than the
    200 -> 100 m one (not yet converging at these spacings), or None."""
    bad = {}
    for s, by_q in res["convergence"].items():
        if not _distinct(s):
            continue
        for q, c in by_q.items():
            pairs = c["pairs"]
            if len(pairs) >= 2 and abs(pairs[-1][2]) >= abs(pairs[-2][2]):
                bad.setdefault(q, []).append(s)
    if not bad:
        return None
    label = {"rupture_time": "rupture time", "peak_rate": "peak slip rate", "final_slip": "final slip"}
    return "; ".join(f"the {label[q]} at {', '.join(v)}" for q, v in bad.items())


def figures(figrel, figs):
    return "\n\n".join(f"![{Path(f).stem}]({figrel}/{f})" for f in figs)


def write_page(res, page, figrel, figs, command=None):
    problem = res["problem"]
    text = (tpv101_page if problem == "tpv101" else tpv103_page)(res, figrel, figs, command)
    Path(page).write_text(text)


HEADER = """*Written by `studies/tpv101/run.py` from its own output; this version by `{cmd}`.
Every number on this page comes from the runs in `out/tpv101/` (`OUT/{problem}_results.json`).*"""


def _conv_summary(res):
    pairs = list(res["fields"].items())
    if not pairs:
        return ""
    txt = "; ".join(f"{k.replace('-', ' -> ')} m: {d['rms']:.4f} s RMS (largest {d['max_abs']:.4f} s)" for k, d in pairs)
    out = f"The rupture-time field changes between successive grid spacings by {txt}"
    if len(pairs) >= 2:
        r = pairs[0][1]["rms"] / pairs[1][1]["rms"]
        out += f", a ratio of {r:.2f} (observed order {math.log2(r):.2f}, dt halving with dx)"
    return out + "."


def _common_notes(res):
    dxs = _dxs(res)
    return f"""* **Rupture time.** The stations' rupture time is the first crossing of 1 mm/s by the
  strike slip rate, interpolated linearly between time steps (uguca's the same, between its
  steps). The field's is cracklab's `rupture_time` output: the time of the first step at
  which the slip-rate magnitude exceeds 1 mm/s, not interpolated, so it lies up to one
  step (dt above; on average half a step) after the crossing; uguca's field is interpolated.
  The field comparisons use the nodes the two grids share inside the 30 km x 15 km
  velocity-weakening box (|strike| <= 15 km, |dip| <= 7.5 km), where both ruptured.
* **Components.** All series are the strike (x1) components. cracklab slides in both
  directions (the slip rate collinear with the traction); off the two axes through the
  hypocentre the dip slip is not zero.
* **Time stepping** is the builder's: the product scheme at beta = 0.25 (dt = 0.25 dx /
  c_s), the default history engine, one process on the shared 2-core machine (wall times are
  not benchmarks). The periodic cell is the builders' 72 km x 36 km at every grid spacing
  ({', '.join(f'{d:g}' for d in dxs)} m)."""


def tpv101_page(res, figrel, figs, command):
    cmd = command or "python -m studies.tpv101.run"
    dom = domain_table(res)
    dom_txt = "" if dom is None else f"""
## The periodic cell

The same grid spacing in another periodic cell (`run.py --domain L1 L3`), against the
72 km x 36 km runs above:

{dom}
"""
    return f"""# SCEC TPV101: convergence and uguca

{HEADER.format(cmd=cmd, problem=res['problem'])}

TPV101 (SCEC/USGS; Harris et al. 2018) is rate-and-state friction with the ageing law in a
whole space: a = 0.008 + 0.008 (1 - B(x) B(z)) (velocity weakening in a 30 km x 15 km box with
a 3 km tanh transition, strengthening outside), b 0.012, L 0.02 m, V0 1e-6 m/s, f0 0.6,
sigma_n 120 MPa, tau0 75 MPa with the initial state sliding at V_ini = 1e-12 m/s, and the
forced nucleation 25 MPa F(r) G(t) (R 3 km, T 1 s) at the hypocentre, 15 s.
`cracklab.scenes.tpv101` builds it on the periodic 72 km x 36 km cell (docs/reference/scenes.md). The
reference is the same problem computed at 100 m with uguca, another spectral
boundary-integral code (its station files and rupture-time field, `tpv101_uguca`, with a README
giving uguca's settings, are not in the repository):
its stations faultst000dp075 (the hypocentre), faultst000dp030 (4.5 km up dip) and
faultst090dp075 (9 km along strike), and its rupture-time field.

{verdict(res)}

## Runs

{runs_table(res)}

## Acceptance

Against uguca at 100 m: at its three stations the rupture time within {C.TOLERANCES['rupture_time']:g} s, the
peak slip rate within {100 * C.TOLERANCES['peak_rate']:g} % and the final slip
(at 15 s) within {100 * C.TOLERANCES['final_slip']:g} %; the rupture-time field within {C.TOLERANCES['field_rms']:g} s RMS where
both ruptured. Convergence: between 100 m and 50 m every one of SCEC's nine stations'
rupture time and the field's RMS difference within {C.TOL_CONVERGENCE:g} s, and the field's difference
smaller than between 200 m and 100 m.

{acceptance_table(res)}

## At uguca's stations

Each series measured on its own time steps (cracklab's dt above, uguca's 10.1 ms); the
final slip at 15 s.

{uguca_table(res)}

## The rupture-time field

{field_table(res)}

## Convergence: 200, 100, 50 m

{_conv_summary(res)} At SCEC's stations (the differences between successive spacings;
"ratio" is the 200-100 m difference over the 100-50 m one, 2 for a first-order quantity, 4
for a second-order one). The whole-space problem is symmetric about the two axes through
the hypocentre, so only four of the nine stations differ: faultst000dp030, faultst120dp030,
faultst000dp075 and faultst090dp075 stand for the others (in every run the mirrored
stations' numbers differ by at most {_f(symmetry(res)['rupture_time'], '{:.1e}')} s in rupture time,
{_f(symmetry(res)['peak_rate'], '{:.1e}')} m/s in peak slip rate and {_f(symmetry(res)['final_slip'], '{:.1e}')} m in final
slip). The acceptance above checks all nine.

{convergence_table(res, distinct=True)}

## Where cracklab and uguca differ: which converges

uguca's 100 m result and cracklab's 100 m result against cracklab's 50 m run, taken as the
nearer estimate of the converged answer (uguca's README: from 200 m to 100 m uguca's own
peak slip rates changed by up to 30 %, its rupture times by 0.058 s RMS):

{which_converges(res)}
{dom_txt}
## Figures

{figures(figrel, figs)}

## What is left

* Not converging at these spacings (the change from 100 to 50 m not smaller than from 200 to
  100 m): {unconverged(res) or "nothing among the station numbers"}. The peak slip rate is a
  single sample of a front that a few cells resolve, with the grid-scale oscillation behind it
  (figures); it is the quantity uguca's README also finds the least converged (up to 30 % from
  200 to 100 m).

## Notes

{_common_notes(res)}
* **uguca's settings differ** (its README): dt = 0.35 dx / c_s, the history truncated at
  T_cut = 100, the dip slip rate held at zero, and the state integrated at constant V over
  a step.
* TPV102, the same problem below a free surface (`scenes.tpv102`), has no study yet.
"""


def tpv103_page(res, figrel, figs, command):
    cmd = command or "python -m studies.tpv101.run --problem tpv103"
    dxs = _dxs(res)
    stab = []
    for dx in dxs:
        m = res["runs"][f"{dx:g}"]
        vmax = max(v["peak_rate"] for v in m["stations"].values())
        stab.append(f"at {dx:g} m the run reaches {m['t_reached']:.3f} s with "
                    f"{'every recorded value finite' if m['finite'] else '**non-finite values**'} "
                    f"(largest slip rate at the stations {vmax:.2f} m/s)")
    return f"""# SCEC TPV103: strong velocity weakening, convergence

{HEADER.format(cmd=cmd, problem=res['problem'])}

TPV103 (SCEC/USGS) is rate-and-state friction with the slip law and strong velocity
weakening in a whole space: a = 0.01 + 0.01 (1 - B B), b 0.014, L 0.4 m, f_w 0.2,
V_w = 0.1 + 0.9 (1 - B B) m/s, V0 1e-6 m/s, f0 0.6, sigma_n 120 MPa, tau0 40 MPa with the
initial state sliding at V_ini = 1e-16 m/s, and the forced nucleation 45 MPa F(r) G(t)
(R 3 km, T 1 s), 12 s; the geometry, box and stations of TPV101 (`cracklab.scenes.tpv103`,
docs/reference/scenes.md). There is no independent reference here: the study checks that the run is
stable to 12 s and that it converges between 100 m and 50 m.

{verdict(res)}

## Runs

{runs_table(res)}

Stability: {'; '.join(stab)}.

## Acceptance

The 100 m run reaches 12 s with every recorded value finite; between 100 m and 50 m every
one of SCEC's nine stations' rupture time and the rupture-time field's RMS difference within
{C.TOL_CONVERGENCE:g} s, and the final slip within {100 * C.TOL_CONVERGENCE_SLIP:g} %.

{acceptance_table(res)}

## Convergence

{_conv_summary(res)}

{field_table(res)}

At SCEC's stations (differences between successive spacings; "ratio" the first over the
second, 2 for a first-order quantity, 4 for a second-order one; the four stations that the
problem's symmetry about the two axes through the hypocentre does not repeat: the mirrored
stations' numbers differ by at most {_f(symmetry(res)['rupture_time'], '{:.1e}')} s in rupture time,
{_f(symmetry(res)['peak_rate'], '{:.1e}')} m/s in peak slip rate and {_f(symmetry(res)['final_slip'], '{:.1e}')} m in final
slip; the acceptance checks all nine):

{convergence_table(res, distinct=True)}

## Figures

{figures(figrel, figs)}

## What is left

* Not converging at these spacings (the last change not smaller than the one before):
  {unconverged(res) or "nothing among the station numbers"}.
* TPV104, the same problem below a free surface (`scenes.tpv104`), has no study yet.

## Notes

{_common_notes(res)}
"""
