"""BP1-QD's events against the step's pair and tolerance (docs/studies/cycles.md, "The
step's tolerance"): the run at dz = 25 m over 1500 years with Dormand-Prince 5(4) at 1e-5,
1e-6 and 1e-7, to set against the page's run at that dz (the builder's Bogacki-Shampine
3(2) at 1e-4): how far the event times and peak slip rates move, against the grid's
difference between 50 and 25 m, and what each costs in steps and time.

    python -m studies.cycles.tolerance [-o OUT] [--dz 25] [--years 1500]

writes OUT/qd_tolerance.json: {case: {dz, years, pair, tolerance, wall_s, accepted_steps,
t_start_s (the events' starts, s), peak_slip_rate}}.
"""
from __future__ import annotations

import sys
from pathlib import Path

from studies.cycles.fd_checks import catalogue, run_all

CASES = {f"dormand_prince {tol:g}": {"pair": "dormand_prince", "tolerance": tol} for tol in (1e-5, 1e-6, 1e-7)}


def run_case(out, dz, years, pair, tolerance) -> dict:
    from cracklab.scenes import bp1

    scene = bp1(dz=dz, years=years, tolerance=tolerance, pair=pair)
    return {"dz": dz, "years": years, "pair": pair, "tolerance": tolerance,
            **catalogue(scene, Path(out) / f"bp1_check_dz{dz:g}_{pair}_tol{tolerance:g}.zarr")}


def main(argv=None) -> int:
    return run_all(argv, __doc__, 25.0, 1500.0, CASES, run_case, "qd_tolerance.json")


if __name__ == "__main__":
    sys.exit(main())
