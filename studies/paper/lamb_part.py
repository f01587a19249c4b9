"""Lamb's problem, Figs. 8 and 9 of the paper (section 3.2).

512 x 512 unit square, beta = 0.5, P = 1 at the centre node, displacement formulation
(the paper's scheme) with the exponential history engine. Recorded: the opening field
after 100, 200 and 400 steps, and the opening history at stations 16, 32, 64 (along
x1, along x3 and on the diagonal) and 128 cells from the load. The history 64 cells
away is compared with Pekeris (1955) as corrected in ERRATA.md section 2:
delta_2 = 2 P G(tau) / (pi mu r), tau = c_s t / r, static value 3 P / (4 pi mu r).
"""
from __future__ import annotations

import math

import numpy as np

from .common import OUT, Timer, simulate_or_reuse, fmt, machine, plt, read_summary, save, table, write_page, write_summary

N = 512
BETA = 0.5
STEPS = 512            # t = 0.5: the first P wave from a periodic image reaches the 64-cell station at t = 0.505
FIELD_STEPS = (100, 200, 400)
FIG8_STEP = 200
STORE = OUT / "lamb.zarr"
#: station name -> offset from the load in cells (d1, d3)
STATIONS = {"r16": (16, 0), "r32": (32, 0), "r64": (64, 0), "r64_x3": (0, 64), "r64_diag": (45, 45),
            "r128": (128, 0)}
MAIN = "r64"
#: half-widths, in cells of distance travelled, of the windows left out around P, S and R
WINDOW_CELLS = {"P": 1.5, "S": 1.5, "R": 3.0}


# ----------------------------------------------------------------------------- helpers
def arrival_times(r, material):
    """Arrival times of the P, S and Rayleigh waves at distance r: r/c_d, r/c_s, r/c_R."""
    r = float(r)
    if not r > 0:
        raise ValueError(f"r must be > 0, got {r!r}")
    return {"P": r / material.cd, "S": r / material.cs, "R": r / material.cR}


def image_arrival(station, load, L, cd):
    """Earliest time at which the P wave of a periodic image of the load (the load
    shifted by (i L1, k L3), (i, k) != (0, 0)) reaches ``station``. Before it the
    periodic problem and the single load in the infinite plane coincide."""
    L1, L3 = (L, L) if np.ndim(L) == 0 else L
    d1, d3 = station[0] - load[0], station[1] - load[1]
    best = math.inf
    for i in (-1, 0, 1):
        for k in (-1, 0, 1):
            if i == 0 and k == 0:
                continue
            best = min(best, math.hypot(d1 - i * L1, d3 - k * L3))
    return best / cd


def window_mask(tau, arrivals, widths):
    """True where tau is farther than widths[w] from every arrival arrivals[w] (both dicts
    of reduced times, same keys)."""
    tau = np.asarray(tau, dtype=float)
    keep = np.ones(tau.shape, dtype=bool)
    for key, ta in arrivals.items():
        keep &= np.abs(tau - ta) > widths[key]
    return keep


