"""Comparison and acceptance of the TPV101/TPV103 study (docs/studies/tpv101.md, docs/studies/tpv103.md).

Plain functions on numpy arrays, checked on synthetic data with known answers
(tests/studies/test_tpv101_study.py):

* ``rupture_time``, ``station_metrics``: rupture time (first crossing of 1 mm/s,
  interpolated between samples), peak slip rate and final slip of one station series;
* ``compare_station``: cracklab against the uguca reference at one station, each on
  its own time steps, the final slip at the common end time;
* ``match_nodes``, ``field_difference``: two rupture-time fields on the nodes they share
  inside the velocity-weakening box, where both ruptured (RMS, largest, mean);
* ``convergence``: the differences between successive grid spacings and their ratio;
* ``check_tpv101``, ``check_tpv103``: the acceptance of issue 19 (points 3-5) as rows
  of value, limit and pass, the study's result.

The reference (``shared/reference/tpv101_uguca``): station files with six columns
t (s), h-slip (m), h-slip-rate (m/s), h-shear-stress (MPa), theta (s), log10 theta after
'#' header lines; ``rupture_time.nc`` on coordinates strike and depth (m), the
hypocentre at strike 0, depth 7.5 km.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from studies.benchmarks import measures
from studies.benchmarks.harness import reference_dir

THRESHOLD = 1e-3                 # m/s: rupture = slip rate first above 1 mm/s
REF_COLUMNS = ("t", "slip", "rate", "stress", "theta", "log10_theta")
REF_STATIONS = ("faultst000dp075", "faultst000dp030", "faultst090dp075")
HYPO_DEPTH = 7500.0              # m
BOX = (15000.0, 7500.0)          # half widths of the velocity-weakening box (strike, dip), m
ACCEPT_DX = 100.0                # m: the comparison with uguca
FINE_DX = 50.0                   # m: the convergence check 100 m -> 50 m
#: issue 19, point 4: against uguca at 100 m
TOLERANCES = {"rupture_time": 0.1, "peak_rate": 0.15, "final_slip": 0.05, "field_rms": 0.1}
#: issue 19, points 3 and 5: between 100 m and 50 m (s)
TOL_CONVERGENCE = 0.05
TOL_CONVERGENCE_SLIP = 0.05      # relative final slip between 100 m and 50 m (TPV103)


REFERENCE = "tpv101_uguca"


def default_reference_dir() -> Path:
    """The reference's folder when no ``--reference`` is given (``harness.reference_dir``)."""
    return reference_dir(REFERENCE)


def load_reference(station: str, directory=None) -> dict:
    """uguca's series at one station: dict of arrays keyed by ``REF_COLUMNS``."""
    path = reference_dir(REFERENCE, directory) / f"{station}.txt"
    data = np.loadtxt(path, comments="#")
    if data.ndim != 2 or data.shape[1] != len(REF_COLUMNS):
        raise ValueError(f"{path}: expected {len(REF_COLUMNS)} columns, got shape {data.shape}")
    return {name: data[:, j] for j, name in enumerate(REF_COLUMNS)}


def load_reference_field(directory=None):
    """uguca's rupture-time field: (strike offsets (m), dip offsets (m, depth minus the
    hypocentre's), rupture time (s) as a (strike, dip) array, NaN where it never ruptured)."""
    import xarray as xr

    path = reference_dir(REFERENCE, directory) / "rupture_time.nc"
    with xr.open_dataset(path) as ds:
        rt = ds.rupture_time.transpose("strike", "depth").values.astype(float)
        return ds.strike.values.astype(float), ds.depth.values.astype(float) - HYPO_DEPTH, rt


def rupture_time(t, rate, threshold=THRESHOLD, interpolate=True) -> float:
    """First time ``rate`` exceeds ``threshold`` (NaN if it never does): linearly
    interpolated between that sample and the one before (``interpolate``, this study's
    definition), else that sample's time (``studies.benchmarks.measures.rupture_time``)."""
    return measures.rupture_time(t, rate, threshold, interpolate)


