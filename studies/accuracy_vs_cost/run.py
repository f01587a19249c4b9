"""Run time against error: Lamb's problem and the single-mode (modal) problem.

For each problem the error against the exact solution and the wall time are measured
across grid size (Lamb) or gamma = q c_s dt (modal), beta, history engine (direct
untruncated, direct truncated at T_cut = 50 and 100, exponential) and time integration
(Numerics.formulation: displacement, velocity, product), and the Pareto front (error
against seconds) is drawn.

Lamb (cracklab.scenes.lamb, unit square, point load P = 1 at the centre): the opening at
a station r = 0.25 from the load is compared with the Pekeris solution
(cracklab.analysis.exact.lamb_opening) for tau = c_s t / r <= 1.7, i.e. before the P wave of the
nearest periodic image arrives (tau = 0.75/(0.25 sqrt 3) = 1.73).  The exact opening is
singular at the Rayleigh arrival, so, as in tests/physics/test_lamb.py, the windows
|tau - tau_P| < 0.03, |tau - tau_S| < 0.03 and |tau - tau_R| < 0.08 are left out.
Error = root mean square of (numerical - exact) over the remaining samples, divided by the
static value 3 P / (4 pi mu r) ("lamb_rms"); the maximum is reported too ("lamb_max").

Modal (one Fourier mode, unit step load, traction-free, nu = 1/4): the recurrences of the
three grid schemes (cracklab.solver.halfspace / cracklab.solver.stepper with q = mu = c_s = 1) are stepped
through the history engines themselves, so that truncation and the exponential engine can
be compared (cracklab.analysis.modal.modal_response has no engine option; the untruncated direct
runs reproduce it to round-off, checked by ``--check``).  Error = max |r - r_exact| over
the samples of the 50th Rayleigh period T in [49 P, 50 P], P = 2 pi / s_R (2 pi for mode
III), divided by the long-time amplitude (0.5844 for mode I, 0.1566 for mode II) or, for
mode III, by the J0 envelope sqrt(2 / (pi T)).  r_exact is J0 for mode III; for modes I
and II it is cracklab.analysis.exact.modal_exact (Talbot inversion, ~3 s per point at T ~ 340)
evaluated at 20 points of the window and interpolated by a least-squares fit of
the exact asymptotic form: the Rayleigh pole, A cos(s_R T) + B sin(s_R T), plus the branch
point terms T^-3/2 and T^-5/2 times cos/sin(T) and cos/sin(a T).  The fit residual at the
20 points is printed (about 1e-9); the fit is cached in modal_reference.json.

Cost: the CPU time of the run (time.process_time: one process, one thread, after a warm-up
of the kernel fits, numba compilation and FFTW plans), which is what the wall time would be
on an idle core; the wall time is recorded too ("wall_seconds"), but on 2 cores shared with
other jobs (load average up to 20 during the runs here) it is several times larger and noisy.

    .venv/bin/python studies/accuracy_vs_cost/run.py            # full, ~10 min
    .venv/bin/python studies/accuracy_vs_cost/run.py --quick    # < 1 min
    .venv/bin/python studies/accuracy_vs_cost/run.py --from-csv studies/accuracy_vs_cost/results/results.csv

Writes results/results.csv, results/results.zarr, docs/figures/accuracy_pareto.png and
(full run, or --docs) docs/studies/accuracy_vs_cost.md; --quick writes results/quick/ only.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
try:
    import cracklab  # noqa: F401
except ImportError:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

NU = 0.25
FIG_DIR = ROOT / "docs" / "figures"
DOC = ROOT / "docs" / "studies" / "accuracy_vs_cost.md"
OUT = HERE / "results"
REFERENCE = HERE / "modal_reference.json"
#: errors within 0.1 % count as equal on the drawn and tabulated fronts (the exponential
#: engine matches the direct one to ~1e-6, which must not put both on the front)
FRONT_RTOL = 1e-3
FIELDS = ["problem", "mode", "n", "beta", "gamma", "formulation", "engine", "T_cut", "steps",
          "seconds", "wall_seconds", "error", "error_max", "status"]

#: engine labels: (Numerics.engine, window)
ENGINES = {"direct": ("direct", None), "direct T50": ("direct", 50.0), "direct T100": ("direct", 100.0),
           "exponential": ("exponential", None)}
FORMULATIONS = ("displacement", "velocity", "product")


# ----------------------------------------------------------------------------- Pareto front
def pareto_front(cost, error, rtol=0.0):
    """Indices of the points on the Pareto front (minimise both), sorted by cost.

    A point is on the front when no other point has cost <= and error <= with at least one
    strict; of exact duplicates, the first is kept.  NaN/inf errors or costs never are.
    With ``rtol`` > 0, errors within a factor 1 + rtol of each other count as equal: a point
    must beat the best error of every cheaper point by more than that factor.
    """
    cost = np.asarray(cost, dtype=float)
    error = np.asarray(error, dtype=float)
    ok = np.flatnonzero(np.isfinite(cost) & np.isfinite(error))
    order = ok[np.lexsort((error[ok], cost[ok]))]  # by cost, then error
    front, best = [], math.inf
    for i in order:
        if error[i] * (1.0 + rtol) < best:
            front.append(int(i))
            best = error[i]
    return front


# ----------------------------------------------------------------------------- Lamb
LAMB_R = 0.25
LAMB_TAU_END = 1.7
LAMB_WINDOWS = (0.03, 0.03, 0.08)


def lamb_error(t, d, r=LAMB_R, P=1.0, mu=1.0, cs=1.0, tau_end=LAMB_TAU_END):
    """(rms, max) of the opening error against Pekeris away from the arrivals, / static value."""
    from cracklab.analysis.exact import lamb_arrivals, lamb_opening

    t = np.asarray(t, dtype=float)
    d = np.asarray(d, dtype=float)
    tau = cs * t / r
    keep = tau <= tau_end * (1 + 1e-12)
    for ta, w in zip(lamb_arrivals(), LAMB_WINDOWS):
        keep &= np.abs(tau - ta) > w
    if not np.all(np.isfinite(d[keep])):
        return math.inf, math.inf
    e = (d[keep] - lamb_opening(r, t[keep], P=P, mu=mu, cs=cs)) / (3.0 * P / (4.0 * math.pi * mu * r))
    return float(np.sqrt(np.mean(e * e))), float(np.max(np.abs(e)))


def _lamb_scene(n, beta, formulation, engine, t_end=None):
    from cracklab import Record
    from cracklab.model.scene import Numerics
    from cracklab.scenes import lamb

    eng, window = ENGINES[engine]
    return lamb(n=n, beta=beta, t_end=t_end or LAMB_TAU_END * LAMB_R,
                record=Record(fields=(), stations={"s": (0.5 + LAMB_R, 0.5)}),
                numerics=Numerics(formulation=formulation, engine=eng, window=window))


def _lamb_memory(n, beta, engine):
    """Bytes of the direct engine's ring buffer and weights (48 bytes per mode and slot)."""
    eng, window = ENGINES[engine]
    if eng != "direct":
        return 0.0
    modes = (n // 2 + 1) * n
    steps = math.ceil(LAMB_TAU_END * LAMB_R * n / beta)
    slots = 2 ** math.ceil(math.log2(max(steps, 256)))  # the buffer doubles from 256
    if window is not None:  # the windowed engine allocates its whole window at once
        slots = math.ceil(window / (2 * math.pi * beta / n)) + 1
    return 48.0 * modes * slots


def lamb_run(n, beta, formulation, engine):
    from cracklab import simulate, stations

    scene = _lamb_scene(n, beta, formulation, engine)
    t0, c0 = time.perf_counter(), time.process_time()
    ds = simulate(scene)
    sec, cpu = time.perf_counter() - t0, time.process_time() - c0
    st = stations(ds).sel(station="s")
    rms, mx = lamb_error(st.t.values, st.delta_2.values)
    return dict(problem="lamb", mode="I", n=n, beta=beta, gamma=beta * math.pi * math.sqrt(2.0),
                formulation=formulation, engine=engine, T_cut=ENGINES[engine][1] or math.inf,
                steps=scene.nsteps, seconds=cpu, wall_seconds=sec, error=rms, error_max=mx, status="ok")


LAMB_BETAS = {"displacement": (0.25, 0.5), "velocity": (0.07,), "product": (0.25, 0.5)}
LAMB_FULL_N = (32, 64, 128, 256)
LAMB_QUICK_N = (32,)
MEMORY_CAP = 2.0e9
#: the product scheme's direct engine evaluates Z at 10 Gauss points per distinct |q| for
#: every lag weight and, every step, for the start-up weight E_0(n): n = 256 took 471 s
#: (wall, loaded machine) at beta = 0.5, so it is left out of the study
PRODUCT_MAX_N = 128
#: a windowed direct engine tabulates its whole window before the first step; with the
#: product rule that is ~1000 to 4000 lags of Z moments per distinct |q| (minutes at n = 64)
PRODUCT_WINDOW_MAX_N = 32


def _lamb_skip(n, beta, formulation, engine):
    """Reason to leave a Lamb case out, or None."""
    mem = _lamb_memory(n, beta, engine)
    if mem > MEMORY_CAP:
        why = "window allocated up front" if ENGINES[engine][1] else "history"
        return f"skipped: direct engine needs ~{mem / 1e9:.1f} GB ({why})"
    if formulation == "product" and engine == "direct" and n > PRODUCT_MAX_N:
        return "skipped: product weights too slow (~470 s at n = 256)"
    if formulation == "product" and ENGINES[engine][1] and n > PRODUCT_WINDOW_MAX_N:
        slots = _lamb_memory(n, beta, engine) / (48.0 * (n // 2 + 1) * n)
        return f"skipped: {slots:.0f}-lag product weight table (~10 Z evaluations per lag and wavenumber)"
    return None


def lamb_cases(quick):
    ns = LAMB_QUICK_N if quick else LAMB_FULL_N
    cases, skipped = [], []
    for n in ns:
        for f in FORMULATIONS:
            for beta in LAMB_BETAS[f][-1:] if quick else LAMB_BETAS[f]:
                for e in ENGINES:
                    why = _lamb_skip(n, beta, f, e)
                    if why:
                        skipped.append(dict(problem="lamb", mode="I", n=n, beta=beta,
                                            gamma=beta * math.pi * math.sqrt(2.0), formulation=f, engine=e,
                                            T_cut=ENGINES[e][1] or math.inf,
                                            steps=math.ceil(LAMB_TAU_END * LAMB_R * n / beta - 1e-9),
                                            seconds=math.nan, wall_seconds=math.nan, error=math.nan,
                                            error_max=math.nan, status=why))
                        continue
                    cases.append((n, beta, f, e))
    return cases, skipped


def lamb_warmup(ns):
    """Kernel fits, numba compilation and FFTW plans, outside the timed runs."""
    from cracklab import simulate

    for f in FORMULATIONS:
        simulate(_lamb_scene(32, LAMB_BETAS[f][0], f, "exponential"))
    for n in ns:
        for f in FORMULATIONS:
            simulate(_lamb_scene(n, LAMB_BETAS[f][0], f, "direct", t_end=3.0 * LAMB_BETAS[f][0] / n))


# ----------------------------------------------------------------------------- modal
def rayleigh_period(mode):
    from cracklab.analysis.modal import long_time_period

    return long_time_period(mode, NU)


def modal_run(mode, gamma, formulation, engine, T_end):
    """r_0..r_N of one mode stepped through a history engine, as the grid stepper does it.

    q = mu = c_s = 1 and tau0 = 1, so that dt = gamma and r = v / V(0+) = 1 + f.
    displacement: f_n = -(gamma/2) S[D]_n (C, trapezoid), D_n = D_{n-1} + dt v_{n-1}.
    velocity: f_n = -(Z0/2) D*_n + (gamma/2) (S[V]_n - w_n V_0 / 2) (Z, discretized, lag 1),
      D*_n = D_{n-1} + dt v_{n-1}/2, then D_n = D_{n-1} + dt (v_{n-1} + v_n)/2.
    product: f = H + K V with H = -(Z0/2) Dk_n + (gamma/2)(S[V]_n + E_0(n) V_0), applied to
      the predicted (V = v_{n-1}) then the corrected velocity (one pass).
    """
    from cracklab.history import make_engine
    from cracklab.elastic.kernels import Z as Zk
    from cracklab.elastic.kernels import eta_hat
    from cracklab.analysis.modal import product_weights

    eng_name, window = ENGINES[engine]
    N = int(math.ceil(T_end / gamma - 1e-9))
    eta = float(eta_hat(mode, NU))
    V0 = 2.0 / eta
    g = np.array([gamma])
    rule = {"displacement": "trapezoid", "velocity": "discretized", "product": "product"}[formulation]
    form = "displacement" if formulation == "displacement" else "velocity"
    extra = {"nsteps": N + 1} if eng_name == "exponential" else {}  # as cracklab.solver.interfaces.for_scene does
    eng = make_engine(eng_name, kernel=mode, gamma=g, nu=NU, rule=rule, formulation=form,
                      lag=0 if formulation == "displacement" else 1, window=window, **extra)
    v = np.empty(N + 1)
    v[0] = V0
    D = 0.0
    x = np.zeros(1)
    if formulation == "displacement":
        pre = -0.5 * gamma
        eng.push(x)  # n = 0: D_0 = 0
        for n in range(1, N + 1):
            D += gamma * v[n - 1]
            x[0] = D
            v[n] = V0 * (1.0 + pre * eng.push(x)[0].real)
        return v / V0
    z0 = float(Zk(mode, np.zeros(1), NU)[0])
    static, pre = -0.5 * z0, 0.5 * gamma
    if formulation == "velocity":
        for n in range(1, N + 1):
            x[0] = v[n - 1]
            conv = eng.push(x)[0].real - 0.5 * float(eng.weight(n - 1)[0].real) * v[0]
            f = static * (D + 0.5 * gamma * v[n - 1]) + pre * conv
            v[n] = V0 * (1.0 + f)
            D += 0.5 * gamma * (v[n - 1] + v[n])
        return v / V0
    w0 = float(product_weights(mode, gamma, 0, nu=NU, order=1, part="lag"))
    K = pre * (w0 - 0.5 * z0)
    dk = 0.0
    for n in range(1, N + 1):
        dk = 0.5 * gamma * v[0] if n == 1 else dk + gamma * v[n - 1]
        x[0] = v[n - 1]
        H = static * dk + pre * (eng.push(x)[0].real + float(eng.start_weight(n)[0].real) * v[0])
        vp = V0 * (1.0 + H + K * v[n - 1])
        v[n] = V0 * (1.0 + H + K * vp)
    return v / V0


def ref_basis(T, mode):
    """Columns of the reference's long-time form of r(T) (the Rayleigh oscillation and the
    T^-3/2, T^-5/2 tails at the two wave speeds), whose coefficients modal_reference fits."""
    from cracklab.analysis.exact import rayleigh_speed_ratio
    from cracklab.elastic.kernels import wave_speed_ratio

    s = rayleigh_speed_ratio(NU)
    a = wave_speed_ratio(NU)
    T = np.asarray(T, dtype=float)
    cols = [np.cos(s * T), np.sin(s * T)]
    for p in (1.5, 2.5):
        for w in (1.0, a):
            cols += [np.cos(w * T) * T**-p, np.sin(w * T) * T**-p]
    return np.column_stack(cols)


def _exact_point(args):
    from cracklab.analysis.exact import modal_exact

    mode, T = args
    return float(modal_exact(mode, T, NU))


def modal_reference(npts=20, jobs=2, period=50):
    """Least-squares coefficients of the exact r(T) over the 50th period (modes I and II), cached."""
    key = f"nu={NU},period={period},npts={npts}"
    if REFERENCE.exists():
        data = json.loads(REFERENCE.read_text())
        if data.get("key") == key:
            return data
    out = {"key": key}
    tasks = []
    for mode in ("I", "II"):
        P = rayleigh_period(mode)
        Ts = np.linspace((period - 1) * P, period * P, npts)
        tasks += [(mode, float(T)) for T in Ts]
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            vals = list(pool.map(_exact_point, tasks))
    else:
        vals = [_exact_point(t) for t in tasks]
    for mode in ("I", "II"):
        sel = [i for i, (m, _) in enumerate(tasks) if m == mode]
        T = np.array([tasks[i][1] for i in sel])
        y = np.array([vals[i] for i in sel])
        A = ref_basis(T, mode)
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        out[mode] = dict(T=T.tolist(), r=y.tolist(), coef=coef.tolist(),
                         residual=float(np.max(np.abs(A @ coef - y))))
    REFERENCE.write_text(json.dumps(out, indent=1))
    return out


def modal_exact_window(mode, T, ref):
    from scipy.special import j0

    if mode == "III":
        return j0(T)
    return ref_basis(T, mode) @ np.asarray(ref[mode]["coef"])


def modal_error(T, r, mode, ref, period=50):
    """max |r - r_exact| over the samples of the given Rayleigh period, / long-time amplitude."""
    from cracklab.analysis.modal import long_time_amplitude

    P = rayleigh_period(mode)
    T = np.asarray(T, dtype=float)
    r = np.asarray(r, dtype=float)
    sel = (T >= (period - 1) * P - 1e-9) & (T <= period * P + 1e-9)
    if not np.all(np.isfinite(r[T <= period * P + 1e-9])):
        return math.inf
    e = np.abs(r[sel] - modal_exact_window(mode, T[sel], ref))
    if mode == "III":
        e = e / np.sqrt(2.0 / (math.pi * T[sel]))
    else:
        e = e / long_time_amplitude(mode, NU)
    return float(np.max(e))


MODAL_FULL_GAMMAS = (0.05, 0.1, 0.2, 0.5, 1.0)
MODAL_QUICK_GAMMAS = (0.5,)


def modal_cases(quick):
    cases = []
    for mode in ("I", "II", "III"):
        for g in MODAL_QUICK_GAMMAS if quick else MODAL_FULL_GAMMAS:
            for f in FORMULATIONS:
                for e in ENGINES:
                    cases.append((mode, g, f, e))
    return cases


def modal_one(mode, gamma, formulation, engine, ref, period=50):
    T_end = period * rayleigh_period(mode) + gamma
    t0, c0 = time.perf_counter(), time.process_time()
    r = modal_run(mode, gamma, formulation, engine, T_end)
    sec, cpu = time.perf_counter() - t0, time.process_time() - c0
    T = gamma * np.arange(r.size)
    err = modal_error(T, r, mode, ref, period)
    return dict(problem="modal", mode=mode, n=1, beta=math.nan, gamma=gamma, formulation=formulation,
                engine=engine, T_cut=ENGINES[engine][1] or math.inf, steps=r.size - 1, seconds=cpu,
                wall_seconds=sec, error=err, error_max=err, status="ok" if math.isfinite(err) else "blow-up")


def check_modal_against_modal_response():
    """The untruncated direct runs reproduce cracklab.analysis.modal.modal_response (printed)."""
    from cracklab.analysis.modal import modal_response

    schemes = {"displacement": ("displacement", "trapezoid", "explicit"),
               "velocity": ("velocity", "discretized", "semi-implicit"),
               "product": ("velocity", "product", "predictor-corrector")}
    worst = 0.0
    for mode in ("I", "II", "III"):
        for f, (ff, c, i) in schemes.items():
            r = modal_run(mode, 0.3, f, "direct", 60.0)
            ref = modal_response(mode, gamma=0.3, T_end=60.0, nu=NU, formulation=ff, convolution=c,
                                 integration=i).values
            d = float(np.max(np.abs(r - ref[:r.size])))
            worst = max(worst, d)
            print(f"  check {mode:>3} {f:<12} max |engine loop - modal_response| = {d:.1e}")
    return worst


# ----------------------------------------------------------------------------- output
def write_csv(rows, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: r[k] for k in FIELDS})


def read_csv(path):
    rows = []
    with open(path) as fh:
        for r in csv.DictReader(fh):
            for k in ("n", "steps"):
                r[k] = int(r[k])
            for k in ("beta", "gamma", "T_cut", "seconds", "wall_seconds", "error", "error_max"):
                r[k] = float(r[k])
            rows.append(r)
    return rows


def write_zarr(rows, path):
    import xarray as xr

    ds = xr.Dataset(coords={"run": np.arange(len(rows))})
    for k in FIELDS:
        vals = [r[k] for r in rows]
        ds[k] = ("run", np.array(vals, dtype=object if isinstance(vals[0], str) else float))
    for k in ("problem", "mode", "formulation", "engine", "status"):
        ds[k] = ds[k].astype(str)
    ds["seconds"].attrs = {"units": "s", "long_name": "CPU time of the run (process time, one thread)"}
    ds["wall_seconds"].attrs = {"units": "s", "long_name": "wall time of the run (one process, nice 10, "
                                                          "shared machine)"}
    ds["error"].attrs = {"units": "1", "long_name": "Lamb: rms opening error / static value; "
                                                   "modal: max error over the 50th period / amplitude"}
    ds["error_max"].attrs = {"units": "1", "long_name": "Lamb: max opening error / static value"}
    ds.attrs["description"] = __doc__.split("\n")[0]
    front = np.zeros(len(rows), dtype=bool)
    for prob in ("lamb", "modal"):
        for sub in _panels(rows, prob):
            idx = [i for i, r in enumerate(rows) if r["problem"] == prob and r["mode"] == sub]
            for j in pareto_front([rows[i]["seconds"] for i in idx], [rows[i]["error"] for i in idx], FRONT_RTOL):
                front[idx[j]] = True
    ds["on_front"] = ("run", front)
    import warnings

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*Zarr V3 specification.*")
        ds.to_zarr(path, mode="w", consolidated=False)


def _panels(rows, prob):
    return ["I"] if prob == "lamb" else [m for m in ("I", "II", "III") if any(
        r["problem"] == "modal" and r["mode"] == m for r in rows)]


MARK = {"displacement": "o", "velocity": "s", "product": "^"}
COLOR = {"direct": "C0", "direct T50": "C3", "direct T100": "C1", "exponential": "C2"}


def label(r):
    if r["problem"] == "lamb":
        return f"n={r['n']} b={r['beta']:g} {r['formulation'][:4]} {r['engine']}"
    return f"g={r['gamma']:g} {r['formulation'][:4]} {r['engine']}"


def figure(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    panels = [("lamb", "I")] + [("modal", m) for m in _panels(rows, "modal")]
    ncol = 2 if len(panels) > 2 else len(panels)
    nrow = math.ceil(len(panels) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.8 * ncol, 5.4 * nrow), squeeze=False)
    axes = axes.ravel()
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    for ax, (prob, mode) in zip(axes, panels):
        sub = [r for r in rows if r["problem"] == prob and r["mode"] == mode and math.isfinite(r["seconds"])]
        err = np.array([r["error"] for r in sub])
        big = np.nanmax(np.where(np.isfinite(err), err, np.nan)) if np.any(np.isfinite(err)) else 1.0
        for r in sub:
            e = r["error"] if math.isfinite(r["error"]) else 3 * big
            ax.loglog(r["seconds"], e, MARK[r["formulation"]], color=COLOR[r["engine"]], ms=6,
                      mfc="none" if not math.isfinite(r["error"]) else COLOR[r["engine"]], alpha=0.75)
        idx = pareto_front([r["seconds"] for r in sub], err, FRONT_RTOL)
        fx = [sub[i]["seconds"] for i in idx]
        fy = [sub[i]["error"] for i in idx]
        ax.step(fx, fy, where="post", color="k", lw=1.2, zorder=0)
        ax.loglog(fx, fy, "o", ms=12, mfc="none", mec="k", mew=1.3)
        for i in idx:
            ax.annotate(label(sub[i]), (sub[i]["seconds"], sub[i]["error"]), fontsize=6.5,
                        xytext=(4, 3), textcoords="offset points")
        ax.set_xlabel("CPU time of the run [s]")
        ax.set_ylabel("rms opening error / static value" if prob == "lamb"
                      else "max error, 50th period / long-time amplitude")
        ax.set_title("Lamb's problem, station r = 0.25" if prob == "lamb" else f"single mode {mode}")
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], ls="", marker=MARK[f], color="grey", label=f) for f in FORMULATIONS]
    handles += [Line2D([], [], ls="", marker="o", color=COLOR[e], label=e) for e in ENGINES]
    handles += [Line2D([], [], ls="-", marker="o", mfc="none", color="k", label="Pareto front")]
    axes[0].legend(handles=handles, fontsize=7, loc="lower left")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _fmt(x, p=2):
    if isinstance(x, float) and not math.isfinite(x):
        return "blow-up" if x == math.inf else "-"
    return f"{x:.{p}e}" if isinstance(x, float) else str(x)


