"""Comparison of cracklab TPV6 station series with the MDSBI reference (docs/studies/tpv6.md).

Plain functions on 1-D numpy arrays, checked on synthetic series with known answers
(tests/studies/test_tpv6_study.py). The series measures (rupture time, peak, final value,
resampling) are TPV3's (studies.benchmarks.measures); TPV6 adds

* ``load_reference``: one station's two files (far and near side) as the slip, slip rate,
  normal stress and each side's face motion;
* ``compare_station``: the acceptance numbers of one station on the reference's samples,
  the RMS difference of the normal-stress history in MPa and each side's final displacement;
* ``check_acceptance``: the TPV6 acceptance of issue 18 (rupture time within 0.1 s, final
  slip within 5 %, peak slip rate within 20 %, the normal stress within 5 MPa RMS) over
  stations at one grid spacing, the study's pass/fail result;
* ``ripple``: the oscillation of a series about its running mean (behind the front);
* ``load_contours``: the reference's rupture-time contours (contour.dat).

The reference files (``shared/reference/tpv6_mdsbi``) have one header line and the columns
t, h-disp, h-vel, h-stress, v-disp, v-vel, v-stress, n-disp, n-vel, n-stress (s, m, m/s,
MPa): the displacement and velocity of that side's face, and the traction on the fault
(n-stress negative in compression, as cracklab's tau_2). Station faultstSSSdpDDD is the pair
farstSSSdpDDD.txt (the compliant far side: cracklab's top, x2 > 0) and nearstSSSdpDDD.txt.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from studies.benchmarks.harness import reference_dir
from studies.benchmarks.measures import final_value, peak, resample, rupture_time  # noqa: F401 - named here too

THRESHOLD = 1e-3          # m/s: rupture = first time the slip rate exceeds 1 mm/s
COLUMNS = ("t", "h_disp", "h_vel", "h_stress", "v_disp", "v_vel", "v_stress", "n_disp", "n_vel", "n_stress")
SIDES = ("far", "near")   # cracklab's top (x2 > 0) and bottom
# acceptance at 100 m (issue 18), at the five reference stations
TOL_RUPTURE_TIME = 0.1    # s, absolute
TOL_FINAL_SLIP = 0.05     # relative
TOL_PEAK_RATE = 0.20      # relative
TOL_NORMAL_RMS = 5.0      # MPa, RMS of the normal-stress difference over the common samples
TOLERANCES = {"rupture_time": TOL_RUPTURE_TIME, "final_slip": TOL_FINAL_SLIP, "peak_rate": TOL_PEAK_RATE,
              "normal_rms": TOL_NORMAL_RMS}
QUANTITY = {"rupture_time": "rupture time", "final_slip": "final slip", "peak_rate": "peak slip rate",
            "normal_rms": "normal-stress history (RMS)"}
ACCEPT_DX = 100.0         # m
RIPPLE_WINDOW = 0.25      # s: the running mean that ``ripple`` removes
RIPPLE_DELAY = 0.3        # s: the ripple is measured from this long after the reference's rupture time


REFERENCE = "tpv6_mdsbi"


def default_reference_dir() -> Path:
    """The reference's folder when no ``--reference`` is given (``harness.reference_dir``)."""
    return reference_dir(REFERENCE)


def reference_file(station: str, side: str, directory=None) -> Path:
    """The reference's file of ``station`` (faultstSSSdpDDD) on ``side`` ("far" or "near")."""
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, got {side!r}")
    if not station.startswith("faultst"):
        raise ValueError(f"station must be named faultstSSSdpDDD, got {station!r}")
    return reference_dir(REFERENCE, directory) / f"{side}{station[len('fault'):]}.txt"


def _read(path) -> dict:
    data = np.loadtxt(path, skiprows=1)
    if data.ndim != 2 or data.shape[1] != len(COLUMNS):
        raise ValueError(f"{path}: expected {len(COLUMNS)} columns, got shape {data.shape}")
    return {name: data[:, j] for j, name in enumerate(COLUMNS)}


