"""netCDF4 export of a run's store, of one ensemble member or of a whole ensemble
(``cracklab.ensemble.export_netcdf``, ``cracklab export``)."""
from __future__ import annotations

import contextlib
import json
from pathlib import Path

import numpy as np

from ..errors import InputError, StoreError
from ..output.stores import store_for, zarr_of


def _nc_attr(value):
    """An attr value netCDF4 can hold: booleans as "true"/"false", tables and mixed lists
    as JSON text, None dropped."""
    from .identity import canonical

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


CHUNK_BYTES = 4 << 20          # netCDF chunks of at most 4 MB
COMPLEVEL = 4
SMALL_BYTES = 1 << 10


#: standard names that make a variable a time coordinate (CF 1.10, section 4.4)
TIME_NAMES = ("time", "forecast_reference_time")


def _is_time_reference(units) -> bool:
    """True for units with a reference time ("s since 2000-01-01"), which CF 1.10 section 4.4
    requires of a time coordinate."""
    from ..model.units import parse

    u = parse(units) if isinstance(units, str) else None
    return u is not None and u.is_time_reference()


def _members_scenes(ds) -> list:
    """The scenes (plain data) of an ensemble's members (attr ``scenes``) or of one run."""
    try:
        if "scenes" in ds.attrs:
            return [sc for sc in json.loads(ds.attrs["scenes"]).values() if isinstance(sc, dict)]
        if "scene" in ds.attrs:
            return [json.loads(ds.attrs["scene"])]
    except (TypeError, ValueError):
        pass
    return []


def _parameter_units(ds) -> dict:
    """{coordinate: units} for the swept parameters of an ensemble (numeric coordinates with
    the attr ``parameter``) that have none: a scene key's unit in the members' scene units
    (``cracklab.model.keys``, the laws' declared kinds), "1" for counts and options, and "1"
    for any parameter when every member's scene is dimensionless. A builder argument of a
    scene with units gets none (the builder does not declare its quantity), nor does a
    parameter whose members' units differ."""
    from ..laws import LAWS
    from ..model.keys import SECTION_KEYS, TOP_KEYS
    from ..model.units import unit

    scenes = _members_scenes(ds)
    units = {json.dumps(sc.get("units") or {}, sort_keys=True) for sc in scenes}
    if len(units) != 1:
        return {}
    units = json.loads(units.pop()) or {"length": "1", "time": "1", "stress": "1"}
    laws = {str((sc.get("law") or {}).get("kind")) for sc in scenes}
    out = {}
    for name, var in ds.coords.items():
        key = var.attrs.get("parameter")
        if not isinstance(key, str) or "units" in var.attrs or var.dtype.kind not in "iuf":
            continue
        section, _, rest = key.partition(".")
        kinds = set()
        if key in TOP_KEYS:
            kinds.add(TOP_KEYS[key].unit)
        elif section in SECTION_KEYS and rest in SECTION_KEYS[section]:
            kinds.add(SECTION_KEYS[section][rest].unit)
        elif section == "law" and laws <= set(LAWS):
            kinds |= {LAWS[k].parameters().get(rest, ("?",))[0] for k in laws}
        kinds = {"1" if k == "-" else k for k in kinds}
        if len(kinds) == 1 and kinds <= {"1", "length", "time", "stress", "velocity"}:
            out[name] = unit(units, kinds.pop())
        elif set(units.values()) == {"1"}:
            out[name] = "1"
    return out


