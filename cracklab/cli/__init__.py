"""Command-line entry point (``cracklab``).

Every command takes ``-h`` / ``--help``, writes its output where ``-o`` says, reports a bad
input as one line naming the option typed (``Error: --n1: ...``), refuses to replace an
output that holds another scene's results unless ``--overwrite``, and ends on Ctrl-C with
exit status 130 and one line saying where to pick up."""
from __future__ import annotations

import json
import os
import sys

import click

CONTEXT = {"help_option_names": ["-h", "--help"]}
INTERRUPTED = 130       # exit status on Ctrl-C (128 + SIGINT), as shells report it


@click.group(context_settings=CONTEXT)
@click.version_option(package_name="cracklab")
def main() -> None:
    """cracklab: spectral boundary-integral simulation of dynamic fracture."""


def fail(exc, flags: dict | None = None):
    """A ClickException for ``exc``, an InputError named in terms of the options typed:
    ``flags`` maps an error's field (or its first part) to the option, e.g.
    {"grid.n1": "--n1", "checkpoint_every": "--checkpoint-every"}:
    "--n1 (grid.n1): must be ...", "--checkpoint-every: must be ..."."""
    from ..errors import InputError

    text = str(exc)
    if isinstance(exc, InputError) and flags:
        field = exc.field
        flag = flags.get(field) or flags.get(field.split(".")[0])
        if flag is not None and flag != field:
            rest = text[len(field) + 2:] if text.startswith(field + ": ") else text
            same = flag.lstrip("-").replace("-", "_") == field
            text = f"{flag}: {rest}" if same else f"{flag} ({field}): {rest}"
    return click.ClickException(text)


def _interrupted(line: str):
    click.echo(f"cracklab: {line}", err=True)
    sys.exit(INTERRUPTED)


@main.command(context_settings=CONTEXT)
@click.option("-o", "--out", "--output", "out", default="out", show_default=True,
              type=click.Path(file_okay=False), help="Directory to write demo output into.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run the ensemble on this dask scheduler (default: env DASK_SCHEDULER_ADDRESS, "
                   "else an embedded local cluster).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the local cluster (default: one per core).")
@click.option("--no-lamb", is_flag=True, help="Skip the Lamb verification figure.")
def demo(out: str, scheduler, workers, no_lamb) -> None:
    """Run the demonstration: the asperity ensemble of studies/asperity_ensemble on a
    local dask cluster into OUT/ensemble.zarr with summary figures OUT/*.png, and
    Lamb's problem against Pekeris (OUT/lamb.zarr, OUT/lamb.png)."""
    import cracklab.cli.demo

    from ..errors import InputError

    try:
        ok = cracklab.cli.demo.main(out=out, scheduler=scheduler, workers=workers, lamb=not no_lamb)
    except InputError as exc:
        raise fail(exc, {"scheduler": "--scheduler"}) from None
    except KeyboardInterrupt:
        _interrupted("interrupted; rerun the same command to resume (complete members are kept)")
    if ok is False:
        sys.exit(1)


def _read_toml(path: str, what: str) -> dict:
    """The tables of a TOML input file: one InputError for a binary file, malformed TOML or
    an empty file (``what``: "a scene", "a study")."""
    from ..errors import InputError
    from ..model.scene_io import read_toml_file

    data = read_toml_file(path)
    if not data:
        raise InputError(path, f"is empty: no TOML tables or keys (expected {what}; see docs/guide/getting_started.md)")
    return data


def _load_scene(path: str):
    from ..errors import InputError

    if path.endswith(".toml") or not os.path.isdir(path):     # a scene TOML, whatever its name
        from pathlib import Path

        from ..model.scene_io import scene_from_data

        data = _read_toml(path, "a scene: [material], [grid], [law], [loading], t_end")
        return scene_from_data(data, base=Path(path).absolute().parent)  # file references relative to it
    import xarray as xr

    from ..output.simulate import scene_of

    try:
        ds = xr.open_zarr(path, consolidated=False)
    except Exception as exc:  # noqa: BLE001 - reported as one clear line
        raise InputError(path, f"cannot open as a scene TOML or a cracklab Zarr store: {exc}") from None
    if "scene" not in ds.attrs:
        raise InputError(path, "is a Zarr store but not a cracklab run (no 'scene' attribute)")
    from ..output.checkpoint import RUN_FORMAT

    fmt = ds.attrs.get("cracklab_run_format", RUN_FORMAT)
    if not isinstance(fmt, int) or fmt > RUN_FORMAT:
        raise InputError(path, f"was written by cracklab {ds.attrs.get('cracklab_version', '?')} in store "
                               f"format {fmt!r}; this cracklab reads formats up to {RUN_FORMAT}")
    return scene_of(ds)


