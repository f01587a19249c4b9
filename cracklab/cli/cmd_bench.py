"""``cracklab bench``: the cost per step of a run (the bench itself is ``cli.bench``)."""
from __future__ import annotations

import json
import sys

import click

from .common import CONTEXT, exit_interrupted, fail, main


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
    """Median cost per step (second half of the run), a same-process FFT pair and the step by stage.

    The step by stage is part of every report: the transforms, the history engines'
    advance, the wait for the engines' worker (with --engine-threads 2 or more), the taps,
    the law and the glue (the rest: the scheme's passes, the load, the growth check), each
    in ms per step and in units of the FFT pair timed in the same run, and their sum set
    against the plain step's median (within 25 % unless the host is busy). They are timed
    on blocks of steps that alternate with plain ones, through wrappers set only on those
    steps: a run outside the bench carries none. With --json: stages_ms, stages_fft_pairs,
    stages_total_ms, stages_vs_step, worker_ms (docs/studies/performance.md, "Where the
    time goes, by stage")."""
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
        exit_interrupted("interrupted; nothing was written")
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
        from .bench import stage_table

        staged = ("stages_ms", "stages_fft_pairs", "stages_total_ms", "stages_vs_step", "stage_steps", "worker_ms")
        for k, v in result.items():
            if k.startswith("newton") and v is None or k in staged and result["stages_ms"] is not None:
                continue
            click.echo(f"{k:>22}: {v:.4g}" if isinstance(v, float) else f"{k:>22}: {v}")
        table = stage_table(result)
        if table:
            click.echo(table)
