"""``cracklab sweep``: the ensemble of a study file into one Zarr store on dask, or a dry run."""
from __future__ import annotations

import os
import sys

import click

from ..ensemble.clusters import KINDS
from .common import CONTEXT, disk_line, fmt_time, exit_interrupted, load_toml, fail, main


SWEEP_FLAGS = {"scheduler": "--scheduler", "store": "-o", "workers": "--workers", "cluster": "--cluster",
               "cluster_options": "--cluster-option"}


@main.command(context_settings=CONTEXT)
@click.argument("study", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", default=None, type=click.Path(), help="Zarr store of the ensemble (required "
              "but with --dry-run).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Address of a running dask scheduler (default: env DASK_SCHEDULER_ADDRESS, "
                   "else an embedded LocalCluster); one that cannot be reached within 5 s is an error.")
@click.option("--cluster", type=click.Choice(list(KINDS), case_sensitive=False), default=None,
              help="Run the workers as batch jobs of this system (dask-jobqueue), submitted from here and "
                   "cancelled at the end; OUTPUT must be reachable from the nodes (an object store URL, or "
                   "a shared file system). See docs/guide/cluster.md.")
@click.option("--cluster-option", "cluster_options", multiple=True, metavar="KEY=VALUE",
              help="An option of the --cluster jobs (repeatable): queue, account, walltime, memory, cores, "
                   "processes, job_extra_directives, ... (dask-jobqueue's names; over dask's jobqueue "
                   "configuration). Default: one core and one worker per job, memory for the largest member.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the embedded LocalCluster (default: one per core, as many as "
                   "the memory holds), or with --cluster of the batch jobs in all (default: one per member "
                   "to run).")
@click.option("--resume/--no-resume", default=True, show_default=True,
              help="Skip members already complete in OUTPUT.")
@click.option("--overwrite", is_flag=True,
              help="Replace OUTPUT even when it holds the ensemble of another study (refused otherwise).")
@click.option("--dry-run", is_flag=True,
              help="Check every member, print the members, their steps and memory, and an estimated run "
                   "time (from a few timed steps of the largest member); start nothing.")
@click.option("--no-memory-check", is_flag=True,
              help="Run even when the members' memory exceeds the memory available.")
@click.option("--no-disk-check", is_flag=True,
              help="Run even when the bound on the members' output exceeds the free space of OUTPUT's disk.")
@click.option("--allow-files", "allow", multiple=True, metavar="DIR", type=click.Path(file_okay=False),
              help="Also read the field files of the study's base scene (study.scene) from DIR (repeatable); "
                   "without it they are read only from that scene file's folder and below.")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--import", "imports", multiple=True, metavar="MODULE",
              help="Import this Python module first (repeatable): a module of yours that registers "
                   "scene builders with cracklab.register_builder. A study file itself never imports "
                   "code: it names only registered builders.")
