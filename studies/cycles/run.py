"""SEAS BP1-QD and BP1-FD with cracklab (docs/studies/cycles.md): a sequence of earthquakes
on an antiplane fault in a half space, at two grid spacings, quasi-dynamic and fully dynamic.

    python -m studies.cycles.run [-o OUT] [--dz 50 25] [--fd 200 100] [--years 1500] [--report-only]

Runs ``cracklab.scenes.bp1`` at each spacing into OUT/bp1_dz<dz>.zarr, and BP1-FD
(``dynamic=True``) at each ``--fd`` spacing into OUT/bp1fd_dz<dz>.zarr (a complete store of
the same scene is reused), with the wall time in OUT/bp1[fd]_dz<dz>.json, and writes

* OUT/cycles_results.json       every number of the page,
* docs/figures/cycles_*.png     slip profiles, largest slip rate against time, stations,
* docs/studies/cycles.md        the page, written from these results.
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from studies.benchmarks import harness as H

ROOT = Path(__file__).resolve().parents[2]
YEAR = 365.0 * 24.0 * 3600.0


def store_of(out, dz, dynamic=False) -> Path:
    return Path(out) / f"bp1{'fd' if dynamic else ''}_dz{dz:g}.zarr"


def run_one(out, dz, years, tolerance, force=False, log=print, dynamic=False) -> dict:
    import xarray as xr

    from cracklab import simulate
    from cracklab.model.scene_io import scene_to_json
    from cracklab.scenes import bp1

    scene = bp1(dz=dz, years=years, tolerance=None if dynamic else tolerance, dynamic=dynamic)
    store = store_of(out, dz, dynamic)
    meta_path = store.with_suffix(".json")
    text, _ = scene_to_json(scene)
    if not force and store.exists() and meta_path.exists():
        old = xr.open_zarr(store)
        if old.attrs.get("scene") == text:
            log(f"dz = {dz:g} m: reusing {store}")
            return json.loads(meta_path.read_text())
    if force and store.exists():        # a rerun from the start, not a resume of the store
        shutil.rmtree(store)
    log(f"dz = {dz:g} m: {scene.grid.n1} nodes, {years:g} years -> {store}", flush=True)
    t0 = time.time()
    ds = simulate(scene, store=str(store), resume=True)       # a killed run goes on from its checkpoint
    wall = time.time() - t0
    meta = {"dz": dz, "years": years, "tolerance": scene.sequence.tolerance, "pair": scene.sequence.pair,
            "wall_s": wall, "nodes": scene.grid.n1,
            "resumed_from": None if ds.attrs.get("cracklab_resumed_from") is None else
            int(ds.attrs["cracklab_resumed_from"]),
            **{k: ds.attrs[k] for k in ("accepted_steps", "smallest_step", "largest_step")}}
    meta_path.write_text(json.dumps(meta, indent=1))
    log(f"dz = {dz:g} m: done in {wall:.0f} s, {meta['accepted_steps']} steps", flush=True)
    return meta


def kept_section(text, heading) -> list[str]:
    """The lines of ``text`` from ``heading`` to the next heading of its level (none if absent):
    a section written from runs of another code that OUT does not hold, kept as it was."""
    lines = text.splitlines()
    if heading not in lines:
        return []
    start = lines.index(heading)
    level = heading.split(" ")[0] + " "
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith(level)), len(lines))
    return lines[start:end]


DOMAIN_DZ, DOMAIN_YEARS, DOMAIN_DEPTHS = 200.0, 400.0, (80e3, 160e3, 320e3, 640e3)


def run_domain(out, log=print) -> dict:
    """The periodic images' effect: BP1-QD at 200 m for 400 years with the creeping region
    reaching each of ``DOMAIN_DEPTHS`` (the images 2 depth apart): {depth km: (event
    starts in years, wall s)}."""
    import xarray as xr

    from cracklab import analysis, simulate
    from cracklab.scenes import bp1

    res = {}
    for depth in DOMAIN_DEPTHS:
        path = Path(out) / f"domain_depth{depth / 1e3:g}km.json"
        if path.exists():
            res[f"{depth / 1e3:g}"] = json.loads(path.read_text())
            continue
        t0 = time.time()
        ev = analysis.events(simulate(bp1(dz=DOMAIN_DZ, years=DOMAIN_YEARS, depth=depth)))
        big = ev.peak_slip_rate.values > 0.1            # the earthquakes, not threshold blips
        row = {"t_start_yr": (ev.t_start.values[big] / YEAR).tolist(), "wall_s": time.time() - t0}
        path.write_text(json.dumps(row))
        log(f"depth {depth / 1e3:g} km: events at {row['t_start_yr']} yr")
        res[f"{depth / 1e3:g}"] = row
    del xr
    return res


def earthquakes(t_start, gap=YEAR):
    """Start times of the earthquakes: events that start within ``gap`` of the one before
    are one earthquake (a rupture that stops at depth and starts again within hours)."""
    quakes = []
    for t in t_start:
        if not quakes or t - quakes[-1][-1] > gap:
            quakes.append([t])
        else:
            quakes[-1].append(t)
    return [q[0] for q in quakes]


def analyse(out, dzs, dynamic=False) -> dict:
    import xarray as xr

    from cracklab import analysis

    res = {"runs": {}}
    for dz in dzs:
        ds = xr.open_zarr(store_of(out, dz, dynamic))
        ev = analysis.events(ds).load()
        meta = json.loads(store_of(out, dz, dynamic).with_suffix(".json").read_text())
        t = ds.t_station.values
        V = ds.max_slip_rate.values
        fast = V >= ds.attrs["event_threshold"]
        dt = np.diff(t, prepend=t[0])
        quakes = earthquakes(ev.t_start.values)
        meta.update({
            "events": {k: ev[k].values.tolist() for k in ev.data_vars},
            "earthquakes_yr": (np.array(quakes) / YEAR).tolist(),
            "recurrence_yr": (np.diff(quakes) / YEAR).tolist(),
            "time_in_events_s": float(np.sum(dt[fast])),
            "steps_in_events": int(np.sum(fast)),
            "steps_below_1e-7": int(np.sum(V < 1e-7)),      # the interseismic steps (the plate rate 1e-9 m/s)
            # the steps at the events' peak (largest slip rate above 0.1 m/s) and their median length
            "steps_above_0.1": int(np.sum(V >= 0.1)),
            "step_above_0.1_median_s": float(np.median(dt[V >= 0.1])) if np.any(V >= 0.1) else None,
            # the wall time stepping in events and between them (runs recorded since it is counted)
            "wall_in_events_s": ds.attrs.get("wall_time_in_events"),
            "wall_between_events_s": ds.attrs.get("wall_time_between_events"),
        })
        res["runs"][f"{dz:g}"] = meta
    return res


#: the pairs as the page names them
PAIR_TITLES = {"dormand_prince": "Dormand-Prince 5(4)", "bogacki_shampine": "Bogacki-Shampine 3(2)"}


def pair_of(run):
    """The embedded pair of a run's meta (its ``pair``; Dormand-Prince 5(4) in a meta written
    before the runs recorded it)."""
    from cracklab.solver.sequence.pairs import PAIRS

    return PAIRS[run.get("pair", "dormand_prince")]


def stability_polynomial(pair) -> np.ndarray:
    """The coefficients (z^0 first) of ``pair``'s stability function R(z) = 1 + z b (I - z A)^-1 1,
    a polynomial for an explicit pair: 1, then b A^(k-1) 1 for k = 1 .. stages."""
    from cracklab.solver.sequence.integrate import tableau

    A_rows, b, _ = tableau(pair)
    n = len(b)
    A = np.zeros((n, n))
    for i, row in enumerate(A_rows):
        A[i, :row.size] = row
    coef, x = [1.0], np.ones(n)
    for _ in range(n):
        coef.append(float(b @ x))
        x = A @ x
    return np.array(coef)


def real_stability(pair) -> float:
    """The reach of ``pair``'s stability region along the negative real axis: the least x > 0
    with |R(-x)| = 1, R its stability function (:func:`stability_polynomial`; to 1e-6)."""
    coef = stability_polynomial(pair)[::-1]

    def grows(x):
        return abs(np.polyval(coef, -x)) > 1

    xs = np.arange(0.01, 10.0, 0.01)
    hi = next(x for x in xs if grows(x))
    lo = hi - 0.01
    while hi - lo > 1e-6:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if grows(mid) else (mid, hi)
    return 0.5 * (lo + hi)


def _phases(r) -> str:
    """The wall time a run spent stepping in events / between them, or '-' if not counted."""
    fast, slow = r.get("wall_in_events_s"), r.get("wall_between_events_s")
    return "-" if fast is None or slow is None else f"{fast:.0f} s / {slow:.0f} s"


def analyse_ensemble(store) -> dict:
    """Per member of an ensemble of BP1 sequences (studies/cycles/ensemble.toml): its swept
    parameters, its earthquakes' start times, recurrence and largest slip rates, from the
    tidy table of ``analysis.events``."""
    import cracklab

    ens = cracklab.open_ensemble(store)
    swept = [c for c in ens.coords if ens[c].dims == ("member",) and c not in ("member", "status", "scene_name")]
    table = cracklab.analysis.events(ens).to_dataframe().dropna(subset=["t_start"]).reset_index()
    out = {"swept": swept, "members": []}
    for mid, rows in table.groupby("member", sort=False):
        quakes = earthquakes(rows["t_start"].values)
        out["members"].append({"member": str(mid), **{c: float(ens[c].sel(member=mid)) for c in swept},
                               "events": int(len(rows)), "earthquakes_yr": (np.array(quakes) / YEAR).tolist(),
                               "recurrence_yr": (np.diff(quakes) / YEAR).tolist(),
                               "peak_slip_rate": float(rows["peak_slip_rate"].max()),
                               "mean_slip": float(rows["mean_slip"].mean())})
    out["rows"] = int(len(table))
    return out


def fig_profiles(out, dz, figdir, dynamic=False):
    import xarray as xr

    plt = H.pyplot()

    ds = xr.open_zarr(store_of(out, dz, dynamic))
    shallow = ds.x1.values <= 45e3                  # the frictional fault (40 km) and a little creep
    slip, kind = ds.delta_3.isel(x3=0, x1=shallow).load(), ds.snapshot_kind.values
    z = ds.x1.values[shallow] / 1e3
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, k in enumerate(kind):
        slow = k == "slow" if isinstance(k, str) else k == 0      # snapshot_kind: 0 is the slow cadence
        ax.plot(slip.values[i], z, color="tab:blue" if slow else "tab:red", lw=0.5)
    ax.invert_yaxis()
    fast = "0.1 s" if dynamic else "second"
    ax.set(xlabel="cumulative slip (m)", ylabel="depth (km)",
           title=f"BP1-{'FD' if dynamic else 'QD'}, dz = {dz:g} m: slip every 5 years (blue) and every {fast} during "
                 "events (red)")
    ax.title.set_fontsize(9)
    return H.save(fig, Path(figdir) / f"cycles_bp1{'fd' if dynamic else ''}_profiles_dz{dz:g}.png", 110)


#: BICyclE's BP1-QD earthquakes at 7.5 km (years), read off the plot of the SEAS platform's
#: data in RSFaultZ's repository (benchmarks/BP1QD/BP1QD.png), to about 2 years
BICYCLE_YR = (198.0, 275.0, 353.0, 432.0, 510.0, 588.0, 667.0)


def fig_station(out, dz, figdir):
    """Shear stress and log10 slip rate at fltst_dp075 (and the slip rate at the surface)
    over the first 700 years: the figure the SEAS comparisons show."""
    import xarray as xr

    plt = H.pyplot()

    ds = xr.open_zarr(store_of(out, dz))
    t = ds.t_station.values / YEAR
    keep = t <= 700.0
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.6))
    ax[0].plot(t[keep], ds.station_tau_3.sel(station="fltst_dp075").values[keep] / 1e6, "k", lw=0.8)
    ax[0].set(xlabel="time (years)", ylabel="shear stress (MPa)", title="fltst_dp075 (7.5 km)")
    for name, colour in (("fltst_dp075", "k"), ("fltst_dp000", "tab:orange")):
        ax[1].plot(t[keep], np.log10(ds[f"station_v_3"].sel(station=name).values[keep]), colour, lw=0.8,
                   label=name)
    for x in BICYCLE_YR:
        ax[1].axvline(x, color="m", ls=":", lw=0.8)
    ax[1].set(xlabel="time (years)", ylabel="log10 slip rate (m/s)",
              title="dotted: BICyclE's earthquakes (read off its plot)")
    ax[1].legend(fontsize=8, loc="lower right")
    for a in ax:
        a.title.set_fontsize(9)
    return H.save(fig, Path(figdir) / f"cycles_bp1_station_dz{dz:g}.png", 110)


def fig_max_rate(out, dzs, figdir):
    import xarray as xr

    plt = H.pyplot()

    fig, ax = plt.subplots(figsize=(7, 3.5))
    for dz in dzs:
        ds = xr.open_zarr(store_of(out, dz))
        ax.semilogy(ds.t_station.values / YEAR, ds.max_slip_rate.values, lw=0.8, label=f"dz = {dz:g} m")
    ax.set(xlabel="time (years)", ylabel="largest slip rate (m/s)", title="BP1-QD: largest slip rate on the fault")
    ax.legend()
    return H.save(fig, Path(figdir) / "cycles_bp1_max_slip_rate.png", 110)


def fig_qd_fd(out, dz, figdir):
    """The largest slip rate against time, BP1-QD and BP1-FD at ``dz``: over the run, and over
    the first earthquake's first minute."""
    import xarray as xr

    plt = H.pyplot()

    fig, ax = plt.subplots(1, 2, figsize=(11, 3.6))
    for dynamic, colour, label in ((False, "tab:blue", "QD"), (True, "tab:red", "FD")):
        ds = xr.open_zarr(store_of(out, dz, dynamic))
        t, V = ds.t_station.values, ds.max_slip_rate.values
        ax[0].semilogy(t / YEAR, V, color=colour, lw=0.8, label=f"BP1-{label}")
        first = np.argmax(V > ds.attrs["event_threshold"])
        near = (t >= t[first] - 10.0) & (t <= t[first] + 60.0)
        ax[1].plot(t[near] - t[first], V[near], color=colour, lw=0.8, label=f"BP1-{label}")
    ax[0].set(xlabel="time (years)", ylabel="largest slip rate (m/s)", title=f"dz = {dz:g} m")
    ax[1].set(xlabel="time from the first event's start (s)", ylabel="largest slip rate (m/s)",
              title="the first earthquake")
    for a in ax:
        a.legend(fontsize=8)
        a.title.set_fontsize(9)
    return H.save(fig, Path(figdir) / f"cycles_bp1_qd_fd_dz{dz:g}.png", 110)


