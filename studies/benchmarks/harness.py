"""The harness of the benchmark studies (studies/tpv3, tpv5, tpv6, tpv101; docs/studies/tpv3.md,
tpv5.md, tpv6.md, tpv101.md, tpv103.md): what every benchmark does the same way.

* ``reference_dir``, ``mdsbi_station``: where a benchmark's reference lies (``--reference
  DIR``, the environment variable ``CRACKLAB_REFERENCE``, or ``shared/reference/<name>``
  beside the repository) and one MDSBI station file read from it;
* ``numerics``, ``build``: a ``cracklab.scenes`` builder's scene with the studies' time
  stepping, its stations, the rupture time and the final fields recorded;
* ``run_scene``, ``complete``, ``load_run``, ``read_meta``: one run per grid spacing,
  streamed to OUT/<tag>.zarr with its wall time in OUT/<tag>.json, reused when the store
  holds a finished run of the same scene;
* ``strike_series``, ``reference_series``, ``compare_strike``, ``analyse_runs``: the
  stations of a run against the reference, and the runs' metadata;
* ``parser``, ``spacings``, ``page_paths``, ``figure_link``, ``command_line``: the command
  line shared by the studies' ``run.py`` and where its runs, page and figures go;
* ``ok``, ``per_dx``, ``station_rows``, ``measure_rows``, ``verdict_lines``, ``report``,
  ``exit_status``, ``fill_notes``: the page's and the console's pieces of the acceptance
  (``studies.benchmarks.measures.check_acceptance``) and the discussion's placeholders;
* ``pyplot``, ``save``, ``station_figure``, ``front_figure``: the figures' common steps.

Each benchmark (``studies.<name>.run``) keeps its stations, acceptance limits, page text
and its own analyses. Run a study from the repository's root as a module, e.g.
``python -m studies.tpv3.run``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REFERENCE_ENV = "CRACKLAB_REFERENCE"


# ------------------------------------------------------------------------------ reference
def reference_dir(name: str, directory=None) -> Path:
    """The folder of the reference ``name`` (e.g. "tpv3_mdsbi"): ``directory`` when given
    (``--reference DIR``), else ``$CRACKLAB_REFERENCE/<name>``, else the nearest
    ``shared/reference/<name>`` beside the repository's root (``../shared/reference/<name>``)
    or beside its parent (a worktree one folder deeper); no folder higher up is searched, so
    what a machine keeps far above a checkout is never taken for its reference."""
    if directory:
        return Path(directory)
    env = os.environ.get(REFERENCE_ENV)
    if env:
        return Path(env) / name
    for parent in list(ROOT.parents)[:2]:
        cand = parent / "shared" / "reference" / name
        if cand.is_dir():
            return cand
    raise FileNotFoundError(f"reference {name!r} not found beside {ROOT}: give --reference DIR or set "
                            f"{REFERENCE_ENV} to the folder that holds {name}/")


def mdsbi_station(name: str, station: str, directory=None) -> dict:
    """One station file of the MDSBI reference ``name`` (``measures.read_mdsbi``)."""
    from studies.benchmarks.measures import read_mdsbi

    return read_mdsbi(reference_dir(name, directory) / f"{station}.txt")


# ------------------------------------------------------------------------------ runs
def numerics(formulation="product2", engine="exponential"):
    """The studies' time stepping: ``Numerics`` with the rupture threshold of the measures
    (1 mm/s)."""
    from cracklab.model.scene import Numerics

    from studies.benchmarks.measures import THRESHOLD

    return Numerics(formulation=formulation, engine=engine, rupture_threshold=THRESHOLD)


def build(builder, dx, *, t_end=None, domain=None, fields=("delta_1",), **kw):
    """``builder(dx=dx, ...)`` (a ``cracklab.scenes`` builder; ``t_end`` and the periodic cell
    ``domain`` passed when given, ``kw`` as they are) recording its stations every step, the
    rupture time of the whole plane and ``fields`` at the end."""
    from cracklab.model.record import Record

    if t_end is not None:
        kw["t_end"] = float(t_end)
    if domain is not None:
        kw["domain"] = tuple(float(x) for x in domain)
    base = builder(dx=dx, **kw)
    rec = Record(fields=tuple(fields), times=(base.nsteps * base.dt,), stations=dict(base.record.stations))
    return base.replace(record=rec)


def store_path(out, tag) -> Path:
    """OUT/<tag>.zarr (its metadata: the .json next to it)."""
    return Path(out) / f"{tag}.zarr"


def complete(store, scene, *, finished=False) -> bool:
    """The store holds a run of this very scene with its rupture time and metadata
    (``finished``: and the simulation marked it complete)."""
    import xarray as xr

    from cracklab.output.simulate import scene_of

    if not Path(store).exists() or not Path(store).with_suffix(".json").exists():
        return False
    try:
        ds = xr.open_zarr(store, consolidated=False)
        if finished and ds.attrs.get("cracklab_status") != "complete":
            return False
        return "rupture_time" in ds and scene_of(ds).to_toml() == scene.to_toml()
    except Exception:  # noqa: BLE001 - any unreadable store is rerun
        return False


def run_scene(scene, store, *, label, meta=None, force=False, log=print, resume=False, time_setup=False,
              tolerate=()) -> dict:
    """Run ``scene`` into ``store`` and write its metadata next to it, or reuse a complete
    store of the same scene (``force``: rerun). ``meta``: the study's own entries, first in
    the metadata. ``resume``: a store left by a killed run resumes from its checkpoint (one
    that cannot is started over). ``time_setup``: the history engines' taps are computed
    first and timed apart ("setup_s"; "s_per_step" then counts the stepping only).
    ``tolerate``: exception types that stop the run without failing the study ("error":
    their message, else None). Returns the metadata dict."""
    import cracklab
    from cracklab.output.simulate import simulate

    store = Path(store)
    meta_path = store.with_suffix(".json")
    if not force and complete(store, scene, finished=resume):
        old = json.loads(meta_path.read_text())
        log(f"{label}: reusing {store} (ran in {old['wall_s']:.0f} s)")
        return old
    resuming = resume and store.exists() and not force
    if store.exists() and not resuming:
        shutil.rmtree(store)
    meta_path.unlink(missing_ok=True)
    g = scene.grid
    log(f"{label}: grid {g.shape[0]} x {g.shape[1]} ({g.L1 / 1e3:g} km x {g.L3 / 1e3:g} km), beta = "
        f"{scene.beta:.4f}, dt = {scene.dt:.3e} s, {scene.nsteps} steps to t = {scene.nsteps * scene.dt:g} s "
        f"-> {store}{' (resuming)' if resuming else ''}", flush=True)
    t0 = time.time()
    setup = 0.0
    if time_setup:
        from cracklab.solver.interfaces import for_scene

        for_scene(scene)          # memoised in the process: the run's own interface reuses it
        setup = time.time() - t0
        log(f"{label}: interface set up in {setup:.0f} s", flush=True)
    error = None
    try:
        try:
            simulate(scene, store=str(store), progress=False, resume=resuming)
        except tolerate:
            raise
        except Exception:
            if not resuming:
                raise
            shutil.rmtree(store)              # a store this run cannot resume: start over
            simulate(scene, store=str(store), progress=False)
    except tolerate as exc:
        error = str(exc)
        log(f"{label}: the solver stopped the run: {error}")
    wall = time.time() - t0
    out = dict(meta or {})
    out.update({"t_end": scene.nsteps * scene.dt, "n1": g.n1, "n3": g.n3, "domain": [g.L1, g.L3],
                "beta": scene.beta, "dt": scene.dt, "nsteps": scene.nsteps, "wall_s": wall,
                "s_per_step": (wall - setup) / scene.nsteps, "formulation": scene.formulation,
                "engine": scene.numerics.engine, "cracklab_version": cracklab.__version__, "host": platform.node()})
    if time_setup:
        out["setup_s"] = setup
    if resume:
        out["resumed"] = resuming
    if tolerate:
        out["error"] = error
    meta_path.write_text(json.dumps(out, indent=1))
    log(f"{label}: {'stopped' if error else 'done'} after {wall:.0f} s "
        f"({1e3 * (wall - setup) / scene.nsteps:.1f} ms/step)", flush=True)
    return out


def read_meta(store) -> dict:
    """The metadata written next to a store by ``run_scene``."""
    return json.loads(Path(store).with_suffix(".json").read_text())


def load_run(store):
    """(Dataset, scene, station Dataset) of a run's store."""
    import xarray as xr

    from cracklab.output.simulate import scene_of, stations

    ds = xr.open_zarr(store, consolidated=False)
    return ds, scene_of(ds), stations(ds).load()


