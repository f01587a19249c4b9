"""``cracklab plot``: the figures of a run or an ensemble store."""
from __future__ import annotations

import json

import click

from .common import CONTEXT, StoreArgument, exit_interrupted, output_beside, print_note, pick_member, fail, main


PLOT_KINDS = ("all", "snapshot", "rupture", "length", "summary", "panels", "gif", "stations")


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
        print_note(f"{what} is {progress.describe()}; the figures show what exists")
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


def _refuse_damaged(store):
    """Raise a StoreError naming ``store`` and the remedy when its listing shows damage (a missing
    chunk or array would be drawn as a blank picture), as ``cracklab export`` does."""
    from ..errors import StoreError
    from ..output.stores import store_for
    from ..output.verify import check_run

    report = check_run(store_for(store).tree(), read=False)     # a URL: its keys listed once
    if not report.ok:
        raise StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")


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
@click.argument("store", type=StoreArgument())
@click.option("-o", "--output", type=click.Path(), default=None,
              help="Output file (one kind) or directory (--kind all); default next to STORE (in the current "
                   "directory for a STORE at a URL).")
@click.option("--kind", type=click.Choice(PLOT_KINDS), default="all", show_default=True,
              help="snapshot: a field at one time; rupture: rupture-time contours; length: mean "
                   "crack length vs t; summary / panels: ensemble figures; gif: animation; stations: "
                   "station series of --field (default v_1) at every --station. A fault run's 'all' "
                   "draws rupture-time contours, final slip and station slip rates.")
@click.option("--station", "stations", multiple=True, help="Station to draw with --kind stations (repeat; "
              "default: all).")
@click.option("--field", default="delta_2", show_default=True, help="Field for snapshot and gif.")
@click.option("--time", "time_", type=float, default=None, help="Snapshot time (default: the last).")
@click.option("--member", default=None, help="Ensemble member id (or position) for run figures.")
@click.option("--by", default=None, help="Ensemble parameter that colours the curves.")
@click.option("--x", "x_param", default=None, help="Ensemble parameter on the x axis of the summary.")
@click.option("--allow-partial", is_flag=True,
              help="Draw a failed run or member too (what it recorded before it failed).")
def plot(store, output, kind, field, time_, member, by, x_param, allow_partial, stations) -> None:
    """Figures of a run or of an ensemble STORE (PNG, or GIF for --kind gif).

    Reads the store lazily (a frame at a time, thinned to the figure's size). An unfinished
    run or member is drawn up to its last complete snapshot, with a note; a failed one is
    refused unless --allow-partial; a damaged run store (a missing chunk or array) is
    refused, naming the damage and the remedy (cracklab verify STORE)."""
    from pathlib import Path

    import xarray as xr

    from .. import plots as P
    from ..ensemble import member_path, member_status, open_ensemble, open_member, store_kind
    from ..errors import InputError, StoreError
    from ..plots.common import member_of

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
    parent, stem = output_beside(store)
    try:
        if not ens:
            _refuse_damaged(store)
            from ..output.stores import zarr_of

            ds = _run_for_figures(xr.open_zarr(zarr_of(store), consolidated=False), store, allow_partial,
                                  f"the run in {store}")
        elif member is not None or kind in ("snapshot", "rupture", "gif", "stations"):
            status = member_status(store)
            if member is None and len(status) != 1:
                raise click.ClickException(f"--kind {kind} draws one member: give --member (an id, or a position "
                                           f"0 to {len(status) - 1})")
            mid = pick_member(status, member, allow_partial) if member is not None else status[0]["id"]
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
                print_note(f"{store}: {' and '.join(p for p in parts if p)} of {len(status)} members "
                      f"({', '.join((bad + unfinished)[:4])}{', ...' if len(bad + unfinished) > 4 else ''}); the "
                      f"figures show {shown} member{'s' if shown != 1 else ''}"
                      + ("" if allow_partial or not bad else "; --allow-partial adds what the failed ones recorded"))
    except (InputError, StoreError) as exc:
        raise fail(exc) from None
    if time_ is not None and kind in ("snapshot", "all"):
        _check_time(ds if "member" not in ds.dims else member_of(ds, 0), time_)
    if kind == "stations" and field == "delta_2":
        field = "v_1"
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
            elif kind == "stations":
                from ..plots.faults import station_series

                station_series(ds, field, stations=stations, path=out)
            else:
                P.animate(ds, out, field)
            paths = [out]
    except (ValueError, KeyError) as exc:
        raise click.ClickException(str(exc)) from None
    except KeyboardInterrupt:
        exit_interrupted("interrupted; the figure was not written")
    if not paths:
        raise click.ClickException(f"nothing to draw in {store}")
    for p in paths:
        click.echo(f"cracklab: wrote {p}")
