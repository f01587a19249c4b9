"""What a quasi-dynamic BP1 step costs, by part, and what bounds a 1500-year run
(docs/studies/cycles.md, "Cost against the targets").

    python -m studies.cycles.cost --dz 25 [--steps 300000] [-o OUT/cost_dz25.json]

Times, at the state a short run reaches, one evaluation of the rates (the step's unit: the
builder's pair, Bogacki-Shampine 3(2), takes three per accepted step) and its parts: the transforms of the
static response, the rate-and-state solve at the sliding points, the rest (glue); and the
step's own arithmetic (the pair's stage sums, its error estimate and norm). Then the
floor of a run of ``--steps`` accepted steps (the count of the study's run at that dz)
if the glue and the step's own arithmetic cost nothing; and the steps in BP1-QD's first
event at 200 m for three tolerances (whether the pair's accuracy or its stability sets
the steps of a rupture), with the builder's pair."""
from __future__ import annotations

import argparse
import json
import time

import numpy as np


def _best(fn, repeats):
    """The best of ``repeats`` timings of fn(), in seconds (the machine is shared)."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def breakdown(dz, years=2.0, repeats=200) -> dict:
    """{part: seconds} of one rate evaluation of BP1-QD at ``dz`` (after ``years`` of a run)."""
    from cracklab.scenes import bp1
    from cracklab.solver.sequence.run import system_of

    scene = bp1(dz=dz, years=years)
    system = system_of(scene)
    y = system.initial()
    f = system.rates(0.0, y)
    y = y + 3.15e7 * f                       # a year on: the state of a slow phase
    system.rates(3.15e7, y)
    delta, psi = system.split(y)
    s = system.slides
    h = slice(None) if system._half is None else system._half     # with the mirror: one of a node and its image
    T = np.abs(system.traction(3.15e7, y)[system.comps[0]][s])[h]
    law = system.law
    rates = _best(lambda: system.rates(3.15e7, y), repeats)
    transforms = _best(lambda: system.elastic(delta, 3.15e7), repeats)
    solve = _best(lambda: law.slide_rates(T, psi[s][h], system.sigma_s[h], system.eta, guess=system.lnV,
                                          at=system.at), repeats)
    step = _step(scene, system, y, repeats)
    evals = _pair(scene).evaluations
    return {"pair": scene.sequence.pair, "evaluations": evals, "dz": dz, "nodes": int(scene.grid.n1 * scene.grid.n3),
            "points": int(system.n),
            "sliding_points": int(s.sum()), "solved_points": int(system.solved), "rates_s": rates,
            "transforms_s": transforms, "solve_s": solve, "glue_s": rates - transforms - solve,
            "step_own_s": step, "step_s": evals * rates + step}


def _pair(scene):
    from cracklab.solver.sequence.pairs import PAIRS

    return PAIRS[scene.sequence.pair]


def _step(scene, system, y, repeats):
    """Seconds of an accepted step's own arithmetic, without its evaluations: the
    pair's stage sums and error estimate (integrate.try_step, with rates that cost nothing)
    and the error's norm (integrate.error_norm)."""
    from types import SimpleNamespace

    from cracklab.solver.sequence.integrate import error_norm, tableau, try_step, weighted

    pair = _pair(scene)
    A, b, e = tableau(pair)
    f = system.rates(3.15e7, y)
    k = np.empty((pair.stages, y.size))
    k[0] = f

    def stage_rates(t, y, h, w, k, i):
        yi = weighted(y, h, w, k)
        k[i] = f
        return yi

    free = SimpleNamespace(rates=lambda t, yi: f, stage=lambda dt, k, c: None, stage_rates=stage_rates)
    sums = _best(lambda: try_step(free, pair, A, b, e, k, 3.15e7, y, 1.0), repeats)
    y_new, err, _ = try_step(free, pair, A, b, e, k, 3.15e7, y, 1.0)
    norm = _best(lambda: error_norm(system, y_new, err, scene.sequence.tolerance), repeats)
    return sums + norm


def event_steps(dz=200.0, tolerances=(1e-3, 1e-4, 1e-5), depth=80e3, years=230.0) -> dict:
    """{tolerance: accepted steps in events} of BP1-QD's first event (at ``dz``, the creeping
    region to ``depth``) with the builder's pair: how its steps in a rupture grow with its
    tolerance."""
    from cracklab import Record, simulate
    from cracklab.scenes import bp1

    pair = bp1(dz=dz, years=years, depth=depth).sequence.pair
    out = {}
    for tol in tolerances:
        sc = bp1(dz=dz, years=years, tolerance=tol, depth=depth, pair=pair,
                 record=Record(fields=("v_3",), region={"x1": (0.0, depth)}, stations={}))
        ds = simulate(sc)
        out[f"{tol:g}"] = int(np.sum(ds.max_slip_rate.values >= ds.attrs["event_threshold"]))
    return {"dz": dz, "depth": depth, "years": years, "pair": pair, "steps_in_events": out}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dz", type=float, default=25.0)
    p.add_argument("--steps", type=int, default=None, help="accepted steps of the run to bound")
    p.add_argument("-o", "--out", default=None, help="also write the figures to this JSON file (the study "
                                                     "page reads OUT/cost_dz<dz>.json)")
    args = p.parse_args(argv)
    b = breakdown(args.dz)
    b["first_event"] = event_steps()
    floor = b["evaluations"] * (b["transforms_s"] + b["solve_s"])
    b["step_floor_s"] = floor
    if args.steps:
        b.update({"steps": args.steps, "run_s": args.steps * b["step_s"], "run_floor_s": args.steps * floor})
    text = json.dumps(b, indent=1)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
