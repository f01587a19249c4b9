"""Write docs/studies/accuracy_vs_cost.md from the rows of studies/accuracy_vs_cost/run.py.

Everything with a number in it is computed from the rows; the explanations are fixed text
that the numbers were checked against when the page was last regenerated (see run.py).
"""
from __future__ import annotations

import math
from statistics import median

from run import ENGINES, FRONT_RTOL, front_summary, label, table


def _sub(rows, **kw):
    return [r for r in rows if all(r[k] == v for k, v in kw.items()) and math.isfinite(r["seconds"])]


def _one(rows, **kw):
    s = _sub(rows, **kw)
    return s[0] if s else None


def _e(x):
    return "blow-up" if not math.isfinite(x) else f"{x:.2g}"


def _front_lines(rows, prob, mode):
    out = ["| run | CPU s | error |", "|---|---|---|"]
    for r in front_summary(rows, prob, mode):
        out.append(f"| {label(r)} | {r['seconds']:.3g} | {r['error']:.3g} |")
    return "\n".join(out)


def _engine_counts(rows, prob, mode):
    front = front_summary(rows, prob, mode)
    counts = {}
    for r in front:
        k = f"{r['formulation']} / {r['engine']}"
        counts[k] = counts.get(k, 0) + 1
    return ", ".join(f"{k} ({v})" for k, v in sorted(counts.items(), key=lambda kv: -kv[1]))


def _truncation_modal(rows):
    """median over gamma and formulation of error(T_cut) / error(untruncated), and CPU ratios."""
    out = {}
    for mode in ("I", "II", "III"):
        for cut in ("direct T50", "direct T100"):
            er, cr = [], []
            for r in _sub(rows, problem="modal", mode=mode, engine=cut):
                ref = _one(rows, problem="modal", mode=mode, engine="direct", gamma=r["gamma"],
                           formulation=r["formulation"])
                if ref and ref["error"] > 0:
                    er.append(r["error"] / ref["error"])
                    cr.append(r["seconds"] / ref["seconds"])
            if er:
                out[(mode, cut)] = (median(er), min(er), max(er), median(cr))
    return out


def _speedup(rows, prob, formulation):
    """(n or gamma, CPU direct / exponential, |error difference| / error) per size."""
    out = []
    key = "n" if prob == "lamb" else "gamma"
    for r in _sub(rows, problem=prob, formulation=formulation, engine="exponential"):
        kw = dict(problem=prob, formulation=formulation, engine="direct", mode=r["mode"], **{key: r[key]})
        if prob == "lamb":
            kw["beta"] = r["beta"]
        d = _one(rows, **kw)
        if d:
            out.append((r["mode"], r[key], r.get("beta"), d["seconds"] / r["seconds"],
                        abs(d["error"] - r["error"]) / d["error"]))
    return out


