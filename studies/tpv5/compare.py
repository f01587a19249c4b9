"""Comparison of cracklab TPV5 station series with the MDSBI reference (docs/studies/tpv5.md).

The series measures and the acceptance check are TPV3's (``studies.benchmarks.measures``:
one definition of rupture time, final slip, peak slip rate and of the
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

import math

import numpy as np

from studies.benchmarks.harness import mdsbi_station, reference_dir
from studies.benchmarks.measures import (  # noqa: F401 - TPV3's measures, under this study's name
    ACCEPT_DX, COLUMNS, QUANTITY, THRESHOLD, TOL_FINAL_SLIP, TOL_PEAK_RATE, TOL_RUPTURE_TIME, TOLERANCES,
    acceptance, check_acceptance, compare_station, differences, final_value, fmt_tol, metrics, peak, read_mdsbi,
    resample, rupture_time, series_errors)

REFERENCE = "tpv5_mdsbi"


def default_reference_dir():
    """The reference's folder when no ``--reference`` is given (``harness.reference_dir``)."""
    return reference_dir(REFERENCE)


def load_reference(station: str, directory=None) -> dict:
    """The MDSBI series of one TPV5 station: dict of numpy arrays keyed by ``COLUMNS``."""
    return mdsbi_station(REFERENCE, station, directory)


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
