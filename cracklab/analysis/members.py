"""One analysis over every member of an ensemble: ``member_view`` (a member of an
``open_ensemble`` Dataset as a single run's Dataset) and ``over_members`` (a function of
a run applied per member, its results stacked along ``member`` with the member
coordinates)."""
from __future__ import annotations

import functools

import numpy as np
import xarray as xr

GRID_DIMS = ("t", "x1", "x3")
INPUT_DIMS = ("input_x1", "input_x3")


def _keep(ok, dims):
    """{dim: positions to keep} where ``ok`` (a boolean DataArray) holds anywhere along the others."""
    keep = {}
    for dim in dims:
        if dim not in ok.dims:
            continue
        k = ok.any([d for d in ok.dims if d != dim]).values if ok.ndim > 1 else ok.values
        if k.any() and not k.all():
            keep[dim] = np.nonzero(k)[0]
    return keep


def trim_padding(data):
    """``data`` (one member) without the NaN padding an outer join left on it.

    A run's Dataset: t, x1, x3 where its first recorded snapshot field is NaN throughout,
    and input_x1, input_x3 where its first float input field is. Another Dataset: the
    positions along a dimension where every variable is NaN. A DataArray: the positions
    along any dimension where it is NaN throughout."""
    if isinstance(data, xr.DataArray):
        if data.dtype.kind != "f" or data.ndim == 0:
            return data
        return data.isel(_keep(data.notnull(), data.dims))
    keep = {}
    fields = [v for v in data.data_vars if set(GRID_DIMS) <= set(data[v].dims) and data[v].dtype.kind == "f"]
    if fields and data.sizes.get("t", 0):
        keep.update(_keep(data[fields[0]].notnull(), GRID_DIMS))
    inputs = [v for v in data.data_vars if set(INPUT_DIMS) <= set(data[v].dims) and data[v].dtype.kind == "f"]
    if inputs:
        keep.update(_keep(data[inputs[0]].notnull(), INPUT_DIMS))
    if not fields and not inputs:       # not a run (a result of these functions): all its variables NaN
        floats = [data[v] for v in data.data_vars if data[v].dtype.kind == "f" and data[v].ndim]
        for dim in data.dims:
            own = [v for v in floats if dim in v.dims]
            if own:
                ok = np.logical_or.reduce([v.notnull().any([d for d in v.dims if d != dim]).values for v in own])
                if ok.any() and not ok.all():
                    keep[dim] = np.nonzero(ok)[0]
    return data.isel(keep) if keep else data


def member_view(ens, member):
    """Member ``member`` (an id, or an integer position) of an ensemble Dataset or
    DataArray (``member`` dimension) as one run: the member selected, its padding trimmed
    (``trim_padding``) and, for a Dataset, its scene in attr ``scene`` (as a run's Dataset
    has it, so that ``cracklab.scene_of`` works on it)."""
    from ..ensemble.read import scene_text

    if isinstance(member, (int, np.integer)) and not isinstance(member, bool):
        one = ens.isel(member=int(member))
    else:
        one = ens.sel(member=member)
    mid = str(one["member"].item()) if "member" in one.coords else None
    one = trim_padding(one)
    if isinstance(one, xr.Dataset):
        attrs = {k: v for k, v in ens.attrs.items() if k not in ("scenes", "swept", "axes", "study")}
        text = scene_text(ens, mid)
        if text != "{}":
            attrs["scene"] = text
        one = one.copy()
        one.attrs = attrs
    return one


def member_coords(data) -> dict:
    """The coordinates of ``data`` along ``member`` only (ids, parameters, status, ...)."""
    return {k: v.variable for k, v in data.coords.items() if v.dims == ("member",)}


def stack(results, data):
    """Per-member results (DataArrays or Datasets, in member order) along a new ``member``
    dimension (an outer join of their coordinates), with the member coordinates of ``data``."""
    parts = []
    for r in results:
        drop = [c for c in r.coords if c == "member" or (r[c].ndim == 0 and c in data.coords
                                                         and data[c].dims == ("member",))]
        parts.append(r.drop_vars(drop))
    out = xr.concat(parts, dim="member", join="outer", coords="minimal", compat="override",
                    combine_attrs="override", fill_value=np.nan)
    return out.assign_coords(member_coords(data))


def _is_ensemble(data) -> bool:
    return isinstance(data, (xr.Dataset, xr.DataArray)) and "member" in data.dims


def over_members(func):
    """``func`` of one run, extended to an ensemble: with a ``member`` dimension on its
    first argument it runs once per member (``member_view``; keyword arguments that are
    DataArrays along ``member`` are taken per member too) and the results are stacked
    along ``member`` with the ensemble's member coordinates (``stack``)."""
    @functools.wraps(func)
    def wrapper(data, *args, **kwargs):
        if not _is_ensemble(data):
            return func(data, *args, **kwargs)
        results = []
        for i in range(data.sizes["member"]):
            own = {k: (v.isel(member=i) if _is_ensemble(v) else v) for k, v in kwargs.items()}
            results.append(func(member_view(data, i), *args, **own))
        return stack(results, data)

    return wrapper
