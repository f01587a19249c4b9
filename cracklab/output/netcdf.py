"""netCDF4 export of a run's store, of one ensemble member or of a whole ensemble.

``cracklab.ensemble`` re-exports ``export_netcdf`` and ``netcdf_ready``, so the ensemble's
readers are imported inside the functions here (no import cycle)."""
from __future__ import annotations

import contextlib
import json
from pathlib import Path

import numpy as np

from ..errors import InputError, StoreError


def _nc_attr(value):
    """An attr value netCDF4 can hold: booleans as "true"/"false", tables and mixed lists
    as JSON text, None dropped."""
    from ..ensemble.identity import canonical

    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (dict,)):
        return json.dumps(canonical(value), sort_keys=True)
    if isinstance(value, (list, tuple)):
        if len(value) == 0:
            return ""
        if all(isinstance(v, str) for v in value):
            return json.dumps(list(value))
        if all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) for v in value):
            return np.asarray(value)
        return json.dumps(canonical(value))
    return value


def _nc_attrs(attrs):
    out = {}
    for k, v in attrs.items():
        v = _nc_attr(v)
        if v is not None:
            out[k] = v
    return out


TIME_UNITS = ("s", "ms", "us", "min", "h", "d", "second", "seconds", "minute", "minutes", "hour", "hours",
              "day", "days")
CHUNK_BYTES = 4 << 20          # netCDF chunks of at most 4 MB
COMPLEVEL = 4
SMALL_BYTES = 1 << 10


def _cf_clean(ds):
    """CF conventions the Zarr store does not need: ``standard_name: time`` only on a time
    in time units (a dimensionless run's t has units "1"), and coordinate values on every
    dimension (input_x1 and input_x3 from the scene's grid, else the node index)."""
    for name, var in ds.variables.items():
        if var.attrs.get("standard_name") == "time" and str(var.attrs.get("units", "")).split(" ")[0] not in TIME_UNITS:
            del var.attrs["standard_name"]
    from ..ensemble.read import _with_input_coords

    ds = _with_input_coords(ds, ds.attrs.get("scene", "{}"))
    missing = {d: (d, np.arange(ds.sizes[d]), {"long_name": f"index along {d}"}) for d in ds.dims
               if d not in ds.coords}
    return ds.assign_coords(missing) if missing else ds


def encoding(ds) -> dict:
    """netCDF4 encodings: zlib (level 4; no shuffle, which made the fields larger) in
    chunks of at most ``CHUNK_BYTES`` (whole trailing dimensions, leading ones cut first)
    for every numeric variable of ``SMALL_BYTES`` or more."""
    out = {}
    for name, var in ds.variables.items():
        if var.dtype.kind not in "biuf" or var.ndim == 0 or var.size * var.dtype.itemsize < SMALL_BYTES:
            continue                # small: stored contiguous (a chunked layout costs more than it saves)
        chunks = list(var.shape)
        for axis in range(var.ndim - 1):
            if int(np.prod(chunks)) * var.dtype.itemsize <= CHUNK_BYTES:
                break
            chunks[axis] = max(1, int(CHUNK_BYTES // (var.dtype.itemsize * int(np.prod(chunks[axis + 1:])))))
        out[name] = {"zlib": True, "complevel": COMPLEVEL, "shuffle": False,
                     "chunksizes": tuple(max(1, c) for c in chunks)}
    return out


def netcdf_ready(ds):
    """A copy of ``ds`` that netCDF4 can store and that follows the CF conventions: Zarr
    encodings dropped, attrs made netCDF types, string and object arrays as plain str,
    coordinates on every dimension and ``standard_name`` time only in time units."""
    ds = _cf_clean(ds.copy())
    strings = {}
    for name, var in ds.variables.items():
        var.encoding = {}
        var.attrs = _nc_attrs(var.attrs)
        if var.dtype.kind in "OU":
            vals = np.asarray(var.values)
            fixed = np.array(["" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v)
                              for v in vals.ravel()], dtype=object).reshape(vals.shape)
            strings[name] = (var.dims, fixed, var.attrs)
    coords = {k: v for k, v in strings.items() if k in ds.coords}
    data = {k: v for k, v in strings.items() if k not in ds.coords}
    ds = ds.assign_coords(coords).assign(data)
    for var in ds.variables.values():
        var.encoding = {}
    ds.attrs = _nc_attrs(ds.attrs)
    return ds


def _read_error(store, exc) -> StoreError:
    """A StoreError naming the damaged files of ``store`` (found by ``cracklab.output.verify``)
    for an error met while reading its data."""
    from ..ensemble.store import error_line

    if "://" not in store:
        from .verify import verify

        with contextlib.suppress(Exception):
            report = verify(store)
            if not report.ok:
                return StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
    return StoreError(store, f"cannot be read ({error_line(exc)}); cracklab verify {store} names the damaged "
                             f"files")


def export_netcdf(store, out, *, member=None):
    """Write a run's store, one member of an ensemble (``member`` id), or the whole
    ensemble (``open_ensemble``) to the netCDF4 file ``out``, compressed (zlib with
    chunking, ``encoding``) and CF-clean (``netcdf_ready``); returns its path."""
    import xarray as xr

    from ..ensemble.read import member_status, open_ensemble, open_member
    from ..ensemble.store import store_kind, store_str

    store = store_str(store)
    if store_kind(store) == "ensemble":
        if member and member not in {st["id"] for st in member_status(store)}:
            raise InputError("member", f"{member!r} is not a member of {store}")
        ds = open_member(store, member) if member else open_ensemble(store)
        if member:
            ds.attrs["member_id"] = member
    else:
        if member:
            raise InputError("member", f"{store} is a single run, not an ensemble")
        if "://" not in store:
            from .verify import check_run

            report = check_run(store, read=False)
            if not report.ok:
                raise StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
        try:
            ds = xr.open_zarr(store, consolidated=False)
        except (ValueError, KeyError, OSError) as exc:
            raise _read_error(store, exc) from None
    try:
        ds = ds.load()
    except (ValueError, RuntimeError, OSError) as exc:    # checksum, decompression, decoding errors
        raise _read_error(store, exc) from None
    ds = netcdf_ready(ds)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(out, engine="netcdf4", format="NETCDF4", encoding=encoding(ds))
    return out
