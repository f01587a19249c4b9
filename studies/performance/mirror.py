"""The cost of a free surface by mirror symmetry: `cracklab bench` of the half plane n1 x n3
(``--free-surface``), of the periodic n1 x n3 grid and of the doubled periodic n1 x 2 n3
grid, alternated in one sitting.

    python studies/performance/mirror.py [--cases 256x128,512x256] [--mode shear] [--rounds 5]
                                         [--steps 2000] [--json OUT.json]

Each round runs the three variants one after the other, each `cracklab bench --json`
in its own process of this checkout (one thread, exponential engine, the mode's default
scheme: product for shear). Per case it prints the median ms per step of each variant,
the in-run FFT baseline (``fft_pair_ms``; for the half plane in shear the cost per
component of the shear pair's transform of the doubled cell), the ratios half / periodic
and half / doubled of the medians, the min-max of the per-round ratios, and the ratio of
the fastest rounds (the least disturbed runs of a shared host). docs/studies/performance.md,
"Free surface by mirror symmetry", quotes its output.

``--in-process``: the three runs of a case stepped in one process instead, alternately in
blocks of 20 steps over the second half of the run (the first half fills the histories
untimed), so that every variant sees the host in the same seconds; the medians of the
blocks' ms per step and the median of the blocks' ratios. The three share the caches
there, so the absolute figures are above `cracklab bench`'s; the ratios are what it is for.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
VARIANTS = ("half", "periodic", "doubled")


def bench(n1, n3, variant, mode, steps):
    args = {"half": ["--n1", str(n1), "--n3", str(n3), "--free-surface"],
            "periodic": ["--n1", str(n1), "--n3", str(n3)],
            "doubled": ["--n1", str(n1), "--n3", str(2 * n3)]}[variant]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(
        os.pathsep) if p]))
    cmd = [sys.executable, "-m", "cracklab.cli", "bench", *args, "--mode", mode, "--steps", str(steps), "--json"]
    out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    return json.loads(out.stdout)


def in_process(n1, n3, mode, steps, block=20):
    """ms per step of the three variants stepped alternately in blocks in this process."""
    import numpy as np

    if str(ROOT) not in sys.path:  # this checkout's package, as the benches use
        sys.path.insert(0, str(ROOT))
    from cracklab.cli.bench import bench_scene
    from cracklab.solver.interfaces import for_scene
    from cracklab.solver.spectral import Transforms
    from cracklab.solver.stepper import Stepper

    shapes = {"half": (n1, n3, True), "periodic": (n1, n3, False), "doubled": (n1, 2 * n3, False)}
    its, times = {}, {v: [] for v in VARIANTS}
    for v, (a, b, surface) in shapes.items():
        scene = bench_scene(a, b, mode, steps, "exponential", 1, None, surface)
        its[v] = iter(Stepper(scene, for_scene(scene, Transforms(scene.grid, 1))))
        for _ in range(steps // 2 + 1):
            next(its[v])
    for _ in range((steps - steps // 2) // block):
        for v in VARIANTS:
            t0 = time.perf_counter()
            for _ in range(block):
                next(its[v])
            times[v].append(1e3 * (time.perf_counter() - t0) / block)
    med = {v: float(np.median(times[v])) for v in VARIANTS}
    return {"ms_per_step": med, "half_over_periodic": med["half"] / med["periodic"],
            "half_over_doubled": med["half"] / med["doubled"],
            "block_ratio_half_over_periodic": float(np.median(np.divide(times["half"], times["periodic"]))),
            "blocks": len(times["half"])}


def summary(runs):
    med = {v: statistics.median(r["ms_per_step"] for r in runs[v]) for v in VARIANTS}
    fast = {v: min(r["ms_per_step"] for r in runs[v]) for v in VARIANTS}
    ratios = {other: [h["ms_per_step"] / o["ms_per_step"] for h, o in zip(runs["half"], runs[other])]
              for other in ("periodic", "doubled")}
    return {
        "ms_per_step": med, "fastest_ms_per_step": fast,
        "fft_pair_ms": {v: statistics.median(r["fft_pair_ms"] for r in runs[v]) for v in VARIANTS},
        "half_over_periodic": med["half"] / med["periodic"], "half_over_doubled": med["half"] / med["doubled"],
        "per_round_half_over_periodic": [min(ratios["periodic"]), max(ratios["periodic"])],
        "per_round_half_over_doubled": [min(ratios["doubled"]), max(ratios["doubled"])],
        "fastest_half_over_periodic": fast["half"] / fast["periodic"],
        "fastest_half_over_doubled": fast["half"] / fast["doubled"],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="256x128,512x256")
    ap.add_argument("--mode", default="shear")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--json", dest="out")
    ap.add_argument("--in-process", action="store_true")
    a = ap.parse_args(argv)
    report = {}
    for case in a.cases.split(","):
        n1, n3 = (int(x) for x in case.split("x"))
        if a.in_process:
            s = in_process(n1, n3, a.mode, a.steps)
            report[case] = {"mode": a.mode, "steps": a.steps, "in_process": True, **s}
            print(f"{case} {a.mode} in one process ({s['blocks']} blocks of 20 steps each): ms/step "
                  + ", ".join(f"{v} {s['ms_per_step'][v]:.3f}" for v in VARIANTS)
                  + f"; half/periodic {s['half_over_periodic']:.3f} (median block ratio "
                  f"{s['block_ratio_half_over_periodic']:.3f}), half/doubled {s['half_over_doubled']:.3f}", flush=True)
            continue
        runs = {v: [] for v in VARIANTS}
        for r in range(a.rounds):
            for v in VARIANTS:
                res = bench(n1, n3, v, a.mode, a.steps)
                runs[v].append(res)
                print(f"{case} {a.mode} round {r + 1}: {v:>8} {res['ms_per_step']:.3f} ms/step, "
                      f"FFT pair {res['fft_pair_ms']:.3f} ms, load {os.getloadavg()[0]:.2f}", flush=True)
        s = summary(runs)
        report[case] = {"mode": a.mode, "steps": a.steps, "rounds": a.rounds, **s, "runs": runs}
        print(f"{case} {a.mode}: median ms/step half {s['ms_per_step']['half']:.3f}, periodic "
              f"{s['ms_per_step']['periodic']:.3f}, doubled {s['ms_per_step']['doubled']:.3f}; half/periodic "
              f"{s['half_over_periodic']:.3f} (rounds {s['per_round_half_over_periodic'][0]:.2f}-"
              f"{s['per_round_half_over_periodic'][1]:.2f}, fastest {s['fastest_half_over_periodic']:.3f}); "
              f"half/doubled {s['half_over_doubled']:.3f} (fastest {s['fastest_half_over_doubled']:.3f}); FFT pair "
              + ", ".join(f"{v} {s['fft_pair_ms'][v]:.3f}" for v in VARIANTS), flush=True)
    if a.out:
        Path(a.out).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