def events_table(ev) -> list:
    """The page's table of a run's events (the lists of ``analyse``), and a blank line."""
    lines = ["| event | start (yr) | duration (s) | hypocentre depth (km) | peak slip rate (m/s) | mean slip (m) | "
             "moment per length (N/m) |", "|---|---|---|---|---|---|---|"]
    for i in range(len(ev["t_start"])):
        lines.append(f"| {i} | {ev['t_start'][i] / YEAR:.3f} | {ev['duration'][i]:.1f} | "
                     f"{ev['hypocentre_x1'][i] / 1e3:.2f} | {ev['peak_slip_rate'][i]:.3f} | "
                     f"{ev['mean_slip'][i]:.3f} | {ev['moment'][i]:.4g} |")
    return lines + [""]


def _fd_section(res):
    """The page's lines on BP1-FD: cost, events, and QD against FD at the spacings run both ways."""
    fd = res["fd"]
    lines = ["## BP1-FD: the fully dynamic response", "",
             "The same fault with `dynamic=True`: the elastodynamic history of every mode kept exactly at a "
             "variable step (docs/reference/equations.md, \"Sequences: the dynamic response at a variable step\"), "
             f"tolerance {_tol(next(iter(fd.values()))['tolerance'])}: a predictor-corrector of order 2 whose step "
             "never goes below the dynamic step "
             "beta dz / c_s = 0.5 dz / c_s, and Dormand-Prince 5(4) on the same system while the largest slip rate "
             "is below `sequence.slow_rate` (0.1 of the least sigma a / eta, 1.1e-2 m/s here).", "",
             "| dz | nodes | years | wall time | accepted steps | smallest step | largest step | steps in events | "
             "time in events | wall time in events / between |", "|---|---|---|---|---|---|---|---|---|---|"]
    for dz, r in fd.items():
        wall = f"{r['wall_s']:.0f} s" + (" (resumed)" if r.get("resumed_from") is not None else "")
        lines.append(f"| {dz} m | {r['nodes']} | {r['years']:g} | {wall} | {r['accepted_steps']} | "
                     f"{r['smallest_step']:.2g} s | {r['largest_step'] / YEAR:.2g} yr | {r['steps_in_events']} | "
                     f"{r['time_in_events_s']:.0f} s | {_phases(r)} |")
    lines += ["", "Wall times on a shared 2-core host (other jobs running), not a benchmark.", ""]
    keys = sorted(fd, key=float, reverse=True)
    finest = fd[keys[-1]]
    at25 = fd.get("25")
    target = (f"The target, BP1-FD at 25 m in under 15 minutes on one core: "
              + (f"{at25['wall_s'] / 60:.1f} min here, {'met' if at25['wall_s'] <= 900 else 'not met'}. "
                 if at25 else f"25 m not run yet; the finest run, {keys[-1]} m, took "
                 f"{finest['wall_s'] / 60:.0f} min"))
    if len(keys) >= 2 and float(keys[-1]) > 25:
        growth = finest["wall_s"] / fd[keys[-2]]["wall_s"]
        target += (f", {growth:.1f} times the run at {keys[-2]} m, so 25 m would take about "
                    f"{finest['wall_s'] * growth ** np.log2(float(keys[-1]) / 25) / 60:.0f} min at that rate: not met. ")
    lines += [target + "Between events the order-5 pair takes the long steps (`sequence.slow_rate`); in them the "
              "predictor-corrector's steps are set by the dynamic step and cost one history step each, whose near "
              "part grows as the nodes over beta (docs/reference/equations.md).", ""]
    for dz, r in fd.items():
        ev = r["events"]
        lines += [f"**BP1-FD, dz = {dz} m**: {len(ev['t_start'])} events in {len(r['earthquakes_yr'])} earthquakes "
                  "starting at (years) " + ", ".join(f"{x:.2f}" for x in r["earthquakes_yr"])
                  + "; recurrence intervals (years): " + ", ".join(f"{x:.2f}" for x in r["recurrence_yr"]), ""]
        lines += events_table(ev)
    keys = sorted(fd, key=float, reverse=True)
    if len(keys) >= 2:
        lines += ["### Self-convergence of BP1-FD", ""]
        pairs = list(zip(keys[:-1], keys[1:]))      # consecutive spacings; the finest two below 25 m
        for coarse, fine in pairs[-2 if float(keys[-1]) < 25 else -1:]:
            a, b = fd[coarse], fd[fine]
            qa, qb = a["earthquakes_yr"], b["earthquakes_yr"]
            n = min(len(qa), len(qb))
            lines += [f"Between dz = {coarse} m and {fine} m: the first {n} earthquakes start "
                      + ", ".join(f"{x - y:+.2f}" for x, y in zip(qa[:n], qb[:n]))
                      + f" years apart; mean recurrence {np.mean(a['recurrence_yr']):.2f} and "
                      f"{np.mean(b['recurrence_yr']):.2f} years; largest slip rate "
                      f"{max(a['events']['peak_slip_rate']):.1f} and {max(b['events']['peak_slip_rate']):.1f} m/s.", ""]
        lines += _fd_convergence(fd, keys, res.get("fd_checks"))
    qd = res.get("qd_at_fd", {})
    both = [dz for dz in fd if dz in qd]
    if both:
        lines += ["### QD against FD", "",
                  "| dz | response | earthquakes | first (yr) | mean recurrence (yr) | largest slip rate (m/s) | "
                  "mean slip per event (m) |", "|---|---|---|---|---|---|---|"]
        for dz in both:
            for name, r in (("QD", qd[dz]), ("FD", fd[dz])):
                ev = r["events"]
                rec = f"{np.mean(r['recurrence_yr']):.2f}" if r["recurrence_yr"] else "-"
                lines.append(f"| {dz} m | {name} | {len(r['earthquakes_yr'])} | {r['earthquakes_yr'][0]:.2f} | {rec} | "
                             f"{max(ev['peak_slip_rate']):.2f} | {np.mean(ev['mean_slip']):.2f} |")
        lines.append("")
    return lines


