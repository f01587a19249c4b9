"""An offline check of a netCDF file against the CF conventions 1.10, for the rules a
cracklab export can break; ``cf_problems(path)`` lists what is wrong, by section.

Written against the conventions' text instead of running cfchecker: cfchecker 4.1 (the
release on PyPI) knows CF up to 1.8, so a "CF-1.10" file is an error to it, it refuses the
netCDF-4 string type that CF allows since 1.8 (section 2.2), it needs Debian's libudunits2
and it downloads the standard-name table. Units are parsed here by cf-units (UDUNITS-2,
bundled in its wheel; ``cracklab.model.units.parse``), as the conventions ask (section 3.1).

Rules checked:

* 2.6.1: the global attribute Conventions names CF-1.10.
* 2.3: variable and dimension names begin with a letter and hold letters, digits, "_".
* 2.2: variable types are netCDF's (char, byte, short, int, int64, their unsigned kinds,
  float, double, string).
* 2.5.1: a ``_FillValue`` has its variable's type.
* 3.1: ``units`` is a string UDUNITS knows; every numeric variable has units (a pure
  number says "1"), unless it is a flag variable (``flag_values`` / ``flag_masks``).
* 3 (recommended, required here): every variable has a ``long_name`` or ``standard_name``.
* 3.3: a ``standard_name`` is one of ``STANDARD_NAMES`` (entries of the CF standard-name
  table, with their canonical units) and its units convert to the canonical ones.
* 4: ``axis`` is X, Y, Z or T; no two coordinates of a variable share an axis value; a
  coordinate with axis X, Y or Z is not in units of time.
* 4.4: a time coordinate (axis T, or standard_name time / forecast_reference_time) has
  units with a reference time ("s since 2000-01-01").
* 1.3 / 5: a numeric coordinate variable (1-D, named as its dimension) is strictly
  monotonic and has no missing values.
* cracklab's own promise: every dimension has a coordinate variable.
"""
from __future__ import annotations

import re

import numpy as np

from cracklab.model.units import parse as parse_unit

#: standard names the exports may use, with their canonical units in the CF standard-name
#: table; a name not listed here is reported, so that using one means adding it
#: from the table
STANDARD_NAMES = {"time": "s", "forecast_reference_time": "s"}
TIME_NAMES = ("time", "forecast_reference_time")
NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
TYPES = set("bhilqBHILQfd") | {"S", "U", "O"}


def cf_problems(path) -> list[str]:
    """The CF 1.10 rules (module docstring) the netCDF file ``path`` breaks, one line each
    ("<section> <variable>: what"); empty when it follows them."""
    import netCDF4

    out = []
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_mask(False)
        conventions = str(getattr(nc, "Conventions", ""))
        if "CF-1.10" not in re.split(r"[ ,]+", conventions):
            out.append(f"2.6.1 (global): Conventions is {conventions!r}, not CF-1.10")
        for dim in nc.dimensions:
            if not NAME.match(dim):
                out.append(f"2.3 dimension {dim}: not letters, digits and underscores from a letter")
            if dim not in nc.variables:
                out.append(f"cracklab dimension {dim}: no coordinate variable")
        for name, var in nc.variables.items():
            attrs = {k: var.getncattr(k) for k in var.ncattrs()}
            out += [f"{section} {name}: {what}" for section, what in _variable(nc, name, var, attrs)]
    return out


def _variable(nc, name, var, attrs):
    if not NAME.match(name):
        yield "2.3", "not letters, digits and underscores from a letter"
    kind = var.dtype.char if isinstance(var.dtype, np.dtype) else ("O" if var.dtype is str else "?")
    if kind not in TYPES:
        yield "2.2", f"type {var.dtype} is not a netCDF type"
    numeric = isinstance(var.dtype, np.dtype) and var.dtype.kind in "iuf"
    if "_FillValue" in attrs and isinstance(var.dtype, np.dtype) and \
            np.asarray(attrs["_FillValue"]).dtype != var.dtype:
        yield "2.5.1", f"_FillValue of type {np.asarray(attrs['_FillValue']).dtype}, not {var.dtype}"
    units = attrs.get("units")
    u = None
    if units is not None:
        u = parse_unit(units)
        if not isinstance(units, str):
            yield "3.1", f"units {units!r} is not a string"
        elif u is None:
            yield "3.1", f"units {units!r} is not a UDUNITS unit"
    elif numeric and not ({"flag_values", "flag_masks"} & set(attrs)):
        yield "3.1", "a numeric variable without units (a pure number says \"1\")"
    if "long_name" not in attrs and "standard_name" not in attrs:
        yield "3", "neither long_name nor standard_name"
    std = attrs.get("standard_name")
    if std is not None:
        std = str(std).split()[0] if str(std).split() else ""
        if std not in STANDARD_NAMES:
            yield "3.3", f"standard_name {std!r} is not one the check knows from the table ({', '.join(STANDARD_NAMES)})"
        elif u is not None and not u.is_time_reference() and not u.is_convertible(STANDARD_NAMES[std]):
            yield "3.3", f"units {units!r} do not convert to {std}'s canonical {STANDARD_NAMES[std]!r}"
    axis = attrs.get("axis")
    if axis is not None and axis not in ("X", "Y", "Z", "T"):
        yield "4", f"axis {axis!r} is not X, Y, Z or T"
    if axis == "T" or std in TIME_NAMES:
        if u is None or not u.is_time_reference():
            yield "4.4", f"a time coordinate (axis T or standard_name time) in {units!r}, without a reference time"
    elif axis in ("X", "Y", "Z") and u is not None and (u.is_time_reference() or u.is_convertible("s")):
        yield "4", f"axis {axis} on a variable in units of time ({units!r})"
    if var.dimensions:
        seen = {}
        for dim in var.dimensions:
            a = getattr(nc.variables[dim], "axis", None) if dim in nc.variables else None
            if a is not None and a in seen:
                yield "4", f"dimensions {seen[a]} and {dim} both have axis {a}"
            seen.setdefault(a, dim)
    if var.dimensions == (name,) and numeric and var.size > 0:
        values = np.asarray(var[:], dtype=float)
        fill = attrs.get("_FillValue")
        if not np.all(np.isfinite(values)) or (fill is not None and np.any(values == fill)):
            yield "5", "a coordinate variable with missing values"
        elif values.size > 1 and not (np.all(np.diff(values) > 0) or np.all(np.diff(values) < 0)):
            yield "5", "a coordinate variable that is not strictly monotonic"
