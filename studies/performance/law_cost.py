"""Cost of a rate-and-state step against a slip-weakening step, the two steps alternated in
one process (docs/reference/equations.md, "Rate-and-state friction", Cost).

    python studies/performance/law_cost.py [--n 256] [--steps 200] [--rounds 3] [--json OUT.json]

The two scenes are `cracklab bench`'s friction benches (cracklab.cli.bench.bench_scene:
``--law rate_state``, a TPV101-like rupture, and ``--law slip_weakening``, a TPV3-like one,
on the same n x n grid of 100 m cells with the same time-step rule; 3D shear, exponential
engine, one thread). Each round builds both, runs the first half of each, then times the
second half one step of each in turn, so that both laws meet the same host: the figure
is the ratio of the median step times of the round (wall clock and the thread's CPU time).
It also reports the in-run FFT pair and the rate-and-state law's Newton evaluations and
solves per point and step over the timed half. `cracklab bench` times the same scenes one
process at a time; on a shared host its ratios scatter more.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from cracklab.cli.bench import _Pair, bench_scene
from cracklab.solver.interfaces import for_scene
from cracklab.solver.spectral import Transforms
from cracklab.solver.stepper import Stepper

LAWS = ("slip_weakening", "rate_state")


def one_round(n, steps):
    """(ms per step by law, wall and CPU; FFT pair ms; Newton evaluations, solves per point-step)."""
    runs = {}
    for law in LAWS:
        scene = bench_scene(n, n, "shear", steps, "exponential", 1, None, law, False, False)
        stepper = Stepper(scene, for_scene(scene, Transforms(scene.grid, 1)))
        runs[law] = (stepper, iter(stepper))
    half = (steps + 1) // 2
    for stepper, it in runs.values():
        for _ in range(half):
            next(it)
    ls = runs["rate_state"][0].lstate
    counts0 = (ls["newton_evaluations"], ls["newton_solves"])
    wall = {law: [] for law in LAWS}
    cpu = {law: [] for law in LAWS}
    timed = 0
    for _ in range(steps + 1 - half):
        for law, (stepper, it) in runs.items():
            w0, c0 = time.perf_counter(), time.thread_time()
            try:
                next(it)
            except StopIteration:
                break
            cpu[law].append(time.thread_time() - c0)
            wall[law].append(time.perf_counter() - w0)
        timed += 1
    pair = _Pair(runs["rate_state"][0].scene.grid, 1, (1, 3))
    fft = 1e3 * float(np.median([pair() for _ in range(20)]))
    points = n * n * max(1, len(cpu["rate_state"]))
    newton = ((ls["newton_evaluations"] - counts0[0]) / points, (ls["newton_solves"] - counts0[1]) / points)
    ms = {law: (1e3 * float(np.median(wall[law])), 1e3 * float(np.median(cpu[law]))) for law in LAWS}
    return ms, fft, newton


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=256, help="nodes along x1 and x3 (default 256)")
    ap.add_argument("--steps", type=int, default=200, help="steps of each run; the second half is timed")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", help="write the rounds to this file")
    args = ap.parse_args(argv)
    rows = []
    for r in range(args.rounds):
        ms, fft, newton = one_round(args.n, args.steps)
        row = {"round": r + 1, "ms": ms, "fft_pair_ms": fft, "newton_evaluations": newton[0],
               "newton_solves": newton[1], "ratio_wall": ms["rate_state"][0] / ms["slip_weakening"][0],
               "ratio_cpu": ms["rate_state"][1] / ms["slip_weakening"][1]}
        rows.append(row)
        print(f"round {r + 1}: slip weakening {ms['slip_weakening'][0]:.2f} ms, rate and state "
              f"{ms['rate_state'][0]:.2f} ms per step: {row['ratio_wall']:.2f}x (CPU time {row['ratio_cpu']:.2f}x); "
              f"FFT pair {fft:.3f} ms; Newton {newton[0]:.2f} evaluations, {newton[1]:.2f} solves per point and step",
              flush=True)
    ratios = [row["ratio_wall"] for row in rows]
    print(f"rate-and-state / slip-weakening step: median {statistics.median(ratios):.2f}x "
          f"({min(ratios):.2f}-{max(ratios):.2f} over {len(rows)} rounds)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
