"""``cracklab run``: one scene into a Zarr store (resumable), or a dry run."""
from __future__ import annotations

import json
import sys

import click

from .common import CONTEXT, disk_line, fmt_time, exit_interrupted, load_scene, print_note, fail, main


def _dry_run_scene(sc, source: str, output=None) -> bool:
    """Print what a run of ``sc`` would take; False when it does not fit in memory or on
    the disk of ``output``."""
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
    from ..output.disk import output_size

    line, on_disk = disk_line(output_size(sc), output)
    click.echo(line)
    if verdict != "fits":
        click.echo("  run time  not calibrated (the run does not fit in memory)")
        return False
    cal = calibrate(sc)
    click.echo(f"  run time  about {fmt_time(cal['setup_s'] + cal['run_s'])} ({cal['ms_per_step']:.3g} ms per "
               f"step over {cal['steps_timed']} timed steps, setup {cal['setup_s']:.2g} s)")
    return on_disk


RUN_FLAGS = {"checkpoint_every": "--checkpoint-every", "resume": "--resume"}


def _when(sc, step) -> str:
    """"t = 5.77 s" of ``step`` (the time unit of the scene, none for "1")."""
    u = sc.units["time"]
    return f"t = {step * sc.dt:.4g}{'' if u == '1' else ' ' + u}"


def _outcome(sc, first, wall, result=None) -> str:
    """The line that ends a complete run: steps run, simulated time, wall time (a sequence:
    its accepted steps, their range and its events)."""
    if sc.sequence is not None and result is not None:
        u = sc.units["time"]
        unit = "" if u == "1" else " " + u
        resumed = result.attrs.get("cracklab_resumed_from")
        return (f"complete: {'resumed after accepted step %d, ' % resumed if resumed is not None else ''}"
                f"{result.attrs['accepted_steps']} accepted steps of {result.attrs['smallest_step']:.3g} to "
                f"{result.attrs['largest_step']:.3g}{unit} (t = {sc.t_end:.4g}{unit} simulated), "
                f"{result.sizes.get('event', 0)} events, in {fmt_time(wall)} wall"
                + (f" ({fmt_time(result.attrs['wall_time_in_events'])} of it stepping in events)"
                   if "wall_time_in_events" in result.attrs else ""))
    if first:
        return (f"complete: resumed from step {first}, ran steps {first + 1} to {sc.nsteps} ({_when(sc, first)} "
                f"to {_when(sc, sc.nsteps)[4:]} simulated) in {fmt_time(wall)} wall")
    return (f"complete: ran {sc.nsteps} steps ({_when(sc, sc.nsteps)} simulated) in {fmt_time(wall)} wall")


def _scene_of(scene: str, sets, allow):
    """The scene SCENE names: a TOML file or a store, else a registered builder called
    with the ``--set`` assignments (as ``cracklab new``)."""
    import os

    from ..errors import InputError
    from ..scenes.registry import registered_builders

    if os.path.exists(scene):
        if sets:
            raise click.UsageError(f"--set is for a builder's arguments ({scene} is a file: edit it, or write "
                                   f"a new one with cracklab new)")
        return load_scene(scene, allow=allow)
    if scene in registered_builders():
        from .cmd_new import build

        return build(scene, sets)
    raise InputError("SCENE", f"{scene!r}: no such file or store, nor a scene builder (cracklab new --list "
                              f"lists them)")


@main.command(context_settings=CONTEXT)
@click.argument("scene")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="With SCENE a builder's name: an argument of the builder or a scene path, as for "
                   "cracklab new (repeatable): cracklab run tpv3 --set dx=400 -o tpv3.zarr.")
@click.option("-o", "--output", default=None, type=click.Path(), help="Zarr store to write (required but "
              "with --dry-run): a local path, or a URL (s3://...; both checkpointed).")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--checkpoint-every", default=None, metavar="N|Ss",
              help="Checkpoint the run into OUTPUT every N steps, or every S seconds of wall time "
                   "('60s'); 0: never. Default: every 60 s (at most 10 % of the run time).")
@click.option("--resume/--no-resume", default=True, show_default=True,
              help="When OUTPUT holds an unfinished run of the same scene (killed, interrupted), continue "
                   "it from its last checkpoint (same results); when it holds the complete run, do nothing. "
                   "--no-resume starts the run over.")
@click.option("--overwrite", is_flag=True,
              help="Replace OUTPUT even when it holds the run of another scene (refused otherwise). Only "
                   "cracklab run stores are replaced, never other files or folders.")
@click.option("--dry-run", is_flag=True,
              help="Print the memory estimate, the output's size bound and the free disk space, the steps "
                   "and an estimated run time (from a few timed steps); write nothing.")
