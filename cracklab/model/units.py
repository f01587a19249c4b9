"""Units of the scene's quantities: a scene says its length, time and stress units
(``Scene.units``); every other unit is built from them.

Unit strings are UDUNITS-2 strings, as the CF conventions write them ("m", "MPa",
"m s-1"), parsed with ``cf_units`` (which bundles the UDUNITS-2 library and its unit
database). A scene unit must be a unit of its quantity (a length converts to "m", a
time to "s", a stress to "Pa") or "1" (that quantity is dimensionless). A field read from
a file that carries a ``units`` attr is converted to the scene's unit; a file unit of
another dimension is refused."""
from __future__ import annotations

import numpy as np

from ..errors import InputError

#: the SI unit each scene unit must convert to, and examples of accepted strings
DIMENSIONS = {"length": ("m", '"m", "km", "mm"'), "time": ("s", '"s", "ms", "us"'),
              "stress": ("Pa", '"Pa", "kPa", "MPa", "GPa"')}
#: the unit of a dimensionless quantity
DIMENSIONLESS = "1"


def unit(units: dict, kind: str) -> str:
    """The unit string of a quantity of ``kind`` ("stress", "length", "time", "velocity",
    "stiffness" (stress per length), or "1" for a pure number) in the scene units ``units``."""
    if kind == "1":
        return "1"
    if kind == "velocity":
        return "1" if units["length"] == "1" and units["time"] == "1" else f"{units['length']} {units['time']}-1"
    if kind == "stiffness":        # stress per length (a spring on the slip)
        return "1" if units["length"] == "1" and units["stress"] == "1" else f"{units['stress']} {units['length']}-1"
    return units[kind]


def parameter_kind(law_class, section: str, key: str) -> str:
    """The kind of unit of the scene input ``section.key`` of a scene whose law is of
    class ``law_class`` (the law says its own)."""
    if section == "loading" and key.startswith("tau0_"):
        return "stress"
    if section == "law":
        return law_class.parameters().get(key, ("1", "option"))[0]
    return "1"


def input_kind(scene, section: str, key: str) -> str:
    """The kind of unit of the scene input ``section.key`` (the law says its own)."""
    return parameter_kind(type(scene.law), section, key)


def input_unit(scene, section: str, key: str) -> str:
    """The unit string of the scene input ``section.key``."""
    return unit(scene.units, input_kind(scene, section, key))


def parse(text):
    """The ``cf_units.Unit`` of the UDUNITS string ``text``, or None when UDUNITS does not
    know it (or it is empty)."""
    import cf_units

    if not isinstance(text, str) or not text.strip():
        return None
    with cf_units.suppress_errors():        # UDUNITS prints its parse errors; the caller says them
        try:
            u = cf_units.Unit(text)
        except (ValueError, TypeError):
            return None
        if u.is_unknown() or u.is_no_unit():
            return None
        return u


def check_scene_units(units: dict) -> None:
    """Refuse (InputError naming ``units.<key>``) a scene unit UDUNITS does not know or
    that is not a unit of its quantity (a positive multiple of its SI unit: no offset, no
    logarithm); "1" (dimensionless) is accepted for each."""
    for key, (si, examples) in DIMENSIONS.items():
        text = units[key]
        if text == DIMENSIONLESS:
            continue
        accepted = f"a UDUNITS unit of {key} ({examples}, ...), or \"1\" for a dimensionless {key}"
        u = parse(text)
        if u is None:
            raise InputError(f"units.{key}", f"unknown unit {text!r}; accepted: {accepted}")
        if u.is_time_reference():
            raise InputError(f"units.{key}", f"{text!r} is a date (a time reference), not a unit of {key}; "
                                             f"accepted: {accepted}")
        if not u.is_convertible(si):
            raise InputError(f"units.{key}", f"{text!r} is not a unit of {key} (it does not convert to {si!r}); "
                                             f"accepted: {accepted}")
        zero, one = (float(u.convert(x, si)) for x in (0.0, 1.0))
        if zero != 0.0 or not one > 0.0:
            raise InputError(f"units.{key}", f"{text!r} is not a positive multiple of {si!r} (an offset, "
                                             f"logarithmic or negative unit); accepted: {accepted}")


def convert(field: str, values, file_unit, scene_unit: str, source: str) -> np.ndarray:
    """``values`` (read from ``source``, whose ``units`` attr is ``file_unit``) in the
    scene's unit ``scene_unit``. No ``units`` attr (None or ""): taken as in the scene's
    unit. A unit UDUNITS does not know, or of another dimension than the scene's, is refused
    (InputError naming ``field``); so is a dimensional file unit for a dimensionless ("1")
    quantity, which has no scale to convert to."""
    if file_unit is None or (isinstance(file_unit, str) and not file_unit.strip()):
        return values
    target = parse(scene_unit)
    have = parse(file_unit) if isinstance(file_unit, str) else None
    if have is None:
        raise InputError(field, f"{source} has units {file_unit!r}, which UDUNITS does not know; accepted: a unit "
                                f"that converts to the scene's {scene_unit!r}, or no units attr (taken as "
                                f"{scene_unit!r})")
    if target is None:                  # a scene unit checked at the boundary: only a law's odd kind lands here
        raise InputError(field, f"the scene's unit {scene_unit!r} is not a UDUNITS unit, so {source} (in "
                                f"{file_unit!r}) cannot be converted to it")
    if scene_unit == DIMENSIONLESS and not have.is_dimensionless():
        raise InputError(field, f"{source} is in {file_unit!r}, but the scene's quantity is dimensionless (unit "
                                f"\"1\"): scale the field to the scene's dimensionless units and give it units "
                                f"\"1\" or no units attr")
    if not have.is_convertible(target):
        raise InputError(field, f"{source} is in {file_unit!r}, which does not convert to the scene's unit "
                                f"{scene_unit!r} (another dimension); accepted: a unit that converts to "
                                f"{scene_unit!r}, or no units attr")
    if have == target:
        return values
    return np.asarray(have.convert(np.asarray(values, dtype=float), target))