def strike_series(st, station) -> dict:
    """cracklab's strike components at one station of a station Dataset: t, slip, rate,
    stress (MPa, as the references) and the dip slip rate rate3."""
    s = st.sel(station=station)
    return {"t": st.t.values, "slip": s.delta_1.values, "rate": s.v_1.values,
            "stress": s.tau_1.values / 1e6, "rate3": s.v_3.values}


def reference_series(ref) -> dict:
    """An MDSBI record's strike (h) components under the names of ``strike_series``."""
    return {"t": ref["t"], "slip": ref["h_slip"], "rate": ref["h_rate"], "stress": ref["h_stress"]}


def compare_strike(st, station, ref):
    """One station's strike components against an MDSBI record (``measures.compare_station``)
    with the acceptance of each quantity ("accept"), the whole-series RMS differences
    ("series_rms") and the largest dip slip rate ("max_abs_v3"). Returns (comparison,
    cracklab's series, the reference's series)."""
    import numpy as np

    from studies.benchmarks import measures as M

    sim, r = strike_series(st, station), reference_series(ref)
    cmp = M.compare_station(sim, r)
    cmp["accept"] = M.acceptance(cmp)
    cmp["series_rms"] = M.series_errors(sim, r)
    cmp["max_abs_v3"] = float(np.max(np.abs(sim["rate3"])))
    return cmp, sim, r