def _fd_convergence(fd, keys, checks) -> list:
    """The page's lines on where BP1-FD's grids differ: the order from the three finest grids,
    the finest one's error by Richardson's extrapolation, and the runs at a shorter step or a
    tighter tolerance (``checks``, studies/cycles/fd_checks.py)."""
    lines = []

    def verdict(coarse, fine):
        """Whether the earthquakes of ``coarse`` and ``fine`` start within a year of each other."""
        a, b = fd[coarse]["earthquakes_yr"], fd[fine]["earthquakes_yr"]
        n = min(len(a), len(b))
        upto = next((i for i in range(n) if abs(a[i] - b[i]) > 1), n)
        return (f"met for all {n} earthquakes" if upto == n
                else f"met for the first {upto} earthquakes (to {b[upto - 1] if upto else 0.0:.0f} years), not after")

    if "50" in fd and "25" in fd:
        lines += ["The target, event times within 1 year between 50 and 25 m over 1500 years, is "
                  + verdict("50", "25") + "."
                  + (f" At the next halving, between 25 and 12.5 m, it is {verdict('25', '12.5')}."
                     if "12.5" in fd else ""), ""]
    if len(keys) >= 3:
        c, a, b = (fd[k]["earthquakes_yr"] for k in keys[-3:])
        n = min(len(c), len(a), len(b))
        d1, d2 = c[n - 1] - a[n - 1], a[n - 1] - b[n - 1]
        if d1 * d2 > 0 and abs(d1) > abs(d2):
            ratio = d1 / d2
            err = abs(d2) / (ratio - 1)
            lines += [f"The difference is the grid's: the {n}th earthquake moves by {d1:+.2f} years from {keys[-3]} "
                      f"to {keys[-2]} m and by {d2:+.2f} years from {keys[-2]} to {keys[-1]} m, {ratio:.1f} times less "
                      f"(order {np.log2(ratio):.1f} in dz), so that by Richardson's extrapolation the {keys[-1]} m "
                      f"run's event times are within about {err:.2f} years of the converged ones at that order"
                      + (f", and {float(keys[-1]) / 2:g} m would differ from {keys[-1]} m by about "
                         f"{err * (1 - 1 / ratio):.2f} years (not run here: about 2.5 times the {keys[-1]} m run's "
                         "time)." if float(keys[-1]) >= 25 else "."), ""]
    if checks:
        base = fd.get(f"{next(iter(checks.values()))['dz']:g}")
        if base:
            ref = base["earthquakes_yr"]
            parts = []
            for name, r in checks.items():
                t = [x / YEAR for x in r["t_start_s"]]
                m = min(len(t), len(ref))
                parts.append(f"with {name} ({r['accepted_steps']} steps to {r['years']:g} years) by "
                             + ", ".join(f"{x - y:+.3f}" for x, y in zip(t[:m], ref[:m])) + " years")
            r0 = next(iter(checks.values()))
            lines += [f"Not the time step: at dz = {r0['dz']:g} m to {r0['years']:g} years, against the run above "
                      f"(beta 0.5, tolerance {_tol(base['tolerance'])}), the first earthquakes move " + "; ".join(parts)
                      + " (`python -m studies.cycles.fd_checks`), a small fraction of the difference between the "
                      "grids at those earthquakes.", ""]
    return lines