def _cf_clean(ds):
    """CF 1.10 conventions the Zarr store does not need.

    * A run's ``t`` is the time elapsed since its start, not a date. CF 1.10 section 4.4
      makes a variable with ``axis: T`` or ``standard_name: time`` a time coordinate, and a
      time coordinate's units must carry a reference time ("s since ..."). So a variable
      whose units are not a time reference loses ``axis: T`` and a time standard name: ``t``
      is a plain coordinate (section 4: the axis attribute is optional), in "s" or the
      scene's time unit, or "1" in a dimensionless run.
    * Coordinate values on every dimension: input_x1 and input_x3 from the scene's grid, in
      its length unit (section 3.1: a dimensional quantity has units), else the node index,
      units "1"; an ensemble's swept parameters in their units where they are known
      (``_parameter_units``)."""
    for var in ds.variables.values():
        if _is_time_reference(var.attrs.get("units")):
            continue
        if var.attrs.get("axis") == "T":
            del var.attrs["axis"]
        if var.attrs.get("standard_name") in TIME_NAMES:
            del var.attrs["standard_name"]
    for name, text in _parameter_units(ds).items():
        ds.variables[name].attrs["units"] = text
    from .read import with_input_coords

    ds = with_input_coords(ds, ds.attrs.get("scene", "{}"))
    missing = {d: (d, np.arange(ds.sizes[d]), {"long_name": f"index along {d}", "units": "1"}) for d in ds.dims
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
    """A copy of ``ds`` that netCDF4 can store and that follows the CF conventions 1.10:
    Zarr encodings dropped, attrs made netCDF types, string and object arrays as plain str,
    coordinates on every dimension, ``axis: T`` and ``standard_name: time`` only on a
    time with a reference time (``_cf_clean``)."""
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
    from .store import error_line
    from .verify import verify

    with contextlib.suppress(Exception):
        report = verify(store)
        if not report.ok:
            return StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
    return StoreError(store, f"cannot be read ({error_line(exc)}); cracklab verify {store} names the damaged "
                             f"files")


def _same_content(out: Path, ds) -> bool:
    """True when the netCDF file ``out`` is an export of the same scene (or ensemble study)
    as ``ds``: replacing it loses nothing."""
    try:
        import netCDF4

        with netCDF4.Dataset(out, "r") as nc:
            attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
    except Exception:  # noqa: BLE001 - not a netCDF file (or unreadable)
        return False
    for key in ("scene", "study"):
        if key in ds.attrs:
            return attrs.get(key) == _nc_attr(ds.attrs[key]) and attrs.get("member_id") == ds.attrs.get("member_id")
    return False


def _trimmed(ds, path, allow_partial, what):
    """``ds`` (a run or a member) cut to its complete snapshots, with its RunProgress;
    a failed run raises InputError unless ``allow_partial``."""
    from ..output.checkpoint import run_progress

    progress = run_progress(path)
    if not ds.data_vars:
        why = f": it failed ({progress.error or 'no error recorded'}) before it recorded anything" \
            if progress.status == "failed" else f" ({progress.describe()})"
        raise InputError("member" if "member" in what else "store", f"{what} holds no data{why}")
    if progress.status == "failed" and not allow_partial:
        raise InputError("member" if "member" in what else "store",
                         f"{what} failed ({progress.error or 'no error recorded'}); it holds a partial run: "
                         f"pass --allow-partial (allow_partial=True) to export what it recorded")
    if progress.status != "complete" and "t" in ds.dims and progress.snapshots < ds.sizes["t"]:
        ds = ds.isel(t=slice(0, progress.snapshots))
    return ds, progress


def export_netcdf(store, out, *, member=None, allow_partial=False, overwrite=True):
    """Write a run's store, one member of an ensemble (``member`` id), or the whole
    ensemble (``open_ensemble``: its complete members) to the netCDF4 file ``out``,
    compressed (zlib with chunking, ``encoding``) and CF-clean (``netcdf_ready``); returns
    its path. Read lazily and written chunk by chunk (bounded memory), into a temporary
    file moved into place at the end (a failure leaves no file). An unfinished run or
    member is exported up to its last complete snapshot (attr ``cracklab_status``); a
    failed one is refused unless ``allow_partial``. ``overwrite=False``: refuse to replace
    an existing ``out`` unless it is an export of the same scene."""
    import os

    import xarray as xr

    from .read import member_status, open_ensemble, open_member
    from .store import member_path, store_kind, store_str

    store = store_str(store)
    if store_kind(store) == "ensemble":
        ids = {st["id"]: st for st in member_status(store)}
        if member and member not in ids:
            raise InputError("member", f"{member!r} is not a member of {store}")
        if member:
            ds = open_member(store, member)
            ds, _ = _trimmed(ds, member_path(store, member), allow_partial, f"member {member}")
            ds.attrs["member_id"] = member
        else:
            keep = None
            if allow_partial:
                keep = [i for i, st in ids.items() if st["complete"] or st["status"] == "failed"]
            ds = open_ensemble(store) if keep is None else open_ensemble(store, members=keep, complete_only=False)
    else:
        if member:
            raise InputError("member", f"{store} is a single run, not an ensemble")
        from ..output.verify import check_run

        report = check_run(store_for(store).tree(), read=False)     # a URL: its keys listed once
        if not report.ok:
            raise StoreError(store, f"is damaged: {report.first()}; {report.remedy()}")
        try:
            ds = xr.open_zarr(zarr_of(store), consolidated=False)
        except (ValueError, KeyError, OSError) as exc:
            raise _read_error(store, exc) from None
        ds, _ = _trimmed(ds, store, allow_partial, f"the run in {store}")
    ds = netcdf_ready(ds)
    out = Path(out)
    if out.exists() and not overwrite and not _same_content(out, ds):
        raise InputError("output", f"{out} exists and is not an export of this scene; refusing to replace it: "
                                   f"choose another file, or --overwrite")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding(ds))
        os.replace(tmp, out)
    except (ValueError, RuntimeError) as exc:    # checksum, decompression, decoding errors
        raise _read_error(store, exc) from None
    except OSError as exc:
        import errno

        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EPERM, errno.EROFS):
            raise                                # writing: the caller names the output
        raise _read_error(store, exc) from None
    finally:
        if tmp.exists():
            tmp.unlink()
    return out
