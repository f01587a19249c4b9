"""``cracklab export``: a run or an ensemble store (or one member) to a netCDF4 file."""
from __future__ import annotations

import click

from .common import CONTEXT, StoreArgument, exit_interrupted, print_note, pick_member, fail, main


@main.command(context_settings=CONTEXT)
@click.argument("store", type=StoreArgument())
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
            member = pick_member(member_status(store), member, allow_partial)
        progress = run_progress(member_path(store, member) if member else store) if (member or not ens) else None
        out = export_netcdf(store, output, member=member, allow_partial=allow_partial, overwrite=overwrite)
    except (InputError, StoreError) as exc:
        raise fail(exc, {"member": "--member", "output": flag}) from None
    except OSError as exc:       # a read-only location, a full disk, ...
        raise click.ClickException(f"{flag}: cannot write {output}: {exc.strerror or exc}") from None
    except KeyboardInterrupt:
        exit_interrupted("interrupted; nothing was written")
    if progress is not None and progress.status != "complete":
        print_note(f"{'member ' + member if member else store} is {progress.describe()}; exported "
              f"{progress.snapshots} snapshot{'s' if progress.snapshots != 1 else ''}")
    elif ens and member is None:
        left = [s["id"] for s in member_status(store) if not s["complete"]]
        if left:
            print_note(f"{len(left)} member{'s' if len(left) != 1 else ''} not complete "
                  f"{'(failed ones included) ' if allow_partial else ''}left out: {', '.join(left[:4])}"
                  f"{', ...' if len(left) > 4 else ''}")
    click.echo(f"cracklab: wrote {out}")