def sweep(study: str, output, scheduler, cluster, cluster_options, workers, resume, overwrite, dry_run,
          no_memory_check, no_disk_check, allow, progress, imports) -> None:
    """Run the ensemble of STUDY (a STUDY.toml, see docs/guide/ensembles.md) into OUTPUT.

    Every member's scene paths and parameter types are checked, and its memory estimated,
    before any worker starts. Exits with status 1 when a member failed (the failures are
    listed, and recorded with their error in the member's group); a rerun redoes only what
    is not complete. A second sweep into an OUTPUT that another sweep is running into is
    refused (a lock file in the store; a lock left by a killed sweep is taken over).
    Ctrl-C stops the sweep (exit status 130): the same command resumes it."""
    import importlib

    from ..ensemble import load_study, run_study
    from ..ensemble.clusters import parse_options
    from ..errors import InputError, StoreError

    for module in imports:
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - reported as one clear line
            raise click.ClickException(f"--import: cannot import {module!r}: {type(exc).__name__}: {exc}") from None
    try:
        load_toml(study, "a study: [study], [base], [sweep], [[members]]")
        spec = load_study(study, allow=allow)
        if cluster is not None and scheduler is not None:
            raise click.UsageError("give one of --cluster and --scheduler: --cluster starts its own scheduler here")
        options = parse_options(cluster_options)
        if options and cluster is None:
            raise click.UsageError("--cluster-option is for the jobs of --cluster; give --cluster KIND (one of "
                                   f"{', '.join(KINDS)})")
        if dry_run:
            if not _dry_run_sweep(spec, study, output, workers, resume, cluster=cluster, options=options):
                sys.exit(1)
            return
        if output is None:
            raise click.UsageError("Missing option '-o' / '--output' (the Zarr store of the ensemble).")
        result = run_study(spec, output, scheduler=scheduler, workers=workers, resume=resume,
                           progress=progress, overwrite=overwrite, check_memory=not no_memory_check,
                           check_disk=not no_disk_check, cluster=cluster, cluster_options=options)
    except (InputError, StoreError) as exc:
        if isinstance(exc, InputError) and exc.field == "cluster_options":     # the option's own words
            raise click.ClickException(f"--cluster-option: {str(exc)[len(exc.field) + 2:]}") from None
        raise fail(exc, SWEEP_FLAGS) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"store: cannot write {output}: {exc.strerror or exc}") from None
    except KeyboardInterrupt:
        exit_interrupted(_sweep_interrupted(output))
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


def _dry_run_sweep(spec, source, output, workers, resume, cluster=None, options=None) -> bool:
    """Print what the sweep of ``spec`` would take; False when it does not fit in memory or
    on the disk of ``output``. With ``cluster``: the batch jobs it would submit (their
    options checked; nothing submitted) instead of the local worker processes."""
    from ..ensemble import plan
    from ..ensemble.running import cores, preflight
    from ..ensemble.store import is_complete, store_str
    from ..errors import MemoryBudgetError
    from ..solver.budget import PROCESS_BYTES, available_memory, calibrate, check_memory, fmt_bytes

    members = plan(spec.base, spec.sweep)
    outputs = {}
    estimates = preflight(spec.base, members, sweep=spec.sweep, outputs=outputs)
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
    if cluster is not None:
        return _dry_run_cluster(cluster, options, workers, len(todo), largest) and \
            _dry_run_disk(outputs, known, output)
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
    on_disk = _dry_run_disk(outputs, known, output)
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
    click.echo(f"  run time  about {fmt_time(wall)} on {n} worker{'s' if n > 1 else ''} ({fmt_time(sum(per.values()))} "
               f"of member runs; the largest timed: {cal['ms_per_step']:.3g} ms per step over {cal['steps_timed']} "
               f"steps)")
    return on_disk


def _dry_run_disk(outputs, known, output) -> bool:
    """Print the dry run's disk line; whether the output fits."""
    from ..ensemble.running import sweep_output

    sizes = [outputs[mid] for mid in known if mid in outputs]
    if not sizes:
        return True
    label = f"{len(sizes)} members' output" if len(sizes) != 1 else "1 member's output"
    line, on_disk = disk_line(sweep_output(sizes), output, what="the sweep", reuse=False, label=label)
    click.echo(line)
    return on_disk


def _dry_run_cluster(kind, options, workers, ntodo, largest) -> bool:
    """Print the batch jobs a --cluster sweep would submit (the options checked as the sweep
    checks them, MemoryBudgetError included; nothing submitted)."""
    import math

    from ..ensemble.clusters import check_kind, job_options

    kind = check_kind(kind)
    opts = job_options(kind, options or {}, largest.total)
    n = max(1, min(workers or ntodo, ntodo))
    jobs = math.ceil(n / opts["processes"])
    shown = ", ".join(f"{k}={v}" for k, v in sorted(opts.items()) if k not in ("job_script_prologue",
                                                                                  "scheduler_options"))
    click.echo(f"  memory    largest member {largest.describe()}")
    click.echo(f"  cluster   {jobs} {kind} job{'s' if jobs != 1 else ''} for {n} worker{'s' if n != 1 else ''} "
               f"({shown}); not submitted")
    return True
