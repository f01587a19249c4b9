"""BP1-FD's event times against its time step (docs/studies/cycles.md, "Self-convergence of
BP1-FD"): the run at dz = 50 m to 430 years (three earthquakes) with the dynamic step
halved (beta 0.25 instead of 0.5), with the tolerance ten and a hundred times tighter
(1e-5 and 1e-6 instead of the builder's 1e-4) and with the pair's slow steps below 1e-3 of
the least sigma a / eta instead of 1e-1 (Sequence.slow_rate), to set against the page's
run at 50 m:
whether the event times' difference between 50 and 25 m comes from the time step or from
the grid, and what the builder's tolerance costs in accuracy.

    python -m studies.cycles.fd_checks [-o OUT] [--dz 50] [--years 430]

writes OUT/fd_checks.json: {case: {dz, beta, tolerance, years, slow_fraction, wall_s,
accepted_steps, t_start_s (the events' starts, s), peak_slip_rate}}.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

CASES = {"beta 0.25": {"beta": 0.25, "tolerance": None}, "tolerance 1e-5": {"beta": 0.5, "tolerance": 1e-5},
         "tolerance 1e-6": {"beta": 0.5, "tolerance": 1e-6},
         "the pair below 1e-3 sigma a / eta": {"beta": 0.5, "tolerance": None, "slow": 1e-3}}


def run_case(out, dz, years, beta, tolerance, slow=None) -> dict:
    """``slow``: the slow steps' bound as a fraction of the least sigma a / eta (None: the
    default, dynamic.SLOW_FRACTION)."""
    import dataclasses

    from cracklab.scenes import bp1
    from cracklab.solver.sequence.run import system_of

    scene = bp1(dz=dz, years=years, dynamic=True, tolerance=tolerance).replace(beta=beta)
    tol = scene.sequence.tolerance
    name = f"bp1fd_check_dz{dz:g}_beta{beta:g}_tol{tol:g}"
    if slow is not None:
        rate = system_of(scene).slow_rate(slow)
        scene = scene.replace(sequence=dataclasses.replace(scene.sequence, slow_rate=rate))
        name += f"_slow{slow:g}"
    return {"dz": dz, "beta": beta, "tolerance": tol, "years": years, "slow_fraction": slow,
            **catalogue(scene, Path(out) / f"{name}.zarr")}


def catalogue(scene, store) -> dict:
    """Run ``scene`` into ``store`` (resuming a killed run; a finished one is reopened, and
    ``wall_s`` is then the reopening's): {wall_s, accepted_steps, t_start_s, peak_slip_rate
    of its events, steps_below_1e-7 (the steps whose largest slip rate is below 1e-7 m/s)}."""
    from cracklab import analysis, simulate

    t0 = time.time()
    ds = simulate(scene, store=str(store), resume=True)
    wall = time.time() - t0
    ev = analysis.events(ds)
    return {"wall_s": wall, "accepted_steps": int(ds.attrs["accepted_steps"]), "t_start_s": ev.t_start.values.tolist(),
            "peak_slip_rate": ev.peak_slip_rate.values.tolist(),
            "steps_below_1e-7": int(np.sum(ds.max_slip_rate.values < 1e-7)),
            "wall_s_of_run": float(ds.attrs.get("wall_time_in_events", 0.0) + ds.attrs.get("wall_time_between_events", 0.0))}


def run_all(argv, doc, dz, years, cases, run, name) -> int:
    """The command line of a check (``doc``: its module docstring): each of ``cases``
    ({label: keyword arguments of ``run``}) at --dz, --years into OUT/``name``."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("-o", "--out", default="out/cycles")
    p.add_argument("--dz", type=float, default=dz)
    p.add_argument("--years", type=float, default=years)
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res = {}
    for label, case in cases.items():
        res[label] = run(out, args.dz, args.years, **case)
        print(f"{label}: {res[label]['wall_s']:.0f} s, {res[label]['accepted_steps']} steps, events at "
              f"{res[label]['t_start_s']} s", flush=True)
    (out / name).write_text(json.dumps(res, indent=1))
    return 0


def main(argv=None) -> int:
    return run_all(argv, __doc__, 50.0, 430.0, CASES, run_case, "fd_checks.json")


if __name__ == "__main__":
    sys.exit(main())