def _fmt_time(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.3g} s"
    if seconds < 5400:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


def _dry_run_scene(sc, source: str) -> bool:
    """Print what a run of ``sc`` would take; False when it does not fit in memory."""
    from ..errors import MemoryBudgetError
    from ..history import resolve_engine
    from ..solver.budget import available_memory, calibrate, check_memory, fmt_bytes, run_memory

    est = run_memory(sc)
    g = sc.grid
    rec = sc.record
    nsnap = len(rec.snapshot_steps(sc.nsteps, sc.dt)) if rec.fields else 0
    click.echo(f"cracklab: dry run of {sc.name!r} ({source}); nothing is written")
    click.echo(f"  grid      {g.n1} x {g.n3}{' (half plane)' if g.free_surface else ''}, components "
               f"{', '.join(map(str, sc.components))}, {sc.formulation} scheme, "
               f"{resolve_engine(sc.numerics.engine, sc.numerics.window)} engine")
    click.echo(f"  steps     {sc.nsteps} of dt = {sc.dt:.4g} (t_end = {sc.t_end:g}); {nsnap} snapshots of "
               f"{', '.join(rec.fields) or 'no field'}, {len(rec.stations or {})} stations")
    avail, source_mem = available_memory()
    try:
        check_memory(est)
        verdict = "fits"
    except MemoryBudgetError:
        verdict = "does NOT fit: the run would be refused"
    click.echo(f"  memory    {est.describe()}; {fmt_bytes(avail)} {source_mem}: {verdict}")
    if verdict != "fits":
        click.echo("  run time  not calibrated (the run does not fit in memory)")
        return False
    cal = calibrate(sc)
    click.echo(f"  run time  about {_fmt_time(cal['setup_s'] + cal['run_s'])} ({cal['ms_per_step']:.3g} ms per "
               f"step over {cal['steps_timed']} timed steps, setup {cal['setup_s']:.2g} s)")
    return True


RUN_FLAGS = {"checkpoint_every": "--checkpoint-every", "resume": "--resume"}


@main.command(context_settings=CONTEXT)
@click.argument("scene", type=click.Path(exists=True))
@click.option("-o", "--output", default=None, type=click.Path(), help="Zarr store to write (required but "
              "with --dry-run).")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--checkpoint-every", default=None, metavar="N|Ss",
              help="Checkpoint the run into OUTPUT every N steps, or every S seconds of wall time "
                   "('60s'); 0: never. Default: every 60 s (at most 10 % of the run time).")
@click.option("--resume/--no-resume", default=True, show_default=True,
              help="When OUTPUT holds an unfinished run of the same scene (killed, interrupted), continue "
                   "it from its last checkpoint (same results); when it holds the complete run, do nothing. "
                   "--no-resume starts the run over.")
@click.option("--overwrite", is_flag=True,
              help="Replace OUTPUT even when it holds the run of another scene (refused otherwise).")
@click.option("--dry-run", is_flag=True,
              help="Print the memory estimate, the steps and an estimated run time (from a few timed steps); "
                   "write nothing.")
@click.option("--no-memory-check", is_flag=True,
              help="Run even when the memory estimate exceeds the memory available.")
def run(scene: str, output, progress, checkpoint_every, resume, overwrite, dry_run, no_memory_check) -> None:
    """Run SCENE (a TOML scene or the Zarr store of an earlier run) into OUTPUT.

    Ctrl-C stops the run after the step in progress and checkpoints it: the same command
    continues it. Exit status 130 when interrupted, 1 on an error."""
    from ..errors import InputError, Interrupted, SimulationError, StoreError
    from ..output import checkpoint
    from ..output.simulate import simulate

    try:
        sc = _load_scene(scene)
    except InputError as exc:
        raise fail(exc) from None
    if dry_run:
        if not _dry_run_scene(sc, scene):
            sys.exit(1)
        return
    if output is None:
        raise click.UsageError("Missing option '-o' / '--output' (the Zarr store to write).")
    if progress is None:
        progress = sys.stderr.isatty()
    path = checkpoint.local_path(output)
    done = False
    try:
        if path is not None:
            kind, attrs = checkpoint.inspect(path)
            if kind == "run":
                same = _same_scene(sc, attrs)
                if not same and not overwrite:
                    raise StoreError(path, f"holds the run of another scene ({_scene_label(attrs)}); refusing to "
                                           f"replace it: choose another -o, or --overwrite")
                resume = resume and same and not overwrite
                done = resume and attrs.get("cracklab_status") == "complete"
            else:
                resume = False              # nothing of this scene to continue
    except (StoreError, InputError) as exc:
        raise fail(exc, RUN_FLAGS) from None
    import warnings

    from ..errors import StoreWarning

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", StoreWarning)
            try:
                simulate(sc, progress=progress, store=output, checkpoint_every=checkpoint_every, resume=resume,
                         check_memory=not no_memory_check)
            finally:
                for w in caught:
                    if issubclass(w.category, StoreWarning):
                        click.echo(f"cracklab: {w.message}", err=True)
                    else:
                        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
        done = done and not any(issubclass(w.category, StoreWarning) for w in caught)
    except Interrupted as exc:
        _interrupted(f"interrupted at step {exc.step}; rerun the same command to resume")
    except KeyboardInterrupt:
        step = checkpoint.read_entry(path, "n") if path is not None else None
        _interrupted(f"interrupted at step {step}; rerun the same command to resume" if step is not None else
                     "interrupted before the first checkpoint; rerun the same command to start again")
    except (SimulationError, StoreError, InputError) as exc:
        raise fail(exc, RUN_FLAGS) from None
    if done:
        click.echo(f"cracklab: {output} holds this run, complete (checked); nothing to do (--no-resume computes "
                   f"it again)")
    else:
        click.echo(f"cracklab: wrote {output}")