def analyse_runs(stores: dict, compare, extra=None) -> dict:
    """The runs ``stores`` ({dx key: store}) against the reference: {"runs": {dx key: the
    metadata with "ruptured_fraction" (of the fault's nodes) and "last_rupture_time"},
    "stations": {station: {dx key: comparison}}}, the comparisons being ``compare(st)``
    ({station: comparison} of a station Dataset); ``extra(st, rt, fault)``: more entries of
    the metadata (rt the rupture-time field, fault the mask of the nodes that may slip)."""
    import numpy as np

    res = {"runs": {}, "stations": {}}
    for key, store in stores.items():
        meta = read_meta(store)
        ds, scene, st = load_run(store)
        res["runs"][key] = meta
        for s, cmp in compare(st).items():
            res["stations"].setdefault(s, {})[key] = cmp
        rt = ds.rupture_time.values
        fault = ~np.asarray(scene.law.bonded)
        meta["ruptured_fraction"] = float(np.mean(np.isfinite(rt[fault])))
        meta["last_rupture_time"] = float(np.nanmax(rt)) if np.isfinite(rt).any() else float("nan")
        if extra is not None:
            meta.update(extra(st, rt, fault))
    return res


# ------------------------------------------------------------------------------ command line
def parser(doc: str, name: str, *, dx_help: str, quick_help: str, reference_help: str, t_end=12.0,
           t_end_help="simulated time of the runs (s)", page=None, first=()) -> argparse.ArgumentParser:
    """The options every study's run.py has: -o, --dx, --t-end, --quick, --report-only,
    --force, --figures, --page, --reference (``name``: the study's folder under out/ and
    its page docs/studies/<name>.md unless ``page`` names it; ``first``: (args, kwargs) of options
    added before them)."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    for a, kw in first:
        p.add_argument(*a, **kw)
    p.add_argument("-o", "--out", default=str(ROOT / "out" / name))
    p.add_argument("--dx", type=float, nargs="+", default=None, help=dx_help)
    p.add_argument("--t-end", type=float, default=t_end, help=t_end_help)
    p.add_argument("--quick", action="store_true", help=quick_help)
    p.add_argument("--report-only", action="store_true", help="only redraw figures and page from the stores")
    p.add_argument("--force", action="store_true", help="rerun even if a complete store exists")
    p.add_argument("--figures", default=None, help="figure directory (default docs/figures)")
    p.add_argument("--page", default=None, help=f"page to write (default {page or f'docs/studies/{name}.md'})")
    p.add_argument("--reference", default=None,
                   help=f"{reference_help} (default ${REFERENCE_ENV}/<name>, else ../shared/reference/<name> "
                        "beside the repository)")
    return p


def spacings(args, *, quick, quick_t_end, default, accept_dx=None) -> tuple[Path, list, float]:
    """(output folder, grid spacings coarsest first, simulated time) of a run.py: with
    --quick OUT/quick, --dx or ``quick`` and ``quick_t_end``; else OUT, --dx or ``default``
    and --t-end, ``accept_dx`` added when a finer spacing is asked without it (the finer
    runs are compared with it)."""
    if args.quick:
        return Path(args.out) / "quick", sorted(set(args.dx or quick), reverse=True), quick_t_end
    dxs = list(args.dx or default)
    if accept_dx is not None and any(x < accept_dx for x in dxs) and accept_dx not in dxs:
        dxs = [accept_dx] + dxs
    return Path(args.out), sorted(set(dxs), reverse=True), args.t_end


def page_paths(args, out, page_name, quick) -> tuple[Path, Path]:
    """(figure folder, page) of a run.py: --figures and --page when given, else OUT itself
    with --quick, else docs/figures and docs/studies/<page_name>.md; the figure folder is created."""
    figdir = Path(args.figures or (out if quick else ROOT / "docs" / "figures"))
    page = Path(args.page or (out / f"{page_name}.md" if quick else ROOT / "docs" / "studies" / f"{page_name}.md"))
    figdir.mkdir(parents=True, exist_ok=True)
    return figdir, page


def figure_link(figdir, page) -> str:
    """The figure folder as the page links it: relative to the page's folder (docs/studies/
    pages link docs/figures as ../figures)."""
    import os

    return Path(os.path.relpath(Path(figdir).resolve(), Path(page).resolve().parent)).as_posix()


def command_line(module: str, argv=None) -> str:
    """The command that ran, as the page names it: ``python -m <module> <options>``."""
    import sys

    used = sys.argv[1:] if argv is None else list(argv)
    return " ".join(["python", "-m", module] + used)


# ------------------------------------------------------------------------------ page and console
def ok(b) -> str:
    return "yes" if b else "**no**"


def per_dx(acc) -> dict:
    """{dx: (checks holding, checks)} of a verdict, finest last."""
    out = {}
    for r in acc["checks"]:
        good, n = out.get(r["dx"], (0, 0))
        out[r["dx"]] = (good + r["pass"], n + 1)
    return dict(sorted(out.items(), reverse=True))


def station_rows(res, stations, dxs, mark=None, extra=None) -> str:
    """The acceptance table's rows: each station's rupture time, final slip and peak slip
    rate against the reference's, each difference followed by ``mark(station, dx key,
    quantity)`` (default: " (<limit>: <holds>)" of ``measures.check_acceptance``'s rows);
    ``extra(comparison, station, dx key)``: a last column."""
    if mark is None:
        from studies.benchmarks.measures import fmt_tol

        checks = {(r["station"], f"{r['dx']:g}", r["quantity"]): r for r in res["acceptance"]["checks"]}

        def mark(s, key, q):
            r = checks.get((s, key, q))
            return " (not checked)" if r is None else f" ({fmt_tol(q, r['limit'])}: {ok(r['pass'])})"

    rows = []
    for s in stations:
        for dx in dxs:
            key = f"{dx:g}"
            c = res["stations"][s][key]
            rows.append(
                f"| {s} | {key} m | {c['sim']['rupture_time']:.3f} | {c['ref']['rupture_time']:.3f} | "
                f"{c['diff']['rupture_time']:+.3f}{mark(s, key, 'rupture_time')} | "
                f"{c['sim']['final_slip']:.3f} | {c['ref']['final_slip']:.3f} | "
                f"{100 * c['rel']['final_slip']:+.1f} %{mark(s, key, 'final_slip')} | "
                f"{c['sim']['peak_rate']:.3f} | {c['ref']['peak_rate']:.3f} | "
                f"{100 * c['rel']['peak_rate']:+.1f} %{mark(s, key, 'peak_rate')} |"
                + ("" if extra is None else f" {extra(c, s, key)} |"))
    return "\n".join(rows)


def measure_rows(res, stations, dxs, own_peak=False) -> str:
    """The rows of the measures outside the acceptance: the interpolated rupture time on
    cracklab's own steps and the reference's, the time of the peak slip rate (difference),
    with ``own_peak`` the peak on cracklab's own steps, the final shear stress, and the RMS
    differences of the series (slip / slip rate / stress, % of the reference's peak)."""
    rows = []
    for s in stations:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            f, r, m = c["fine"], c["series_rms"], c["sim"]
            rows.append(
                f"| {s} | {dx:g} m | {f['rupture_time_interp']:.4f} | {c['ref']['rupture_time_interp']:.4f} | "
                f"{m['peak_time']:.2f} ({c['diff']['peak_time']:+.2f}) | {c['ref']['peak_time']:.2f} | "
                + (f"{f['peak_rate']:.3f} at {f['peak_time']:.3f} s | " if own_peak else "")
                + f"{m['final_stress']:.2f} ({c['diff']['final_stress']:+.2f}) | {c['ref']['final_stress']:.2f} | "
                f"{100 * r['slip']:.1f} / {100 * r['rate']:.1f} / {100 * r['stress']:.1f} |")
    return "\n".join(rows)


def verdict_lines(res, dxs, where: str, reference: str = "MDSBI") -> str:
    """The page's acceptance paragraph of ``measures.check_acceptance`` (``where``: "both
    stations", "the five stations")."""
    from studies.benchmarks import measures as M

    acc = res["acceptance"]
    if not acc["checked"]:
        return ("**Acceptance: not checked.** It applies at 100 m; this version has runs at "
                f"{', '.join(f'{x:g} m' for x in dxs)} only.")
    fine = [x for x in dxs if x < M.ACCEPT_DX]
    status = "; ".join(f"{dx:g} m {'PASS' if good == n else 'FAIL'} ({good} of {n} checks hold)"
                       for dx, (good, n) in per_dx(acc).items())
    head = (f"**Acceptance: {'PASS' if acc['pass'] else 'FAIL'}** ({status}). At {M.ACCEPT_DX:g} m, at {where}: "
            f"rupture time within {M.TOL_RUPTURE_TIME:g} s, final slip within {100 * M.TOL_FINAL_SLIP:g} %, "
            f"peak slip rate within {100 * M.TOL_PEAK_RATE:g} % of {reference}")
    if fine:
        head += (f"; at {', '.join(f'{x:g} m' for x in fine)} each difference within the same limit and "
                 f"no larger than at {M.ACCEPT_DX:g} m")
    else:
        head += f" (no run finer than {M.ACCEPT_DX:g} m in this version: the convergence part is not checked)"
    if acc["failures"]:
        head += ". These do not hold:\n\n" + "\n".join(f"* {f}" for f in acc["failures"])
    else:
        head += "."
    return head


def report(res, stations, dxs) -> None:
    """Print each station's three acceptance numbers and the verdict."""
    from studies.benchmarks.measures import ACCEPT_DX

    for s in stations:
        for dx in dxs:
            c = res["stations"][s][f"{dx:g}"]
            print(f"{s:17s} {dx:5g} m  rupture {c['sim']['rupture_time']:.3f} vs {c['ref']['rupture_time']:.3f} "
                  f"({c['diff']['rupture_time']:+.3f} s)  final slip {c['sim']['final_slip']:.3f} vs "
                  f"{c['ref']['final_slip']:.3f} ({100 * c['rel']['final_slip']:+.1f} %)  peak rate "
                  f"{c['sim']['peak_rate']:.3f} vs {c['ref']['peak_rate']:.3f} ({100 * c['rel']['peak_rate']:+.1f} %)")
    acc = res["acceptance"]
    if not acc["checked"]:
        print(f"acceptance: NOT CHECKED (applies at {ACCEPT_DX:g} m)")
        return
    per = "; ".join(f"{dx:g} m {'PASS' if good == n else 'FAIL'} ({good} of {n} checks hold)"
                    for dx, (good, n) in per_dx(acc).items())
    print(f"acceptance: {'PASS' if acc['pass'] else 'FAIL'} ({per})")
    for f in acc["failures"]:
        print(f"  FAIL {f}")


def exit_status(res) -> int:
    """0 when the acceptance holds (or only coarser runs than it needs were made), 1 when it
    fails, 2 when it could not be checked."""
    from studies.benchmarks.measures import ACCEPT_DX

    acc = res["acceptance"]
    if not acc["checked"]:
        return 0 if all(float(k) > ACCEPT_DX for k in res["runs"]) else 2
    return 0 if acc["pass"] else 1


def fill_notes(notes, numbers) -> str:
    """The discussion ``notes`` (a Markdown file with {placeholders}) filled from the dict
    ``numbers`` ("" when there is no such file)."""
    notes = Path(notes)
    if not notes.exists():
        return ""
    try:
        return notes.read_text().format(**numbers)
    except (KeyError, IndexError, ValueError) as exc:
        raise ValueError(f"{notes}: placeholder {exc} not filled from the results") from exc


# ------------------------------------------------------------------------------ figures
def pyplot():
    """matplotlib.pyplot on the Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path, dpi) -> Path:
    """Lay out, write and close one figure."""
    plt = pyplot()
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return Path(path)


def station_figure(ref, runs, series, title, *, ref_keys, ref_label, colours, alpha=0.55, extra=None):
    """Slip, slip rate and shear stress of one station: the reference (``ref[ref_keys[i]]``)
    thick and grey, each run of ``runs`` ({dx key: station Dataset}, ``series(st)`` its
    dict of t, slip, rate, stress) thin; ``extra`` ({label: series dict}) dashed. Returns
    the figure."""
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True)
    for ax, key, rkey, label in zip(axes, ("slip", "rate", "stress"), ref_keys,
                                    ("slip (m)", "slip rate (m/s)", "shear stress (MPa)")):
        ax.plot(ref["t"], ref[rkey], color="k", lw=2.2, alpha=alpha, label=ref_label)
        for name, st in runs.items():
            sim = series(st)
            ax.plot(sim["t"], sim[key], color=colours.get(name), lw=1.0, label=f"cracklab, {name} m")
        for name, sim in (extra or {}).items():
            ax.plot(sim["t"], sim[key], color="tab:green", lw=0.9, ls="--", label=f"cracklab, {name}")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("time (s)")
    axes[0].set_title(title, fontsize=10)
    return fig


def front_figure(ref_t, ref_rate, t_r, runs, series, title, *, ref_label, colours, after, alpha=0.55,
                 threshold=None, height=3.6):
    """The slip rate of one station around its rupture time ``t_r`` (from 0.3 s before to
    ``after`` s after it): the reference and each run of ``runs``."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, height))
    ax.plot(ref_t, ref_rate, color="k", lw=2.2, alpha=alpha, label=ref_label)
    for name, st in runs.items():
        sim = series(st)
        ax.plot(sim["t"], sim["rate"], color=colours.get(name), lw=1.0, label=f"cracklab, {name} m")
    ax.set_xlim(t_r - 0.3, t_r + after)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slip rate (m/s)")
    if threshold is not None:
        ax.axhline(threshold, color="0.5", lw=0.5)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=10)
    return fig