def write_page(rows, path):
    lamb = [r for r in rows if r["problem"] == "lamb"]
    modal = [r for r in rows if r["problem"] == "modal"]
    ns = sorted({r["n"] for r in lamb})
    gammas = sorted({r["gamma"] for r in modal})
    trunc = _truncation_modal(rows)
    sp_lamb = _speedup(rows, "lamb", "displacement")
    sp_lamb_v = _speedup(rows, "lamb", "velocity")
    sp_lamb_p = _speedup(rows, "lamb", "product")
    skipped = [r for r in lamb if not math.isfinite(r["seconds"])]

    # Lamb convergence with the grid: displacement / exponential at the largest beta
    conv = []
    for n in ns:
        for f, b in (("displacement", 0.5), ("product", 0.5), ("velocity", 0.07)):
            r = _one(rows, problem="lamb", n=n, formulation=f, beta=b, engine="direct") or \
                _one(rows, problem="lamb", n=n, formulation=f, beta=b, engine="exponential")
            if r:
                conv.append((n, f, b, r["error"], r["error_max"], r["seconds"]))
    lamb_trunc = []
    for r in _sub(rows, problem="lamb"):
        if r["engine"].startswith("direct T"):
            ref = _one(rows, problem="lamb", n=r["n"], beta=r["beta"], formulation=r["formulation"], engine="direct")
            if ref:
                lamb_trunc.append((r, ref))

    L = []
    w = L.append
    w("# Run time against error: the Pareto front\n")
    w("Which combination of grid (or time step), history engine and time integration gives a "
      "given accuracy for the least computing time? This page measures it for the two problems "
      "with exact solutions, Lamb's problem on the full grid and the single Fourier mode, and is "
      "written by the study from its own output:\n")
    w("```sh\n.venv/bin/python studies/accuracy_vs_cost/run.py            # full: ~6 min on an idle machine\n"
      ".venv/bin/python studies/accuracy_vs_cost/run.py --quick    # ~30 s; writes results/quick/ only\n"
      ".venv/bin/python studies/accuracy_vs_cost/run.py --from-csv studies/accuracy_vs_cost/results/results.csv"
      " --docs\n```\n")
    w("Output: `studies/accuracy_vs_cost/results/results.csv` and `results.zarr` (one row per run, "
      "with `on_front`), `docs/figures/accuracy_pareto.png`, this page. Helpers are tested in "
      "`tests/studies/test_studies_quick.py`.\n")
    w("![Pareto fronts](../figures/accuracy_pareto.png)\n")
    w("Colours: engine (direct untruncated, direct truncated at T_cut = 50 or 100, exponential); "
      "markers: formulation (circle displacement = the paper's explicit scheme with the trapezoid "
      "pre-integrated C; square velocity = semi-implicit with the discretised Z; triangle product = "
      "Z integrated against the piecewise-linear velocity, one predictor-corrector pass, second order, "
      "docs/reference/stability.md). Open markers: runs that blew up (drawn above the panel's largest error). "
      "Ringed and joined: the front, where errors within "
      f"{FRONT_RTOL:g} of each other count as equal (the exponential engine reproduces the direct one "
      "to ~1e-6).\n")

    w("## What is measured\n")
    w("**Lamb's problem** (`cracklab.scenes.lamb`, unit square, point load P = 1 at the centre, nu = 1/4): "
      "the opening at a station r = 0.25 from the load against Pekeris (`cracklab.analysis.exact.lamb_opening`) for "
      "tau = c_s t / r <= 1.7, before the P wave of the nearest periodic image (tau = 1.73). The exact "
      "opening is singular at the Rayleigh arrival, so, as in `tests/physics/test_lamb.py`, the windows "
      "|tau - tau_P| < 0.03, |tau - tau_S| < 0.03, |tau - tau_R| < 0.08 are left out. Error: root mean "
      "square of (numerical - exact) over the other samples, divided by the static value 3P/(4 pi mu r) "
      "(the maximum is in the table). Grids n x n with n in "
      f"{', '.join(map(str, ns))} (the station is n/4 cells from the load), beta = 0.25 and 0.5 "
      "(displacement, product) and 0.07 (velocity: its mode I limit is beta = 0.0765, "
      "`cracklab.solver.stability`).\n")
    w("**Single mode** (one Fourier mode, unit step load, traction-free): the recurrences of the three grid "
      "schemes, stepped through the history engines themselves (q = mu = c_s = 1; the untruncated direct runs "
      "reproduce `cracklab.analysis.modal.modal_response` to 3e-15, checked at every full run), for "
      f"gamma = q c_s dt in {', '.join(f'{g:g}' for g in gammas)}. Error: max |r - r_exact| over the 50th "
      "Rayleigh period (T in [49, 50] x 2 pi / s_R; 2 pi for mode III), divided by the long-time amplitude "
      "(0.5844 mode I, 0.1566 mode II) or the J0 envelope sqrt(2/(pi T)) (mode III). r_exact: J0 for mode "
      "III; for I and II `cracklab.analysis.exact.modal_exact` (Talbot) at 20 points of the period, interpolated by a "
      "least-squares fit of the exact long-time form (Rayleigh pole plus T^-3/2 and T^-5/2 branch-point "
      "terms at frequencies 1 and c_d/c_s); fit residual 2e-12 (I) and 7e-12 (II), coefficient of "
      "sin(s_R T) 0.584385 (I) and 0.156586 (II), as Appendix B predicts.\n")
    w("**Cost**: CPU time of the run (`time.process_time`, one process and one thread, after a warm-up of "
      "kernel fits, numba compilation and FFTW plans), i.e. the wall time on an idle core. The wall time is "
      "in the CSV too: with the study alone on the machine it matches the CPU time (median ratio 1.00, "
      "0.5 to 1.4 over the runs longer than 0.05 s); runs that shared the 2 cores with other jobs made it "
      "1.2 to 15 times the CPU time. Even the CPU times carry +-20 % (cache contention from the host's "
      "other guests).\n")

    w("## What the front shows\n")
    w("### Lamb's problem\n")
    w("Front, cheapest first:\n")
    w(_front_lines(rows, "lamb", "I") + "\n")
    w(f"On the front: {_engine_counts(rows, 'lamb', 'I')}.\n")
    if conv:
        w("Error against grid size (direct engine, or exponential where the direct run was left out):\n")
        w("| n | formulation | beta | rms error | max error | CPU s |")
        w("|---|---|---|---|---|---|")
        for n, f, b, e, m, s in conv:
            w(f"| {n} | {f} | {b:g} | {e:.3g} | {m:.3g} | {s:.3g} |")
        w("")
    if sp_lamb or sp_lamb_v or sp_lamb_p:
        w("Exponential against direct engine, same scheme and grid (CPU time ratio direct / exponential; "
          "relative difference of the errors):\n")
        w("| formulation | n | beta | direct / exponential CPU | error difference |")
        w("|---|---|---|---|---|")
        for f, sp in (("displacement", sp_lamb), ("velocity", sp_lamb_v), ("product", sp_lamb_p)):
            for mode, n, b, ratio, de in sorted(sp, key=lambda x: (x[1], x[2])):
                w(f"| {f} | {n} | {b:g} | {ratio:.2g} | {de:.1e} |")
        w("")
    if lamb_trunc:
        w("Truncated history (direct engine with `Numerics(window=T_cut)`) against the untruncated one:\n")
        w("| n | beta | formulation | T_cut | error / untruncated | CPU / untruncated |")
        w("|---|---|---|---|---|---|")
        for r, ref in sorted(lamb_trunc, key=lambda x: (x[0]["n"], x[0]["formulation"], x[0]["beta"],
                                                        x[0]["T_cut"])):
            w(f"| {r['n']} | {r['beta']:g} | {r['formulation']} | {r['T_cut']:g} | "
              f"{r['error'] / ref['error']:.4f} | {r['seconds'] / ref['seconds']:.2g} |")
        w("")
    w(LAMB_TEXT)

    w("### Single mode, 50th Rayleigh period\n")
    for mode in ("I", "II", "III"):
        if any(r["mode"] == mode for r in modal):
            w(f"Mode {mode} front, cheapest first (on it: {_engine_counts(rows, 'modal', mode)}):\n")
            w(_front_lines(rows, "modal", mode) + "\n")
    if trunc:
        w("Truncation: error of the truncated run over the untruncated one, same scheme and gamma "
          "(median, min and max over gamma and formulation), and the median CPU ratio:\n")
        w("| mode | engine | median | min | max | CPU / untruncated |")
        w("|---|---|---|---|---|---|")
        for (mode, cut), (med, lo, hi, cr) in trunc.items():
            w(f"| {mode} | {cut} | {med:.3g} | {lo:.3g} | {hi:.3g} | {cr:.2g} |")
        w("")
    w(MODAL_TEXT)

    w("## All runs\n")
    w("### Lamb's problem\n")
    w(table(rows, "lamb", "I") + "\n")
    if skipped:
        w("Left out (the reason is in the table): " + "; ".join(
            f"n = {r['n']}, beta = {r['beta']:g}, {r['formulation']}, {r['engine']}" for r in skipped) + ".\n")
    for mode in ("I", "II", "III"):
        if any(r["mode"] == mode for r in modal):
            w(f"### Single mode {mode}\n")
            w(table(rows, "modal", mode) + "\n")
    w(CAVEATS)
    path.write_text("\n".join(L))


