"""Stability of the full-grid schemes, stress-tested: beta from 0.1 to 1.0 (docs/reference/stability.md).

The single-mode map (studies/stability_map.py) predicts, through cracklab.solver.stability.gamma_max
and gamma_max = q_max c_s dt = beta q_max dx (Eq. 52), the largest stable beta of each scheme.
This study checks that prediction on the grid: a traction-free plane (unit square, 64 x 64,
mu = c_s = 1, nu = 1/4, no contact constraint) under a suddenly applied zero-mean random load
(white noise, seed 1), run for a fixed number of steps (2000; plane 3000) at each beta and with each
Numerics.formulation.  One load per kernel, so that each mode is measured on its own:

* mode I: load on component 2 (kernel C_I);
* mode II, mode III: the plane problem (256 x 1), load on component 1 (kernel C_II only) or
  on component 3 (C_III only): in 3D a shear load always exercises both kernels, and the
  less stable one decides;
* shear: 64 x 64, load on components 1 and 3 (C_II and C_III together, what a user runs).

max |v| over the plane is sampled every 5 steps, and its growth rate is the slope of a least-squares line through log max |v|
against the step number over the late half of the run.  It is reported per step, and per
unit T = q c_s t of the highest mode, rate_T = rate_step / gamma_max, the unit of
cracklab.solver.stability.GROWTH_TOLERANCE (the growth of the fastest mode is at least this).  A run
is "unstable" when rate_T > GROWTH_TOLERANCE = 5e-4 or when it blows up (max |v| beyond 1e6
times its initial value, or non-finite: the run is stopped there and the rate is fitted on
what was run); "stable" otherwise.  The product scheme runs on 32 x 32 for 1000 steps (plane:
128 x 1, 1500 steps; see GRID: its direct engine is slow); gamma_max = beta pi sqrt(2) on every
square grid, beta pi on the plane.

The Scene refuses a beta above beta_max (cracklab.stability); this study builds the scene at
an accepted beta and then sets the beta it tests on the frozen dataclass (``_force_beta``),
a study-only path that nothing else uses.  Engines: exponential for the displacement and
velocity formulations (it reproduces the direct scheme to ~1e-6 and costs O(1) per step),
direct for the product scheme (the exponential engine did not support its rule when the
documented runs were made; switching ENGINE below would make them much cheaper).

    .venv/bin/python studies/stability_grid.py --json docs/figures/stability_grid.json
    .venv/bin/python studies/stability_grid.py --quick      # betas 0.1, 0.5, 1; 400-600 steps
    .venv/bin/python studies/stability_grid.py --from-json docs/figures/stability_grid.json

Prints a Markdown table, writes docs/figures/stability_grid.png (--quick:
stability_grid_quick.png) and, with --json, the numbers.
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
except ImportError:
    sys.path.insert(0, str(ROOT))

from cracklab.errors import SimulationError  # noqa: E402
from cracklab.solver.stability import GROWTH_TOLERANCE  # noqa: E402

FIG = ROOT / "docs" / "figures" / "stability_grid.png"
BETAS = (0.1, 0.25, 0.5, 0.75, 1.0)
QUICK_BETAS = (0.1, 0.5, 1.0)
FORMULATIONS = ("displacement", "velocity", "product")
CONVOLUTION = {"displacement": "trapezoid", "velocity": "discretized", "product": "product"}
LOADS = ("I", "II", "III", "shear")
#: plane (2D) runs for the single shear kernels: (n1, steps) per formulation, n3 = 1
PLANE = {"displacement": (256, 3000), "velocity": (256, 3000), "product": (128, 1500)}
QUICK_PLANE = {"displacement": (128, 600), "velocity": (128, 600), "product": (64, 400)}
N = 64
STEPS = 3000
#: history engine per formulation (the documented runs: direct for the product scheme)
ENGINE = {"displacement": "exponential", "velocity": "exponential", "product": "direct"}
#: grid size and step count per formulation.  The product scheme runs on 32 x 32 for half
#: the steps (1000; the others 2000): with the direct engine it evaluates the product weights (10 Gauss points of Z
#: per distinct |q| and lag) and the start-up weight E_0(n) (the same, every step), about
#: 0.1 s per step on 64 x 64 for the two shear channels; 32 x 32 has the same gamma_max.
GRID = {"displacement": (64, 2000), "velocity": (64, 2000), "product": (32, 1000)}
QUICK_GRID = {"displacement": (32, 600), "velocity": (32, 600), "product": (32, 400)}
EVERY = 5
BLOWUP = 1e6
SEED = 1


# ----------------------------------------------------------------------------- growth fit
def growth_rate(steps, vmax, late=0.5):
    """Slope of log(vmax) against the step number over the last ``late`` fraction of the samples.

    Non-positive or non-finite samples end the usable series (the run blew up there);
    returns nan with fewer than 3 usable samples in the window.
    """
    s = np.asarray(steps, dtype=float)
    y = np.asarray(vmax, dtype=float)
    good = np.isfinite(y) & (y > 0)
    if not np.all(good):
        stop = int(np.argmin(good))
        s, y = s[:stop], y[:stop]
    if s.size < 3:
        return math.nan
    start = s[0] + (1.0 - late) * (s[-1] - s[0])
    sel = s >= start
    if np.count_nonzero(sel) < 3:
        return math.nan
    return float(np.polyfit(s[sel], np.log(y[sel]), 1)[0])


def classify(rate_T, blew_up, tol=GROWTH_TOLERANCE):
    if blew_up or not (rate_T <= tol):
        return "unstable"
    return "stable"


# ----------------------------------------------------------------------------- runs
def _force_beta(scene, beta, steps):
    """Study-only: the same scene at a beta the Scene check would refuse, for ``steps`` steps."""
    object.__setattr__(scene, "beta", float(beta))
    object.__setattr__(scene, "t_end", steps * scene.dt)
    assert scene.nsteps == steps
    return scene


def _channel_basis(grid):
    """c = k/q and s = m/q on the spectral layout of cracklab.solver.spectral (rfft along x3)."""
    k, m = grid.wavenumbers()
    q = np.hypot(k, m)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(q > 0, k / q, 0.0), np.where(q > 0, m / q, 0.0)


def _fwd(x):
    return np.fft.rfftn(x, axes=(0, 1))


def _inv(X, shape):
    return np.fft.irfftn(X, s=shape, axes=(0, 1))


def random_loads(grid, load, seed=SEED):
    """Zero-mean random step load (white noise): "I" on component 2, "II" on component 1,
    "III" on component 3, "shear" on components 1 and 3 (independent fields)."""
    rng = np.random.default_rng(seed)

    def field():
        f = rng.standard_normal(grid.shape)
        return f - f.mean()

    comps = {"I": (2,), "II": (1,), "III": (3,), "shear": (1, 3)}[load]
    return {f"tau0_{c}": field() for c in comps}


def build(load, formulation, beta, steps, n=N, seed=SEED):
    """The scene of one run: n x n for loads I and shear, the plane n x 1 for II and III."""
    from cracklab import Grid, Material, Record
    from cracklab.laws import TractionFree
    from cracklab.model.loading import Loading
    from cracklab.model.scene import Numerics, Scene

    plane = load in ("II", "III")
    grid = Grid(n1=n, n3=1 if plane else n, L1=1.0, L3=1.0)
    engine = ENGINE[formulation]
    scene = Scene(material=Material(mu=1.0, cs=1.0, nu=0.25), grid=grid, law=TractionFree(contact=False),
                  loading=Loading(**random_loads(grid, load, seed)), t_end=1e-3, beta=1e-3,
                  record=Record(fields=()), numerics=Numerics(formulation=formulation, engine=engine),
                  name=f"stability_{load}")
    return _force_beta(scene, beta, steps)


def vmax(v):
    """(max, rms) over the plane of |v| (all active components)."""
    a = sum(x * x for x in v.values())
    return float(np.sqrt(a.max())), float(np.sqrt(a.mean()))


def high_band(grid, frac=0.75):
    """v -> norm of the part of v with |q| >= frac q_max (the fastest-growing modes)."""
    k = 2 * np.pi * np.fft.fftfreq(grid.n1, d=grid.dx1)[:, None]
    m = 2 * np.pi * np.fft.rfftfreq(grid.n3, d=grid.dx3)[None, :]
    q = np.hypot(k, m)
    mask = q >= frac * q.max()

    def f(v):
        return float(np.sqrt(sum(np.sum(np.abs(np.fft.rfftn(x, axes=(0, 1))[mask]) ** 2) for x in v.values())))

    return f


def run_case(args):
    """One grid run: growth rate of max |v| of the loaded kernel, and its classification."""
    from cracklab.solver.stepper import steps as stepper

    load, formulation, beta, nsteps, n = args
    scene = build(load, formulation, beta, nsteps, n=n)
    grid = scene.grid
    gamma_max = beta * grid.q_max() * grid.dx_min
    rec_n, rec, rms, hp = [], [], [], []
    band = high_band(grid)
    blew, where = False, None
    t0 = time.perf_counter()
    try:
        for st in stepper(scene):
            if st.n % EVERY and st.n != nsteps:
                continue
            val, rm = vmax(st.v)
            rec_n.append(st.n)
            rec.append(val)
            rms.append(rm)
            hp.append(band(st.v))
            if not math.isfinite(val) or val > BLOWUP * rec[0]:
                blew, where = True, st.n
                break
    except SimulationError as exc:
        blew, where = True, str(exc).split(" at step ")[-1].split(" ")[0]
    sec = time.perf_counter() - t0
    rate = growth_rate(rec_n, rec)
    rate_T = rate / gamma_max if math.isfinite(rate) else (math.inf if blew else math.nan)
    rate_rms = growth_rate(rec_n, rms)
    rate_rms_T = rate_rms / gamma_max if math.isfinite(rate_rms) else (math.inf if blew else math.nan)
    rate_hp = growth_rate(rec_n, hp)
    rate_hp_T = rate_hp / gamma_max if math.isfinite(rate_hp) else (math.inf if blew else math.nan)
    return dict(load=load, mode=load, formulation=formulation, beta=beta, steps=nsteps, n=n,
                gamma_max=gamma_max, seconds=sec, blew_up=blew, blow_up_step=where, rate_step=rate,
                rate_T=rate_T, rate_rms_T=rate_rms_T, rate_hp_T=rate_hp_T,
                series=dict(step=rec_n[::4], vmax=rec[::4], rms=rms[::4], high=hp[::4]),
                growth=float(rec[-1] / rec[0]) if rec and rec[0] > 0 else math.nan,
                status=classify(rate_T, blew), predicted_beta_max=predicted_beta_max(formulation, load, grid))


def current_beta_max(row):
    """beta_max of the current cracklab.solver.stability for a result's grid (the value the run
    recorded came from the limits of its day; the tables and the figure show today's)."""
    from cracklab import Grid

    n = int(row["n"])
    grid = Grid(n1=n, n3=1, L1=1.0, L3=1.0) if GEOMETRY[row["mode"]] == "plane" else Grid(n1=n, n3=n, L1=1.0, L3=1.0)
    return predicted_beta_max(row["formulation"], row["mode"], grid)


