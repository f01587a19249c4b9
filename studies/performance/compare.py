"""Speed and peak memory of two checkouts, `cracklab bench` alternated in one sitting.

    python studies/performance/compare.py A B [--rounds 3] [--steps 2000] [--quick] [--json OUT.json]

A and B are source checkouts (paths to the repository root, e.g. a worktree of the
previous commit and this one). For each round and each case, `cracklab bench --json`
runs once for A, then once for B, each in its own process with ``PYTHONPATH`` set to
the checkout and the checkout as working directory (the bench entry point is read from
the checkout's pyproject.toml, so a moved command-line module is found). The cases and
settings are those of docs/studies/performance.md: 256 x 256 mode I, 512 x 512 mode I and
512 x 512 shear (product scheme), ``--threads 1 --engine-threads 2``, exponential engine.

Per case it reports the median ms_per_step of A and of B over the rounds, their ratio
B/A with the min-max of the per-round ratios (each round's B against the same round's
A), the same ratio with each run's step divided by its own FFT pair (``fft_pair_ms``,
timed inside the run: what is left of the host's noise), the fastest round of B over
the fastest of A (the least disturbed runs of a loaded host), the median fft_pair_ms of
each and the largest peak_rss_mb of each. ``--quick``: 200 steps, one round (a check that it
works, not a measurement). Against the previous commit::

    git worktree add /tmp/before HEAD~1
    python studies/performance/compare.py /tmp/before . --json out/speed.json

The machine is shared: run it when it is otherwise idle, and read the ratios, not the
absolute numbers.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

#: (n1, n3, mode) of docs/studies/performance.md's targets
CASES = [(256, 256, "I"), (512, 512, "I"), (512, 512, "shear")]
THREADS = ["--threads", "1", "--engine-threads", "2"]

# Runs the checkout's `cracklab` entry point with the remaining arguments; prints where
# the package came from on stderr (checked against the checkout).
LAUNCHER = r"""
import importlib, sys, tomllib
spec = tomllib.load(open(sys.argv[1], "rb"))["project"]["scripts"]["cracklab"]
module, func = spec.split(":")
import cracklab
print("cracklab-source:", cracklab.__file__, file=sys.stderr)
sys.argv = ["cracklab"] + sys.argv[2:]
getattr(importlib.import_module(module), func)()
"""


def case_name(case):
    n1, n3, mode = case
    return f"{n1}x{n3} {mode}"


def checkout(path) -> Path:
    root = Path(path).resolve()
    if not (root / "pyproject.toml").is_file() or not (root / "cracklab").is_dir():
        raise SystemExit(f"{root}: not a cracklab checkout (no pyproject.toml and cracklab/ there)")
    with open(root / "pyproject.toml", "rb") as fh:
        if "cracklab" not in tomllib.load(fh).get("project", {}).get("scripts", {}):
            raise SystemExit(f"{root}/pyproject.toml has no [project.scripts] cracklab entry point")
    return root


def commit_of(root: Path):
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True)
        return out.stdout.strip() or None
    except OSError:
        return None


def bench(root: Path, case, steps, python=sys.executable, extra=()):
    """One `cracklab bench --json` of ``case`` from checkout ``root``; its JSON (dict)."""
    n1, n3, mode = case
    cmd = [python, "-c", LAUNCHER, str(root / "pyproject.toml"), "bench", "--n1", str(n1), "--n3", str(n3),
           "--mode", mode, "--steps", str(steps), *THREADS, *extra, "--json"]
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"bench {case_name(case)} in {root} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
    source = next((line.split(":", 1)[1].strip() for line in proc.stderr.splitlines()
                   if line.startswith("cracklab-source:")), "")
    if not Path(source).resolve().is_relative_to(root):
        raise RuntimeError(f"bench for {root} imported cracklab from {source!r}, not from the checkout")
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    result["wall_seconds"] = wall
    return result


def summarise(runs_a, runs_b):
    """Per-case figures from the rounds' results of A and of B (same length, same order)."""
    ms_a = [r["ms_per_step"] for r in runs_a]
    ms_b = [r["ms_per_step"] for r in runs_b]
    pair_a = [r["fft_pair_ms"] for r in runs_a]
    pair_b = [r["fft_pair_ms"] for r in runs_b]
    ratios = [b / a for a, b in zip(ms_a, ms_b)]
    norm = [(b / pb) / (a / pa) for a, b, pa, pb in zip(ms_a, ms_b, pair_a, pair_b)]
    med_a, med_b = statistics.median(ms_a), statistics.median(ms_b)
    return {
        "ms_per_step_a": med_a, "ms_per_step_b": med_b, "ratio": med_b / med_a,
        "ratio_min": min(ratios), "ratio_max": max(ratios), "ratios": ratios,
        "ratio_per_fft_pair": statistics.median(norm), "ratio_per_fft_pair_min": min(norm),
        "ratio_per_fft_pair_max": max(norm),
        "ratio_best": min(ms_b) / min(ms_a),
        "fft_pair_ms_a": statistics.median(pair_a), "fft_pair_ms_b": statistics.median(pair_b),
        "peak_rss_mb_a": max(r["peak_rss_mb"] for r in runs_a),
        "peak_rss_mb_b": max(r["peak_rss_mb"] for r in runs_b),
        "rounds": len(runs_a),
    }