def _tol(x) -> str:
    """A tolerance as the pages write it: 1e-5, 2.5e-7."""
    m, e = f"{float(x):.1e}".split("e")
    return f"{m.rstrip('0').rstrip('.')}e{int(e)}"


def _tolerance_section(checks, base, grid_yr) -> list:
    """The page's lines on the step's tolerance: ``checks`` (studies/cycles/tolerance.py, runs
    at tighter tolerances at the dz of ``base``, the page's run there) against ``base``;
    ``grid_yr``: the largest event-time difference between the two grids."""
    if not checks:
        return []
    first = next(iter(checks.values()))
    if float(first["dz"]) != float(base["dz"]):
        return []
    ref = base["events"]
    title = PAIR_TITLES[pair_of(base).name]
    rows = ["### The step's tolerance", "",
            f"BP1-QD at dz = {first['dz']:g} m over {first['years']:g} years with other pairs and tighter "
            f"tolerances than the builder's {title} at {_tol(base['tolerance'])} (`python -m "
            "studies.cycles.tolerance`): the largest change of an event's start and of a peak slip rate against the "
            "run above, and the steps taken.", "",
            "| pair | tolerance | accepted steps | steps below 1e-7 m/s | wall time | largest change of an event's "
            "start | of a peak slip rate |", "|---|---|---|---|---|---|---|",
            f"| {title} (the run above) | {_tol(base['tolerance'])} | {base['accepted_steps']} | "
            f"{base['steps_below_1e-7']} | {base['wall_s']:.0f} s | - | - |"]
    moved = {}
    for r in checks.values():
        m = min(len(r["t_start_s"]), len(ref["t_start"]))
        dt = max(abs(a - b) for a, b in zip(r["t_start_s"][:m], ref["t_start"][:m])) / YEAR
        dp = max(abs(a / b - 1) for a, b in zip(r["peak_slip_rate"][:m], ref["peak_slip_rate"][:m]))
        moved[r["tolerance"]] = (dt, dp, r)
        rows.append(f"| {PAIR_TITLES[pair_of(r).name]} | {_tol(r['tolerance'])} | {r['accepted_steps']} | "
                    f"{r.get('steps_below_1e-7', '-')} | {r['wall_s']:.0f} s | {dt:.2g} years | {dp:.2g} |")
    dt, dp, tight = moved[min(moved)]
    rows += ["", f"Against the tightest, {PAIR_TITLES[pair_of(tight).name]} at {_tol(tight['tolerance'])}, the "
             f"builder's pair and tolerance move the events' starts by at most {dt:.2g} years and their peak slip "
             f"rates by {dp:.2g}: {100 * dt / grid_yr:.1f} % of the grid's {grid_yr:.3f} years between the two "
             f"spacings, in {base['wall_s'] / tight['wall_s']:.2f} of its wall time.", ""]
    return rows


