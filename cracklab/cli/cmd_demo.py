"""``cracklab demo``: the asperity ensemble on a local dask cluster and Lamb's problem."""
from __future__ import annotations

import sys

import click

from .common import CONTEXT, exit_interrupted, fail, main


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
    from ..errors import InputError
    from .demo import main as run_demo

    try:
        ok = run_demo(out=out, scheduler=scheduler, workers=workers, lamb=not no_lamb)
    except InputError as exc:
        raise fail(exc, {"scheduler": "--scheduler"}) from None
    except KeyboardInterrupt:
        exit_interrupted("interrupted; rerun the same command to resume (complete members are kept)")
    if ok is False:
        sys.exit(1)