def _same_scene(sc, attrs) -> bool:
    from ..model.scene_io import scene_to_json
    from ..output.checkpoint import scene_digest

    text, inputs = scene_to_json(sc)
    if "cracklab_scene_digest" in attrs:
        return attrs["cracklab_scene_digest"] == scene_digest(text, inputs)
    return attrs.get("scene") == text


def _scene_label(attrs) -> str:
    try:
        name = json.loads(attrs.get("scene", "{}")).get("name", "?")
    except ValueError:
        name = "?"
    return f"scene {name!r}, status {attrs.get('cracklab_status', '?')}"


SWEEP_FLAGS = {"scheduler": "--scheduler", "store": "-o", "workers": "--workers"}


@main.command(context_settings=CONTEXT)
@click.argument("study", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", default=None, type=click.Path(), help="Zarr store of the ensemble (required "
              "but with --dry-run).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Address of a running dask scheduler (default: env DASK_SCHEDULER_ADDRESS, "
                   "else an embedded LocalCluster); one that cannot be reached within 5 s is an error.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the embedded LocalCluster (default: one per core, as many as "
                   "the memory holds).")
@click.option("--resume/--no-resume", default=True, show_default=True,
              help="Skip members already complete in OUTPUT.")
@click.option("--overwrite", is_flag=True,
              help="Replace OUTPUT even when it holds the ensemble of another study (refused otherwise).")
@click.option("--dry-run", is_flag=True,
              help="Check every member, print the members, their steps and memory, and an estimated run "
                   "time (from a few timed steps of the largest member); start nothing.")
@click.option("--no-memory-check", is_flag=True,
              help="Run even when the members' memory exceeds the memory available.")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--import", "imports", multiple=True, metavar="MODULE",
              help="Import this Python module first (repeatable): a module of yours that registers "
                   "scene builders with cracklab.register_builder. A study file itself never imports "
                   "code: it names only registered builders.")
def sweep(study: str, output, scheduler, workers, resume, overwrite, dry_run, no_memory_check, progress,
          imports) -> None:
    """Run the ensemble of STUDY (a STUDY.toml, see docs/guide/ensembles.md) into OUTPUT.

    Every member's scene paths and parameter types are checked, and its memory estimated,
    before any worker starts. Exits with status 1 when a member failed (the failures are
    listed, and recorded with their error in the member's group); a rerun redoes only what
    is not complete. A second sweep into an OUTPUT that another sweep is running into is
    refused (a lock file in the store; a lock left by a killed sweep is taken over).
    Ctrl-C stops the sweep (exit status 130): the same command resumes it."""
    import importlib

    from ..ensemble import load_study, run_study
    from ..errors import InputError

    for module in imports:
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - reported as one clear line
            raise click.ClickException(f"--import: cannot import {module!r}: {type(exc).__name__}: {exc}") from None
    try:
        _read_toml(study, "a study: [study], [base], [sweep], [[members]]")
        spec = load_study(study)
        if dry_run:
            if not _dry_run_sweep(spec, study, output, workers, resume):
                sys.exit(1)
            return
        if output is None:
            raise click.UsageError("Missing option '-o' / '--output' (the Zarr store of the ensemble).")
        result = run_study(spec, output, scheduler=scheduler, workers=workers, resume=resume,
                           progress=progress, overwrite=overwrite, check_memory=not no_memory_check)
    except InputError as exc:
        raise fail(exc, SWEEP_FLAGS) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"store: cannot write {output}: {exc.strerror or exc}") from None
    except KeyboardInterrupt:
        _interrupted(_sweep_interrupted(output))
    click.echo(f"cracklab: {result.summary()}")
    if not result.ok:
        sys.exit(1)


