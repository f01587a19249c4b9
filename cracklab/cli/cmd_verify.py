"""``cracklab verify``: check every array of a run or an ensemble store, and its metadata."""
from __future__ import annotations

import sys

import click

from .common import main


@main.command()
@click.argument("store")
@click.option("--quick", is_flag=True,
              help="Check the metadata and that every chunk is present, without reading the data "
                   "(no checksums; only the scene's input arrays are read, for its digest).")
def verify(store, quick) -> None:
    """Check every array of a run or an ensemble STORE (a local path or a URL such as
    s3://bucket/run.zarr): metadata, the arrays a run holds,
    every chunk present and (unless --quick) read with its checksum, and the metadata
    readers see against what is stored.

    The metadata checks: the consolidated metadata (what plain xarray reads) against the
    groups and arrays present, the scene against the digest written with the run, each
    array's shape, data type and units against the scene, an ensemble member's
    parameters against its id and scene, and the member table at the root against the
    member groups. Prints what is damaged (each file; a metadata mismatch with its
    remedy) and what to do, and exits with status 1 when anything is; 0 when the store
    is sound (an unfinished run or incomplete members are reported, and are not damage)."""
    from ..errors import StoreError
    from ..ensemble.verify import verify as check

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