def compare_history(tau, num, exact, static, arrivals, widths, tau_end):
    """Errors of a numerical opening history against the exact one, relative to the static
    opening, by interval between the arrivals (all reduced times tau = c_s t / r).

    Returns a dict: pre_P (max |num| before P - w: the spurious precursor; exact is 0),
    P_S, S_R, after_R (max |num - exact| between the windows), late_mean and late_max
    (mean and max |num/static - 1| over tau in [2, tau_end]), rms (over all samples
    outside the windows and before tau_end), min_value and tau_min (the numerical
    minimum near R, relative to static), tau_R_num (first upward zero crossing after
    that minimum: the measured Rayleigh arrival), overshoot (max num/static - 1 after
    tau_R: the peak of the Gibbs ringing that follows the Rayleigh jump).
    """
    tau, num, exact = (np.asarray(a, dtype=float) for a in (tau, num, exact))
    tP, tS, tR = arrivals["P"], arrivals["S"], arrivals["R"]
    wP, wS, wR = widths["P"], widths["S"], widths["R"]
    err = np.abs(num - exact) / static
    valid = tau <= tau_end

    def mx(sel):
        sel = sel & valid
        return float(err[sel].max()) if np.any(sel) else math.nan

    out = {
        "pre_P": float(np.abs(num[(tau < tP - wP)]).max() / static) if np.any(tau < tP - wP) else math.nan,
        "P_S": mx((tau > tP + wP) & (tau < tS - wS)),
        "S_R": mx((tau > tS + wS) & (tau < tR - wR)),
        "after_R": mx(tau > tR + wR),
    }
    late = valid & (tau >= 2.0)
    rel = num[late] / static - 1.0
    out["late_mean"] = float(rel.mean()) if rel.size else math.nan
    out["late_max"] = float(np.abs(rel).max()) if rel.size else math.nan
    keep = valid & window_mask(tau, arrivals, widths)
    out["rms"] = float(np.sqrt(np.mean(err[keep] ** 2))) if np.any(keep) else math.nan
    near = valid & (tau > tS) & (tau < tR + 2 * wR)
    if not np.any(near):
        out.update(min_value=math.nan, tau_min=math.nan, tau_R_num=math.nan, overshoot=math.nan)
        return out
    i = np.nonzero(near)[0][np.argmin(num[near])]
    out["min_value"] = float(num[i] / static)
    out["tau_min"] = float(tau[i])
    up = np.nonzero((num[i:-1] < 0) & (num[i + 1:] >= 0))[0]
    if up.size:
        j = i + up[0]
        # linear interpolation of the crossing
        out["tau_R_num"] = float(tau[j] + (tau[j + 1] - tau[j]) * (-num[j]) / (num[j + 1] - num[j]))
    else:
        out["tau_R_num"] = math.nan
    after = valid & (tau > tR)
    out["overshoot"] = float(num[after].max() / static - 1.0) if np.any(after) else math.nan
    return out


# ----------------------------------------------------------------------------- run
def scene(n=N, steps=STEPS, beta=BETA):
    from cracklab import Numerics, Record
    from cracklab.scenes import lamb

    dx = 1.0 / n
    dt = beta * dx
    c = n // 2
    stations = {k: ((c + d1) * dx, (c + d3) * dx) for k, (d1, d3) in STATIONS.items()}
    record = Record(fields=("delta_2",), times=tuple(s * dt for s in FIELD_STEPS if s <= steps),
                    stations=stations)
    return lamb(n=n, beta=beta, t_end=steps * dt * (1 - 1e-9), record=record,
                numerics=Numerics(engine="exponential"))