def _cost_section(res, dzs):
    """The page's lines on the cost target (issue 35: 1500 years at 25 m in under a minute),
    from the finest run and ``res["cost"]`` (studies/cycles/cost.py at that dz), if measured."""
    cost = res.get("cost")
    if not cost:
        return []
    r = res["runs"][f"{dzs[-1]:g}"]
    steps = r["accepted_steps"]
    ms = {k: 1e3 * cost[k] for k in ("rates_s", "transforms_s", "solve_s", "glue_s", "step_own_s", "step_s")}
    pair = pair_of(r)
    evals = pair.evaluations
    floor = evals * (cost["transforms_s"] + cost["solve_s"]) * steps
    fe = cost["first_event"]
    met = r["wall_s"] <= 60
    window = (f"The quasi-dynamic system integrates the window of the points that do not creep (docs/reference/"
              f"equations.md, \"Sequences: the quasi-dynamic response on a window\"): {cost['points']} of the "
              f"{cost['nodes']} nodes at dz = {cost['dz']:g} m, the law solved at {cost['solved_points']} of them (a "
              "node and its mirror image have the same traction and state). " if "points" in cost else "")
    return ["### Against the target", "",
            f"The target, 1500 years at 25 m in under a minute on one core: {r['wall_s']:.0f} s here, "
            f"{'met' if met else 'not met'}. " + window
            + f"A rate evaluation costs {ms['rates_s']:.3f} ms: "
            f"the transforms of the static response {ms['transforms_s']:.3f} ms, the rate-and-state solve "
            f"{ms['solve_s']:.3f} ms, the rest {ms['glue_s']:.3f} ms; an accepted step of {PAIR_TITLES[pair.name]} "
            f"takes {evals} evaluations and {ms['step_own_s']:.3f} ms of its own (stage sums, error estimate and "
            f"norm): {ms['step_s']:.2f} ms (`python -m studies.cycles.cost --dz {cost['dz']:g}`, best of 200 on the "
            "shared host). The run took "
            f"{steps} accepted steps, {r['steps_in_events']} of them in events: with nothing but the transforms and "
            f"the solves it would take {floor:.0f} s, at the benchmark's cost of a step {cost['step_s'] * steps:.0f} "
            f"s; the rest of the {r['wall_s']:.0f} s is what the benchmark leaves out: the record of every step "
            "(station series, the largest slip rate, the catalogue), the run's loop, and the states the run passes "
            f"through (the benchmark times one state between events). In events, the first event at {fe['dz']:g} m (creeping region to "
            f"{fe['depth'] / 1e3:g} km) takes "
            + ", ".join(f"{n} steps at tolerance {_tol(tol)}" for tol, n in fe["steps_in_events"].items())
            + f" (accuracy alone would give 10^(1/{pair.order}) = {10 ** (1 / pair.order):.2f} times more per decade, "
            "the pair's order)" + _peak_steps(r, dzs[-1])
            + ". Between events the "
            f"{r['steps_below_1e-7']} steps with every slip rate below 1e-7 m/s are set by the stability of the "
            "explicit pair on the stiff creeping modes (as many at any tolerance of one pair: the table under \"The "
            "step's tolerance\"), and a "
            "stiffly stable step of high order would take fewer: a stabilised explicit step of order 2 "
            "(Runge-Kutta-Chebyshev) was tried and its own error estimate held it to steps as short as "
            "Dormand-Prince 5(4)'s at 1e-5 (CHANGELOG). "
            + ("" if met else
               f"A minute at this count of steps needs each step about {r['wall_s'] / 60:.1f} times cheaper: the "
               f"solve is about {1e9 * cost['solve_s'] / cost['solved_points']:.0f} ns a point, its transcendental "
               "functions called one at a time (numba from pip has "
               "no vectorised maths library), the transforms are of twice the window, and the step's own arithmetic "
               "and the record are of the same order. "
               + (_stiff_clause(res["stiff"]) if res.get("stiff") else
                  "Fewer steps would need a method both stiffly stable and of high order, in events and between "
                  "them (a Rosenbrock or implicit Runge-Kutta method of order 4 or 5, its linear solves through the "
                  "transforms).")), ""]


