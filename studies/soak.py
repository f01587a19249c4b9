"""Soak and memory study (docs/guide/reliability.md, "Long runs").

One command:  nice -n 10 .venv/bin/python studies/soak.py [--quick]

1. soak: a 128 x 128 elliptical crack (engine "exponential") run for 20000 steps into a
   Zarr store with snapshots, stations and checkpoints; the wall time of every step and
   the resident memory (RSS) every 100 steps.
2. big: a 1024 x 1024 crack recording two fields every 5 steps to a store, with a
   checkpoint, for a few dozen steps; its peak RSS.

Each part runs in its own process (clean peak RSS). Writes studies/soak/soak.json and
studies/soak/soak.png (cost per step and RSS against the step).
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "soak"


def _rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run_part(n, nsteps, every, fields, checkpoint_every, rss_every=100):
    """Run one crack into a temporary store; per-step wall times and RSS samples."""
    import cracklab
    from cracklab import Numerics, Record

    sim = importlib.import_module("cracklab.output.simulate")
    dt = 0.5 / n
    scene = cracklab.scenes.elliptical_crack(
        n=n, a=0.25, b=0.2, t_end=nsteps * dt * (1 - 1e-9), numerics=Numerics(engine="exponential"),
        record=Record(fields=fields, every=every, stations={"centre": (0.5, 0.5), "tip": (0.75, 0.5)}))
    assert scene.nsteps == nsteps, scene.nsteps
    stamps = np.zeros(nsteps + 1)
    cpu = np.zeros(nsteps + 1)
    rss = []
    ckpts = []
    real_call, real_ckpt = sim.Recorder.__call__, sim.Recorder.checkpoint

    def call(self, state):
        real_call(self, state)
        stamps[state.n] = time.perf_counter()
        cpu[state.n] = time.process_time()
        if state.n % rss_every == 0:
            rss.append((state.n, _rss_mb()))

    def ckpt(self, stepper, k):
        took = real_ckpt(self, stepper, k)
        size = (Path(self.path) / "_checkpoint" / "state.npz").stat().st_size
        ckpts.append({"step": k, "seconds": took, "mb": size / 2**20})
        return took

    sim.Recorder.__call__, sim.Recorder.checkpoint = call, ckpt
    tmp = Path(tempfile.mkdtemp(prefix="cracklab-soak-"))
    try:
        t0 = time.perf_counter()
        ds = cracklab.simulate(scene, store=tmp / "run.zarr", checkpoint_every=checkpoint_every)
        total = time.perf_counter() - t0
        assert ds.attrs["cracklab_status"] == "complete"
        nsnap = int(ds.sizes["t"])
        store_mb = sum(f.stat().st_size for f in (tmp / "run.zarr").rglob("*") if f.is_file()) / 2**20
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    # ms for steps 1..nsteps, including recording, store writes and checkpoints: wall time
    # (what a user waits; noisy on a shared machine) and CPU time of this process
    cost = np.diff(stamps) * 1e3
    cpu_cost = np.diff(cpu) * 1e3
    return {"n": n, "steps": nsteps, "fields": list(fields), "every": every, "snapshots": nsnap,
            "total_s": total, "cost_ms": cost.tolist(), "cpu_ms": cpu_cost.tolist(), "rss": rss, "peak_rss_mb": _peak_mb(),
            "checkpoints": ckpts, "store_mb": store_mb}


def _child(args):
    res = run_part(args.n, args.steps, args.every, tuple(args.fields.split(",")), args.checkpoint_every,
                   rss_every=max(1, args.steps // 200))
    print(json.dumps(res))


def _spawn(n, steps, every, fields, checkpoint_every):
    cmd = [sys.executable, __file__, "--child", "--n", str(n), "--steps", str(steps), "--every", str(every),
           "--fields", ",".join(fields), "--checkpoint-every", str(checkpoint_every)]
    print("running:", " ".join(cmd[1:]), flush=True)
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def summarise(part):
    cost = np.asarray(part["cost_ms"])
    cpu = np.asarray(part["cpu_ms"])
    med = [float(np.median(b)) for b in np.array_split(cost, 10)]
    cmed = [float(np.median(b)) for b in np.array_split(cpu, 10)]
    rss = np.asarray(part["rss"])
    half = rss[:, 0] >= rss[-1, 0] / 2
    return {
        "median_ms_per_step": float(np.median(cost)),
        "median_ms_per_step_by_tenth": med,
        "last_tenth_over_first_tenth": med[-1] / med[0],
        "median_cpu_ms_per_step": float(np.median(cpu)),
        "median_cpu_ms_per_step_by_tenth": cmed,
        "cpu_last_tenth_over_first_tenth": cmed[-1] / cmed[0],
        "cpu_max_tenth_over_min_tenth": max(cmed) / min(cmed),
        "p99_ms": float(np.percentile(cost, 99)), "max_ms": float(cost.max()),
        "rss_mb_first": float(rss[0, 1]), "rss_mb_last": float(rss[-1, 1]),
        "rss_growth_second_half_mb": float(rss[half, 1].max() - rss[half, 1].min()),
        "peak_rss_mb": part["peak_rss_mb"], "total_s": part["total_s"], "snapshots": part["snapshots"],
        "store_mb": part["store_mb"], "checkpoints": len(part["checkpoints"]),
        "checkpoint_mb": max((c["mb"] for c in part["checkpoints"]), default=0.0),
        "checkpoint_s_max": max((c["seconds"] for c in part["checkpoints"]), default=0.0),
    }


def figure(soak, big, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    for row, part in enumerate((soak, big)):
        label = f"{part['n']} x {part['n']}, {part['steps']} steps"
        ax = axes[row, 0]
        steps = np.arange(1, len(part["cost_ms"]) + 1)
        w = max(1, steps.size // 100)
        k = steps.size // w * w
        for key, colour, name in (("cost_ms", "C0", "wall"), ("cpu_ms", "C1", "CPU")):
            y = np.asarray(part[key])
            ax.plot(steps, y, ",", color=colour, alpha=0.25)
            ax.plot(steps[:k].reshape(-1, w).mean(1), np.median(y[:k].reshape(-1, w), 1), "-", color=colour,
                    label=f"{name} time" + (f", median per {w} steps" if w > 1 else ""))
        ax.set(xlabel="step", ylabel="time per step (ms)", yscale="log", title=f"cost per step: {label}")
        rss = np.asarray(part["rss"])
        ax = axes[row, 1]
        ax.plot(rss[:, 0], rss[:, 1], ".-", color="C2", label=f"RSS (peak {part['peak_rss_mb']:.0f} MB)")
        ax.set(xlabel="step", ylabel="RSS (MB)", title=f"resident memory: {label}", ylim=(0, None))
        for c in part["checkpoints"]:
            for a in axes[row]:
                a.axvline(c["step"], color="0.6", lw=0.8, ls=":")
    for ax in axes.flat:
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle("cracklab soak (dotted: checkpoints); includes recording and store writes", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--n", type=int, default=128)
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--every", type=int, default=500)
    p.add_argument("--fields", default="delta_2,v_2")
    p.add_argument("--checkpoint-every", default="60s")
    p.add_argument("--big-n", type=int, default=1024)
    p.add_argument("--big-steps", type=int, default=30)
    p.add_argument("--quick", action="store_true", help="2000 soak steps (a smoke run)")
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args()
    if args.child:
        return _child(args)
    steps = 2000 if args.quick else args.steps
    soak = _spawn(args.n, steps, args.every, args.fields.split(","), args.checkpoint_every)
    big = _spawn(args.big_n, args.big_steps, 5, ["delta_2", "v_2"], 10)
    result = {"soak": {**summarise(soak), "n": soak["n"], "steps": soak["steps"], "every": soak["every"],
                       "checkpoint_every": args.checkpoint_every, "checkpoint_list": soak["checkpoints"]},
              "big": {**summarise(big), "n": big["n"], "steps": big["steps"], "checkpoint_list": big["checkpoints"]},
              "machine": {"cpus": os.cpu_count(), "loadavg": os.getloadavg()}}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "soak.json").write_text(json.dumps(result, indent=1))
    figure(soak, big, args.out / "soak.png")
    print(json.dumps({k: {kk: vv for kk, vv in v.items() if not isinstance(vv, list)} for k, v in result.items()},
                     indent=1))


if __name__ == "__main__":
    main()