def _sweep_interrupted(output) -> str:
    try:
        from ..ensemble import member_status
        from ..ensemble.store import open_group, store_str

        status = member_status(output)
        done = sum(1 for s in status if s["complete"])
        total = len(open_group(store_str(output), "r").attrs.get("members", [])) or len(status)
        return f"interrupted with {done} of {total} members complete; rerun the same command to resume"
    except Exception:  # noqa: BLE001 - no store yet
        return "interrupted before any member completed; rerun the same command to resume"


def _dry_run_sweep(spec, source, output, workers, resume) -> bool:
    """Print what the sweep of ``spec`` would take; False when it does not fit in memory."""
    from ..ensemble import plan
    from ..ensemble.running import cores, preflight
    from ..ensemble.store import is_complete, store_str
    from ..errors import MemoryBudgetError
    from ..solver.budget import PROCESS_BYTES, available_memory, calibrate, check_memory, fmt_bytes

    members = plan(spec.base, spec.sweep)
    estimates = preflight(spec.base, members, sweep=spec.sweep)
    done = [m for m in members if output and resume and os.path.isdir(output) and is_complete(store_str(output), m.id)]
    todo = [m for m in members if m not in done]
    click.echo(f"cracklab: dry run of the study {spec.name!r} ({source}); every member checked, nothing is written")
    click.echo(f"  members   {len(members)}" + (f" ({len(done)} complete in {output}, {len(todo)} to run)" if done else ""))
    known = {m.id: estimates[m.id] for m in todo if estimates.get(m.id) is not None}
    bad = [m for m in todo if estimates.get(m.id) is None]
    if bad:
        click.echo(f"  note      {len(bad)} member(s) fail to build (a bad value): they would be recorded as failed")
    if not known:
        click.echo("  nothing to run")
        return True
    steps = [e.steps for e in known.values()]
    click.echo(f"  steps     {min(steps)}" + (f" to {max(steps)}" if max(steps) != min(steps) else "") + " per member")
    largest_id = max(known, key=lambda i: known[i].total)
    largest = known[largest_id]
    n = max(1, min(workers or cores(), len(known)))
    avail, source_mem = available_memory()
    if workers is None:
        while n > 1 and n * (largest.total + PROCESS_BYTES) > avail:
            n -= 1
    try:
        check_memory(largest, processes=n)
        verdict = "fits"
    except MemoryBudgetError:
        verdict = "does NOT fit: the sweep would be refused"
    click.echo(f"  memory    largest member {largest.describe()}; {n} worker process{'es' if n > 1 else ''}: "
               f"{fmt_bytes(n * (largest.total + PROCESS_BYTES))} of {fmt_bytes(avail)} {source_mem}: {verdict}")
    if verdict != "fits":
        return False
    from ..ensemble import build_scene

    by_id = {m.id: m for m in todo}

    def cost(mid):
        e = known[mid]
        return e.steps * (e.work + e.history)          # time scales about with the arrays swept per step

    big = max(known, key=cost)
    cal = calibrate(build_scene(spec.base, by_id[big].params))
    per = {mid: cal["setup_s"] + cal["run_s"] * cost(mid) / cost(big) for mid in known}
    wall = max(max(per.values()), sum(per.values()) / n)
    click.echo(f"  run time  about {_fmt_time(wall)} on {n} worker{'s' if n > 1 else ''} ({_fmt_time(sum(per.values()))} "
               f"of member runs; the largest timed: {cal['ms_per_step']:.3g} ms per step over {cal['steps_timed']} "
               f"steps)")
    return True


PLOT_KINDS = ("all", "snapshot", "rupture", "length", "summary", "panels", "gif")


def _note(text: str):
    click.echo(f"cracklab: {text}", err=True)


