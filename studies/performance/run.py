"""Benchmarks of the performance issue, each a `cracklab bench` command; writes a JSON and a
markdown table (docs/studies/performance.md quotes it).

    .venv/bin/python studies/performance/run.py [--quick] [--out out/performance]
    .venv/bin/python studies/performance/run.py --stages [--rounds 3] [--quick]
    .venv/bin/python studies/performance/run.py --scaling [--rounds 3] [--quick]

Each row runs in its own process (`cracklab bench --json`), so peak memory is per row.
``--stages``: where the time of a step goes (the bench's ``stages_ms``) for mode I, shear
with slip weakening, shear with rate and state, and bimaterial shear, 256 x 256, the cases
one after the other in every round; writes stages.json and stages.md (the median round of
each case). ``--scaling``: one core against two (issue 33, target 4): 512 x 512 shear with
slip weakening at one thread, at two (FFTs and engine) and at two engine threads with one
FFT thread, alternated in every round, the one-thread step by stage; writes scaling.json
and scaling.md (each setting's median step and its speed-up on the one-thread median).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

# (n1, n3, mode, steps, engine[, fit_steps]); the rows with fit_steps carry the terms of a
# 10 000-step fit whatever their length, so that they compare the history's length alone
ROWS = [
    (128, 128, "I", 100, "exponential"),
    (128, 128, "I", 1000, "exponential"),
    (128, 128, "I", 10000, "exponential"),
    (256, 256, "I", 2000, "exponential"),
    (512, 512, "I", 2000, "exponential"),
    (512, 512, "shear", 2000, "exponential"),
    (256, 256, "I", 400, "direct"),
    (128, 128, "I", 100, "exponential", 10000),
    (128, 128, "I", 1000, "exponential", 10000),
    (128, 128, "I", 10000, "exponential", 10000),
]
QUICK = [(128, 128, "I", 100, "exponential"), (128, 128, "I", 400, "exponential")]
TARGETS = {(256, 256, "I"): 2.0, (512, 512, "I"): 8.0, (512, 512, "shear"): 16.0}


#: the cases of the breakdown by stage: (name, mode, law, bimaterial, engine threads)
STAGE_CASES = [
    ("mode I", "I", "traction_free", False, 1),
    ("shear, slip weakening", "shear", "slip_weakening", False, 1),
    ("shear, rate and state", "shear", "rate_state", False, 1),
    ("bimaterial shear, slip weakening", "shear", "slip_weakening", True, 1),
    ("shear, slip weakening, 2 engine threads", "shear", "slip_weakening", False, 2),
]
STAGE_GRID, STAGE_STEPS = (256, 256), 400
STAGE_QUICK = dict(grid=(32, 32), steps=40)


def bench(n1, n3, mode, steps, engine, fit_steps=None, *, threads, engine_threads=None, extra=()):
    cmd = [sys.executable, "-m", "cracklab.cli", "bench", "--n1", str(n1), "--n3", str(n3), "--mode", mode,
           "--steps", str(steps), "--engine", engine, "--threads", str(threads), *extra, "--json"]
    if engine_threads is not None:
        cmd[-1:-1] = ["--engine-threads", str(engine_threads)]
    if fit_steps is not None:
        cmd[-1:-1] = ["--fit-steps", str(fit_steps)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    res = json.loads(out.strip().splitlines()[-1])
    res["command"] = "cracklab bench " + " ".join(cmd[4:])
    return res


def table(results) -> str:
    lines = ["| grid | mode | steps | engine | ms / step | us / point / step | FFT pair ms | "
             "ratio to FFT pair | transforms / step | their cost ms | peak RSS MB | target ms |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        tgt = TARGETS.get((r["n1"], r["n3"], r["mode"]))
        steps = f"{r['steps']}" + (f" (fit {r['fit_steps']})" if r.get("fit_steps", 0) > r["steps"] else "")
        lines.append(f"| {r['n1']} x {r['n3']} | {r['mode']} | {steps} | {r['engine']} | "
                     f"{r['ms_per_step']:.2f} | {r['us_per_point_per_step']:.3f} | {r['fft_pair_ms']:.2f} | "
                     f"{r['ms_per_step'] / r['fft_pair_ms']:.1f} | {r['transforms_per_step']:g} | "
                     f"{r['fft_floor_ms']:.2f} | {r['peak_rss_mb']:.0f} | "
                     f"{'' if tgt is None else tgt} |")
    return "\n".join(lines)


def stages(rounds=3, quick=False):
    """The breakdown by stage of every case of STAGE_CASES, ``rounds`` times (the cases in
    turn within a round): the list of the bench's results, each with "case" and "round"."""
    (n1, n3), steps = (STAGE_QUICK["grid"], STAGE_QUICK["steps"]) if quick else (STAGE_GRID, STAGE_STEPS)
    results = []
    for k in range(rounds):
        for name, mode, law, bimaterial, eng_t in STAGE_CASES:
            extra = ["--law", law] + (["--bimaterial"] if bimaterial else [])
            print(f"round {k + 1}: {name}", flush=True)
            load = os.getloadavg()[0]
            res = bench(n1, n3, mode, steps, "exponential", threads=1, engine_threads=eng_t, extra=extra)
            results.append({**res, "case": name, "round": k, "load": load})
    return results


