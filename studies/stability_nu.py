"""Stability limit of each grid scheme and Fourier-mode kernel against Poisson's ratio
(docs/reference/stability.md, "Limits for every Poisson ratio"; tabulated in cracklab/solver/stability.py).

For each time scheme a Scene can run (displacement / trapezoid / explicit, velocity /
discretized / semi-implicit, product / piecewise-linear / one predictor-corrector pass),
each kernel (modes I, II, III) and each Poisson ratio of NUS, the single-mode unit step
response r(T) of ``cracklab.modal_response`` is integrated to T = 2000 and its growth
rate measured as in studies/stability_map.py: the slope of ln(max |r| per period) against
T over [1000, 2000] (mode III: |r| sqrt(T), the rate relative to the T^-1/2 decay of J0).
The scheme is stable at gamma when the rate is at most GROWTH_TOLERANCE = 5e-4 per unit T
(cracklab.stability).

The limit is the largest gamma up to which every gamma of a 0.05 scan is stable, refined by
bisection between the last stable and the first unstable gamma of the scan to 1e-3
(relative).  The scan stops at GAMMA_TOP = 6 (gamma_M = 6 is beta = 1.35 on a square grid).

    .venv/bin/python studies/stability_nu.py                 # ~25 min on 2 busy cores; JSON + figure
    .venv/bin/python studies/stability_nu.py --quick         # 4 Poisson ratios, T = 1000
    .venv/bin/python studies/stability_nu.py --from-json docs/figures/stability_nu.json

Writes docs/figures/stability_nu.json (every limit with the scan's rates) and
docs/figures/stability_nu.png, and prints the table that cracklab/solver/stability.py holds.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
try:
    import cracklab  # noqa: F401
except ImportError:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

from cracklab.analysis.modal import envelope_growth, modal_response  # noqa: E402
from cracklab.solver.stability import GROWTH_TOLERANCE, NU_NODES, SCHEMES  # noqa: E402

MODES = ("I", "II", "III")
T_END = 2000.0
GAMMA_STEP = 0.05
GAMMA_TOP = 6.0
REL_TOL = 1e-3
JSON = ROOT / "docs" / "figures" / "stability_nu.json"
FIG = ROOT / "docs" / "figures" / "stability_nu.png"
QUICK_NUS = (0.0, 0.25, 0.3, 0.45)


def growth(scheme, mode, gamma, nu, T_end=T_END):
    """Growth per unit T of the single-mode response (inf on overflow)."""
    formulation, convolution, integration = SCHEMES[scheme]
    return envelope_growth(modal_response(mode, gamma=gamma, T_end=T_end, nu=nu, formulation=formulation,
                                          convolution=convolution, integration=integration))


def limit(scheme, mode, nu, T_end=T_END):
    """(limit, {gamma: rate} of the scan): see the module docstring."""
    rates = {}
    stable = 0.0
    for k in range(1, int(round(GAMMA_TOP / GAMMA_STEP)) + 1):
        g = round(k * GAMMA_STEP, 10)
        rates[g] = growth(scheme, mode, g, nu, T_end)
        if not rates[g] <= GROWTH_TOLERANCE:
            break
        stable = g
    else:
        return GAMMA_TOP, rates
    lo, hi = stable, g  # the last stable and the first unstable gamma of the scan
    while hi - lo > REL_TOL * hi:
        mid = 0.5 * (lo + hi)
        r = growth(scheme, mode, mid, nu, T_end)
        rates[round(mid, 10)] = r
        if r <= GROWTH_TOLERANCE:
            lo = mid
        else:
            hi = mid
    return lo, rates


def _task(args):
    scheme, mode, nu, T_end = args
    t = time.perf_counter()
    lim, rates = limit(scheme, mode, nu, T_end)
    return scheme, mode, nu, lim, rates, time.perf_counter() - t


def measure(nus, T_end=T_END, jobs=2):
    tasks = [(s, m, nu, T_end) for s in SCHEMES for m in MODES for nu in nus
             if not (m == "III" and nu != nus[0])]  # C_III does not depend on nu
    out = {s: {m: {} for m in MODES} for s in SCHEMES}
    with ProcessPoolExecutor(jobs) as pool:
        for scheme, mode, nu, lim, rates, sec in pool.map(_task, tasks):
            out[scheme][mode][f"{nu:g}"] = {"limit": lim, "rates": {f"{g:g}": r for g, r in sorted(rates.items())},
                                             "seconds": round(sec, 2)}
            print(f"{scheme:>12} {mode:>3} nu = {nu:<6g} limit {lim:.4f}  ({sec:.1f} s)", flush=True)
    return out


def table(data, nus):
    """Markdown table of the limits (gamma = q c_s dt): a row per Poisson ratio."""
    cols = [(sch, m) for sch in SCHEMES for m in MODES]
    lines = ["| nu | " + " | ".join(f"{sch} {m}" for sch, m in cols) + " |", "|---|" + "---|" * len(cols)]
    for nu in nus:
        vals = [data[sch][m].get(f"{nu:g}", data[sch][m].get(f"{nus[0]:g}"))["limit"] for sch, m in cols]
        lines.append(f"| {nu:g} | " + " | ".join(f"{v:.3f}" for v in vals) + " |")
    return "\n".join(lines)


def figure(data, nus, path=FIG):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cracklab.solver.stability import gamma_max

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    fine = np.linspace(min(nus), max(nus), 400)
    for ax, s in zip(axes, SCHEMES):
        for k, m in enumerate(MODES):
            row = data[s][m]
            meas = [row.get(f"{nu:g}", row.get(f"{nus[0]:g}"))["limit"] for nu in nus]
            ax.plot(nus, meas, "o", color=f"C{k}", ms=4, label=f"mode {m}: measured")
            ax.plot(fine, [gamma_max(s, m, nu) for nu in fine], "-", color=f"C{k}", lw=1,
                    label=f"mode {m}: held by a scene (0.97 x, smaller neighbour)")
        ax.axhline(np.pi * np.sqrt(2) * 0.5, color="k", ls=":", lw=0.8)
        ax.set_title(f"{s}  ({'/'.join(SCHEMES[s])})", fontsize=9)
        ax.set_xlabel("Poisson ratio nu")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("stable gamma = q c_s dt")
    axes[0].legend(fontsize=7)
    fig.suptitle("Single-mode stability limits against nu (growth <= 5e-4 per unit T over T = 1000-2000); "
                 "dotted: gamma_M of beta = 0.5 on a square grid", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def check_midpoints(nus=NU_NODES, T_end=T_END, jobs=2):
    """Measure the limit half-way between neighbouring nodes and compare it with the table's
    value there (the smaller node value): {scheme: {mode: [(nu, measured, table), ...]}}."""
    from cracklab.solver.stability import gamma_max

    mids = [0.5 * (a + b) for a, b in zip(nus[:-1], nus[1:])]
    tasks = [(s, m, nu, T_end) for s in SCHEMES for m in MODES[:2] for nu in mids]
    out = {s: {m: [] for m in MODES[:2]} for s in SCHEMES}
    with ProcessPoolExecutor(jobs) as pool:
        for scheme, mode, nu, lim, _, _ in pool.map(_task, tasks):
            tab = gamma_max(scheme, mode, nu, measured=True)
            out[scheme][mode].append((nu, lim, tab))
            flag = "" if lim >= tab else "  BELOW"
            print(f"{scheme:>12} {mode:>3} nu = {nu:<7g} measured {lim:.4f}  table {tab:.4f}  "
                  f"ratio {lim / tab:.3f}{flag}", flush=True)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="4 Poisson ratios, T = 1000")
    p.add_argument("--from-json", type=Path, help="tables and figure from a saved run")
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--check-midpoints", action="store_true",
                   help="measure half-way between the nodes and compare with the table (~10 min)")
    a = p.parse_args(argv)
    if a.check_midpoints:
        out = check_midpoints(jobs=a.jobs)
        path = JSON.with_name("stability_nu_midpoints.json")
        path.write_text(json.dumps(out, indent=1))
        print(f"wrote {path}")
        return
    if a.from_json:
        saved = json.loads(a.from_json.read_text())
        data, nus = saved["limits"], saved["nus"]
    else:
        nus = QUICK_NUS if a.quick else NU_NODES
        t = time.time()
        data = measure(nus, T_end=1000.0 if a.quick else T_END, jobs=a.jobs)
        if not a.quick:
            JSON.write_text(json.dumps({"T_end": T_END, "tolerance": GROWTH_TOLERANCE, "nus": list(nus),
                                        "seconds": round(time.time() - t), "limits": data}, indent=1))
            print(f"wrote {JSON}")
    print(table(data, nus))
    if not a.no_figures and not a.quick:
        figure(data, nus)


if __name__ == "__main__":
    main()
