"""Comparison of cracklab TPV5 station series with the MDSBI reference (docs/tpv5.md).

The series measures and the acceptance check are TPV3's (``studies/tpv3/compare.py``,
loaded from there: one definition of rupture time, final slip, peak slip rate and of the
acceptance for both studies); this module adds what TPV5 needs and TPV3 does not:

* ``load_reference`` of ``shared/reference/tpv5_mdsbi`` (the same file format);
* ``lag_fit``: the rupture-time lag of a first-order scheme against the time step,
  lag(beta) = a + b beta fitted to runs at several beta, with the beta that brings the
  lag within a limit and what that costs in steps;
* ``domain_change``: how much the acceptance quantities of each station move between two
  periodic cells (the domain check);
* ``surface_check``: what the station on the free surface must show (its dip slip rate
  vanishes exactly, it ruptures).

Plain functions on numbers and numpy arrays, checked on synthetic data in
tests/studies/test_tpv5_study.py.
"""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np

_TPV3 = Path(__file__).resolve().parents[1] / "tpv3" / "compare.py"
_spec = importlib.util.spec_from_file_location("_tpv3_compare_for_tpv5", _TPV3)
_C3 = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_C3)

THRESHOLD = _C3.THRESHOLD
COLUMNS = _C3.COLUMNS
TOL_RUPTURE_TIME = _C3.TOL_RUPTURE_TIME   # 0.05 s, issue 18 point 4: the same numbers as TPV3
TOL_FINAL_SLIP = _C3.TOL_FINAL_SLIP       # 3 %
TOL_PEAK_RATE = _C3.TOL_PEAK_RATE         # 15 %
TOLERANCES = _C3.TOLERANCES
ACCEPT_DX = _C3.ACCEPT_DX                 # 100 m
QUANTITY = _C3.QUANTITY
rupture_time = _C3.rupture_time
peak = _C3.peak
final_value = _C3.final_value
resample = _C3.resample
metrics = _C3.metrics
compare_station = _C3.compare_station
differences = _C3.differences
acceptance = _C3.acceptance
check_acceptance = _C3.check_acceptance
series_errors = _C3.series_errors
_fmt_tol = _C3._fmt_tol


def default_reference_dir() -> Path:
    here = Path(__file__).resolve()
    for parent in here.parents:
        cand = parent / "shared" / "reference" / "tpv5_mdsbi"
        if cand.is_dir():
            return cand
    return Path("/work/shared/reference/tpv5_mdsbi")


def load_reference(station: str, directory=None) -> dict:
    """The MDSBI series of one TPV5 station: dict of numpy arrays keyed by ``COLUMNS``."""
    return _C3.load_reference(station, directory or default_reference_dir())


def lag_fit(betas, lags, *, limit=TOL_RUPTURE_TIME, beta_now=None, order=1) -> dict:
    """Fit lag(beta) = a + b beta^p (least squares, p = ``order``) to rupture-time lags (s)
    measured at the time-step factors ``betas`` (at least two different ones): the lag of
    a scheme of order p in dt is a + O(dt^p). Returns {"a": the lag at beta -> 0 (what the
    grid leaves), "b": s per unit beta^p, "order": p, "beta_within": the largest beta whose
    fitted |lag| is within ``limit`` (inf when every beta is, 0 when none is, i.e.
    |a| > limit), "steps_factor": beta_now / beta_within, the factor in steps (and so in
    cost: a step costs the same at any beta with the exponential engine) to reach it from
    ``beta_now`` (the largest beta given, by default; 1 when it already holds)}."""
    x = np.asarray(betas, dtype=float)
    y = np.asarray(lags, dtype=float)
    if x.shape != y.shape or x.size < 2 or np.unique(x).size < 2:
        raise ValueError("need lags at two or more different beta")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and np.all(x > 0)):
        raise ValueError("betas must be > 0 and lags finite")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    b, a = np.polyfit(x ** order, y, 1)
    beta_now = float(x.max() if beta_now is None else beta_now)
    if abs(a) > limit:
        within = 0.0
    elif abs(b) * beta_now ** order <= 1e-9 * limit:      # no dependence on beta (to round-off)
        within = math.inf
    else:
        # |a + b beta^p| <= limit for 0 <= beta <= within
        edge = (math.copysign(limit, b) - a) / b
        within = max(edge, 0.0) ** (1.0 / order)
    factor = math.inf if within == 0 else max(1.0, beta_now / within)
    return {"a": float(a), "b": float(b), "order": int(order), "beta_within": float(within),
            "steps_factor": float(factor), "beta_now": beta_now}


def domain_change(main: dict, other: dict) -> dict:
    """How the acceptance quantities move between two cells: ``main`` and ``other`` are
    {station: compare_station result} of the same dx. Returns per station and as the
    largest over stations: rupture time (s, absolute), final slip and peak slip rate
    (relative to ``main``'s values), final stress (MPa)."""
    per = {}
    for s, a in main.items():
        b = other[s]
        per[s] = {"rupture_time": abs(b["sim"]["rupture_time"] - a["sim"]["rupture_time"]),
                  "final_slip": abs(b["sim"]["final_slip"] / a["sim"]["final_slip"] - 1.0),
                  "peak_rate": abs(b["sim"]["peak_rate"] / a["sim"]["peak_rate"] - 1.0),
                  "final_stress": abs(b["sim"]["final_stress"] - a["sim"]["final_stress"])}
    worst = {q: max(v[q] for v in per.values()) for q in ("rupture_time", "final_slip", "peak_rate",
                                                          "final_stress")}
    return {"stations": per, "max": worst}


def surface_check(t, rate_strike, rate_dip) -> dict:
    """The free-surface station: the dip component of its slip rate must vanish exactly
    (delta_3 is odd about the surface) and its strike slip rate must rupture.
    Returns {"max_abs_dip_rate", "rupture_time", "pass"}."""
    dip = float(np.max(np.abs(np.asarray(rate_dip, dtype=float))))
    rt = rupture_time(t, rate_strike)
    return {"max_abs_dip_rate": dip, "rupture_time": rt, "pass": bool(dip == 0.0 and rt == rt)}
