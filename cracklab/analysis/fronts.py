"""The crack front of a run or an ensemble: xarray in, xarray out.

The crack grows along +x1 from an initial crack (section 4 problems, ``cracklab.scenes.
asperity_row`` and ``random_toughness``). Two views of where the crack is:

* from ``rupture_time`` (x1, x3), the first time each point moved (its velocity first
  exceeded ``Numerics.rupture_threshold``): for a cohesive law that is when the point
  enters the cohesive zone, so this front is the **leading edge of the cohesive zone**;
  it is available at any time, not only at snapshots;
* from the opening ``delta_2`` (t, x1, x3) against ``delta_c``: the points whose opening
  has reached delta_c are broken, and this front is the **crack tip proper** (the
  trailing edge of the cohesive zone), known at the snapshot times.

Both search along +x1, per x3, from ``start`` (the tip of the initial crack by default)
for the first point that has not failed, and place the front between it and the failed
point behind it by linear interpolation (of the rupture time, or of the opening).

:func:`mean_crack_length` is the front's mean crack length (the failed area's is
``cracklab.analysis.crack_length``); :func:`front_speed`, :func:`cohesive_zone`,
:func:`roughness` and :func:`structure_function` describe the front's motion and shape.

Every function takes a single run or an ensemble (``cracklab.open_ensemble``, or a
result of these functions with a ``member`` dimension): on an ensemble it runs once per
member (:func:`member_view`) and returns its results along ``member``, with the member
coordinates (ids, swept parameters, status), so that the result of member m equals the
function of that member's own Dataset.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from .members import over_members


# ---------------------------------------------------------------------------- helpers
def _scene_of(data):
    if isinstance(data, xr.Dataset) and "scene" in data.attrs:
        from ..output.simulate import scene_of

        try:
            return scene_of(data)
        except Exception:  # noqa: BLE001 - analysis works without the scene too
            return None
    return None


def initial_front(scene) -> xr.DataArray:
    """x1 of the forward tip of the scene's initial crack (``law.initial_crack``) per x3:
    the first cracked node whose neighbour in +x1 (periodically) is not cracked. Rows
    without such a node get x1 = 0."""
    grid = scene.grid
    crack = getattr(scene.law, "initial_crack", None)
    out = np.zeros(grid.shape[1])
    if crack is not None:
        crack = np.broadcast_to(np.asarray(crack, dtype=bool), grid.shape)
        tips = crack & ~np.roll(crack, -1, axis=0)
        has = tips.any(axis=0)
        out = np.where(has, grid.x1[np.argmax(tips, axis=0)], 0.0)
    return xr.DataArray(out, dims=("x3",), coords={"x3": grid.x3}, name="initial_front",
                        attrs={"long_name": "tip of the initial crack", "units": scene.units["length"]})


def _start_index(x1, x3, start, data):
    """Per-x3 index of the first node at or beyond ``start`` (x1 coordinate)."""
    if start is None:
        scene = _scene_of(data)
        start = initial_front(scene) if scene is not None else float(x1[0])
    if isinstance(start, xr.DataArray):
        if "x3" in start.dims:
            start = start.sel(x3=x3, method="nearest").values
        else:
            start = float(start)
    start = np.broadcast_to(np.asarray(start, dtype=float), (len(x3),))
    tol = 1e-9 * (abs(x1[-1] - x1[0]) + 1.0)
    return np.searchsorted(x1, start - tol, side="left")


def _first_unbroken(broken, s):
    """Index along axis 0 of the first False at or beyond s[k] in each column k (n if none)."""
    n = broken.shape[0]
    b = broken.copy()
    b[np.arange(n)[:, None] < s[None, :]] = True
    unb = ~b
    has = unb.any(axis=0)
    return np.where(has, np.argmax(unb, axis=0), n)


def _length_units(data):
    return data["x1"].attrs.get("units", "1") if "x1" in data.coords else "1"


def _coord_attrs(data, name):
    if name in data.coords:
        return dict(data[name].attrs)
    if name == "t" and "units" in getattr(data, "attrs", {}) and "x1" in data.dims:
        return {"units": data.attrs["units"], "long_name": "time"}     # a bare rupture_time
    return {}


def _front_da(values, t, x3, data, long_name, name="front"):
    coords = {"t": ("t", t, _coord_attrs(data, "t")), "x3": ("x3", x3, _coord_attrs(data, "x3"))}
    return xr.DataArray(values, dims=("t", "x3"), coords=coords, name=name,
                        attrs={"long_name": long_name, "units": _length_units(data)})


def _delta_c(data, delta_c):
    if delta_c is None:
        scene = _scene_of(data)
        if scene is None or not hasattr(scene.law, "delta_c"):
            raise ValueError("give delta_c= (the result carries no scene with a cohesive law)")
        delta_c = scene.law.delta_c
    return delta_c


def _ratio(data, field, delta_c):
    """Opening / delta_c as (t, x1, x3) numpy, with the x1 and x3 coordinates."""
    da = data[field] if isinstance(data, xr.Dataset) else data
    da = da.transpose("t", "x1", "x3")
    dc = delta_c
    if isinstance(dc, xr.DataArray):
        dc = dc.broadcast_like(da.isel(t=0)).transpose("x1", "x3").values
    dc = np.asarray(dc, dtype=float)
    if dc.ndim == 2 and dc.shape != da.shape[1:]:
        # a full-grid field against a recorded sub-region: cut it by coordinates
        scene = _scene_of(data)
        if scene is None:
            raise ValueError(f"delta_c has shape {dc.shape}, the field {da.shape[1:]}")
        i = np.searchsorted(scene.grid.x1, da["x1"].values - 1e-12)
        k = np.searchsorted(scene.grid.x3, da["x3"].values - 1e-12)
        dc = dc[np.ix_(i, k)]
    return da.values / dc, da["t"].values, da["x1"].values, da["x3"].values


# ---------------------------------------------------------------------------- the front
@over_members
def front_position(data, *, method=None, times=None, start=None, delta_c=None, field="delta_2"):
    """Crack-front position x1_f(t, x3).

    ``data``: a run's Dataset, a ``rupture_time`` DataArray (x1, x3), or an opening
    DataArray (t, x1, x3). ``method``: "rupture_time" (default when there is one) or
    "opening" (``field`` against ``delta_c``, a number or (x1, x3) field; default: the
    run's law.delta_c). ``times`` (rupture_time method): when to evaluate, default the
    Dataset's t. ``start``: x1 (number or DataArray over x3) from which to search along
    +x1; default the tip of the run's initial crack (``initial_front``), else the first x1.
    Where every point up to the end of the record has failed, the front is the last x1.
    Returns DataArray "front" on (t, x3)."""
    if method is None:
        has_rt = (isinstance(data, xr.Dataset) and "rupture_time" in data) or \
                 (isinstance(data, xr.DataArray) and "t" not in data.dims)
        method = "rupture_time" if has_rt else "opening"
    if method == "rupture_time":
        return _front_from_rupture_time(data, times, start)
    if method == "opening":
        return _front_from_opening(data, start, _delta_c(data, delta_c), field)
    raise ValueError(f"method must be 'rupture_time' or 'opening', got {method!r}")


def _front_from_rupture_time(data, times, start):
    rt_da = data["rupture_time"] if isinstance(data, xr.Dataset) else data
    rt_da = rt_da.transpose("x1", "x3")
    rt = rt_da.values
    x1, x3 = rt_da["x1"].values, rt_da["x3"].values
    if times is None:
        if not isinstance(data, xr.Dataset) or "t" not in data.coords or data.sizes.get("t", 0) == 0:
            raise ValueError("give times= (no snapshot times in the data)")
        times = data["t"].values
    times = np.atleast_1d(np.asarray(times, dtype=float))
    s = _start_index(x1, x3, start, data)
    rtf = np.where(np.isnan(rt), np.inf, rt)
    n = len(x1)
    cols = np.arange(len(x3))
    out = np.empty((len(times), len(x3)))
    for m, t in enumerate(times):
        i = _first_unbroken(rtf <= t, s)
        j = np.clip(i - 1, 0, n - 1)
        ic = np.clip(i, 0, n - 1)
        rj, ri = rtf[j, cols], rtf[ic, cols]
        with np.errstate(invalid="ignore", divide="ignore"):
            frac = np.where(np.isfinite(ri), np.clip((t - rj) / (ri - rj), 0.0, 1.0), 0.0)
        front = x1[j] + frac * (x1[ic] - x1[j])
        front = np.where(i >= n, x1[-1], front)
        front = np.where(i <= s, x1[np.clip(s, 0, n - 1)], front)
        out[m] = front
    return _front_da(out, times, x3, data, "crack-front position (leading edge of the cohesive zone, "
                                          "from rupture_time)")


def _front_from_opening(data, start, delta_c, field):
    ratio, t, x1, x3 = _ratio(data, field, delta_c)
    peak = np.maximum.accumulate(np.nan_to_num(ratio, nan=0.0), axis=0)   # no healing
    s = _start_index(x1, x3, start, data)
    n = len(x1)
    cols = np.arange(len(x3))
    out = np.empty((len(t), len(x3)))
    for m in range(len(t)):
        r = peak[m]
        i = _first_unbroken(r >= 1.0, s)
        j = np.clip(i - 1, 0, n - 1)
        ic = np.clip(i, 0, n - 1)
        rj, ri = r[j, cols], r[ic, cols]
        with np.errstate(invalid="ignore", divide="ignore"):
            frac = np.clip((rj - 1.0) / (rj - ri), 0.0, 1.0)
        front = x1[j] + frac * (x1[ic] - x1[j])
        front = np.where(i >= n, x1[-1], front)
        front = np.where(i <= s, x1[np.clip(s, 0, n - 1)], front)
        out[m] = front
    return _front_da(out, t, x3, data, "crack-front position (opening = delta_c)")


@over_members
def mean_crack_length(front, *, origin=0.0):
    """Mean crack length vs time: the front averaged over x3, measured from ``origin``
    (x1 = 0 by default, so that it starts at l0 for the section 4 scenes)."""
    out = front.mean("x3") - origin
    out.name = "crack_length"
    out.attrs = {"long_name": "mean crack length", "units": front.attrs.get("units", "1")}
    return out


@over_members
def front_speed(x, *, window=None, polyorder=2):
    """d x / d t along "t" for a front (t, x3) or a mean length (t).

    Without ``window``: second-order finite differences (np.gradient on the t
    coordinate). With ``window`` (a time span): Savitzky-Golay derivative over the odd
    number of samples that spans it (at least polyorder + 2), exact for polynomials up
    to ``polyorder``; needs uniformly spaced t."""
    t = x["t"].values
    axis = x.get_axis_num("t")
    if window is None:
        v = np.gradient(x.values, t, axis=axis)
    else:
        from scipy.signal import savgol_filter

        dt = np.diff(t)
        if not np.allclose(dt, dt[0], rtol=1e-6, atol=0):
            raise ValueError("front_speed(window=...) needs uniformly spaced t; resample first")
        n = int(round(window / dt[0]))
        n = max(n + (n % 2 == 0), polyorder + 2 + (polyorder % 2))
        if n > len(t):
            raise ValueError(f"window {window} spans {n} samples, more than the {len(t)} there are")
        v = savgol_filter(x.values, n, polyorder, deriv=1, delta=dt[0], axis=axis, mode="interp")
    units = x.attrs.get("units", "1")
    tunits = x["t"].attrs.get("units", "1")
    out = x.copy(data=v)
    out.name = "speed"
    out.attrs = {"long_name": "front speed", "units": units if units == tunits == "1" else f"{units} {tunits}-1"}
    return out


@over_members
def cohesive_zone(data, *, delta_c=None, field="delta_2", start=None, eps=1e-3):
    """Extent along x1 of the cohesive zone ahead of the crack tip, per (t, x3): from the
    tip (opening crossing delta_c, as ``front_position(method="opening")``) to where the
    opening ahead falls to ``eps`` * delta_c (linear interpolation between nodes, so the
    leading edge is located to within a cell). NaN where no zone is recorded ahead.
    Returns DataArray "cohesive_zone" on (t, x3)."""
    ratio, t, x1, x3 = _ratio(data, field, _delta_c(data, delta_c))
    peak = np.maximum.accumulate(np.nan_to_num(ratio, nan=0.0), axis=0)
    tip = _front_from_opening(data, start, delta_c if delta_c is not None else _delta_c(data, None), field).values
    s = _start_index(x1, x3, start, data)
    n = len(x1)
    cols = np.arange(len(x3))
    out = np.full((len(t), len(x3)), np.nan)
    for m in range(len(t)):
        r = np.nan_to_num(ratio[m], nan=0.0)
        i = _first_unbroken(peak[m] >= 1.0, s)                 # first node of the zone
        closed = r <= eps
        k = _first_unbroken(~closed, np.minimum(i, n))         # first closed node ahead
        ok = (i < n) & (k < n) & (k > i)
        kp = np.clip(k - 1, 0, n - 1)
        kc = np.clip(k, 0, n - 1)
        rp, rc = r[kp, cols], r[kc, cols]
        with np.errstate(invalid="ignore", divide="ignore"):
            frac = np.clip((rp - eps) / (rp - rc), 0.0, 1.0)
        lead = x1[kp] + frac * (x1[kc] - x1[kp])
        out[m] = np.where(ok, lead - tip[m], np.nan)
    return _front_da(out, t, x3, data if isinstance(data, xr.Dataset) else data.to_dataset(name=field),
                     "extent of the cohesive zone along x1", name="cohesive_zone")


# ---------------------------------------------------------------------------- roughness
@over_members
def roughness(front):
    """Roughness of the front line x1_f(x3) over time: Dataset on t with ``width``
    (standard deviation along x3), ``mean`` (mean position) and ``advance`` (mean
    position minus its first value). ``width`` against ``advance`` is the growth of the
    roughness with the mean propagation distance (``ds.swap_dims(t="advance")``)."""
    units = front.attrs.get("units", "1")
    mean = front.mean("x3")
    width = front.std("x3")
    advance = mean - mean.isel(t=0)
    ds = xr.Dataset({
        "width": width.assign_attrs(long_name="standard deviation of the front along x3", units=units),
        "mean": mean.assign_attrs(long_name="mean front position", units=units),
        "advance": advance.assign_attrs(long_name="mean propagation distance", units=units),
    })
    return ds


@over_members
def structure_function(front, *, max_lag=None):
    """Second-order structure function of the front along x3 (periodic):
    S(r, t) = < (x1_f(x3 + r) - x1_f(x3))^2 >_x3 for r = k dx3, k = 1 .. n3 // 2
    (or up to ``max_lag`` nodes). Returns DataArray "structure_function" on (t, lag)."""
    x3 = front["x3"].values
    n3 = len(x3)
    kmax = n3 // 2 if max_lag is None else int(max_lag)
    h = front.transpose("t", "x3").values
    dx3 = x3[1] - x3[0] if n3 > 1 else 1.0
    lags = np.arange(1, kmax + 1)
    S = np.stack([np.mean((np.roll(h, -k, axis=1) - h) ** 2, axis=1) for k in lags], axis=1)
    units = front.attrs.get("units", "1")
    return xr.DataArray(S, dims=("t", "lag"), coords={"t": front["t"].values, "lag": lags * dx3},
                        name="structure_function",
                        attrs={"long_name": "second-order structure function of the front",
                               "units": f"{units}2" if units != "1" else "1"})