def load_reference(station: str, directory=None) -> dict:
    """One station of the reference: {"t", "slip", "rate" (far minus near, along strike),
    "normal" (n-stress, MPa), "shear" (h-stress, MPa), "far", "near" (each side's columns)}."""
    far, near = (_read(reference_file(station, s, directory)) for s in SIDES)
    if far["t"].shape != near["t"].shape or not np.allclose(far["t"], near["t"]):
        raise ValueError(f"{station}: the far and near files have different times")
    return {"t": far["t"], "slip": far["h_disp"] - near["h_disp"], "rate": far["h_vel"] - near["h_vel"],
            "normal": far["n_stress"], "shear": far["h_stress"], "far": far, "near": near}


def load_contours(path=None) -> dict:
    """The reference's rupture-time contours: {time (s): [array (n, 2) of (strike, depth) in m,
    one per contour line]}. contour.dat: '#' comments, then blocks 'Contour <t>' followed by
    'x z' rows; a blank line or a new 'Contour' header ends a line."""
    path = Path(path or default_reference_dir() / "contour.dat")
    out: dict = {}
    level, rows = None, []

    def close():
        if level is not None and rows:
            out.setdefault(level, []).append(np.array(rows, dtype=float))

    for line in path.read_text().splitlines():
        text = line.strip()
        if text.lower().startswith("contour"):
            close()
            level, rows = float(text.split()[1]), []
        elif not text:
            close()
            rows = []
        elif level is not None and not text.startswith("#"):
            try:
                x, z = (float(v) for v in text.split()[:2])
            except ValueError:
                continue
            rows.append((x, z))
    close()
    if not out:
        raise ValueError(f"{path}: no 'Contour <t>' block found")
    return out


def metrics(t, slip, rate, *, at=None, threshold=THRESHOLD) -> dict:
    """Rupture time (first sample above 1 mm/s), final slip (at the end or at ``at``), peak
    slip rate and its time."""
    p, tp = peak(t, rate)
    return {"rupture_time": rupture_time(t, rate, threshold), "final_slip": final_value(t, slip, at),
            "peak_rate": p, "peak_time": tp}


def rms(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) ** 2)))