def _run_for_figures(ds, path, allow_partial, what):
    """A run's (or member's) Dataset with only what exists: cut to its complete snapshots,
    the rupture times of its checkpoint when the run is unfinished; notes what is shown."""
    import numpy as np

    from ..output import checkpoint

    progress = checkpoint.run_progress(path)
    if progress.status == "failed" and not allow_partial:
        raise click.ClickException(f"{what} failed ({progress.error or 'no error recorded'}); its figures would show "
                                   f"a partial run: pass --allow-partial to draw what it recorded")
    if progress.status != "complete":
        _note(f"{what} is {progress.describe()}; the figures show what exists")
        if "t" in ds.dims and progress.snapshots < ds.sizes["t"]:
            ds = ds.isel(t=slice(0, progress.snapshots))
        if "rupture_time" not in ds:
            rupture = checkpoint.read_entry(path, "rupture")
            if rupture is not None:
                from ..output.simulate import scene_of

                s1, s3 = scene_of(ds).record.region_slices(scene_of(ds).grid)
                values = np.asarray(rupture)[s1, s3]
                if values.shape == (ds.sizes.get("x1"), ds.sizes.get("x3")):
                    ds = ds.assign(rupture_time=(("x1", "x3"), values, {
                        "long_name": f"first time the point failed (up to step {progress.step})",
                        "units": ds["t"].attrs.get("units", "1")}))
    if not any("t" in ds[v].dims and ds.sizes["t"] > 0 for v in ds.data_vars) and "rupture_time" not in ds:
        raise click.ClickException(f"{what} holds nothing to draw yet ({progress.describe()})")
    return ds


def _pick_member(status, member, allow_partial):
    """The member id for --member (an id, or a position among the members in plan order)."""
    ids = [s["id"] for s in status]
    if member in ids:
        return member
    if member.lstrip("-").isdigit():
        i = int(member)
        if 0 <= i < len(ids):
            return ids[i]
        raise click.ClickException(f"--member {member}: no such member; the store has {len(ids)} member"
                                   f"{'s' if len(ids) != 1 else ''} (positions 0 to {len(ids) - 1}, or an id: "
                                   f"{', '.join(ids[:4])}{', ...' if len(ids) > 4 else ''})")
    raise click.ClickException(f"--member {member}: not a member id of this store (ids: {', '.join(ids[:4])}"
                               f"{', ...' if len(ids) > 4 else ''}; or give a position 0 to {len(ids) - 1})")


def _check_parameter(ds, option, name):
    """The coordinate name of the swept parameter ``name`` (--by, --x), or a clear error."""
    from ..ensemble import coordinate_name

    swept = json.loads(ds.attrs.get("swept", "[]"))
    names = {coordinate_name(p): p for p in swept}
    coord = coordinate_name(name)
    if coord in names and coord in ds.coords:
        return coord
    raise click.ClickException(f"{option} {name}: not a swept parameter of this ensemble; choose one of: "
                               f"{', '.join(p for p in swept if p not in ('builder',)) or 'none (nothing swept)'}")


def _check_time(ds, time_):
    import numpy as np

    t = ds["t"].values if "t" in ds.coords else np.zeros(0)
    if t.size == 0:
        raise click.ClickException("--time: this result has no snapshots")
    tol = 0.5 * (float(np.min(np.diff(t))) if t.size > 1 else abs(float(t[0])) or 1.0)
    if not (float(t[0]) - tol <= time_ <= float(t[-1]) + tol):
        raise click.ClickException(f"--time {time_:g}: outside the snapshots, t = {float(t[0]):g} to "
                                   f"{float(t[-1]):g} ({t.size} snapshot{'s' if t.size != 1 else ''})")


@main.command(context_settings=CONTEXT)
@click.argument("store", type=click.Path(exists=True))
@click.option("-o", "--output", type=click.Path(), default=None,
              help="Output file (one kind) or directory (--kind all); default next to STORE.")
@click.option("--kind", type=click.Choice(PLOT_KINDS), default="all", show_default=True,
              help="snapshot: a field at one time; rupture: rupture-time contours; length: mean "
                   "crack length vs t; summary / panels: ensemble figures; gif: animation.")
@click.option("--field", default="delta_2", show_default=True, help="Field for snapshot and gif.")
@click.option("--time", "time_", type=float, default=None, help="Snapshot time (default: the last).")
@click.option("--member", default=None, help="Ensemble member id (or position) for run figures.")
@click.option("--by", default=None, help="Ensemble parameter that colours the curves.")
@click.option("--x", "x_param", default=None, help="Ensemble parameter on the x axis of the summary.")
@click.option("--allow-partial", is_flag=True,
              help="Draw a failed run or member too (what it recorded before it failed).")
