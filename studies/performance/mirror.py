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
the fastest rounds (the least disturbed runs of a shared host). docs/performance.md,
"Free surface by mirror symmetry", quotes its output.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
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
    a = ap.parse_args(argv)
    report = {}
    for case in a.cases.split(","):
        n1, n3 = (int(x) for x in case.split("x"))
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