def analyse(ds, sc):
    """Per-station comparison with Pekeris; returns (summary dict, exact series array)."""
    from cracklab import stations as station_series
    from cracklab.analysis.exact import lamb_opening

    mat, grid = sc.material, sc.grid
    load = (grid.x1[grid.n1 // 2], grid.x3[grid.n3 // 2])
    st = station_series(ds).load()
    t = st.t.values
    res, exact_all = {}, []
    for name in st.station.values:
        s = st.sel(station=name)
        x1, x3 = float(s.x1), float(s.x3)
        r = math.hypot(x1 - load[0], x3 - load[1])
        cells = r / grid.dx1
        exact = lamb_opening(r, t, P=1.0, mu=mat.mu, cs=mat.cs)
        exact_all.append(exact)
        arr = {k: v * mat.cs / r for k, v in arrival_times(r, mat).items()}
        widths = {k: w / cells for k, w in WINDOW_CELLS.items()}
        t_img = image_arrival((x1, x3), load, grid.L1, mat.cd)
        static = 3.0 / (4.0 * math.pi * mat.mu * r)
        tau = t * mat.cs / r
        res[str(name)] = dict(r=r, cells=cells, static=static, tau_image=t_img * mat.cs / r,
                              arrivals=arr, widths=widths,
                              errors=compare_history(tau, s.delta_2.values, exact, static, arr, widths,
                                                     tau_end=min(tau[-1], t_img * mat.cs / r)))
    return res, np.array(exact_all)


def field_profile_error(field, sc, t):
    """Max |num - exact| / static(r) of the opening along +x1 from the load at time t, over
    8 <= r/dx <= 190 and outside the windows (WINDOW_CELLS) around the P, S and R fronts."""
    from cracklab.analysis.exact import lamb_opening

    grid, mat = sc.grid, sc.material
    c = grid.n1 // 2
    cells = np.arange(8, 191)
    r = cells * grid.dx1
    num = field[c + cells, c]
    ex = lamb_opening(r, t, mu=mat.mu, cs=mat.cs)
    static = 3.0 / (4.0 * math.pi * mat.mu * r)
    keep = np.ones(r.shape, dtype=bool)
    for key, speed in (("P", mat.cd), ("S", mat.cs), ("R", mat.cR)):
        keep &= np.abs(cells - speed * t / grid.dx1) > WINDOW_CELLS[key]
    return float(np.max(np.abs(num - ex)[keep] / static[keep])), cells, num, ex


def run(n=N, steps=STEPS, store=STORE, write_docs=True, reuse=False):
    """Simulate (or, with ``reuse``, read the existing store), analyse, draw, write the page."""
    import xarray as xr

    timer = Timer()
    sc = scene(n=n, steps=steps)
    ds = simulate_or_reuse(sc, store, timer, reuse, "lamb")
    with timer("analysis"):
        res, exact = analyse(ds, sc)
        names = list(ds.station.values)
        extra = xr.Dataset({"pekeris_delta_2": (("station", "t_station"), exact,
                                                {"long_name": "Pekeris opening 2 P G(tau) / (pi mu r), ERRATA 2",
                                                 "units": "1"})})
        extra.to_zarr(str(store), mode="a", consolidated=False)
        ds = xr.open_zarr(str(store), consolidated=False)
        snap = ds.delta_2.sel(t=FIG8_STEP * sc.dt, method="nearest")
        prof_err, cells, prof_num, prof_ex = field_profile_error(snap.values, sc, float(snap.t))
    with timer("figures"):
        figs = figures(ds, sc, res)
    summary = dict(n=n, beta=BETA, steps=sc.nsteps, dt=sc.dt, engine="exponential",
                   formulation=sc.formulation, stations=res, station_order=[str(s) for s in names],
                   profile_step=FIG8_STEP, profile_error=prof_err, seconds=timer.seconds,
                   machine=machine(), figures=figs, store=str(store.relative_to(OUT.parents[1])),
                   field_max=float(np.nanmax(snap.values)), field_min=float(np.nanmin(snap.values)))
    if write_docs:
        write_summary("lamb", summary)
        docs()  # from the JSON summary, as --docs-only does
    return summary


# ----------------------------------------------------------------------------- figures
def figures(ds, sc, res):
    from cracklab import stations as station_series
    from cracklab.analysis.exact import lamb_opening

    P = plt()
    grid = sc.grid
    c = grid.n1 // 2
    out = {}
    snap = ds.delta_2.sel(t=FIG8_STEP * sc.dt, method="nearest").values
    # Fig. 8: 3D view of the opening after 200 steps, centre quarter, every other node
    h = 192
    sub = snap[c - h:c + h + 1:3, c - h:c + h + 1:3]
    x = (np.arange(-h, h + 1, 3)) * grid.dx1
    X1, X3 = np.meshgrid(x, x, indexing="ij")
    static64 = 3.0 / (4.0 * math.pi * 64 * grid.dx1)
    zmax = 4.0 * static64
    fig = P.figure(figsize=(11, 5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.plot_surface(X1, X3, np.clip(sub, -0.5 * zmax, zmax), cmap="viridis", rstride=1, cstride=1, linewidth=0,
                    antialiased=False)
    ax.set_xlabel("x1 - X/2")
    ax.set_ylabel("x3 - X/2")
    ax.set_zlabel("opening (P/(mu X) units)")
    ax.set_title(f"opening after {FIG8_STEP} steps (clipped at {zmax:.2f})", fontsize=9)
    ax.view_init(elev=30, azim=-60)
    ax2 = fig.add_subplot(1, 2, 2)
    xx = (np.arange(-h, h + 1)) * grid.dx1
    R = np.hypot(xx[:, None], xx[None, :])
    R[h, h] = grid.dx1
    scaled = snap[c - h:c + h + 1, c - h:c + h + 1] * 4.0 * math.pi * sc.material.mu * R / 3.0
    from matplotlib.colors import TwoSlopeNorm

    im = ax2.imshow(scaled.T, origin="lower", extent=[xx[0], xx[-1], xx[0], xx[-1]], cmap="RdBu_r",
                    norm=TwoSlopeNorm(vcenter=0.0, vmin=-0.25, vmax=1.25))
    t = FIG8_STEP * sc.dt
    for k, col in zip((1 / math.sqrt(3), 1.0, 1 / sc.material.cR), ("C0", "C2", "C3")):
        ax2.add_patch(P.Circle((0, 0), t / k, fill=False, ls="--", lw=0.8, color=col))
    ax2.set_title("opening x 4 pi mu r / (3P), i.e. over its static value\n(P, S, R fronts dashed)", fontsize=9)
    ax2.set_xlabel("x1 - X/2")
    ax2.set_ylabel("x3 - X/2")
    fig.colorbar(im, ax=ax2, shrink=0.8)
    fig.tight_layout()
    out["fig8"] = save(fig, "paper_lamb_fig8")

    # profile along x1 at step 200 against Pekeris
    err, cells, num, ex = field_profile_error(snap, sc, t)
    fig, ax = P.subplots(figsize=(7, 3.8))
    stat = 3.0 / (4.0 * math.pi * cells * grid.dx1)
    rr = np.linspace(cells[0], cells[-1], 2000)
    ax.plot(rr, lamb_opening(rr * grid.dx1, t) / (3.0 / (4.0 * math.pi * rr * grid.dx1)), "k-", lw=1,
            label="Pekeris")
    ax.plot(cells, num / stat, "C1.", ms=3, label="numerical, along x1")
    diag = np.arange(6, 86)
    rd = diag * math.sqrt(2) * grid.dx1
    ax.plot(diag * math.sqrt(2), snap[c + diag, c + diag] / (3.0 / (4.0 * math.pi * rd)), "C0x", ms=3,
            label="numerical, diagonal")
    for k, lab in zip((1 / math.sqrt(3), 1.0, 1 / sc.material.cR), "PSR"):
        ax.axvline(t / k / grid.dx1, color="0.6", lw=0.8, ls=":")
        ax.text(t / k / grid.dx1, 1.6, lab, ha="center")
    ax.set_ylim(-1.5, 1.8)
    ax.set_xlabel("distance from the load r / dx")
    ax.set_ylabel("opening / static value 3P/(4 pi mu r)")
    ax.set_title(f"opening against distance after {FIG8_STEP} steps (t = {t:.4f})", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out["profile"] = save(fig, "paper_lamb_profile")

    # Fig. 9: history 64 cells from the load, with insert
    st = station_series(ds).load()
    s = st.sel(station=MAIN)
    info = res[MAIN]
    r, static = info["r"], info["static"]
    tau = st.t.values / r
    tf = np.linspace(0, tau[-1], 8000)
    fig, ax = P.subplots(figsize=(8, 4.5))
    ax.plot(tf, lamb_opening(r, tf * r) / static, "k-", lw=1, label="Pekeris (ERRATA 2)")
    ax.plot(tau, s.delta_2.values / static, "C1-", lw=1.2, label="numerical, 512 x 512, beta = 0.5")
    for k, v in info["arrivals"].items():
        ax.axvline(v, color="0.5", lw=0.8, ls=":")
        ax.text(v, 1.45, k, ha="center")
    ax.set_ylim(-1.2, 1.6)
    ax.set_xlim(0, tau[-1])
    ax.set_xlabel("tau = c_s t / r")
    ax.set_ylabel("opening / static value 3P/(4 pi mu r)")
    ax.set_title("opening 64 cells from the load (r = X/8)", fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    ins = ax.inset_axes([0.08, 0.08, 0.38, 0.35])
    sel = tau < info["arrivals"]["S"] + 0.05
    ins.plot(tf[tf < tau[sel][-1]], lamb_opening(r, tf[tf < tau[sel][-1]] * r) / static, "k-", lw=0.8)
    ins.plot(tau[sel], s.delta_2.values[sel] / static, "C1-", lw=1)
    ins.axvline(info["arrivals"]["P"], color="0.5", lw=0.8, ls=":")
    ins.set_ylim(-0.06, 0.02)
    ins.tick_params(labelsize=7)
    ins.set_title("before and at P", fontsize=7)
    fig.tight_layout()
    out["fig9"] = save(fig, "paper_lamb_fig9")

    # all stations
    fig, ax = P.subplots(figsize=(8, 4.2))
    for name in st.station.values:
        inf_ = res[str(name)]
        tt = st.t.values / inf_["r"]
        m = tt <= inf_["tau_image"]
        ax.plot(tt[m], st.sel(station=name).delta_2.values[m] / inf_["static"], lw=1,
                label=f"{name} ({inf_['cells']:.1f} cells)")
    ax.plot(tf, lamb_opening(1.0, tf) / (3.0 / (4.0 * math.pi)), "k-", lw=1, label="Pekeris")
    ax.set_xlim(0, 4)
    ax.set_ylim(-1.2, 1.6)
    ax.set_xlabel("tau = c_s t / r")
    ax.set_ylabel("opening / static value")
    ax.set_title("all stations, up to the first periodic-image arrival", fontsize=9)
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    fig.tight_layout()
    out["stations"] = save(fig, "paper_lamb_stations")
    return out


# ----------------------------------------------------------------------------- docs
def docs(s=None):
    s = s or read_summary("lamb")
    main = s["stations"][MAIN]
    e = main["errors"]
    arr = main["arrivals"]
    rows = []
    for name in s["station_order"]:
        st = s["stations"][name]
        er = st["errors"]
        rows.append([name, f"{st['cells']:.1f}", fmt(er["pre_P"], 2), fmt(er["P_S"], 2), fmt(er["S_R"], 2),
                     fmt(er["after_R"], 2), fmt(er["late_mean"], 2), fmt(er["rms"], 2),
                     f"{er['tau_R_num']:.3f}", fmt(er["min_value"], 3), fmt(er["overshoot"], 2),
                     f"{st['tau_image']:.2f}"])
    sec = s["seconds"]
    wc = WINDOW_CELLS

    def L(name):
        name = name if isinstance(name, str) else f"r{name}"
        return float(s["stations"][name]["errors"]["late_mean"])

    text = f"""# Paper, Figs. 8 and 9: Lamb's problem

Geubelle & Rice (1995), section 3.2: a pair of opposite step point loads P on a traction-free
plane, opening compared with Pekeris (1955). Reproduced with `studies/paper/lamb_part.py`:

```sh
nice -n 10 .venv/bin/python studies/paper/run.py lamb      # run, figures, this page
.venv/bin/python studies/paper/run.py lamb --docs-only      # this page from {s['store']}
```

Setup as in the paper: `cracklab.scenes.lamb(n=512, beta=0.5)` (unit square, mu = c_s = 1,
nu = 1/4, P = 1 as tau0 = P/(dx1 dx3) at the centre node), {s['formulation']} formulation
(trapezoid pre-integrated kernel, explicit update; the paper's scheme), exponential history
engine, {s['steps']} steps of dt = {s['dt']:.6g}. Reference: ERRATA.md section 2 (the
printed formula is garbled and its static value is wrong): opening
2 P G(tau) / (pi mu r), tau = c_s t / r, static value 3 P / (4 pi mu r).

Run time: {sec['simulate']:.0f} s for the simulation, {sec['analysis']:.0f} s analysis,
{sec['figures']:.0f} s figures ({s['machine']}), with the 2 cores shared with
other jobs (load average 12 to 19 during the run). Store: `{s['store']}` (opening field after
{', '.join(str(k) for k in FIELD_STEPS)} steps, station series, and `pekeris_delta_2`, the exact
series at every station).

## Fig. 8: the opening after {s['profile_step']} steps

![Opening after 200 steps](../figures/paper_lamb_fig8.png)

As in the paper: the dilatational precursor (a shallow negative opening inside the
P front, radius {s['profile_step'] * s['dt'] * 3 ** 0.5 / (1 / 512):.0f} cells), the Rayleigh front
(the sharp ring, radius {s['profile_step'] * s['dt'] * 0.9194 / (1 / 512):.0f} cells) and the 1/r
singularity behind it. The field is clipped for display: its values run from
{s['field_min']:.3g} to {s['field_max']:.3g} (the load node). The same field against
distance, along x1 and along the diagonal, with Pekeris at the same time:

![Opening against distance after 200 steps](../figures/paper_lamb_profile.png)

Along x1, over 8 to 190 cells from the load and outside the windows around the arrivals,
the largest difference from Pekeris is {s['profile_error']:.3f} of the local static value.

## Fig. 9: the opening 64 cells from the load

![Opening history 64 cells from the load](../figures/paper_lamb_fig9.png)

Arrivals (dotted): P at tau = {arr['P']:.4f} (1/sqrt 3), S at {arr['S']:.4f}, R at {arr['R']:.4f}
(c_s/c_R). The measured Rayleigh arrival (the upward zero crossing after the minimum) is
tau = {e['tau_R_num']:.4f}, {100 * (e['tau_R_num'] / arr['R'] - 1):+.2f}% from the exact one, i.e. the smoothed jump
crosses zero {(e['tau_R_num'] - arr['R']) * main['cells']:.2f} cells of shear-wave travel after the exact arrival
((tau_R,measured - tau_R) r / dx): the smoothing spreads the jump over a cell or two.

Error table: differences from Pekeris relative to the static value 3P/(4 pi mu r) at
each station, in the intervals between the arrivals; the windows left out are
+-{wc['P']:g} cells of travel around P and S and +-{wc['R']:g} cells around R (at 64 cells:
+-{main['widths']['P']:.3f} and +-{main['widths']['R']:.3f} in tau). Only times
before the first P wave from a periodic image of the load are used (last column).

{table(["station", "r (cells)", "max abs before P", "P-S", "S-R", "after R", "late mean (tau>=2)",
            "rms", "tau_R measured", "min / static", "overshoot after R", "tau of first image"], rows)}

"max abs before P" is the spurious precursor (the exact opening is 0 there), "late mean"
the mean of opening/static - 1 over tau >= 2, "min / static" the numerical minimum near
the Rayleigh arrival (the exact opening tends to -infinity there), "overshoot after R" the
largest opening/static - 1 after tau_R (the peak of the Gibbs ringing that follows the
jump; the exact opening is flat there). All stations:

![All stations](../figures/paper_lamb_stations.png)

## What agrees with the paper and what does not

- Agrees: the history 64 cells away follows Pekeris away from the arrivals: largest
  differences of {100 * e['P_S']:.2f}% of the static value between P and S, {100 * e['S_R']:.1f}% between S and
  R (the approach to the singularity at R) and {100 * e['after_R']:.1f}% after R (the tail of the
  Gibbs ringing), rms {e['rms']:.4f} over all times outside the windows; the P arrival, the change of slope at S and the Rayleigh spike are
  where they should be; the opening settles on the static value (mean offset
  {100 * e['late_mean']:+.2f}% over tau >= 2).
- Agrees: as the paper says, the numerical solution smooths the singularity at R (its
  minimum is {e['min_value']:.2f} times the static value instead of -infinity) and rings after
  it (Gibbs, overshoot {100 * e['overshoot']:.0f}% of the static value; the deeper the smoothed
  spike, the larger the ringing: the overshoot grows with the distance in cells, see the table), and there are small oscillations before P
  ({100 * e['pre_P']:.2f}% of the static value at most), the truncated series of a point load
  whose spectrum is flat.
- Differs from the printed text: the paper's formula for the opening is garbled and its
  static value P/(4 pi mu r) is a third of the correct 3P/(4 pi mu r) (ERRATA.md
  section 2); the numerical static value agrees with the corrected one, which confirms
  the erratum. The paper plots u2 (half the opening); here the opening is normalised by
  its static value, so the curves have the paper's shape.
- The 16- and 32-cell stations are closer to the load, where the singular R spike and
  the node load's truncated spectrum weigh more: the errors between the arrivals and the
  precursor grow as the distance shrinks. At late times the opening along the axes is
  slightly low, {100 * L(16):+.2f}%, {100 * L(32):+.2f}% and {100 * L(64):+.2f}% at 16, 32 and 64 cells
  (the deficit falls as 1/r), but on the diagonal it is {100 * L('r64_diag'):+.3f}% at 64 cells: the
  node load is a truncated Fourier series, whose near field is slightly anisotropic.
  The 64-cell stations along x1 and along x3 give identical histories (the symmetry of
  the grid).
- The window around R matters: the Gibbs ringing after the Rayleigh jump lasts about 3 to
  4 cells of travel, so "after R" with a 3-cell window still holds the tail of it
  ({100 * e['after_R']:.1f}% at 64 cells); the late-time error is {100 * e['late_max']:.2f}%.
"""
    write_page("paper_lamb.md", text)