def plot(store, output, kind, field, time_, member, by, x_param, allow_partial) -> None:
    """Figures of a run or of an ensemble STORE (PNG, or GIF for --kind gif).

    Reads the store lazily (a frame at a time, thinned to the figure's size). An unfinished
    run or member is drawn up to its last complete snapshot, with a note; a failed one is
    refused unless --allow-partial."""
    from pathlib import Path

    import xarray as xr

    from .. import plots as P
    from ..ensemble import member_path, member_status, open_ensemble, open_member, store_kind
    from ..errors import InputError, StoreError

    try:
        ens = store_kind(store) == "ensemble"
    except (InputError, StoreError) as exc:
        raise fail(exc) from None
    if not ens:
        for option, value in (("--member", member), ("--by", by), ("--x", x_param)):
            if value is not None:
                raise click.ClickException(f"{option}: {store} is a single run, not an ensemble")
        if kind in ("summary", "panels"):
            raise click.ClickException(f"--kind {kind} needs an ensemble store")
    stem = Path(store.rstrip("/")).name.removesuffix(".zarr")
    parent = Path(store.rstrip("/")).parent
    try:
        if not ens:
            ds = _run_for_figures(xr.open_zarr(store, consolidated=False), store, allow_partial, f"the run in {store}")
        elif member is not None or kind in ("snapshot", "rupture", "gif"):
            status = member_status(store)
            if member is None and len(status) != 1:
                raise click.ClickException(f"--kind {kind} draws one member: give --member (an id, or a position "
                                           f"0 to {len(status) - 1})")
            mid = _pick_member(status, member, allow_partial) if member is not None else status[0]["id"]
            ds = _run_for_figures(open_member(store, mid), member_path(store, mid), allow_partial, f"member {mid}")
            ens = False
        else:
            status = member_status(store)
            bad = [s["id"] for s in status if not s["complete"] and s["status"] in ("failed", "damaged")]
            unfinished = [s["id"] for s in status if not s["complete"] and s["id"] not in bad]
            keep = None
            if bad and allow_partial:
                keep = [s["id"] for s in status if s["complete"] or s["id"] in bad]
            ds = open_ensemble(store) if keep is None else open_ensemble(store, members=keep, complete_only=False)
            shown = ds.sizes["member"]
            if by is not None:
                by = _check_parameter(ds, "--by", by)
            if x_param is not None:
                x_param = _check_parameter(ds, "--x", x_param)
            if bad or unfinished:
                parts = [f"{len(bad)} failed" if bad else "", f"{len(unfinished)} unfinished" if unfinished else ""]
                _note(f"{store}: {' and '.join(p for p in parts if p)} of {len(status)} members "
                      f"({', '.join((bad + unfinished)[:4])}{', ...' if len(bad + unfinished) > 4 else ''}); the "
                      f"figures show {shown} member{'s' if shown != 1 else ''}"
                      + ("" if allow_partial or not bad else "; --allow-partial adds what the failed ones recorded"))
    except (InputError, StoreError) as exc:
        raise fail(exc) from None
    if time_ is not None and kind in ("snapshot", "all"):
        _check_time(ds if "member" not in ds.dims else P._member(ds, 0), time_)
    if field not in ds.data_vars and kind in ("snapshot", "gif"):
        recorded = [v for v in ds.data_vars if "t" in ds[v].dims]
        raise click.ClickException(f"--field {field}: not recorded in this result; recorded: "
                                   f"{', '.join(recorded) or 'no field'}")
    try:
        if kind == "all":
            out = Path(output) if output else parent / f"{stem}_plots"
            paths = P.summary_figures(ds, out, field=field, by=by, x=x_param)
        else:
            ext = "gif" if kind == "gif" else "png"
            out = Path(output) if output else parent / f"{stem}_{kind}.{ext}"
            if kind in ("summary", "panels") and not ens:
                raise click.ClickException(f"--kind {kind} draws a whole ensemble; leave out --member")
            if kind == "snapshot":
                P.snapshot(ds, field, t=time_, path=out)
            elif kind == "rupture":
                if "rupture_time" not in ds:
                    raise click.ClickException("--kind rupture: no rupture times yet (they are written at the end "
                                               "of the run, and in its checkpoints)")
                P.rupture_contours(ds, path=out)
            elif kind == "length":
                P.crack_length_plot(ds, by=by, path=out)
            elif kind == "summary":
                P.ensemble_summary(ds, by=by, x=x_param, path=out)
            elif kind == "panels":
                P.ensemble_panels(ds, path=out)
            else:
                P.animate(ds, out, field)
            paths = [out]
    except (ValueError, KeyError) as exc:
        raise click.ClickException(str(exc)) from None
    except KeyboardInterrupt:
        _interrupted("interrupted; the figure was not written")
    if not paths:
        raise click.ClickException(f"nothing to draw in {store}")
    for p in paths:
        click.echo(f"cracklab: wrote {p}")


@main.command(context_settings=CONTEXT)
@click.argument("store", type=click.Path(exists=True))
@click.option("-o", "--output", "output", default=None, type=click.Path(dir_okay=False),
              help="netCDF4 file to write.")
@click.option("--netcdf", "netcdf", default=None, type=click.Path(dir_okay=False), hidden=True,
              help="The old name of -o.")
