"""``cracklab summary``: the parameters and summary measures of every member, as a table."""
from __future__ import annotations

import click

from .common import CONTEXT, StoreArgument, main


@main.command(context_settings=CONTEXT)
@click.argument("store", type=StoreArgument(dir_only=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write the table to this CSV file instead of printing it.")
def summary(store, output) -> None:
    """The parameters and summary measures of every member of an ensemble STORE (or of a
    run), one row per member: swept parameters, status, final crack length and growth,
    ruptured area, front position, width and speed, run time (cracklab.ensemble.summary).

    A fault run (a shear component active) gets rupture measures instead of the crack-front
    ones: rupture area, mean slip and moment (NaN when slip is not recorded), peak slip rate
    (station series and snapshots of v_1/v_3), first, median and last rupture time."""
    from ..analysis import summary as table_of
    from ..errors import InputError, StoreError

    try:
        table = table_of(store)
    except (InputError, StoreError) as exc:
        raise click.ClickException(str(exc)) from None
    if "member" not in table.dims:
        from pathlib import Path

        table = table.expand_dims(run=[Path(store.rstrip("/").rsplit("/", 1)[-1]).name])
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
