"""Throughput of a sweep, in members per minute: a store on the local disk against one on
an S3 server on loopback (moto's, as the tests start it: tests/s3_server.py), on one and
two worker processes of an embedded dask cluster, and, where a one-node Slurm can be
started here (tests/slurm.py: root, the Debian packages installed), on two Slurm jobs
(``--cluster slurm``) writing to the S3 server.

    python3 studies/cluster/throughput.py [--members 12] [--n 64] [--t-end 1.0] [--json FILE]

Each configuration sweeps the same study (elliptical_crack, n x n/2 grid, the opening
recorded every 4 steps) into a fresh store, after one member run here to fill numba's
cache. "members/min" is the members over the sweep's wall time, the cluster's start
included; "s/member" is the median of the members' own run time (attr elapsed_s, on the
worker). Prints a Markdown table (docs/guide/cluster.md shows one) and the host's load.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))       # the loopback S3 server and Slurm of the tests


def study(members: int, n: int, t_end: float):
    from cracklab import ensemble as E

    builder = E.Builder("elliptical_crack", n=n, a=0.25, b=0.2, t_end=t_end)
    sweep = E.Sweep(product={"p": [round(1.0 + 0.05 * i, 3) for i in range(members)]},
                    base={"record.every": 4, "record.fields": ["delta_2"]})
    return builder, sweep


def one(label, store, builder, sweep, **kw):
    from cracklab import ensemble as E

    t0 = time.perf_counter()
    result = E.run(builder, sweep, store, progress=False, resume=False, **kw)
    wall = time.perf_counter() - t0
    assert result.ok, result.failed
    per = [float(E.open_member(store, s["id"]).attrs["elapsed_s"]) for s in E.member_status(store)]
    n = len(per)
    row = {"config": label, "members": n, "wall_s": round(wall, 2), "members_per_min": round(60 * n / wall, 1),
           "s_per_member": round(statistics.median(per), 3), "load": round(os.getloadavg()[0], 2)}
    print(f"  {label}: {row['members_per_min']} members/min ({wall:.1f} s, {row['s_per_member']} s/member, "
          f"load {row['load']})", file=sys.stderr, flush=True)
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=12)
    parser.add_argument("--n", type=int, default=64)
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--json", default=None, help="also write the rows to this file")
    args = parser.parse_args(argv)
    from cracklab import ensemble as E
    from s3_server import S3Server
    import slurm

    builder, sweep = study(args.members, args.n, args.t_end)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        E.run(builder, E.Sweep(product={"p": [1.0]}, base=sweep.base), f"{tmp}/warm.zarr", scheduler="synchronous",
              progress=False)                                     # numba's cache filled
        server = S3Server().start()
        try:
            os.environ.update(server.env(tmp))
            bucket = server.make_bucket()
            for workers in (1, 2):
                rows.append(one(f"local disk, {workers} worker{'s' if workers > 1 else ''}", f"{tmp}/w{workers}.zarr",
                                builder, sweep, workers=workers))
                rows.append(one(f"S3 on loopback, {workers} worker{'s' if workers > 1 else ''}",
                                f"s3://{bucket}/w{workers}.zarr", builder, sweep, workers=workers))
            if slurm.missing() is None:
                cluster = slurm.Slurm(f"{tmp}/slurm").start()
                try:
                    os.environ.update(cluster.env)
                    rows.append(one("S3 on loopback, 2 Slurm jobs", f"s3://{bucket}/slurm.zarr", builder, sweep,
                                    cluster="slurm", workers=2,
                                    cluster_options={"interface": "lo", "log_directory": f"{tmp}/jobs"}))
                finally:
                    cluster.stop()
            else:
                print(f"  no Slurm row: {slurm.missing()}", file=sys.stderr)
        finally:
            server.stop()
    grid = f"{args.n} x {args.n // 2}"
    print(f"\n{args.members} members (elliptical_crack, {grid}, t_end {args.t_end}, the opening every 4 steps); "
          f"{os.cpu_count()} cores; load average at the end {os.getloadavg()[0]:.1f}\n")
    print("| configuration | members/min | wall (s) | s/member (median, on the worker) | load (1 min) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for r in rows:
        print(f"| {r['config']} | {r['members_per_min']} | {r['wall_s']} | {r['s_per_member']} | {r['load']} |")
    if args.json:
        Path(args.json).write_text(json.dumps({"members": args.members, "n": args.n, "t_end": args.t_end,
                                               "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":   # required: the local cluster starts worker processes
    sys.exit(main())