@click.option("--member", default=None, help="Only this ensemble member, by id or position (default: the whole "
              "ensemble, its complete members).")
@click.option("--overwrite", is_flag=True,
              help="Replace OUTPUT even when it is not an export of the same scene (refused otherwise).")
@click.option("--allow-partial", is_flag=True,
              help="Export a failed run or member too (what it recorded); with the whole ensemble, its failed "
                   "members too.")
def export(store, output, netcdf, member, overwrite, allow_partial) -> None:
    """Write a run or an ensemble STORE (or one --member of it) to a netCDF4 file.

    Read lazily and written chunk by chunk. An unfinished run or member is exported up
    to its last complete snapshot (with a note); a failed one is refused unless
    --allow-partial; nothing is written on an error."""
    from ..ensemble import export_netcdf, member_path, member_status, store_kind
    from ..errors import InputError, StoreError
    from ..output.checkpoint import run_progress

    if (output is None) == (netcdf is None):
        raise click.UsageError("give the netCDF file to write with -o (once)")
    flag = "-o" if netcdf is None else "--netcdf"
    output = output or netcdf
    try:
        ens = store_kind(store) == "ensemble"
        if member is not None and ens:
            member = _pick_member(member_status(store), member, allow_partial)
        progress = run_progress(member_path(store, member) if member else store) if (member or not ens) else None
        out = export_netcdf(store, output, member=member, allow_partial=allow_partial, overwrite=overwrite)
    except (InputError, StoreError) as exc:
        raise fail(exc, {"member": "--member", "output": flag}) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"{flag}: cannot write {output}: {exc.strerror or exc}") from None
    except KeyboardInterrupt:
        _interrupted("interrupted; nothing was written")
    if progress is not None and progress.status != "complete":
        _note(f"{'member ' + member if member else store} is {progress.describe()}; exported "
              f"{progress.snapshots} snapshot{'s' if progress.snapshots != 1 else ''}")
    elif ens and member is None:
        left = [s["id"] for s in member_status(store) if not s["complete"]]
        if left:
            _note(f"{len(left)} member{'s' if len(left) != 1 else ''} not complete "
                  f"{'(failed ones included) ' if allow_partial else ''}left out: {', '.join(left[:4])}"
                  f"{', ...' if len(left) > 4 else ''}")
    click.echo(f"cracklab: wrote {out}")

@main.command(context_settings=CONTEXT)
@click.argument("store", type=click.Path(exists=True, file_okay=False))
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write the table to this CSV file instead of printing it.")
def summary(store, output) -> None:
    """The parameters and summary measures of every member of an ensemble STORE (or of a
    run), one row per member: swept parameters, status, final crack length and growth,
    ruptured area, front position, width and speed, run time (cracklab.ensemble.summary)."""
    from ..analysis import summary as table_of
    from ..errors import InputError, StoreError

    try:
        table = table_of(store)
    except (InputError, StoreError) as exc:
        raise click.ClickException(str(exc)) from None
    if "member" not in table.dims:
        from pathlib import Path

        table = table.expand_dims(run=[Path(store.rstrip("/")).name])
    frame = table.to_dataframe()
    first = [c for c in table.coords if c in frame.columns]          # parameters and status, then the measures
    frame = frame[first + [c for c in frame.columns if c not in first]]
    if output:
        try:
            frame.to_csv(output)
        except OSError as exc:
            raise click.ClickException(f"-o: cannot write {output}: {exc.strerror or exc}") from None
        click.echo(f"cracklab: wrote {output} ({len(frame)} row{'s' if len(frame) != 1 else ''})")
        return
    import pandas as pd

    with pd.option_context("display.max_columns", None, "display.width", 200, "display.max_rows", None):
        click.echo(frame.to_string())


@main.command()
@click.argument("store", type=click.Path(exists=True, file_okay=False))
@click.option("--quick", is_flag=True,
              help="Check the metadata and that every chunk is present, without reading the data "
                   "(no checksums).")
def verify(store, quick) -> None:
    """Check every array of a run or an ensemble STORE: metadata, the arrays a run holds,
    every chunk present and (unless --quick) read with its checksum.

    Prints what is damaged (each file, and what to do) and exits with status 1 when
    anything is; 0 when the store is sound (an unfinished run or incomplete members are
    reported, and are not damage)."""
    from ..errors import StoreError
    from ..output.verify import verify as check

    try:
        report = check(store, read=not quick)
    except StoreError as exc:
        raise click.ClickException(str(exc)) from None
    lines = report.lines()
    click.echo(f"cracklab verify: {lines[0]}")
    for line in lines[1:]:
        click.echo(line)
    if not report.ok:
        sys.exit(1)