def table(rows, prob, mode):
    sub = [r for r in rows if r["problem"] == prob and r["mode"] == mode]
    on = set(pareto_front([r["seconds"] for r in sub], [r["error"] for r in sub], FRONT_RTOL))
    out = []
    if prob == "lamb":
        out.append("| n | beta | formulation | engine | steps | CPU s | wall s | rms error | max error | front |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        key = lambda r: (r["n"], r["formulation"], r["beta"], list(ENGINES).index(r["engine"]))  # noqa: E731
    else:
        out.append("| gamma | formulation | engine | steps | CPU s | wall s | error | front |")
        out.append("|---|---|---|---|---|---|---|---|")
        key = lambda r: (r["gamma"], r["formulation"], list(ENGINES).index(r["engine"]))  # noqa: E731
    for i in sorted(range(len(sub)), key=lambda i: key(sub[i])):
        r = sub[i]
        if math.isfinite(r["seconds"]):
            sec = f"{r['seconds']:.2f} | {r['wall_seconds']:.2f}"
        else:
            sec = f"{r['status'].replace('|q|', 'wavenumber')} | -"
        star = "**yes**" if i in on else ""
        if prob == "lamb":
            err = f"{_fmt(r['error'])} | {_fmt(r['error_max'])}" if math.isfinite(r["seconds"]) else "- | -"
            out.append(f"| {r['n']} | {r['beta']:g} | {r['formulation']} | {r['engine']} | {r['steps']} | "
                       f"{sec} | {err} | {star} |")
        else:
            out.append(f"| {r['gamma']:g} | {r['formulation']} | {r['engine']} | {r['steps']} | {sec} | "
                       f"{_fmt(r['error'])} | {star} |")
    return "\n".join(out)


def front_summary(rows, prob, mode):
    sub = [r for r in rows if r["problem"] == prob and r["mode"] == mode]
    idx = pareto_front([r["seconds"] for r in sub], [r["error"] for r in sub], FRONT_RTOL)
    return [sub[i] for i in idx]


# ----------------------------------------------------------------------------- main
def _key(r):
    g = round(float(r["gamma"]), 9) if r["problem"] == "modal" else round(float(r["beta"]), 9)
    return (r["problem"], r["mode"], int(r["n"]), g, r["formulation"], r["engine"])


def run(quick, jobs_ref=2, reuse=None, partial=None):
    """All cases; rows of ``reuse`` (a list of rows) with the same key are taken as they are;
    each new row is appended to the CSV ``partial`` as it comes."""
    done = {_key(r): r for r in (reuse or []) if r["status"] == "ok"}
    rows = []

    def keep(row):
        rows.append(row)
        if partial is not None:
            write_csv(rows, partial)
    t_start = time.perf_counter()
    ref = modal_reference(jobs=jobs_ref)
    for m in ("I", "II"):
        print(f"modal reference, mode {m}: fit residual {ref[m]['residual']:.1e}, "
              f"coefficient of sin(s_R T) {ref[m]['coef'][1]:.5f}, cos {ref[m]['coef'][0]:.1e}")
    print(f"[{time.perf_counter() - t_start:.0f} s] modal runs")
    if not quick:
        worst = check_modal_against_modal_response()
        print(f"  worst difference {worst:.1e}")
    modal_run("I", 0.5, "displacement", "exponential", 5.0)  # warm-up
    modal_run("I", 0.5, "velocity", "exponential", 5.0)
    modal_run("I", 0.5, "product", "exponential", 5.0)
    for mode, g, f, e in modal_cases(quick):
        hit = done.get(("modal", mode, 1, round(g, 9), f, e))
        row = hit or modal_one(mode, g, f, e, ref)
        keep(row)
        print(f"[{time.perf_counter() - t_start:.0f} s]  modal {mode:>3} gamma {g:<5g} {f:<12} {e:<12} {row['seconds']:7.2f} s cpu "
              f"{row['wall_seconds']:7.2f} s wall  error {row['error']:.2e}")
    print(f"[{time.perf_counter() - t_start:.0f} s] Lamb runs")
    cases, skipped = lamb_cases(quick)
    lamb_warmup(sorted({c[0] for c in cases}))
    for n, beta, f, e in cases:
        hit = done.get(("lamb", "I", n, round(beta, 9), f, e))
        row = hit or lamb_run(n, beta, f, e)
        keep(row)
        print(f"[{time.perf_counter() - t_start:.0f} s]  lamb n {n:<4} beta {beta:<5g} {f:<12} {e:<12} {row['steps']:5d} steps "
              f"{row['seconds']:7.2f} s cpu {row['wall_seconds']:7.2f} s wall  rms {row['error']:.2e}  "
              f"max {row['error_max']:.2e}")
    for s in skipped:
        print(f"  lamb n {s['n']:<4} beta {s['beta']:<5g} {s['formulation']:<12} {s['engine']:<12} {s['status']}")
    rows += skipped
    print(f"[{time.perf_counter() - t_start:.0f} s] done")
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="Lamb n = 32; modal gamma = 0.5 (< 1 min of CPU)")
    ap.add_argument("--out", type=Path, default=OUT, help="directory of results.csv and results.zarr")
    ap.add_argument("--from-csv", type=Path, help="redraw and rewrite the docs from a results.csv")
    ap.add_argument("--docs", action="store_true", help="write docs/studies/accuracy_vs_cost.md (default: full runs)")
    ap.add_argument("--no-figure", action="store_true")
    ap.add_argument("--reuse", type=Path, help="take the runs already in this CSV (e.g. results.partial.csv) "
                                                "instead of running them again")
    args = ap.parse_args(argv)
    if args.quick and args.out == OUT:
        args.out = OUT / "quick"  # never overwrite the full results
    if args.from_csv:
        rows = read_csv(args.from_csv)
    else:
        rows = run(args.quick, reuse=read_csv(args.reuse) if args.reuse else None,
                   partial=args.out / "results.partial.csv")
        write_csv(rows, args.out / "results.csv")
        write_zarr(rows, args.out / "results.zarr")
        (args.out / "results.partial.csv").unlink(missing_ok=True)
        print(f"wrote {args.out / 'results.csv'} and results.zarr")
    fig = FIG_DIR / ("accuracy_pareto.png" if not args.quick else "accuracy_pareto_quick.png")
    if args.quick:
        fig = args.out / "accuracy_pareto_quick.png"
    if not args.no_figure:
        figure(rows, fig)
        print(f"wrote {fig}")
    for prob, modes in (("lamb", ["I"]), ("modal", _panels(rows, "modal"))):
        for m in modes:
            print(f"\nPareto front, {prob} {m}:")
            for r in front_summary(rows, prob, m):
                print(f"  {label(r):<45} {r['seconds']:8.2f} s  error {r['error']:.2e}")
    if (not args.quick and not args.from_csv) or args.docs:
        from docs_page import write_page  # noqa: E402  (studies/accuracy_vs_cost/docs_page.py)

        write_page(rows, DOC)
        print(f"wrote {DOC}")


if __name__ == "__main__":
    sys.path.insert(0, str(HERE))
    main()