LAMB_TEXT = """\
- **The front is the exponential engine**: the paper's displacement scheme at beta = 0.5 at every grid
  size (and at beta = 0.25 for n = 32, the cheapest run), and the product scheme at n = 256, where it is
  the most accurate run (0.0029 against 0.0037, for 3.6 times the CPU; at n = 64 its 0.025 costs
  more than the displacement scheme's 0.010 at n = 128). Refining the grid is what buys accuracy: displacement scheme, beta = 0.5,
  rms error 0.085, 0.044, 0.010, 0.0037 of the static value for n = 32, 64, 128, 256.
- **Smaller beta is not more accurate here**: at beta = 0.25 the error is larger (displacement: 0.067
  against 0.044 at n = 64, 0.0118 against 0.0037 at n = 256; product at n = 256: 0.0059 against 0.0029)
  for twice the steps. The error of a point load a few tens of cells away is dominated by the grid's
  ringing of the Rayleigh pulse (the load's flat spectrum), which the schemes' damping at the larger
  gamma smooths; this problem measures the spatial error more than the time integration.
- **Engine.** Same scheme and grid: the exponential engine reproduces the direct engine's error (relative
  difference 1e-6 to 2e-4; 4e-4 at n = 256, beta = 0.25) and is 1.9 to 5.6 times cheaper at beta = 0.5
  with the displacement scheme, 1.5 to 9.8 times at beta = 0.25, and 4.4 to 22 times with the product
  scheme (14 and 22 at beta = 0.5, n = 64 and 128: its direct engine evaluates the product weights
  from Z).
  On the smallest, shortest run (velocity scheme, n = 32) the two cost the same (0.97). The
  direct runs of the product scheme at n = 256 and of the velocity scheme at n = 256 (~3.2 GB) were
  left out.
- **The velocity formulation** must run at beta <= 0.0765 (its mode I limit), 7 times the steps of
  beta = 0.5, and is the least accurate here (0.038 at n = 256): dominated everywhere.
- **Truncation** does not change the error up to n = 64, where q c_s t_end exceeds T_cut only for the
  shortest waves; at n = 128, T_cut = 50 raises it by 28 to 43 % (T_cut = 100: 1.5 %). It never saves
  time: the direct engine with a window allocates and tabulates its whole window, ceil(T_cut/gamma_min) + 1
  slots for every mode (gamma_min = 2 pi c_s dt), before the first step, which here is longer than the
  run: 1.9 to 26 times the CPU of the untruncated run, and 6.5 to 92 GB at n = 256 (left out).
"""