BENCH_FLAGS = {"materials": "--bimaterial", "grid.n1": "--n1", "grid.n3": "--n3", "grid": "--n1/--n3", "law": "--law", "mode": "--mode",
               "free_surface": "--free-surface", "grid.free_surface": "--free-surface",
               "numerics.engine": "--engine", "numerics.fft_threads": "--threads",
               "numerics.engine_threads": "--engine-threads", "t_end": "--steps", "beta": "--n1/--n3"}


@main.command(context_settings=CONTEXT)
@click.option("--n1", type=click.IntRange(min=2), default=256, show_default=True,
              help="Nodes along x1 (a fast FFT size: products of 2, 3, 5 and 7).")
@click.option("--n3", type=click.IntRange(min=1), default=256, show_default=True,
              help="Nodes along x3; 1: the plane problem.")
@click.option("--mode", type=click.Choice(["I", "II", "III", "shear", "mixed"]), default=None,
              help="Fracture mode of the load; mixed: all three components (the opening and both "
                   "slips, as a law that follows the normal traction runs)  [default: I, shear with a "
                   "friction --law]")
@click.option("--steps", "nsteps", type=click.IntRange(min=2), default=200, show_default=True,
              help="Steps of the run; the second half is timed.")
@click.option("--engine", type=click.Choice(["exponential", "direct", "auto"]), default="exponential",
              show_default=True, help="History engine (numerics.engine).")
@click.option("--threads", type=click.IntRange(min=1), default=1, show_default=True,
              help="Threads for the FFTs and the history engine (more than one helps only on an "
                   "otherwise idle machine).")
@click.option("--engine-threads", type=click.IntRange(min=1), default=None,
              help="Threads for the history engine only (default: --threads); with 2 or more it "
                   "advances its states on a thread of its own, overlapping the FFTs (fastest on two "
                   "cores: --threads 1 --engine-threads 2).")
@click.option("--fit-steps", type=click.IntRange(min=1), default=None,
              help="Fit the kernels for this many steps instead of the run's length (the exponential "
                   "engine's terms then do not depend on --steps).")
@click.option("--law", type=click.Choice(["traction_free", "slip_weakening", "rate_state"]), default="traction_free",
              show_default=True,
              help="traction_free: a random load on a traction-free plane; slip_weakening: a TPV3-like rupture; "
                   "rate_state: a TPV101-like rupture (ageing law, forced nucleation), which reports its Newton "
                   "evaluations and solves per point and step; the friction benches are shear ruptures on 100 m "
                   "cells with the same time-step rule.")
@click.option("--free-surface", is_flag=True,
              help="The half plane of n1 x (n3 + 1) nodes below a free surface on x3 = 0 (mirror symmetry, "
                   "Grid(free_surface=True)); to set against the periodic n1 x n3 grid and the doubled "
                   "n1 x 2 n3 one (docs/studies/performance.md, 'Free surface by mirror symmetry').")
@click.option("--bimaterial", is_flag=True,
              help="A bottom half space of another material (mu 0.6, c_s 0.8 times the top's, nu 0.3; the "
                   "product scheme): to set against the same bench of one material "
                   "(docs/studies/performance.md, 'Bimaterial interface').")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
@click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
              help="Also write the result as one JSON object to this file.")
def bench(n1, n3, mode, nsteps, engine, threads, engine_threads, fit_steps, law, free_surface, bimaterial,
          as_json, output) -> None:
    """Median cost per step (second half of the run) and a same-process FFT pair."""
    from .bench import run as run_bench
    from ..errors import InputError

    if mode is None:
        mode = "I" if law == "traction_free" else "shear"
    try:
        result = run_bench(n1, n3, mode, nsteps, engine, progress=not as_json and sys.stderr.isatty(),
                           threads=threads, engine_threads=engine_threads, fit_steps=fit_steps, law=law,
                           free_surface=free_surface, bimaterial=bimaterial)
    except InputError as exc:
        raise fail(exc, BENCH_FLAGS) from None
    except KeyboardInterrupt:
        _interrupted("interrupted; nothing was written")
    if output is not None:
        try:
            with open(output, "w") as fh:
                json.dump(result, fh)
                fh.write("\n")
        except OSError as exc:
            raise click.ClickException(f"-o: cannot write {output}: {exc.strerror or exc}") from None
    if as_json:
        click.echo(json.dumps(result))
    else:
        for k, v in result.items():
            if k.startswith("newton") and v is None:
                continue
            click.echo(f"{k:>22}: {v:.4g}" if isinstance(v, float) else f"{k:>22}: {v}")


if __name__ == "__main__":
    main()