def station_metrics(t, slip, rate, *, at=None, threshold=THRESHOLD) -> dict:
    """Rupture time (interpolated crossing), peak slip rate and its time, and the slip at
    time ``at`` (linear interpolation; the last sample when None) of one series."""
    t = np.asarray(t, dtype=float)
    slip = np.asarray(slip, dtype=float)
    rate = np.asarray(rate, dtype=float)
    if at is None:
        final = float(slip[-1])
    else:
        if not t[0] <= at <= t[-1] * (1 + 1e-9):
            raise ValueError(f"time {at} outside the series [{t[0]}, {t[-1]}]")
        final = float(np.interp(at, t, slip))
    i = int(np.nanargmax(rate))
    return {"rupture_time": rupture_time(t, rate, threshold), "peak_rate": float(rate[i]),
            "peak_time": float(t[i]), "final_slip": final}


def compare_station(sim: dict, ref: dict, *, threshold=THRESHOLD) -> dict:
    """One station, cracklab (``sim``) against the reference (``ref``), dicts with t, slip,
    rate. Each is measured on its own time steps; the final slip at the common end time.

    Returns {"sim", "ref": station_metrics, "diff": {"rupture_time": sim - ref (s)},
    "rel": {"peak_rate", "final_slip": sim / ref - 1}, "t_end"}."""
    t_end = min(float(sim["t"][-1]), float(ref["t"][-1]))
    m_sim = station_metrics(sim["t"], sim["slip"], sim["rate"], at=t_end, threshold=threshold)
    m_ref = station_metrics(ref["t"], ref["slip"], ref["rate"], at=t_end, threshold=threshold)
    return {"sim": m_sim, "ref": m_ref,
            "diff": {"rupture_time": m_sim["rupture_time"] - m_ref["rupture_time"],
                     "peak_time": m_sim["peak_time"] - m_ref["peak_time"]},
            "rel": {k: m_sim[k] / m_ref[k] - 1.0 for k in ("peak_rate", "final_slip")}, "t_end": t_end}


