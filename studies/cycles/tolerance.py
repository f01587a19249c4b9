"""BP1-QD's events against the step's tolerance (docs/studies/cycles.md, "The step's
tolerance"): the run at dz = 25 m over 1500 years at tolerances ten and a hundred times
tighter than the builder's (1e-6 and 1e-7 against 1e-5), to set against the page's run at
that dz: how far the event times and peak slip rates move, against the grid's difference
between 50 and 25 m, and what each tolerance costs in steps.

    python -m studies.cycles.tolerance [-o OUT] [--dz 25] [--years 1500]

writes OUT/qd_tolerance.json: {tolerance: {dz, years, tolerance, wall_s, accepted_steps,
t_start_s (the events' starts, s), peak_slip_rate}}.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

TOLERANCES = (1e-6, 1e-7)


def run_case(out, dz, years, tolerance) -> dict:
    from cracklab import analysis, simulate
    from cracklab.scenes import bp1

    scene = bp1(dz=dz, years=years, tolerance=tolerance)
    t0 = time.time()
    ds = simulate(scene, store=str(Path(out) / f"bp1_check_dz{dz:g}_tol{tolerance:g}.zarr"), resume=True)
    wall = time.time() - t0
    ev = analysis.events(ds)
    return {"dz": dz, "years": years, "tolerance": tolerance, "wall_s": wall,
            "accepted_steps": int(ds.attrs["accepted_steps"]), "t_start_s": ev.t_start.values.tolist(),
            "peak_slip_rate": ev.peak_slip_rate.values.tolist()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default="out/cycles")
    p.add_argument("--dz", type=float, default=25.0)
    p.add_argument("--years", type=float, default=1500.0)
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res = {}
    for tol in TOLERANCES:
        res[f"{tol:g}"] = run_case(out, args.dz, args.years, tol)
        print(f"tolerance {tol:g}: {res[f'{tol:g}']['wall_s']:.0f} s, {res[f'{tol:g}']['accepted_steps']} steps",
              flush=True)
    (out / "qd_tolerance.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