def predicted_beta_max(formulation, mode, grid):
    """beta_max of cracklab.solver.stability for this grid: gamma_max / (q_max dx_min), over the
    modes the load exercises (II and III for "shear" in 3D)."""
    from cracklab.solver.stability import beta_max

    comps = {"I": (2,), "II": (1,), "III": (3,), "shear": (1, 3)}[mode]
    return beta_max(grid, formulation, CONVOLUTION[formulation], comps, nu=0.25)


def study(betas, grid=GRID, plane=PLANE, jobs=2, partial=None):
    """Run every (load, formulation, beta); print each result as it comes; with ``partial``
    (a path) rewrite the JSON of the results so far after each one."""
    from concurrent.futures import as_completed

    tasks = [(load, f, b) + (plane[f][::-1] if load in ("II", "III") else grid[f][::-1])
             for load in LOADS for f in FORMULATIONS for b in betas]
    tasks.sort(key=lambda t: (t[1] != "product", t[2]))  # slow ones first
    res = []

    def done(r):
        res.append(r)
        print(f"  [{len(res)}/{len(tasks)}] {r['mode']:>5} {r['formulation']:<12} beta {r['beta']:<5g} "
              f"{r['n']}x{1 if r['mode'] in ('II', 'III') else r['n']} {r['steps']} steps: rate_T {r['rate_T']:+.2e} "
              f"(high band {r['rate_hp_T']:+.2e}) {r['status']}{' blow-up' if r['blew_up'] else ''}, "
              f"{r['seconds']:.1f} s", flush=True)
        if partial is not None:
            partial.write_text(json.dumps(dict(betas=betas, results=res), indent=1, default=str))

    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            for fut in as_completed([pool.submit(run_case, t) for t in tasks]):
                done(fut.result())
    else:
        for t in tasks:
            done(run_case(t))
    return res


