"""``cracklab verify``: check every array of a run or an ensemble store."""
from __future__ import annotations

import sys

import click

from .common import main


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
