"""The summary table of an ensemble: parameters and summary measures per member
(``summary``; ``cracklab.ensemble.summary`` and ``cracklab summary STORE`` give it)."""
from __future__ import annotations

import os

import numpy as np
import xarray as xr

from .faults import FAULT, fault_measures, is_fault
from .fronts import front_position
from .members import member_coords, over_members
from .rupture import rupture_statistics, scene_dict

FRONT = {
    "front_position": "mean crack-front position at the end of the run (from rupture_time)",
    "front_width": "standard deviation of the crack front along x3 at the end of the run",
    "late_front_speed": "mean front speed over the last quarter of the run",
}


@over_members
def measures(data) -> xr.Dataset:
    """The summary measures of one run (per member for an ensemble): its
    ``rupture_statistics`` and, at its end, the mean crack-front position and the front's
    standard deviation along x3 (``front_position`` from rupture_time), and the mean
    front speed over the last quarter of the run."""
    out = rupture_statistics(data)
    t_end = float(out["duration"])
    units = data["x1"].attrs.get("units", "1")
    tunits = data["rupture_time"].attrs.get("units", "1")
    values = dict.fromkeys(FRONT, np.nan)
    fault = is_fault(data)
    if np.isfinite(t_end) and t_end > 0 and not fault:
        front = front_position(data, method="rupture_time", times=[0.75 * t_end, t_end])
        mean = front.mean("x3").values
        values = {"front_position": float(mean[-1]), "front_width": float(front.isel(t=-1).std("x3")),
                  "late_front_speed": float((mean[-1] - mean[0]) / (0.25 * t_end))}
    speed = "1" if units == tunits == "1" else f"{units} {tunits}-1"
    for k, v in values.items():
        out[k] = ((), v, {"long_name": FRONT[k], "units": speed if k == "late_front_speed" else units})
    faults = fault_measures(data) if fault else {k: (np.nan, {"long_name": FAULT[k][0]}) for k in FAULT}
    for k, (v, attrs) in faults.items():
        out[k] = ((), v, attrs)
    return out


def summary(data, *, complete_only=False) -> xr.Dataset:
    """Parameters and summary measures per member, as an xarray Dataset along ``member``:
    the coordinates are the member ids, the swept parameters (in their own types, as
    ``open_ensemble`` gives them), ``status`` and ``error`` (its one-line error, "" if none);
    the data variables are the measures (``measures``: crack length and growth, ruptured
    area and fraction, last rupture time, front position, width and late speed) and
    ``elapsed_s`` (the member's run time). ``.to_dataframe()`` is a tidy pandas table, one
    row per member.

    ``data``: an ensemble store (every member, with NaN measures where a member is not
    complete unless ``complete_only``), an ``open_ensemble`` Dataset, a run store or a
    run's Dataset (one row, no ``member`` dimension)."""
    from ..ensemble.read import member_coords as store_coords
    from ..ensemble.read import member_status, open_ensemble
    from ..ensemble.store import store_kind, store_str

    if isinstance(data, (str, os.PathLike)):
        store = store_str(data)
        if store_kind(store) == "run":
            from ..output.stores import zarr_of

            ds = xr.open_zarr(zarr_of(store), consolidated=False)
            return measures(ds).assign_attrs(title=f"cracklab summary of {store}", store=store)
        status = member_status(store)
        if complete_only:
            status = [s for s in status if s["complete"]]
        done = [s["id"] for s in status if s["complete"]]
        table = measures(open_ensemble(store, members=done)) if done else _empty()
        coords = store_coords(status)
        ids = coords["member"][1]
        table = _reindex(table, ids)
        table = table.assign_coords(coords)
        table = table.assign_coords(error=("member", np.array([_one_line(s.get("error")) for s in status],
                                                              dtype=object), {"long_name": "error of the member's run"}))
        table["elapsed_s"] = ("member", np.array([_number(s.get("elapsed_s")) for s in status]),
                              {"long_name": "run time of the member", "units": "s"})
        return table.assign_attrs(title=f"cracklab summary of {store}", store=store)
    if "member" not in data.dims:
        return measures(data).assign_attrs(title="cracklab summary of a run")
    table = measures(data)
    return table.assign_coords(member_coords(data)).assign_attrs(title="cracklab summary of an ensemble")


def _empty() -> xr.Dataset:
    """The measures of no member (an ensemble without complete members)."""
    from .rupture import STATISTICS

    names = {**{k: v[0] for k, v in STATISTICS.items()}, **FRONT}
    return xr.Dataset({k: ("member", np.zeros(0), {"long_name": v}) for k, v in names.items()},
                      coords={"member": ("member", np.array([], dtype=object))})


def _reindex(table, ids):
    """``table`` along ``member`` = ``ids`` (NaN for the members it lacks)."""
    keep = table.drop_vars([c for c in table.coords if c != "member"])
    return keep.reindex(member=np.asarray(ids, dtype=object), fill_value=np.nan)


def _one_line(text) -> str:
    return str(text).strip().splitlines()[0] if text else ""


def _number(value) -> float:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else np.nan


__all__ = ["summary", "measures", "scene_dict"]