def ripple(t, y, t_from, window=RIPPLE_WINDOW) -> float:
    """RMS of the part of ``y`` that a centred running mean over ``window`` seconds removes,
    over t >= ``t_from`` (the running mean taken over whole windows inside the series):
    the oscillation about the smooth history, e.g. behind a rupture front."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    dt = float(np.median(np.diff(t)))
    n = max(1, int(round(window / dt)) | 1)             # odd: centred
    if y.size < n:
        return float("nan")
    smooth = np.convolve(y, np.ones(n) / n, mode="valid")
    h = n // 2
    tt, rest = t[h:y.size - h], y[h:y.size - h] - smooth
    keep = tt >= t_from
    return float(np.sqrt(np.mean(rest[keep] ** 2))) if keep.any() else float("nan")


def compare_station(sim: dict, ref: dict, *, threshold=THRESHOLD) -> dict:
    """Compare one station. ``sim``: t, slip, rate, normal (MPa) and optionally far_disp,
    near_disp (each side's displacement along strike); ``ref``: :func:`load_reference`.
    cracklab's series is sampled at the reference's times (0.005 s) up to the common end
    and both are measured alike.

    Returns {"sim", "ref": metrics, "diff": {rupture_time (s), peak_time (s)}, "rel":
    {final_slip, peak_rate}, "normal_rms" (MPa), "normal_range": {"sim", "ref": (min, max)},
    "ripple": {"normal", "rate": {"sim", "ref"}} (``ripple`` from 0.3 s after the reference's
    rupture time), "faces": {side: {"sim", "ref" final displacement, "rms"}}, "t_end"}.
    """
    t_end = min(float(sim["t"][-1]), float(ref["t"][-1]))
    keep = ref["t"] <= t_end * (1 + 1e-9)
    tr = ref["t"][keep]
    t_end = float(tr[-1])
    common = {k: resample(sim["t"], sim[k], tr)[1] for k in ("slip", "rate", "normal")}
    m_sim = metrics(tr, common["slip"], common["rate"], at=t_end, threshold=threshold)
    m_ref = metrics(tr, ref["slip"][keep], ref["rate"][keep], at=t_end, threshold=threshold)
    out = {"sim": m_sim, "ref": m_ref, "t_end": t_end,
           "diff": {k: m_sim[k] - m_ref[k] for k in ("rupture_time", "peak_time")},
           "rel": {k: m_sim[k] / m_ref[k] - 1.0 for k in ("final_slip", "peak_rate")},
           "normal_rms": rms(common["normal"], ref["normal"][keep]),
           "normal_range": {"sim": [float(common["normal"].min()), float(common["normal"].max())],
                            "ref": [float(ref["normal"][keep].min()), float(ref["normal"][keep].max())]}}
    t_from = m_ref["rupture_time"] + RIPPLE_DELAY
    out["ripple"] = {k: {"sim": ripple(tr, common[k], t_from), "ref": ripple(tr, ref[k][keep], t_from)}
                     for k in ("normal", "rate")}
    faces = {}
    for side in SIDES:
        key = f"{side}_disp"
        if key in sim:
            ys = resample(sim["t"], sim[key], tr)[1]
            yr = ref[side]["h_disp"][keep]
            faces[side] = {"sim": float(ys[-1]), "ref": float(yr[-1]), "rel": float(ys[-1] / yr[-1] - 1.0),
                           "rms": rms(ys, yr)}
    out["faces"] = faces
    return out


def differences(cmp: dict) -> dict:
    """The four acceptance quantities of one comparison as magnitudes: rupture time (s),
    final slip and peak slip rate (relative), the normal stress's RMS difference (MPa)."""
    return {"rupture_time": abs(float(cmp["diff"]["rupture_time"])),
            "final_slip": abs(float(cmp["rel"]["final_slip"])),
            "peak_rate": abs(float(cmp["rel"]["peak_rate"])),
            "normal_rms": abs(float(cmp["normal_rms"]))}


def _fmt(quantity, value):
    if value != value:
        return "nan"
    if quantity == "rupture_time":
        return f"{value:.3f} s"
    if quantity == "normal_rms":
        return f"{value:.2f} MPa"
    return f"{100 * value:.1f} %"


def check_acceptance(comparisons: dict, *, dx=ACCEPT_DX, tolerances=None) -> dict:
    """The TPV6 acceptance at grid spacing ``dx`` as a checked result.

    ``comparisons``: {station: {dx: compare_station(...) result}} (dx a number or its
    ``f"{dx:g}"`` key). Every station must have a comparison at ``dx`` (a station without one
    fails) with each of the four differences within its tolerance (a NaN, e.g. a station that
    never ruptures, fails). Returns {"pass", "dx", "checks": one row per (station, quantity)
    with value, limit and pass, "failures": the failed rows as sentences}."""
    tol = TOLERANCES if tolerances is None else tolerances
    rows = []
    for station, by_dx in comparisons.items():
        by_dx = {float(k): v for k, v in by_dx.items()}
        cmp = by_dx.get(float(dx))
        diff = differences(cmp) if cmp is not None else {q: float("nan") for q in tol}
        for q in tol:
            rows.append({"station": station, "dx": float(dx), "quantity": q, "value": diff[q], "limit": tol[q],
                         "pass": bool(diff[q] <= tol[q])})
    failures = [f"{r['station']} at {r['dx']:g} m: {QUANTITY[r['quantity']]} differs by "
                f"{_fmt(r['quantity'], r['value'])}, limit {_fmt(r['quantity'], r['limit'])}"
                for r in rows if not r["pass"]]
    return {"pass": bool(rows and not failures), "dx": float(dx), "checks": rows, "failures": failures}