@click.option("--no-memory-check", is_flag=True,
              help="Run even when the memory estimate exceeds the memory available.")
@click.option("--no-disk-check", is_flag=True,
              help="Run even when the bound on the output's size exceeds the free space of OUTPUT's disk.")
@click.option("--allow-files", "allow", multiple=True, metavar="DIR", type=click.Path(file_okay=False),
              help="Also read the scene's field files from DIR (repeatable); without it a scene reads them "
                   "only from its own folder and below (and the folders of env CRACKLAB_ALLOW_FILES).")
def run(scene: str, sets, output, progress, checkpoint_every, resume, overwrite, dry_run, no_memory_check,
        no_disk_check, allow) -> None:
    """Run SCENE (a TOML scene, the Zarr store of an earlier run, or the name of a scene
    builder with its --set arguments) into OUTPUT.

    Ends with a line on stderr saying how it ended: complete (the steps run, the simulated
    and the wall time; or resumed from step N), interrupted at step N, or failed (the
    error; what was recorded is kept in OUTPUT), and "wrote OUTPUT" on stdout. A builder's
    scene as a file: cracklab new tpv3 dx=400 -o tpv3.toml.

    Ctrl-C stops the run after the step in progress and checkpoints it: the same command
    continues it. Exit status 130 when interrupted, 1 on an error."""
    import time
    import warnings

    from ..errors import InputError, Interrupted, SimulationError, StoreError, StoreWarning
    from ..output import checkpoint
    from ..output.simulate import simulate

    try:
        sc = _scene_of(scene, sets, allow)
    except (InputError, StoreError) as exc:
        raise fail(exc) from None
    if dry_run:
        if not _dry_run_scene(sc, scene, output):
            sys.exit(1)
        return
    if output is None:
        raise click.UsageError("Missing option '-o' / '--output' (the Zarr store to write).")
    if progress is None:
        progress = sys.stderr.isatty()
    path = checkpoint.local_path(output)
    done, first = False, 0
    if path is None:            # a URL: its Store keeps the checkpoints
        from ..output.stores import store_for

        try:
            path = store_for(output)
            path.check()        # its scheme, credentials and bucket, before any step
        except StoreError as exc:
            raise fail(exc) from None
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
                if resume and not done:
                    first = int(checkpoint.read_entry(path, "n") or 0)
            else:
                if overwrite and kind in ("other", "ensemble"):
                    what = "an ensemble store (cracklab sweep)" if kind == "ensemble" else \
                        "not a cracklab run store (nor empty)"
                    raise StoreError(path, f"exists and is {what}; --overwrite replaces only cracklab run "
                                           f"stores: choose another -o, or delete it yourself")
                resume = False              # nothing of this scene to continue
    except (StoreError, InputError) as exc:
        raise fail(exc, RUN_FLAGS) from None
    t0 = time.monotonic()
    caught = []
    try:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", StoreWarning)
                result = simulate(sc, progress=progress, store=output, checkpoint_every=checkpoint_every,
                                  resume=resume, check_memory=not no_memory_check, check_disk=not no_disk_check)
        finally:
            # shown once the recording has stopped: while it records, showwarning appends to ``caught``
            for w in caught:
                if issubclass(w.category, StoreWarning):
                    click.echo(f"cracklab: {w.message}", err=True)
                else:
                    warnings.showwarning(w.message, w.category, w.filename, w.lineno)
        if any(issubclass(w.category, StoreWarning) for w in caught):
            done, first = False, 0              # a damaged store: the run was done again from the start
    except Interrupted as exc:
        exit_interrupted(f"interrupted at step {exc.step}; {_when(sc, exc.step)} simulated of t_end = {sc.t_end:g}, "
                     f"{fmt_time(time.monotonic() - t0)} wall; rerun the same command to resume")
    except KeyboardInterrupt:
        step = checkpoint.read_entry(path, "n") if path is not None else None
        exit_interrupted(f"interrupted at step {step}; rerun the same command to resume" if step is not None else
                     "interrupted before the first checkpoint; rerun the same command to start again")
    except SimulationError as exc:
        kept = f"; what was recorded up to it is kept in {output} (status failed)" if output else ""
        raise click.ClickException(f"the run failed after {fmt_time(time.monotonic() - t0)} wall: {exc}"
                                   f"{kept}") from None
    except (StoreError, InputError) as exc:
        raise fail(exc, RUN_FLAGS) from None
    if done:
        click.echo(f"cracklab: {output} holds this run, complete (checked); nothing to do (--no-resume computes "
                   f"it again)")
    else:
        print_note(_outcome(sc, first, time.monotonic() - t0, result))
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