def _stiff_clause(st) -> str:
    """The page's sentences on what a stiffly stable step would save (studies/cycles/stiff.py)."""
    bs3, *rad = st["runs"]
    ref, stab = st["reference"], st["stability"]
    off = {r["tolerance"]: abs(r["event_start_error_yr"]) for r in rad}
    match = min((r for r in rad if abs(r["event_start_error_yr"]) <= abs(bs3["event_start_error_yr"])),
                key=lambda r: r["steps"], default=rad[-1])
    n2 = 2 * st["window_points"]
    return (f"Fewer steps: over the first cycle at {st['dz']:g} m (to {st['t_end_yr']:.1f} years; `python -m "
            f"studies.cycles.stiff`) {PAIR_TITLES[bs3['method']]} at {_tol(bs3['tolerance'])} takes {bs3['steps']} "
            f"steps ({bs3['steps_in_event']} in the event, {bs3['rejected']} rejected) and starts the event "
            f"{abs(bs3['event_start_error_yr']):.1e} years from {PAIR_TITLES[ref['method']]} at "
            f"{_tol(ref['tolerance'])}; its steps are a median {stab['event']['median']:.2f} of its stability "
            f"limit in the event and {stab['between']['median']:.2f} between events (the eigenvalues of the "
            f"Jacobian at {stab['event']['samples']} and {stab['between']['samples']} steps): on this grid accuracy, "
            "not stability, sets them in the event. Radau IIA of order 5 (stiffly stable; scipy's, with the Jacobian through "
            "the static response) takes "
            + ", ".join(f"{r['steps']} steps at {_tol(r['tolerance'])} (the event {off[r['tolerance']]:.1e} years "
                        "off)" for r in rad)
            + f": at the explicit pair's accuracy {bs3['steps'] / match['steps']:.1f} times fewer steps, each with "
            f"{match['factorisations'] / match['steps']:.1f} factorisations of a dense {n2} x {n2} matrix on average "
            f"(the static response couples every point) and {match['evaluations'] / match['steps']:.1f} rate "
            "evaluations against the explicit pair's "
            f"{bs3['evaluations'] / bs3['steps']:.1f}. So a stiffly stable step would save at most a factor of about "
            f"{bs3['steps'] / match['steps']:.0f} in steps at equal accuracy, and only if its linear solves cost "
            "less than that many explicit steps: with dense factorisations they cost far more, and with iterative "
            "solves through the transforms each iteration costs a transform pair. The way to the target is a "
            "cheaper explicit step, not fewer steps.")



def _peak_steps(r, dz) -> str:
    """The page's clause on the steps at the events' peak of the run ``r`` at ``dz``: their
    median against the pair's stability on the modes the radiation damping dominates, whose
    rate is at most pi c_s / dz (a mode q: (mu q / 2) / eta = q c_s)."""
    from cracklab.scenes import bp1

    med = r.get("step_above_0.1_median_s")
    if not med:
        return ""
    pair = pair_of(r)
    reach = real_stability(pair)
    limit = reach * dz / (np.pi * bp1(dz=dz, years=1.0).material.cs)
    near = 0.7 <= med / limit <= 1.3
    return (f". At {dz:g} m the {r['steps_above_0.1']} steps with a slip rate above 0.1 m/s have a median of "
            f"{1e3 * med:.1f} ms: on the modes the radiation damping dominates the rate is up to pi c_s / dz, and "
            f"{PAIR_TITLES[pair.name]} is stable to h lambda = {reach:.2f} on the negative axis, so to {reach:.2f} "
            f"dz / (pi c_s) = {1e3 * limit:.1f} ms: "
            + ("about as long as the pair's stability allows on those modes (the rate-and-state term adds to the "
               "damping where the slip rate is lower), so accuracy and stability meet there" if near else
               "longer than the pair's stability allows on those modes: the slip rates there are too low for "
               "the radiation damping to dominate" if med > limit else
               "shorter than the pair's stability allows, so its accuracy sets them"))