def table(summary, steps) -> str:
    lines = ["| case | steps | A ms/step | B ms/step | B/A (per round) | B/A per FFT pair | best B / best A | "
             "A FFT pair ms | B FFT pair ms | A peak RSS MB | B peak RSS MB |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, s in summary.items():
        lines.append(
            f"| {name} | {steps[name]} | {s['ms_per_step_a']:.2f} | {s['ms_per_step_b']:.2f} | "
            f"{s['ratio']:.3f} ({s['ratio_min']:.3f}-{s['ratio_max']:.3f}) | "
            f"{s['ratio_per_fft_pair']:.3f} ({s['ratio_per_fft_pair_min']:.3f}-{s['ratio_per_fft_pair_max']:.3f}) | "
            f"{s['ratio_best']:.3f} | "
            f"{s['fft_pair_ms_a']:.2f} | {s['fft_pair_ms_b']:.2f} | "
            f"{s['peak_rss_mb_a']:.0f} | {s['peak_rss_mb_b']:.0f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("a", help="checkout A (the base, e.g. the previous commit)")
    parser.add_argument("b", help="checkout B")
    parser.add_argument("--rounds", type=int, default=3, help="A, B pairs per case (default 3)")
    parser.add_argument("--steps", type=int, default=None, help="steps per bench (default 2000; --quick 200)")
    parser.add_argument("--quick", action="store_true", help="200 steps, one round")
    parser.add_argument("--cases", nargs="+", default=None, metavar="N1xN3:MODE",
                        help="a subset, e.g. 256x256:I 512x512:shear")
    parser.add_argument("--json", metavar="OUT.json", help="write the summary and every run")
    parser.add_argument("--python", default=sys.executable, help="interpreter for the benches (default: this one)")
    args = parser.parse_args(argv)

    roots = {"a": checkout(args.a), "b": checkout(args.b)}
    rounds = 1 if args.quick else args.rounds
    if rounds < 1:
        parser.error("--rounds must be >= 1")
    steps = args.steps or (200 if args.quick else 2000)
    cases = CASES
    if args.cases:
        cases = []
        for c in args.cases:
            try:
                grid, mode = c.split(":")
                n1, n3 = (int(x) for x in grid.lower().split("x"))
            except ValueError:
                parser.error(f"--cases: {c!r} is not N1xN3:MODE")
            cases.append((n1, n3, mode))
    print(f"A = {roots['a']} ({commit_of(roots['a'])})\nB = {roots['b']} ({commit_of(roots['b'])})\n"
          f"{rounds} round(s), {steps} steps, cracklab bench {' '.join(THREADS)}", flush=True)
    runs = {case_name(c): {"a": [], "b": []} for c in cases}
    t0 = time.perf_counter()
    for r in range(rounds):
        for case in cases:
            for side in ("a", "b"):
                res = bench(roots[side], case, steps, python=args.python)
                runs[case_name(case)][side].append(res)
                print(f"round {r + 1}/{rounds} {case_name(case):>14} {side.upper()}: {res['ms_per_step']:8.3f} ms/step, "
                      f"FFT pair {res['fft_pair_ms']:.3f} ms, peak RSS {res['peak_rss_mb']:.0f} MB "
                      f"({res['wall_seconds']:.0f} s)", flush=True)
    summary = {name: summarise(v["a"], v["b"]) for name, v in runs.items()}
    print(f"\n{table(summary, {name: steps for name in summary})}\n\n({time.perf_counter() - t0:.0f} s; "
          f"B/A below 1: B is faster)")
    if args.json:
        out = {"a": {"path": str(roots["a"]), "commit": commit_of(roots["a"])},
               "b": {"path": str(roots["b"]), "commit": commit_of(roots["b"])},
               "rounds": rounds, "steps": steps, "threads": THREADS, "summary": summary, "runs": runs,
               "created_unix": time.time()}
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(out, indent=1))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
