"""Run the asperity ensemble (study.toml next to this file) and draw its summary figures.

    python3 studies/asperity_ensemble/run.py [-o OUT] [--scheduler ADDRESS] [--workers N]

writes OUT/ensemble.zarr (one Zarr v3 store, a group per member) and OUT/ensemble_*.png,
OUT/ensemble_random.gif (OUT defaults to ./out). It is the ensemble part of
`cracklab demo`; the same from the command line:

    cracklab sweep studies/asperity_ensemble/study.toml -o out/ensemble.zarr
    cracklab plot out/ensemble.zarr -o out/ensemble_plots

A rerun skips the members already complete in the store (delete it to start over).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

STUDY = Path(__file__).resolve().with_name("study.toml")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", default="out")
    parser.add_argument("--scheduler", default=None, help="address of a running dask scheduler")
    parser.add_argument("--workers", type=int, default=None, help="local worker processes")
    args = parser.parse_args(argv)
    from cracklab.cli.demo import ensemble_demo

    ok = ensemble_demo(args.out, study=STUDY, scheduler=args.scheduler, workers=args.workers)
    return 0 if ok else 1


if __name__ == "__main__":   # required: the local cluster starts worker processes
    sys.exit(main())