def write_page(res, dzs, page, figs, command, kept_figs=()):
    runs = res["runs"]
    fd = res.get("fd") or res.get("fd_kept")
    lines = ["# Sequences: SEAS BP1-QD and BP1-FD" if fd else "# Sequences: SEAS BP1-QD", "",
             f"Written by `{command}` (studies/cycles/run.py) from its runs; every number below is in "
             "OUT/cycles_results.json" + (", but for the section on BP1-FD and its figures, kept as the page had "
                                          "them (their runs are not in OUT)." if res.get("fd_kept") else "."), "",
             "SEAS BP1-QD (Erickson et al. 2020, Seismol. Res. Lett. 91): a vertical strike-slip fault in a half "
             "space, antiplane, rate-and-state friction with the ageing law, velocity weakening to 15 km, the "
             "transition to velocity strengthening over 3 km, friction to 40 km and creep at the plate rate "
             "1e-9 m/s below. `cracklab.scenes.bp1` builds it (the free surface as a mirror, the creeping region "
             "to 320 km); the response is quasi-dynamic (the static kernel plus radiation damping), the time step "
             f"adaptive ({PAIR_TITLES[pair_of(runs[f'{dzs[0]:g}']).name]}, tolerance "
             f"{_tol(runs[f'{dzs[0]:g}']['tolerance'])}). An event lasts while "
             "the largest slip rate exceeds "
             "1 mm/s.", "",
             "## Cost", "",
             "| dz | nodes | years | wall time | accepted steps | smallest step | largest step | steps in events | "
             "wall time in events / between |", "|---|---|---|---|---|---|---|---|---|"]
    for dz in dzs:
        r = runs[f"{dz:g}"]
        lines.append(f"| {dz:g} m | {r['nodes']} | {r['years']:g} | {r['wall_s']:.0f} s | {r['accepted_steps']} | "
                     f"{r['smallest_step']:.2g} s | {r['largest_step'] / YEAR:.2g} yr | {r['steps_in_events']} | "
                     f"{_phases(r)} |")
    lines += ["", "Wall times on a shared 2-core host (one core per run, other jobs running), not a benchmark. "
              "The wall time in events and between them is what the run counted while stepping (its attrs "
              "`wall_time_in_events`, `wall_time_between_events`): the rest is its set-up and output; '-' for a "
              "run that was recorded before they were counted.", ""]
    lines += _cost_section(res, dzs)
    lines += ["## Events", ""]
    for dz in dzs:
        r = runs[f"{dz:g}"]
        ev = r["events"]
        lines += [f"**dz = {dz:g} m**: {len(ev['t_start'])} events in {len(r['earthquakes_yr'])} earthquakes (events "
                  "that start within a year of each other are one: a rupture that stops at depth and starts again "
                  "within hours); the earthquakes start at (years) "
                  + ", ".join(f"{x:.2f}" for x in r["earthquakes_yr"]) + "; recurrence intervals (years): "
                  + ", ".join(f"{x:.2f}" for x in r["recurrence_yr"]), ""]
        lines += events_table(ev)
    if res.get("domain"):
        lines += ["## The periodic images", "",
                  f"The grid holds the fault, its mirror image above the surface and the creeping plane down to "
                  f"`depth`; the cell repeats every 2 depth, and the locked fault's images slow its loading. At "
                  f"dz = {DOMAIN_DZ:g} m over {DOMAIN_YEARS:g} years (the earthquakes, peak slip rate above 0.1 m/s):",
                  "", "| depth | first event (yr) | second (yr) | interval (yr) |", "|---|---|---|---|"]
        for d, row in res["domain"].items():
            t = row["t_start_yr"]
            lines.append(f"| {d} km | {t[0]:.2f} | {t[1]:.2f} | {t[1] - t[0]:.2f} |" if len(t) > 1 else
                         f"| {d} km | {t[0]:.2f} | - | - |")
        lines += ["", "`scenes.bp1` takes depth = 320 km by default.", ""]
    if len(dzs) >= 2:
        a, b = runs[f"{dzs[0]:g}"], runs[f"{dzs[1]:g}"]
        qa, qb = a["earthquakes_yr"], b["earthquakes_yr"]
        n = min(len(qa), len(qb))
        ra, rb = np.mean(a["recurrence_yr"]), np.mean(b["recurrence_yr"])
        worst = max(abs(x / y - 1) for x, y in zip(a["recurrence_yr"], b["recurrence_yr"]))
        lines += ["## Self-convergence", "",
                  f"Between dz = {dzs[0]:g} m and {dzs[1]:g} m: the {n} earthquakes start within "
                  f"{max(abs(x - y) for x, y in zip(qa[:n], qb[:n])):.3f} years of each other over "
                  f"{a['years']:g} years; the mean recurrence interval is {ra:.3f} and {rb:.3f} years "
                  f"({100 * abs(ra / rb - 1):.3f} %), each interval within {100 * worst:.2f} %.", ""]
        lines += _tolerance_section(res.get("qd_tolerance"), b, max(abs(x - y) for x, y in zip(qa[:n], qb[:n])))
    fine = runs[f"{dzs[-1]:g}"]
    q = fine["earthquakes_yr"]
    n = min(len(q), len(BICYCLE_YR))
    ev = fine["events"]
    hypo = [h for t, h in zip(ev["t_start"], ev["hypocentre_x1"]) if t / YEAR in q]     # each earthquake's first
    big = [i for i, v in enumerate(ev["peak_slip_rate"]) if v > 0.1]
    lines += ["## Against published results", "",
              "- The BP1-QD description (Erickson & Jiang 2018, the SEAS platform's document; a copy is in "
              "RSFaultZ's repository, benchmarks/BP1QD/BP1QD_BP2QD.pdf) gives as a sanity check about 30 earthquakes "
              "in 3000 years, nucleating at 12-13 km and arresting at about 18 km, every ~100 years, with about 3 m of "
              "surface slip and a largest surface slip rate of about 5 m/s. Here (dz = "
              f"{dzs[-1]:g} m): {len(q)} earthquakes in {fine['years']:g} years (about {2 * len(q) * 1500 / fine['years']:.0f}"
              f" in 3000), every {np.mean(fine['recurrence_yr']):.1f} years, {sum(12e3 <= h <= 14e3 for h in hypo)} of "
              f"them nucleating at {min(h for h in hypo if h >= 12e3) / 1e3:.1f}-{max(hypo) / 1e3:.1f} km (the "
              f"others where the largest slip rate first exceeds 1 mm/s at the surface), the largest slip rate "
              f"{max(ev['peak_slip_rate']):.1f} m/s.",
              "- BICyclE's results on the SEAS platform, as RSFaultZ's repository plots them (benchmarks/BP1QD/"
              "BP1QD.png; shear stress and slip rate at 7.5 km, 0 to 700 years): earthquakes at about "
              + ", ".join(f"{x:.0f}" for x in BICYCLE_YR[:n]) + " years (read off the plot, to about 2 years); here "
              + ", ".join(f"{x:.1f}" for x in q[:n]) + " years: within "
              + f"{max(abs(a - b) for a, b in zip(q[:n], BICYCLE_YR[:n])):.1f} years. The stress at 7.5 km rises from "
              "26.6 MPa to about 30 MPa before each earthquake and peaks near 45 MPa in both, and the slip rate there "
              "peaks near 10^-0.4 m/s in both (the figure below).",
              f"- Every earthquake here is one event (none stops at depth to start again): its largest slip rate is "
              f"{min(ev['peak_slip_rate'][i] for i in big):.2f}-{max(ev['peak_slip_rate'][i] for i in big):.2f} m/s "
              "(the description's sanity check: about 5 m/s). Before `Sequence.mirror` (docs/reference/equations.md, "
              "\"Sequences\") the fault and its mirror image parted by round-off and from the third earthquake on the "
              "ruptures stopped at depth and started again at the surface.", ""]
    if res.get("fd"):
        lines += _fd_section(res)
    elif res.get("fd_kept"):
        lines += res["fd_kept"]
    if res.get("uguca"):
        from studies.cycles.uguca import section
        lines += section(res["uguca"])
    elif res.get("uguca_kept"):
        lines += res["uguca_kept"]
    if res.get("ensemble"):
        e = res["ensemble"]
        lines += ["## An ensemble of sequences", "",
                  "`cracklab sweep studies/cycles/ensemble.toml` runs BP1-QD with the velocity-weakening zone "
                  "reaching 10, 12.5 and 15 km (dz = 200 m, 600 years) into one store; "
                  "`cracklab.analysis.events(cracklab.open_ensemble(store)).to_dataframe().dropna(subset=['t_start'])` "
                  f"is the tidy table of every member's events ({e['rows']} rows here). Per member:", "",
                  "| " + " | ".join(e["swept"]) + " | events | earthquakes | first (yr) | mean recurrence (yr) | "
                  "largest slip rate (m/s) | mean slip per event (m) |",
                  "|---" * (len(e["swept"]) + 6) + "|"]
        for m in e["members"]:
            rec = f"{np.mean(m['recurrence_yr']):.1f}" if m["recurrence_yr"] else "-"
            lines.append("| " + " | ".join(f"{m[c]:g}" for c in e["swept"]) + f" | {m['events']} | "
                         f"{len(m['earthquakes_yr'])} | {m['earthquakes_yr'][0]:.1f} | {rec} | "
                         f"{m['peak_slip_rate']:.2f} | {m['mean_slip']:.2f} |")
        lines.append("")
    lines += ["## Figures", ""] + [f"![{Path(f).stem}]({f})" for f in figs] + list(kept_figs) + [""]
    page.write_text("\n".join(lines))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default="out/cycles")
    p.add_argument("--dz", type=float, nargs="+", default=[50.0, 25.0])
    p.add_argument("--fd", type=float, nargs="*", default=[], help="spacings of BP1-FD runs")
    p.add_argument("--years", type=float, default=1500.0)
    p.add_argument("--tolerance", type=float, default=None, help="BP1-QD's (default: the builder's)")
    p.add_argument("--report-only", action="store_true")
    p.add_argument("--force", action="store_true")
    p.add_argument("--ensemble", default=None, help="the store of `cracklab sweep studies/cycles/ensemble.toml`, "
                                                    "for the page's section on it")
    p.add_argument("--keep-fd", action="store_true", help="without --fd: the page's BP1-FD section and figures "
                                                              "kept as they are")
    p.add_argument("--page", default=str(ROOT / "docs" / "studies" / "cycles.md"))
    p.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        for dz in args.fd:
            run_one(out, dz, args.years, args.tolerance, force=args.force, dynamic=True)
        for dz in args.dz:
            run_one(out, dz, args.years, args.tolerance, force=args.force)
    res = analyse(out, args.dz)
    if args.fd:
        res["fd"] = analyse(out, args.fd, dynamic=True)["runs"]
        res["qd_at_fd"] = analyse(out, [dz for dz in args.fd if store_of(out, dz).exists()])["runs"]
    res["domain"] = run_domain(out) if not args.report_only or (out / "domain_depth80km.json").exists() else {}
    if args.ensemble:
        res["ensemble"] = analyse_ensemble(args.ensemble)
    if (out / "uguca_bp1.json").exists():       # python -m studies.cycles.uguca
        res["uguca"] = json.loads((out / "uguca_bp1.json").read_text())
    elif Path(args.page).exists():      # uguca's runs are not in OUT: their section as the page has it
        res["uguca_kept"] = kept_section(Path(args.page).read_text(), "## Against uguca")
    kept_figs = []
    if args.keep_fd and not args.fd and Path(args.page).exists():      # BP1-FD's runs not in OUT
        text = Path(args.page).read_text()
        res["fd_kept"] = kept_section(text, "## BP1-FD: the fully dynamic response")
        kept_figs = [line for line in kept_section(text, "## Figures") if "bp1fd_" in line or "_qd_fd_" in line]
    if (out / "qd_tolerance.json").exists():    # python -m studies.cycles.tolerance
        res["qd_tolerance"] = json.loads((out / "qd_tolerance.json").read_text())
    if (out / "fd_checks.json").exists():       # python -m studies.cycles.fd_checks
        res["fd_checks"] = json.loads((out / "fd_checks.json").read_text())
    if (out / "stiff.json").exists():           # python -m studies.cycles.stiff
        res["stiff"] = json.loads((out / "stiff.json").read_text())
    cost = out / f"cost_dz{args.dz[-1]:g}.json"
    if cost.exists():
        res["cost"] = json.loads(cost.read_text())
    (out / "cycles_results.json").write_text(json.dumps(res, indent=1))
    figdir = Path(args.figures)
    figdir.mkdir(parents=True, exist_ok=True)
    page = Path(args.page)
    figs = [fig_max_rate(out, args.dz, figdir), fig_station(out, args.dz[-1], figdir)] + \
        [fig_profiles(out, dz, figdir) for dz in args.dz] + \
        [fig_qd_fd(out, dz, figdir) for dz in args.fd if store_of(out, dz).exists()] + \
        [fig_profiles(out, dz, figdir, dynamic=True) for dz in args.fd]
    rel = [Path("..") / "figures" / f.name for f in figs]
    write_page(res, args.dz, page, rel, "python -m studies.cycles.run " + " ".join(argv or sys.argv[1:]), kept_figs)
    print(f"wrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
