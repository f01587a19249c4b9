"""Benchmarks of the performance issue, each a `cracklab bench` command; writes a JSON and a
markdown table (docs/studies/performance.md quotes it).

    .venv/bin/python studies/performance/run.py [--quick] [--out out/performance]

Each row runs in its own process (`cracklab bench --json`), so peak memory is per row.
"""
from __future__ import annotations

import argparse
import json
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


def bench(n1, n3, mode, steps, engine, fit_steps=None, *, threads, engine_threads=None):
    cmd = [sys.executable, "-m", "cracklab.cli", "bench", "--n1", str(n1), "--n3", str(n3), "--mode", mode,
           "--steps", str(steps), "--engine", engine, "--threads", str(threads), "--json"]
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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two small rows only")
    ap.add_argument("--threads", nargs="+", default=["1", "2", "2/1"],
                    help="thread settings to measure, each over every row: N (FFTs and engine) or E/F "
                         "(E engine threads, F FFT threads); default 1 2 2/1")
    ap.add_argument("--out", default="out/performance")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
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