# ----------------------------------------------------------------------------- output
def per_mode(results):
    """{(formulation, mode): {beta: record}}."""
    out = {}
    for r in results:
        out.setdefault((r["formulation"], r["mode"]), {})[r["beta"]] = r
    return out


def measured_limit(rows, betas):
    """Largest beta such that every tested beta up to it is stable (0 if none), and the
    first unstable beta (None if none)."""
    lim, first_bad = 0.0, None
    for b in sorted(betas):
        if b not in rows:
            continue
        if rows[b]["status"] == "stable" and first_bad is None:
            lim = b
        elif rows[b]["status"] != "stable" and first_bad is None:
            first_bad = b
    return lim, first_bad


def agreement(pred, lim, first_bad):
    """Does the measured stable range agree with beta_max = pred (on the tested betas)?"""
    if first_bad is None:
        return "agrees (no tested beta unstable)" if lim >= pred else "no unstable beta tested"
    if lim <= pred < first_bad:
        return "agrees"
    if pred >= first_bad:
        return f"DISAGREES: unstable at beta = {first_bad:g} <= beta_max"
    return f"conservative: stable up to {lim:g} > beta_max"


GEOMETRY = {"I": "3D", "II": "plane", "III": "plane", "shear": "3D"}


def report(results, betas):
    pm = per_mode(results)
    lines = ["| formulation | load (grid) | " + " | ".join(f"beta {b:g}" for b in betas)
             + " | beta_max (stability.py) | measured | |",
             "|---|---|" + "---|" * len(betas) + "---|---|---|"]
    summary = []
    for f in FORMULATIONS:
        for m in LOADS:
            rows = pm.get((f, m), {})
            if not rows:
                continue
            any_row = next(iter(rows.values()))
            geo = f"{any_row['n']} x {1 if GEOMETRY[m] == 'plane' else any_row['n']}, {any_row['steps']} steps"
            cells = []
            for b in betas:
                v = rows.get(b)
                if v is None:
                    cells.append("-")
                    continue
                rt = v["rate_T"]
                txt = "blow-up" if v["blew_up"] and not math.isfinite(rt) else f"{rt:+.1e}"
                if v["blew_up"] and math.isfinite(rt):
                    txt += " (blow-up)"
                cells.append(f"**{txt}**" if v["status"] != "stable" else txt)
            pred = current_beta_max(any_row)
            lim, bad = measured_limit(rows, betas)
            verdict = agreement(pred, lim, bad)
            meas = f"stable to {lim:g}" + (f", unstable from {bad:g}" if bad is not None else "")
            lines.append(f"| {f} | {m} ({geo}) | " + " | ".join(cells)
                         + f" | {pred:.3f} | {meas} | {verdict} |")
            summary.append(dict(formulation=f, mode=m, beta_max=pred, stable_to=lim, unstable_from=bad,
                                verdict=verdict))
    lines += ["", "Growth per unit T of the high band |q| >= 0.75 q_max (norm of its spectrum; "
                  "diagnostic, closer to the single-mode rate at gamma_max):", "",
              "| formulation | load | " + " | ".join(f"beta {b:g}" for b in betas) + " |",
              "|---|---|" + "---|" * len(betas)]
    for f in FORMULATIONS:
        for m in LOADS:
            rows = pm.get((f, m), {})
            if not rows:
                continue
            cells = []
            for b in betas:
                v = rows.get(b)
                h = float(v["rate_hp_T"]) if v is not None else math.nan
                cells.append("-" if v is None else "blow-up" if math.isinf(h) else
                             f"{h:+.1e}" + (" (blow-up)" if v["blew_up"] else ""))
            lines.append(f"| {f} | {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines), summary


def figure(results, betas, path=FIG):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pm = per_mode(results)
    fig, axes = plt.subplots(1, len(LOADS), figsize=(5 * len(LOADS), 4.8), sharey=True)
    for ax, m in zip(axes, LOADS):
        for k, f in enumerate(FORMULATIONS):
            rows = pm.get((f, m), {})
            bs = [b for b in betas if b in rows]
            if not bs:
                continue
            y = np.array([rows[b]["rate_T"] for b in bs], dtype=float)
            yplot = np.where(np.isfinite(y), y, 1.0)
            ax.plot(bs, yplot, "o-", color=f"C{k}", label=f)
            for b, yy, v in zip(bs, yplot, (rows[b] for b in bs)):
                if v["blew_up"]:
                    ax.plot(b, yy, "x", color="k", ms=9)
            ax.axvline(current_beta_max(rows[bs[0]]), color=f"C{k}", ls=":", lw=1.2)
        ax.axhline(GROWTH_TOLERANCE, color="k", ls="--", lw=0.8)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_yscale("symlog", linthresh=1e-5)
        ax.set_xlabel("beta = c_s dt / dx")
        ax.set_title({"I": "mode I (3D, opening load)", "II": "mode II (plane, load on x1)",
                      "III": "mode III (plane, load on x3)", "shear": "shear II + III (3D, load on x1, x3)"}[m])
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("growth of max|v| per unit T at q_max (blow-up plotted at 1, x)")
    axes[0].legend(fontsize=8, title="formulation (dotted: beta_max of stability.py)", title_fontsize=7)
    sizes = sorted({(r["formulation"], r["n"], r["steps"]) for r in results if GEOMETRY[r["mode"]] == "3D"},
                   key=lambda x: FORMULATIONS.index(x[0]))
    plane = sorted({(r["n"], r["steps"]) for r in results if GEOMETRY[r["mode"]] == "plane"})
    fig.suptitle("Grid stability, traction-free plane, random step load (3D: "
                 + "; ".join(f"{f} {n} x {n}, {s} steps" for f, n, s in sizes)
                 + "; plane: " + ", ".join(f"{n} x 1, {s} steps" for n, s in plane)
                 + f"); dashed: GROWTH_TOLERANCE = {GROWTH_TOLERANCE:g}", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"betas {QUICK_BETAS}, 32 x 32, 400-600 steps")
    ap.add_argument("--steps", type=int, default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", type=Path, help="write the numbers to this JSON file")
    ap.add_argument("--from-json", type=Path, help="print and draw from a file written by --json")
    ap.add_argument("--no-figure", action="store_true")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    if args.from_json:
        data = json.loads(args.from_json.read_text())
        results, betas = data["results"], tuple(data["betas"])
    else:
        betas = QUICK_BETAS if args.quick else BETAS
        grid = dict(QUICK_GRID if args.quick else GRID)
        plane = dict(QUICK_PLANE if args.quick else PLANE)
        if args.steps:
            grid = {f: (n, args.steps) for f, (n, _) in grid.items()}
            plane = {f: (n, args.steps) for f, (n, _) in plane.items()}
        results = study(betas, grid, plane, args.jobs, partial=args.json)
        if args.json:
            args.json.write_text(json.dumps(dict(betas=betas, results=results), indent=1, default=str))
    text, summary = report(results, betas)
    print(text)
    print()
    for s in summary:
        print(f"{s['formulation']:>12} mode {s['mode']:>3}: beta_max {s['beta_max']:.3f}, measured stable to "
              f"{s['stable_to']:g}, unstable from {s['unstable_from']}: {s['verdict']}")
    print("\nrun time per case (s): " + ", ".join(
        f"{r['mode']}/{r['formulation'][:4]}/{r['beta']:g}: {r['seconds']:.1f}" for r in results))
    if not args.no_figure:
        fig = FIG.with_name("stability_grid_quick.png") if args.quick else FIG
        figure(results, betas, fig)
        print(f"wrote {fig}")
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