def stage_table(results) -> str:
    """Per case, the round of the median step (ratio to its own FFT pair): ms per step and
    each stage in ms, with the same figure in units of that run's FFT pair in brackets; the
    engine's worker (overlapped, not in the step's stages) where it runs; the rounds'
    range of the step's ratio and the host's load average."""
    from cracklab.cli.bench import STAGES

    head = ["case", "ms / step", "FFT pair ms", "timed by stage"] + list(STAGES) + \
        ["worker (overlapped)", "step / pair (rounds)", "load"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in dict.fromkeys(r["case"] for r in results):
        rows = sorted((r for r in results if r["case"] == name), key=lambda r: r["ms_per_step"] / r["fft_pair_ms"])
        r = rows[len(rows) // 2]
        pair = r["fft_pair_ms"]
        cell = lambda ms: "-" if ms is None else f"{ms:.2f} ({ms / pair:.1f})"
        ratios = [x["ms_per_step"] / x["fft_pair_ms"] for x in rows]
        loads = [x["load"] for x in rows]
        lines.append(f"| {name} | {cell(r['ms_per_step'])} | {pair:.3f} | {cell(r['stages_total_ms'])} | "
                     + " | ".join(cell(r["stages_ms"][s]) for s in STAGES)
                     + f" | {cell(r['worker_ms'])} | {ratios[0]:.1f}-{ratios[-1]:.1f} | "
                       f"{min(loads):.1f}-{max(loads):.1f} |")
    return "\n".join(lines)


#: the settings of the scaling study: (name, FFT threads, engine threads)
SCALING = [("1 thread", 1, 1), ("2 threads", 2, 2), ("2 engine threads, 1 FFT thread", 1, 2)]
SCALING_CASE = dict(grid=(512, 512), mode="shear", law="slip_weakening", steps=200)


def scaling(rounds=3, quick=False):
    """Every setting of SCALING on SCALING_CASE (32 x 32 with ``quick``), in turn in every
    round: the bench's results, each with "setting", "round" and the host's "load"."""
    case = SCALING_CASE
    (n1, n3), steps = ((32, 32), 40) if quick else (case["grid"], case["steps"])
    results = []
    for k in range(rounds):
        for name, fft_t, eng_t in SCALING:
            print(f"round {k + 1}: {name}", flush=True)
            load = os.getloadavg()[0]
            res = bench(n1, n3, case["mode"], steps, "exponential", threads=fft_t, engine_threads=eng_t,
                        extra=["--law", case["law"]])
            results.append({**res, "setting": name, "round": k, "load": load})
    return results


def scaling_table(results) -> str:
    """Per setting: the rounds' steps, their median, its speed-up on the one-thread median,
    the median FFT pair and the median step in FFT pairs; then the one-thread round of the
    median step by stage."""
    from cracklab.cli.bench import STAGES

    med = lambda xs: sorted(xs)[len(xs) // 2]
    one = med([r["ms_per_step"] for r in results if r["setting"] == SCALING[0][0]])
    lines = ["| setting | ms / step (rounds) | median | speed-up | FFT pair ms | step / pair | load |",
             "|---|---|---|---|---|---|---|"]
    for name, _, _ in SCALING:
        rows = [r for r in results if r["setting"] == name]
        ms, pair = med([r["ms_per_step"] for r in rows]), med([r["fft_pair_ms"] for r in rows])
        loads = [r["load"] for r in rows]
        each = ", ".join(f"{r['ms_per_step']:.2f}" for r in rows)
        lines.append(f"| {name} | {each} | "
                     f"{ms:.2f} | {one / ms:.2f}x | {pair:.2f} | {ms / pair:.1f} | {min(loads):.1f}-{max(loads):.1f} |")
    rows = sorted((r for r in results if r["setting"] == SCALING[0][0]), key=lambda r: r["ms_per_step"])
    r = rows[len(rows) // 2]
    lines += ["", "one thread, by stage (ms per step): " + ", ".join(
        f"{s} {r['stages_ms'][s]:.2f}" for s in STAGES if r["stages_ms"].get(s) is not None)
        + f"; the stages sum to {r['stages_total_ms']:.2f} ms"]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two small rows only")
    ap.add_argument("--threads", nargs="+", default=["1", "2", "2/1"],
                    help="thread settings to measure, each over every row: N (FFTs and engine) or E/F "
                         "(E engine threads, F FFT threads); default 1 2 2/1")
    ap.add_argument("--out", default="out/performance")
    ap.add_argument("--stages", action="store_true", help="the breakdown by stage (STAGE_CASES) instead")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of the breakdown by stage or of the scaling")
    ap.add_argument("--scaling", action="store_true", help="one core against two (SCALING) instead")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for flag, name, run, tabulate in ((args.scaling, "scaling", scaling, scaling_table),
                                      (args.stages, "stages", stages, stage_table)):
        if flag:
            results = run(args.rounds, args.quick)
            (out / f"{name}.json").write_text(json.dumps(results, indent=1))
            md = tabulate(results)
            (out / f"{name}.md").write_text(md + "\n")
            print(md)
            return
    results = []
    configs = []
    for spec in args.threads:
        e, _, f = str(spec).partition("/")
        configs.append((int(e), int(f or e)))
    for eng_t, fft_t in configs:
        for row in (QUICK if args.quick else ROWS):
            if (eng_t, fft_t) != (1, 1) and row[4] == "direct":
                continue  # the direct engine's reference row, one thread only
            print("cracklab bench", row, f"engine threads={eng_t}, FFT threads={fft_t}", flush=True)
            results.append(bench(*row, threads=fft_t, engine_threads=eng_t))
            print(f"  {results[-1]['ms_per_step']:.2f} ms/step", flush=True)
    (out / "bench.json").write_text(json.dumps(results, indent=1))

    def title(e, f):
        name = f"{e} thread{'s' if e > 1 else ''}" if e == f else f"{e} engine threads, {f} FFT thread{'s' if f > 1 else ''}"
        overlap = any(r.get("overlap") for r in results if (r["engine_threads"], r["threads"]) == (e, f))
        return name + (" (the engine's advance overlapped with the FFTs and the law)" if overlap else "")

    md = "\n\n".join(title(e, f) + ":\n\n" + table([r for r in results if (r["engine_threads"], r["threads"]) == (e, f)])
                      for e, f in configs)
    (out / "bench.md").write_text(md + "\n")
    print(md)


if __name__ == "__main__":
    main()