def match_nodes(a, b, tol=1e-6):
    """Indices (ia, ib) of the coordinates that ``a`` and ``b`` (1-D, any order) share
    to within ``tol``, in increasing order of ``a``'s."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    order = np.argsort(b)
    bs = b[order]
    hi = np.clip(np.searchsorted(bs, a), 0, len(bs) - 1)
    lo = np.clip(hi - 1, 0, len(bs) - 1)
    near = np.where(np.abs(a - bs[lo]) < np.abs(a - bs[hi]), lo, hi)
    ia = np.nonzero(np.abs(a - bs[near]) <= tol)[0]
    ia = ia[np.argsort(a[ia], kind="stable")]
    return ia, order[near[ia]]


def field_difference(xa, za, rta, xb, zb, rtb, *, half_widths=BOX, tol=1e-6) -> dict:
    """Rupture-time field a minus field b on the nodes both grids share inside the box
    |x| <= half_widths[0], |z| <= half_widths[1] (coordinates: offsets from the
    hypocentre; fields (x, z) arrays, NaN where a point never ruptured).

    Returns {"rms", "max_abs", "mean": of a - b where both ruptured, "n_both",
    "only_a", "only_b": nodes ruptured in one field only, "n_box": shared nodes in the box}.
    """
    ix_a, ix_b = match_nodes(xa, xb, tol)
    iz_a, iz_b = match_nodes(za, zb, tol)
    xs = np.asarray(xa, dtype=float)[ix_a]
    zs = np.asarray(za, dtype=float)[iz_a]
    A = np.asarray(rta, dtype=float)[np.ix_(ix_a, iz_a)]
    B = np.asarray(rtb, dtype=float)[np.ix_(ix_b, iz_b)]
    inside = (np.abs(xs)[:, None] <= half_widths[0] + tol) & (np.abs(zs)[None, :] <= half_widths[1] + tol)
    fa, fb = np.isfinite(A) & inside, np.isfinite(B) & inside
    both = fa & fb
    d = (A - B)[both]
    nan = float("nan")
    return {"rms": float(np.sqrt(np.mean(d**2))) if d.size else nan,
            "max_abs": float(np.max(np.abs(d))) if d.size else nan,
            "mean": float(np.mean(d)) if d.size else nan,
            "n_both": int(both.sum()), "only_a": int((fa & ~fb).sum()), "only_b": int((fb & ~fa).sum()),
            "n_box": int(inside.sum())}


def convergence(values: dict) -> dict:
    """Differences between successive grid spacings of one quantity.

    ``values``: {dx: value}. Returns {"pairs": [(coarse, fine, value_coarse - value_fine)],
    "ratios": [|d_k| / |d_(k+1)| of successive pairs] (2 for a first-order quantity when dx
    halves), "order": log2 of each ratio}."""
    dxs = sorted((float(k) for k in values), reverse=True)
    v = {float(k): float(x) for k, x in values.items()}
    pairs = [(a, b, v[a] - v[b]) for a, b in zip(dxs, dxs[1:])]
    ratios, orders = [], []
    for (_, _, d1), (_, _, d2) in zip(pairs, pairs[1:]):
        r = abs(d1) / abs(d2) if d2 != 0 else float("inf")
        ratios.append(r)
        orders.append(math.log2(r) if 0 < r < float("inf") else float("nan"))
    return {"pairs": pairs, "ratios": ratios, "order": orders}


def _row(check, value, limit, unit, *, rule="within"):
    ok = bool(value <= limit) if rule == "within" else bool(value < limit)
    return {"check": check, "value": float(value), "limit": float(limit), "unit": unit, "rule": rule, "pass": ok}


def check_tpv101(ref_stations: dict, ref_field: dict, runs: dict, fields: dict, *, tolerances=None,
                 tol_convergence=TOL_CONVERGENCE, accept_dx=ACCEPT_DX, fine_dx=FINE_DX) -> dict:
    """The TPV101 acceptance of issue 19 (points 3 and 4).

    ``ref_stations``: {station: compare_station result at ``accept_dx``};
    ``ref_field``: field_difference of the ``accept_dx`` run against uguca;
    ``runs``: {station: {dx: station_metrics}} of cracklab's runs;
    ``fields``: {(coarse dx, fine dx): field_difference between the two runs}.

    Against uguca: every station's rupture time within 0.1 s, peak slip rate within 15 %
    and final slip within 5 %, the rupture-time field within 0.1 s RMS where both ruptured.
    Convergence: between ``accept_dx`` and ``fine_dx`` every station's rupture time and the
    field's RMS within 0.05 s, and the field's RMS difference smaller than between the two
    coarser spacings when there are three. A NaN (a station that never ruptured, a missing
    run) fails. Returns {"pass", "checked" (the uguca and the convergence parts found),
    "rows", "failures"}."""
    tol = dict(TOLERANCES if tolerances is None else tolerances)
    rows = []
    for s, cmp in ref_stations.items():
        rows.append(_row(f"{s}, {accept_dx:g} m vs uguca: rupture time", abs(cmp["diff"]["rupture_time"]),
                         tol["rupture_time"], "s"))
        rows.append(_row(f"{s}, {accept_dx:g} m vs uguca: peak slip rate", abs(cmp["rel"]["peak_rate"]),
                         tol["peak_rate"], "rel"))
        rows.append(_row(f"{s}, {accept_dx:g} m vs uguca: final slip", abs(cmp["rel"]["final_slip"]),
                         tol["final_slip"], "rel"))
    if ref_field is not None:
        rows.append(_row(f"rupture-time field, {accept_dx:g} m vs uguca: RMS where both ruptured",
                         ref_field["rms"], tol["field_rms"], "s"))
    conv = _convergence_rows(runs, fields, tol_convergence, accept_dx, fine_dx)
    rows += conv
    fails = [r for r in rows if not r["pass"]]
    checked = bool(ref_stations) and ref_field is not None and bool(conv)
    return {"pass": checked and not fails, "checked": checked, "rows": rows,
            "failures": [_sentence(r) for r in fails]}


def _convergence_rows(runs, fields, tol, accept_dx, fine_dx, slip_tol=None):
    rows = []
    fields = {(float(a), float(b)): v for (a, b), v in fields.items()}
    for s, by_dx in runs.items():
        by_dx = {float(k): v for k, v in by_dx.items()}
        if accept_dx in by_dx and fine_dx in by_dx:
            a, b = by_dx[accept_dx], by_dx[fine_dx]
            rows.append(_row(f"{s}: rupture time, {accept_dx:g} m vs {fine_dx:g} m",
                             abs(a["rupture_time"] - b["rupture_time"]), tol, "s"))
            if slip_tol is not None:
                rows.append(_row(f"{s}: final slip, {accept_dx:g} m vs {fine_dx:g} m",
                                 abs(a["final_slip"] / b["final_slip"] - 1.0), slip_tol, "rel"))
    key = (accept_dx, fine_dx)
    if key in fields:
        rows.append(_row(f"rupture-time field, {accept_dx:g} m vs {fine_dx:g} m: RMS", fields[key]["rms"], tol, "s"))
        coarser = [k for k in fields if k[1] == accept_dx]
        for k in coarser:
            rows.append(_row(f"rupture-time field: RMS {accept_dx:g}-{fine_dx:g} m smaller than {k[0]:g}-{k[1]:g} m",
                             fields[key]["rms"], fields[k]["rms"], "s", rule="below"))
    return rows


def check_tpv103(stable: dict, runs: dict, fields: dict, *, tol_convergence=TOL_CONVERGENCE,
                 tol_slip=TOL_CONVERGENCE_SLIP, accept_dx=ACCEPT_DX, fine_dx=FINE_DX, t_end=12.0) -> dict:
    """The TPV103 acceptance of issue 19 (point 5).

    ``stable``: {"t_end": simulated time reached, "finite": bool (every recorded value
    finite)} of the ``accept_dx`` run; ``runs``, ``fields`` as in :func:`check_tpv101`.
    The run reaches ``t_end`` with finite values; between ``accept_dx`` and ``fine_dx``
    every station's rupture time and the field's RMS within 0.05 s, the final slip within 5 %."""
    rows = []
    if stable is not None:
        rows.append(_row(f"{accept_dx:g} m: simulated time short of {t_end:g} s", max(t_end - stable["t_end"], 0.0),
                         1e-9 * t_end, "s"))
        rows.append(_row(f"{accept_dx:g} m: non-finite recorded values", 0.0 if stable["finite"] else 1.0, 0.0, ""))
    conv = _convergence_rows(runs, fields, tol_convergence, accept_dx, fine_dx, slip_tol=tol_slip)
    rows += conv
    fails = [r for r in rows if not r["pass"]]
    checked = stable is not None and bool(conv)
    return {"pass": checked and not fails, "checked": checked, "rows": rows,
            "failures": [_sentence(r) for r in fails]}


def fmt_value(value, unit):
    if value != value:
        return "nan"
    if unit == "rel":
        return f"{100 * value:.1f} %"
    if unit == "s":
        return f"{value:.3f} s"
    return f"{value:g}"


def _sentence(r):
    rel = "within" if r["rule"] == "within" else "below"
    return f"{r['check']}: {fmt_value(r['value'], r['unit'])}, not {rel} {fmt_value(r['limit'], r['unit'])}"
