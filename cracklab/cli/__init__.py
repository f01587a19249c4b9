"""Command-line entry point (``cracklab``)."""
from __future__ import annotations

import json
import os
import sys

import click


@click.group()
@click.version_option(package_name="cracklab")
def main() -> None:
    """cracklab: spectral boundary-integral simulation of dynamic fracture."""


@main.command()
@click.option("--out", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory to write demo output into.")
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

    ok = cracklab.cli.demo.main(out=out, scheduler=scheduler, workers=workers, lamb=not no_lamb)
    if ok is False:
        sys.exit(1)


def _load_scene(path: str):
    from ..errors import InputError

    if path.endswith(".toml"):
        from ..model.scene_io import scene_from_toml_file

        return scene_from_toml_file(path)    # file references relative to its directory
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


@main.command()
@click.argument("scene", type=click.Path(exists=True))
@click.option("-o", "--output", required=True, type=click.Path(), help="Zarr store to write.")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--checkpoint-every", default=None, metavar="N|Ss",
              help="Checkpoint the run into OUTPUT every N steps, or every S seconds of wall time "
                   "('60s'); 0: never. Default: every 60 s (at most 10 % of the run time).")
@click.option("--resume", is_flag=True,
              help="Continue the run killed in OUTPUT from its last checkpoint (same results); "
                   "starts over when there is none, does nothing when OUTPUT is complete.")
def run(scene: str, output: str, progress, checkpoint_every, resume) -> None:
    """Run SCENE (a TOML scene or the Zarr store of an earlier run) into OUTPUT."""
    from ..errors import InputError, SimulationError, StoreError
    from ..output.simulate import simulate

    try:
        sc = _load_scene(scene)
    except InputError as exc:
        raise click.ClickException(str(exc)) from None
    if progress is None:
        progress = sys.stderr.isatty()
    import warnings

    from ..errors import StoreWarning

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", StoreWarning)
            try:
                simulate(sc, progress=progress, store=output, checkpoint_every=checkpoint_every, resume=resume)
            finally:
                for w in caught:
                    if issubclass(w.category, StoreWarning):
                        click.echo(f"cracklab: {w.message}", err=True)
                    else:
                        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    except (SimulationError, StoreError, InputError) as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"cracklab: wrote {output}")


@main.command()
@click.argument("study", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(), help="Zarr store of the ensemble.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Address of a running dask scheduler (default: env DASK_SCHEDULER_ADDRESS, "
                   "else an embedded LocalCluster).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the embedded LocalCluster (default: one per core).")
@click.option("--resume/--no-resume", default=True, show_default=True,
              help="Skip members already complete in OUTPUT.")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
@click.option("--import", "imports", multiple=True, metavar="MODULE",
              help="Import this Python module first (repeatable): a module of yours that registers "
                   "scene builders with cracklab.register_builder. A study file itself never imports "
                   "code: it names only registered builders.")
def sweep(study: str, output: str, scheduler, workers, resume, progress, imports) -> None:
    """Run the ensemble of STUDY (a STUDY.toml, see docs/ensembles.md) into OUTPUT.

    Exits with status 1 when a member failed (the failures are listed, and recorded
    with their error in the member's group); a rerun redoes only what is not complete.
    A second sweep into an OUTPUT that another sweep is running into is refused
    (a lock file in the store; a lock left by a killed sweep is taken over)."""
    import importlib

    from ..ensemble import run_study
    from ..errors import InputError

    for module in imports:
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - reported as one clear line
            raise click.ClickException(f"--import: cannot import {module!r}: {type(exc).__name__}: {exc}") from None
    try:
        result = run_study(study, output, scheduler=scheduler, workers=workers, resume=resume,
                           progress=progress)
    except InputError as exc:
        raise click.ClickException(str(exc)) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"store: cannot write {output}: {exc.strerror or exc}") from None
    click.echo(f"cracklab: {result.summary()}")
    if not result.ok:
        sys.exit(1)


PLOT_KINDS = ("all", "snapshot", "rupture", "length", "summary", "panels", "gif")


