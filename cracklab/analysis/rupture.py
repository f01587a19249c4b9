"""What the rupture times of a run say: the crack length of the failed area over time
(``crack_length``) and a few numbers per run (``rupture_statistics``)."""
from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from ..laws.base import cell_area_and_width, failed_length
from .members import over_members


def scene_dict(data) -> dict:
    """The scene (its JSON form, as a dict) of a run's Dataset; {} when it has none."""
    text = data.attrs.get("scene") if isinstance(data, (xr.Dataset, xr.DataArray)) else None
    try:
        out = json.loads(text) if text else {}
    except ValueError:
        return {}
    return out if isinstance(out, dict) else {}


def member_scenes(data) -> list[dict]:
    """The scenes of a run (one) or of every member of an ensemble."""
    if "member" in data.dims and "scenes" in data.attrs:
        try:
            return [s for s in json.loads(data.attrs["scenes"]).values() if isinstance(s, dict)]
        except ValueError:
            return []
    return [scene_dict(data)]


def cell_and_width(data, scene: dict) -> tuple[float, float]:
    """The cell area and the width across the crack (:func:`cracklab.analysis.cell_area_and_width`)
    of the scene's grid; without one, of the recorded coordinates: dx1 and the number of
    nodes along x3 (the width in units of dx3)."""
    from ..errors import InputError
    from ..model.grid import Grid

    g = scene.get("grid", {}) if isinstance(scene, dict) else {}
    if {"n1", "n3", "L1", "L3"} <= set(g):
        try:
            return cell_area_and_width(Grid(n1=g["n1"], n3=g["n3"], L1=g["L1"], L3=g["L3"]))
        except (InputError, TypeError):
            pass
    x1, x3 = data["x1"].values, data["x3"].values
    dx1 = float(np.median(np.diff(x1))) if len(x1) > 1 else 1.0
    return dx1, float(len(x3) if len(x3) > 1 else 1)


def _units(data, name, default="1"):
    return data[name].attrs.get("units", default) if name in data.variables else default


def crack_length(data, t=None, *, n=256) -> xr.DataArray:
    """Mean crack length l(t) = (area where rupture_time <= t) / L3 (the plane's extent
    along x3; in the plane problem, the length that failed). ``data``: a run's Dataset or
    an ensemble (then (member, t)). ``t``: times (default ``n`` points from 0 to the
    largest t_end of the run or of the members)."""
    if t is None:
        ends = [float(s["t_end"]) for s in member_scenes(data) if isinstance(s.get("t_end"), (int, float))]
        t_end = max(ends) if ends else math.nan
        if not math.isfinite(t_end):
            rt = np.asarray(data["rupture_time"].values)
            t_end = float(np.max(rt[np.isfinite(rt)])) if np.isfinite(rt).any() else 1.0
        t = np.linspace(0.0, t_end, n)
    return _crack_length(data, np.atleast_1d(np.asarray(t, dtype=float)))


@over_members
def _crack_length(data, t):
    rt = data["rupture_time"]
    area, width = cell_and_width(data, scene_dict(data))
    values = np.asarray(rt.values)
    v = np.sort(values[np.isfinite(values)].ravel())
    length = failed_length(np.searchsorted(v, t, side="right"), area, width)   # failed cells at each t
    return xr.DataArray(length, dims=("t",), coords={"t": ("t", t, {"long_name": "time", "units": _units(data, "rupture_time")})},
                        name="crack_length",
                        attrs={"long_name": "mean crack length (ruptured area / L3)", "units": _units(data, "x1")})


STATISTICS = {
    "crack_length": ("final mean crack length (ruptured area / L3)", "length"),
    "initial_crack_length": ("mean crack length of the initial crack", "length"),
    "crack_growth": ("growth of the mean crack length over the run", "length"),
    "mean_growth_rate": ("crack growth over the duration of the run", "speed"),
    "ruptured_area": ("area that ruptured (per unit length along x3 in the plane problem)", "area"),
    "ruptured_fraction": ("fraction of the recorded plane that ruptured", "1"),
    "last_rupture": ("time the last point ruptured", "time"),
    "duration": ("duration of the run (t_end)", "time"),
}


@over_members
def rupture_statistics(data) -> xr.Dataset:
    """Numbers per run from its ``rupture_time``: ``crack_length`` (final failed length, as
    :func:`crack_length` at t_end), ``initial_crack_length`` (of the scene's initial crack;
    NaN without one), ``crack_growth`` (their difference), ``mean_growth_rate`` (growth over
    ``duration``, the scene's t_end), ``ruptured_area``, ``ruptured_fraction`` (of the
    recorded nodes) and ``last_rupture`` (NaN when nothing ruptured). A Dataset of scalars
    (per member for an ensemble)."""
    rt = np.asarray(data["rupture_time"].values)
    scene = scene_dict(data)
    area, width = cell_and_width(data, scene)
    finite = np.isfinite(rt)
    count = int(np.count_nonzero(finite))
    final = float(failed_length(count, area, width))
    initial = np.nan
    if "input_law_initial_crack" in data:
        crack = np.asarray(data["input_law_initial_crack"].values)
        crack = np.nan_to_num(crack.astype(float), nan=0.0) > 0.5
        initial = float(failed_length(int(np.count_nonzero(crack)), area, width))
    duration = scene.get("t_end")
    if not isinstance(duration, (int, float)) or isinstance(duration, bool):
        duration = float(data["t"].values[-1]) if "t" in data.coords and data.sizes.get("t", 0) else np.nan
    duration = float(duration)
    growth = final - initial
    length_u, time_u = _units(data, "x1"), _units(data, "rupture_time")
    plane = data.sizes.get("x3", 0) == 1 or scene.get("grid", {}).get("n3") == 1
    units = {"length": length_u, "time": time_u, "1": "1",
             "speed": "1" if length_u == time_u == "1" else f"{length_u} {time_u}-1",
             "area": length_u if plane or length_u == "1" else f"{length_u}2"}
    values = {"crack_length": final, "initial_crack_length": initial, "crack_growth": growth,
              "mean_growth_rate": growth / duration if duration > 0 else np.nan,
              "ruptured_area": count * area, "ruptured_fraction": count / rt.size if rt.size else np.nan,
              "last_rupture": float(np.max(rt[finite])) if count else np.nan, "duration": duration}
    return xr.Dataset({k: ((), v, {"long_name": STATISTICS[k][0], "units": units[STATISTICS[k][1]]})
                       for k, v in values.items()})
