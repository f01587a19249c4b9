"""Stability map of the single-mode (modal) time-stepping schemes, and the accuracy of the
stable ones (docs/reference/stability.md).

For every scheme below, mode I, II, III (nu = 1/4) and gamma = q c_s dt in
{0.05, 0.1, 0.2, ..., 2.6}, the unit step response r(T) of one Fourier mode is
integrated to T = 2000 and the growth rate of its envelope is measured:

    growth = slope of ln(max |r| over each period) against T, over [T_end/2, T_end]

(the period is 2 pi / s_R for modes I and II, 2 pi for mode III; for mode III
|r| sqrt(T) is used, i.e. the rate relative to the T^-1/2 decay of the exact J0).
"inf" means that the recurrence overflowed.  A scheme is called stable at gamma when
the growth is below GROWTH_TOL = 1e-5 per unit T (a factor 1.02 over T = 2000).

Schemes: the 12 of section 3.1 (cracklab.analysis.modal.SCHEMES), the new product-integration
schemes of cracklab.analysis.modal (convolution "product" / "product-cubic", integration
"explicit" / "semi-implicit" / "predictor-corrector"), Heun (predictor-corrector) on the
default displacement scheme, and three candidates that only this study implements:

* ``V/disc(cumtrapz Z)/semi``: the velocity + discretized + semi-implicit scheme with
  Z(T) = Z(0) - (cumulative trapezoid of C on the step grid) instead of the exact Z;
* ``V/product/AB2``: piecewise-linear velocity with the current velocity extrapolated,
  v_n ~ 2 v_{n-1} - v_{n-2}, i.e. delta_n = delta_{n-1} + dt (3 v_{n-1} - v_{n-2})/2 in
  the functional (explicit, one pass);
* ``V/held-v/explicit``: piecewise-constant velocity (v_{k} held over [t_k, t_{k+1}]),
  Z integrated exactly, explicit update (37) -- the same as the displacement
  formulation with the exact integral of C against piecewise-linear delta.

Then, for the default and the stable schemes: the error against the exact response
(cracklab.analysis.exact.modal_exact) for T <= 10 at gamma = 0.2, 0.1, 0.05, 0.025; the
precision factors of the 10th and 50th periods (method "fit"); the mode I long-time
amplitude and period and the mode III error against J0 at gamma = 0.05; timings.

Prints Markdown tables and writes docs/figures/stability_map.png (growth against gamma,
every scheme, one panel per mode), docs/figures/stability_rates.png (the main schemes)
and docs/figures/stability_accuracy.png.  Figures need matplotlib (in the project
venv).  About 6 minutes on 2 cores:

    .venv/bin/python studies/stability_map.py            # all, with figures
    python3 studies/stability_map.py --no-figures        # numbers only
    python3 studies/stability_map.py --quick             # fewer gammas, T_end = 1000
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

from cracklab import kernels  # noqa: E402

from cracklab.analysis import exact
from cracklab.errors import InputError  # noqa: E402
from cracklab.analysis.modal import (  # noqa: E402
    SCHEMES,
    eta_hat,
    long_time_period,
    modal_response,
    precision_factor,
    product_weights,
)

NU = 0.25
MODES = ("I", "II", "III")
GAMMAS = (0.05,) + tuple(round(0.1 * k, 2) for k in range(1, 27))
T_END = 2000.0
GROWTH_TOL = 1e-5
FIG_DIR = ROOT / "docs" / "figures"


# ----------------------------------------------------------------------------- schemes
def _abbrev(f, c, i, passes=None):
    name = f"{'D' if f == 'displacement' else 'V'}/{c}/{i}"
    return name if passes in (None, 1) else f"{name}x{passes}"


#: (name, modal_response keywords or the name of a study-only recurrence)
SCHEME_TABLE = [(_abbrev(f, c, i), dict(formulation=f, convolution=c, integration=i)) for f, c, i in SCHEMES]
SCHEME_TABLE += [
    ("D/trapezoid/predictor-corrector",
     dict(formulation="displacement", convolution="trapezoid", integration="predictor-corrector")),
    ("V/disc(cumtrapz Z)/semi-implicit", "cumtrapz"),
    ("V/held-v/explicit", "held"),
    ("V/product/AB2", "ab2"),
]
for conv in ("product", "product-cubic"):
    for integ, passes in (("explicit", 1), ("semi-implicit", 1), ("predictor-corrector", 1),
                          ("predictor-corrector", 2)):
        kw = dict(formulation="velocity", convolution=conv, integration=integ)
        if passes != 1:
            kw["corrector_passes"] = passes
        SCHEME_TABLE.append((_abbrev("velocity", conv, integ, passes), kw))

DEFAULT = "D/trapezoid/explicit"
RECOMMENDED = "V/product-cubic/predictor-corrector"
#: usable on the full grid (explicit, exact cancellation, or a fixed number of passes)
NOT_USABLE = {"V/product/semi-implicit", "V/product-cubic/semi-implicit"}
MAIN = [DEFAULT, "V/discretized/semi-implicit", "D/trapezoid/predictor-corrector", "V/product/AB2",
        "V/product/predictor-corrector", "V/product/predictor-correctorx2", RECOMMENDED,
        "V/product-cubic/predictor-correctorx2"]


def _explicit_Q(mode, gamma, N, Q):
    """r_n = 1 - (gamma/eta) sum_{m=1}^{n} Q_m r_{n-m} (Q_0 unused)."""
    e = gamma / eta_hat(mode, NU)
    r = np.full(N + 1, np.nan)
    r[0] = 1.0
    wr = np.ascontiguousarray(Q[1:N + 1][::-1])
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, N + 1):
            r[n] = 1.0 - e * float(np.dot(wr[N - n:], r[:n]))
            if not math.isfinite(r[n]):
                r[n:] = np.nan
                break
    return r


def _cumtrapz_Z(mode, gamma, N):
    """V + discretized + semi-implicit with Z(j gamma) = Z(0) - cumtrapz(C): in the cancelled
    form r_n = 1 - (gamma/eta) sum_{j=1}^n w_j I_h(j gamma) r_{n-j}, w_n = 1/2, else 1."""
    C = np.asarray(kernels.C(mode, gamma * np.arange(N + 1), NU), dtype=float)
    I_h = np.concatenate([[0.0], gamma * np.cumsum(0.5 * (C[1:] + C[:-1]))])
    e = gamma / eta_hat(mode, NU)
    r = np.full(N + 1, np.nan)
    r[0] = 1.0
    wr = np.ascontiguousarray(I_h[1:][::-1])
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, N + 1):
            h = float(np.dot(wr[N - n:], r[:n])) - 0.5 * I_h[n] * r[0]
            r[n] = 1.0 - e * h
            if not math.isfinite(r[n]):
                r[n:] = np.nan
                break
    return r


def _held(mode, gamma, N):
    """Velocity held over each step; weights on r_{n-m}: Q_m = Z(0) - (mean of Z over
    [(m-1) gamma, m gamma]) = mean of I = int_0^T C over that cell."""
    T = gamma * np.arange(N + 1)
    zi = np.asarray(kernels.Z_integral(mode, T, NU), dtype=float)
    Q = np.zeros(N + 1)
    Q[1:] = kernels.static_integral(mode, NU) - np.diff(zi) / gamma
    return _explicit_Q(mode, gamma, N, Q)


def _ab2(mode, gamma, N):
    """Piecewise-linear velocity, exact Z, current velocity extrapolated (one pass)."""
    e = gamma / eta_hat(mode, NU)
    z0 = kernels.static_integral(mode, NU)
    j = np.arange(N + 1)
    W = np.asarray(product_weights(mode, gamma, j, nu=NU, order=1, part="lag"), dtype=float)
    E0 = np.asarray(product_weights(mode, gamma, j, nu=NU, order=1, part="start0"), dtype=float)
    wr = np.ascontiguousarray(W[::-1])
    r = np.full(N + 1, np.nan)
    r[0] = 1.0
    total = 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, N + 1):
            S = float(np.dot(wr[N - n:N], r[:n])) + E0[n] * r[0]
            x = r[n - 1] if n == 1 else 2.0 * r[n - 1] - r[n - 2]  # extrapolated v_n
            d = total - 0.5 * r[0] + 0.5 * x  # trapezoid with the extrapolated v_n
            r[n] = 1.0 - e * z0 * d + e * (S + W[0] * x)
            total += r[n]
            if not math.isfinite(r[n]):
                r[n:] = np.nan
                break
    return r


_CUSTOM = {"cumtrapz": _cumtrapz_Z, "held": _held, "ab2": _ab2}


def response(spec, mode, gamma, T_end):
    """(T, r) of a scheme of SCHEME_TABLE."""
    if isinstance(spec, str):
        N = int(math.ceil(T_end / gamma - 1e-9))
        r = _CUSTOM[spec](mode, gamma, N)
        return gamma * np.arange(N + 1), r
    out = modal_response(mode, gamma=gamma, T_end=T_end, nu=NU, **spec)
    return out["T"].values, out.values


# ----------------------------------------------------------------------------- growth
def growth_rate(T, r, mode, t0=None):
    """Slope of ln(max |r| per period) over [t0, T_end] (default t0 = T_end / 2); mode III
    uses |r| sqrt(T).  inf if r overflowed."""
    y = np.abs(np.asarray(r, dtype=float))
    if not np.all(np.isfinite(y)):
        return math.inf
    T = np.asarray(T, dtype=float)
    if t0 is None:
        t0 = 0.5 * T[-1]
    if mode == "III":
        y = y * np.sqrt(T)
    P = long_time_period(mode, NU)
    tm, ym = [], []
    for a in np.arange(t0, T[-1] - P + 1e-9, P):
        sel = (T >= a) & (T < a + P)
        if not np.any(sel):
            continue
        k = np.argmax(y[sel])
        tm.append(T[sel][k])
        ym.append(y[sel][k])
    ym = np.asarray(ym)
    if len(tm) < 3 or np.any(ym <= 0):
        return math.nan
    return float(np.polyfit(tm, np.log(ym), 1)[0])


def _map_task(args):
    name, spec, mode, gamma, T_end = args
    try:
        T, r = response(spec, mode, gamma, T_end)
    except InputError:  # singular step equation (1 - B = 0): no value
        return name, mode, gamma, math.nan
    return name, mode, gamma, growth_rate(T, r, mode)


def stability_map(gammas=GAMMAS, T_end=T_END, jobs=2):
    tasks = [(name, spec, mode, g, T_end) for name, spec in SCHEME_TABLE for mode in MODES for g in gammas]
    # big runs first, so that the pool stays busy
    tasks.sort(key=lambda t: -t[4] / t[3])
    out = {name: {m: {} for m in MODES} for name, _ in SCHEME_TABLE}
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            results = list(pool.map(_map_task, tasks, chunksize=4))
    else:
        results = [_map_task(t) for t in tasks]
    for name, mode, g, rate in results:
        out[name][mode][g] = rate
    return out


def stable_limit(rates, gammas, tol=GROWTH_TOL):
    """Largest gamma of the grid such that growth <= tol at every grid gamma up to it (0 if none)."""
    lim = 0.0
    for g in gammas:
        v = rates[g]
        if not (v <= tol):
            break
        lim = g
    return lim


# ----------------------------------------------------------------------------- accuracy
ACC_GAMMAS = (0.2, 0.1, 0.05, 0.025)
T_GRID = 0.2 * np.arange(1, 51)
ACC_SCHEMES = [DEFAULT, "V/discretized/semi-implicit", "V/product/predictor-corrector", RECOMMENDED]
PF_GAMMAS = (0.05, 0.1, 0.2, 0.3, 0.5, 0.8, 1.0, 1.5, 2.0, 2.2)


def _spec(name):
    return dict(SCHEME_TABLE)[name]


def accuracy():
    import scipy.special as sp

    ref = {m: (sp.j0(T_GRID) if m == "III" else np.asarray(exact.modal_exact(m, T_GRID, NU), dtype=float))
           for m in MODES}
    errs = {}
    for name in ACC_SCHEMES:
        for m in MODES:
            e = []
            for g in ACC_GAMMAS:
                T, r = response(_spec(name), m, g, 10.0)
                s = round(0.2 / g)
                e.append(float(np.max(np.abs(r[s::s][:T_GRID.size] - ref[m]))))
            errs[(name, m)] = e
    return errs


def _pf_task(args):
    import xarray as xr

    name, m, g = args
    T, r = response(_spec(name), m, g, 50 * long_time_period(m, NU) + 1.0)
    da = xr.DataArray(r, dims=("T",), coords={"T": T}, attrs={"mode": m, "nu": NU})
    return name, m, g, tuple(precision_factor(da, period=p, method="fit") for p in (10, 50))


def precision(jobs=2):
    tasks = [(n, m, g) for n in ACC_SCHEMES for m in MODES for g in PF_GAMMAS]
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            res = list(pool.map(_pf_task, tasks))
    else:
        res = [_pf_task(t) for t in tasks]
    return {(n, m, g): v for n, m, g, v in res}


def long_time_checks():
    """Mode I amplitude and period over 150 <= T <= 200 and mode III max |r - J0| (T <= 30),
    gamma = 0.05 (the checks of tests/analysis/test_modal.py)."""
    import scipy.special as sp

    s_R = exact.rayleigh_speed_ratio(NU)
    out = {}
    for name in ACC_SCHEMES:
        T, y = response(_spec(name), "I", 0.05, 200.0)
        m = (T >= 150.0) & (T <= 200.0)
        M = np.column_stack([np.cos(s_R * T[m]), np.sin(s_R * T[m])])
        (c, s), *_ = np.linalg.lstsq(M, y[m], rcond=None)
        Tw, yw = T[m], y[m]
        k = np.nonzero(np.sign(yw[:-1]) * np.sign(yw[1:]) < 0)[0]
        tz = Tw[k] - yw[k] * (Tw[k + 1] - Tw[k]) / (yw[k + 1] - yw[k])
        period = 2.0 * np.polyfit(np.arange(tz.size), tz, 1)[0]
        T3, y3 = response(_spec(name), "III", 0.05, 30.0)
        out[name] = dict(amplitude=math.hypot(c, s), period=period,
                         j0_error=float(np.max(np.abs(y3 - sp.j0(T3)))))
    return out


def timings():
    """Seconds per modal run (mode II, gamma = 0.1, T_end = 2000: 20000 steps)."""
    out = {}
    for name in (DEFAULT, "V/product/predictor-corrector", RECOMMENDED):
        t = time.perf_counter()
        response(_spec(name), "II", 0.1, 2000.0)
        out[name] = time.perf_counter() - t
    return out


# ----------------------------------------------------------------------------- output
def _fmt(v):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "sing."
    if math.isinf(v):
        return "inf"
    return f"{v:.1e}"


def print_map(rates, gammas, show=(0.1, 0.3, 0.5, 1.0, 1.5, 2.0, 2.2, 2.3, 2.5)):
    show = [g for g in show if g in gammas]
    print(f"\n### Growth per unit T (T_end = {T_END:g}; mode III relative to J0)\n")
    print("| scheme | mode | " + " | ".join(f"{g:g}" for g in show) + " | stable up to |")
    print("|---|---|" + "---|" * (len(show) + 1))
    for name, _ in SCHEME_TABLE:
        for m in MODES:
            row = rates[name][m]
            lim = stable_limit(row, gammas)
            mark = " (not usable)" if name in NOT_USABLE and m == "I" else ""
            print(f"| {name if m == 'I' else ''}{mark} | {m} | " + " | ".join(_fmt(row[g]) for g in show)
                  + f" | {lim:g} |")


def print_accuracy(errs, pf, lt, tm):
    print("\n### Max error against the exact r(T), T <= 10\n")
    print("| scheme | mode | " + " | ".join(f"gamma {g:g}" for g in ACC_GAMMAS) + " | order |")
    print("|---|---|" + "---|" * (len(ACC_GAMMAS) + 1))
    for name in ACC_SCHEMES:
        for m in MODES:
            e = errs[(name, m)]
            order = math.log2(e[-2] / e[-1])
            print(f"| {name if m == 'I' else ''} | {m} | " + " | ".join(f"{x:.2e}" for x in e) + f" | {order:.2f} |")
    print("\n### Precision factors, 10th / 50th period (method 'fit')\n")
    print("| scheme | mode | " + " | ".join(f"{g:g}" for g in PF_GAMMAS) + " |")
    print("|---|---|" + "---|" * len(PF_GAMMAS))
    for name in ACC_SCHEMES:
        for m in MODES:
            cells = []
            for g in PF_GAMMAS:
                a, b = pf[(name, m, g)]
                cells.append("blow-up" if not (math.isfinite(a) and math.isfinite(b)) or max(a, b) > 1e3
                             else f"{a:.3f} / {b:.3f}")
            print(f"| {name if m == 'I' else ''} | {m} | " + " | ".join(cells) + " |")
    print("\n### Long-time form at gamma = 0.05 (mode I: 0.5844, period 6.83399; mode III: J0)\n")
    print("| scheme | mode I amplitude | mode I period | mode III max abs(r - J0), T <= 30 |")
    print("|---|---|---|---|")
    for name, v in lt.items():
        print(f"| {name} | {v['amplitude']:.4f} | {v['period']:.5f} | {v['j0_error']:.2e} |")
    print("\n### Modal run time (mode II, gamma = 0.1, 20000 steps)\n")
    for name, t in tm.items():
        print(f"- {name}: {t:.2f} s")


def figures(rates, gammas, errs, pf):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("\n(matplotlib not available: figures not written; use the project venv)")
        return
    FIG_DIR.mkdir(parents=True, exist_ok=True)
    names = [n for n, _ in SCHEME_TABLE]
    g = np.asarray(gammas)

    # 1. the map: every scheme, colour = signed log growth
    fig, axes = plt.subplots(1, 3, figsize=(17, 9), sharey=True)
    for ax, m in zip(axes, MODES):
        Zm = np.array([[rates[n][m][x] for x in gammas] for n in names], dtype=float)
        Zm = np.where(np.isinf(Zm), 10.0, Zm)
        s = np.sign(Zm) * np.clip(np.log10(np.maximum(np.abs(Zm), 1e-9) / GROWTH_TOL) + 1.0, 0.0, 5.0)
        s = np.where(np.abs(Zm) <= GROWTH_TOL, 0.0, s)
        im = ax.imshow(s, aspect="auto", cmap="RdBu_r", vmin=-5, vmax=5, interpolation="nearest",
                       extent=(-0.5, len(gammas) - 0.5, len(names) - 0.5, -0.5))
        ax.set_xticks(range(len(gammas))[::2])
        ax.set_xticklabels([f"{x:g}" for x in gammas][::2], rotation=90)
        ax.set_xlabel("gamma = q c_s dt")
        ax.set_title(f"mode {m}")
        ax.axvline(gammas.index(2.2) + 0.5 if 2.2 in gammas else len(gammas) - 0.5, color="k", lw=0.8, ls=":")
    axes[0].set_yticks(range(len(names)))
    axes[0].set_yticklabels([n + (" *" if n == RECOMMENDED else "") for n in names], fontsize=8)
    cb = fig.colorbar(im, ax=axes, shrink=0.6)
    cb.set_ticks([-5, -3, -1, 0, 1, 3, 5])
    cb.set_ticklabels(["-1e-2", "-1e-4", "-1e-5", "|.|<1e-5", "1e-5", "1e-3", ">=0.1"])
    cb.set_label("envelope growth per unit T (red grows, blue decays; inf = overflow)")
    fig.suptitle("Single-mode stability map, T_end = 2000 (mode III relative to J0); * recommended")
    fig.savefig(FIG_DIR / "stability_map.png", dpi=110, bbox_inches="tight")
    plt.close(fig)

    # 2. growth rate against gamma, main schemes
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), sharey=True)
    for ax, m in zip(axes, MODES):
        for n in MAIN:
            y = np.array([rates[n][m][x] for x in gammas], dtype=float)
            y = np.where(np.isinf(y), 1.0, y)
            ax.plot(g, y, "o-" if n == RECOMMENDED else ".-", ms=3, lw=2.2 if n == RECOMMENDED else 1.0, label=n)
        ax.set_yscale("symlog", linthresh=1e-6)
        ax.axhline(GROWTH_TOL, color="k", lw=0.6, ls="--")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("gamma")
        ax.set_title(f"mode {m}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("envelope growth per unit T (overflow plotted at 1)")
    axes[-1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(FIG_DIR / "stability_rates.png", dpi=110)
    plt.close(fig)

    # 3. accuracy: error for T <= 10 and precision factors
    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    colors = {n: f"C{k}" for k, n in enumerate(ACC_SCHEMES)}
    for ax, m in zip(axes[0], MODES):
        for n in ACC_SCHEMES:
            ax.loglog(ACC_GAMMAS, errs[(n, m)], "o-", color=colors[n], label=n)
        ax.set_title(f"mode {m}: max abs error, T <= 10")
        ax.set_xlabel("gamma")
        ax.set_xticks(ACC_GAMMAS)
        ax.set_xticklabels([f"{x:g}" for x in ACC_GAMMAS])
        ax.minorticks_off()
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=7)
    for ax, m in zip(axes[1], MODES):
        for n in ACC_SCHEMES:
            for p, ls in ((0, "-"), (1, "--")):
                y = [pf[(n, m, x)][p] for x in PF_GAMMAS]
                ax.plot(PF_GAMMAS, y, ls, marker=".", color=colors[n],
                        label=f"{n}, {'10th' if p == 0 else '50th'} period")
        ax.set_ylim(0, 1.3)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_title(f"mode {m}: precision factor (fit)")
        ax.set_xlabel("gamma")
        ax.grid(alpha=0.3)
    axes[1][0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(FIG_DIR / "stability_accuracy.png", dpi=110)
    plt.close(fig)
    print(f"\nwrote {FIG_DIR / 'stability_map.png'}, stability_rates.png, stability_accuracy.png")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="gammas 0.1, 0.5, 1, 1.5, 2, 2.2, 2.5; T_end = 1000")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--no-figures", action="store_true")
    ap.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    ap.add_argument("--from-json", type=Path, help="print and draw from a file written by --json")
    args = ap.parse_args(argv)
    if args.from_json:
        data = json.loads(args.from_json.read_text())
        gammas = tuple(data["gammas"])
        rates = {n: {m: {float(g): v for g, v in row.items()} for m, row in modes.items()}
                 for n, modes in data["growth"].items()}
        errs = {tuple(k.split("|")): v for k, v in data["errors"].items()}
        pf = {(k.split("|")[0], k.split("|")[1], float(k.split("|")[2])): tuple(v)
              for k, v in data["precision"].items()}
        print_map(rates, gammas)
        print_accuracy(errs, pf, data["long_time"], data["timings"])
        if not args.no_figures:
            figures(rates, gammas, errs, pf)
        return
    global T_END
    gammas = GAMMAS
    if args.quick:
        gammas, T_END = (0.1, 0.5, 1.0, 1.5, 2.0, 2.2, 2.5), 1000.0
    t0 = time.perf_counter()
    rates = stability_map(gammas, T_END, args.jobs)
    t1 = time.perf_counter()
    print_map(rates, gammas)
    print(f"\n(map: {len(SCHEME_TABLE)} schemes x 3 modes x {len(gammas)} gammas in {t1 - t0:.0f} s)")
    errs = accuracy()
    pf = precision(args.jobs)
    lt = long_time_checks()
    tm = timings()
    print_accuracy(errs, pf, lt, tm)
    if not args.no_figures:
        figures(rates, gammas, errs, pf)
    if args.json:
        args.json.write_text(json.dumps({
            "T_end": T_END, "gammas": list(gammas), "growth": rates,
            "errors": {f"{n}|{m}": e for (n, m), e in errs.items()},
            "precision": {f"{n}|{m}|{g}": v for (n, m, g), v in pf.items()},
            "long_time": lt, "timings": tm}, indent=1, default=float))
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
