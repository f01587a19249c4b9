"""Rupture measures of a fault run (shear components active): ruptured area, mean slip
and moment, peak slip rate, rupture-time statistics (``cracklab summary`` of a fault run)."""
from __future__ import annotations

import numpy as np

from .rupture import cell_and_width, scene_dict

FAULT = {
    "rupture_area": ("area that ruptured: finite rupture_time cells x cell area (per unit length in 2D)", "area"),
    "mean_slip": ("mean final slip |(delta_1, delta_3)| over the ruptured area (NaN: slip not recorded)", "length"),
    "moment": ("seismic moment mu x rupture_area x mean_slip (per unit length in 2D)", "moment"),
    "peak_slip_rate": ("max |(v_1, v_3)| over the recorded data (see its 'source' attribute)", "speed"),
    "first_rupture": ("earliest rupture_time", "time"),
    "median_rupture": ("median of the finite rupture_time values", "time"),
    "last_rupture_time": ("latest rupture_time", "time"),
}


def is_fault(data) -> bool:
    """Whether the run's scene has a shear component active (``Scene.components``)."""
    from ..output.simulate import scene_of

    try:
        return bool(set(scene_of(data).components) & {1, 3})
    except Exception:           # no scene, or one that no longer validates: not a fault run
        return False


def _magnitude(data, names, dims):
    parts = [np.asarray(data[n].values, dtype=float) for n in names if n in data and set(dims) <= set(data[n].dims)]
    return np.sqrt(sum(p ** 2 for p in parts)) if parts else None


def fault_measures(data) -> dict:
    """The FAULT measures of one run's Dataset, as {name: (value, attrs)}."""
    scene = scene_dict(data)
    cell, _ = cell_and_width(data, scene)
    mu = float(scene.get("material", {}).get("mu", np.nan))
    rt = np.asarray(data["rupture_time"].values, dtype=float) if "rupture_time" in data else np.zeros(0)
    finite = np.isfinite(rt)
    area = float(finite.sum() * cell)
    times = rt[finite]
    mean_slip = moment = np.nan
    if "t" in data.dims and data.sizes["t"] > 0:
        slip = _magnitude(data.isel(t=-1), ("delta_1", "delta_3"), ("x1", "x3"))
        if slip is not None and finite.any():
            mean_slip = float(slip[finite].mean())
            moment = float(mu * np.sum(slip[finite] * cell))
    peak, sources = np.nan, []
    rate = _magnitude(data, ("station_v_1", "station_v_3"), ("station",))
    if rate is not None and rate.size:
        peak, sources = float(np.nanmax(rate)), ["station series"]
    if "t" in data.dims and data.sizes["t"] > 0:
        rate = _magnitude(data, ("v_1", "v_3"), ("t", "x1", "x3"))
        if rate is not None and rate.size:
            peak, sources = float(np.nanmax([peak, np.nanmax(rate)])), sources + ["snapshots"]
    values = {"rupture_area": area, "mean_slip": mean_slip, "moment": moment, "peak_slip_rate": peak,
              "first_rupture": float(times.min()) if times.size else np.nan,
              "median_rupture": float(np.median(times)) if times.size else np.nan,
              "last_rupture_time": float(times.max()) if times.size else np.nan}
    out = {}
    for k, v in values.items():
        attrs = {"long_name": FAULT[k][0]}
        if k == "peak_slip_rate":
            attrs["source"] = " and ".join(sources) or "none: no slip rate recorded"
        out[k] = (v, attrs)
    return out