MODAL_TEXT = """\
- **Truncation is not an option.** A history truncated at T_cut = 50 or 100 is identical to the full one
  up to T_cut and then drifts. In modes I and II the truncated recurrence **grows exponentially**
  (displacement scheme, gamma = 0.2, mode II: max |r| 0.23 at T = 50, 4.9 at T = 200, 7.8e4 at T = 690
  with T_cut = 50, 43 at T = 690 with T_cut = 100; mode I with T_cut = 50: about 5e-3 per unit T), so
  at the 50th period the error is 1 to 800 times that of the full history in mode I (but see gamma = 0.2
  below), 70 to 6e4 times (T_cut = 50) and 1.7 to 2e3 times (T_cut = 100) in mode II; in mode III it is
  of order 1 of the J0 envelope (the T^-1/2 tail is the memory). This is far from the 3 % to 30 %
  quoted for truncated kernels in other codes: a hard cut of the kernel, as `Numerics(window=...)` does, is unusable
  for long runs here. It saves about 20 to 30 % of the CPU of these one-mode runs (median). Truncated runs reach the
  front only at the inaccurate end, and in mode I at gamma = 0.2, where the growth due to truncation
  happens to offset the damping of the displacement scheme at the 50th period (error 0.11 against 0.15
  untruncated): a coincidence of one period, not accuracy.
- **Engine.** Exponential and untruncated direct engines give the same error (to the 1e-3 of the
  engine tests) at about the same CPU time: for one mode the Python step loop dominates. Both appear on
  every front.
- **Time integration.** At the accurate end the velocity formulation (semi-implicit, discretised Z) is
  the front in modes I and III (gamma = 0.05: 1.9e-3 and 2.2e-3 to 2.4e-3 of the amplitude), and in
  mode II the product scheme is (gamma = 0.05: 3.8e-3; the velocity scheme 5.9e-3), as its mode II does
  not grow. The paper's displacement scheme is the cheapest at a given gamma but first order (2.4e-2 at
  gamma = 0.05, 5.6e-2 at 0.1 in mode I). The second-order product scheme damps the Rayleigh
  oscillation (precision factor 0.94 at the 50th period at gamma = 0.1 in mode I, docs/reference/stability.md):
  1.6e-2 at gamma = 0.05 in mode I, 4.2e-3 in mode III. On the grid, though, the velocity scheme is
  limited to beta <= 0.077 (mode I) and 0.061 (shear), 6.5 to 8 times the steps of beta = 0.5, which is
  why it loses Lamb's problem.
"""

CAVEATS = """\
## Caveats and what is left

- CPU times on a shared machine: +-20 %; the ranking of points closer than that is not significant.
- The Lamb error mixes space and time discretisation; at the grids that fit here the spatial error of the
  point load dominates, so this problem says little about the time integration. The single mode isolates it.
- The product scheme's direct engine spends most of its time evaluating Z for the product weights; with
  the exponential engine (which has the product rule) it is on the Lamb front at n = 256.
- The windowed direct engine allocates its whole window up front; a ring buffer of min(window, steps)
  slots would make truncation as cheap as it should be (it would still be inaccurate, see above).
- These numbers: the engines as of commit 5fab240. Re-run the study to update; the prose above quotes
  the tables and is checked by hand.
"""