@main.command()
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
def plot(store, output, kind, field, time_, member, by, x_param) -> None:
    """Figures of a run or of an ensemble STORE (PNG, or GIF for --kind gif)."""
    from pathlib import Path

    import xarray as xr

    from .. import plots as P
    from ..ensemble import open_ensemble, store_kind
    from ..errors import InputError, StoreError

    try:
        ens = store_kind(store) == "ensemble"
        ds = open_ensemble(store) if ens else xr.open_zarr(store, consolidated=False)
    except (InputError, StoreError) as exc:
        raise click.ClickException(str(exc)) from None
    stem = Path(store.rstrip("/")).name.removesuffix(".zarr")
    parent = Path(store.rstrip("/")).parent
    if member is not None and member.isdigit() and ens and member not in set(map(str, ds.member.values)):
        member = int(member)
    try:
        if kind == "all":
            out = Path(output) if output else parent / f"{stem}_plots"
            paths = P.summary_figures(ds, out, field=field, by=by, x=x_param, gif_member=member)
        else:
            ext = "gif" if kind == "gif" else "png"
            out = Path(output) if output else parent / f"{stem}_{kind}.{ext}"
            if kind in ("summary", "panels") and not ens:
                raise click.ClickException(f"--kind {kind} needs an ensemble store")
            if kind == "snapshot":
                P.snapshot(ds, field, t=time_, member=member, path=out)
            elif kind == "rupture":
                P.rupture_contours(ds, member=member, path=out)
            elif kind == "length":
                P.crack_length_plot(ds if member is None else P._member(ds, member), by=by, path=out)
            elif kind == "summary":
                P.ensemble_summary(ds, by=by, x=x_param, path=out)
            elif kind == "panels":
                P.ensemble_panels(ds, path=out)
            else:
                P.animate(ds, out, field, member=member)
            paths = [out]
    except (ValueError, KeyError) as exc:
        raise click.ClickException(str(exc)) from None
    for p in paths:
        click.echo(f"cracklab: wrote {p}")


@main.command()
@click.argument("store", type=click.Path(exists=True))
@click.option("--netcdf", "netcdf", required=True, type=click.Path(dir_okay=False),
              help="netCDF4 file to write.")
@click.option("--member", default=None, help="Only this ensemble member (default: the whole ensemble).")
def export(store, netcdf, member) -> None:
    """Write a run or an ensemble STORE (or one --member of it) to a netCDF4 file."""
    from ..ensemble import export_netcdf
    from ..errors import InputError, StoreError

    try:
        out = export_netcdf(store, netcdf, member=member)
    except (InputError, StoreError) as exc:
        raise click.ClickException(str(exc)) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"--netcdf: cannot write {netcdf}: {exc.strerror or exc}") from None
    click.echo(f"cracklab: wrote {out}")


@main.command()
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


@main.command()
@click.option("--n1", type=int, default=256, show_default=True)
@click.option("--n3", type=int, default=256, show_default=True)
@click.option("--mode", type=click.Choice(["I", "II", "III", "shear"]), default=None,
              help="Fracture mode of the load  [default: I, shear with a friction --law]")
@click.option("--steps", "nsteps", type=int, default=200, show_default=True)
@click.option("--engine", default="exponential", show_default=True)
@click.option("--threads", type=int, default=1, show_default=True,
              help="Threads for the FFTs and the history engine (more than one helps only on an "
                   "otherwise idle machine).")
@click.option("--engine-threads", type=int, default=None,
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
                   "n1 x 2 n3 one (docs/performance.md, 'Free surface by mirror symmetry').")
@click.option("--bimaterial", is_flag=True,
              help="A bottom half space of another material (mu 0.6, c_s 0.8 times the top's, nu 0.3; the "
                   "product scheme): to set against the same bench of one material "
                   "(docs/performance.md, 'Bimaterial interface').")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def bench(n1, n3, mode, nsteps, engine, threads, engine_threads, fit_steps, law, free_surface, bimaterial,
          as_json) -> None:
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
        raise click.ClickException(str(exc)) from None
    if as_json:
        click.echo(json.dumps(result))
    else:
        for k, v in result.items():
            if k.startswith("newton") and v is None:
                continue
            click.echo(f"{k:>22}: {v:.4g}" if isinstance(v, float) else f"{k:>22}: {v}")


if __name__ == "__main__":
    main()
