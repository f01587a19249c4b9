"""Units of the scene's quantities: a scene says its length, time and stress units
(``Scene.units``); every other unit is built from them."""
from __future__ import annotations


def unit(units: dict, kind: str) -> str:
    """The unit string of a quantity of ``kind`` ("stress", "length", "time", "velocity",
    or "1" for a pure number) in the scene units ``units``."""
    if kind == "1":
        return "1"
    if kind == "velocity":
        return "1" if units["length"] == "1" and units["time"] == "1" else f"{units['length']} {units['time']}-1"
    return units[kind]


def input_kind(scene, section: str, key: str) -> str:
    """The kind of unit of the scene input ``section.key`` (the law says its own)."""
    if section == "loading" and key.startswith("tau0_"):
        return "stress"
    if section == "law":
        return type(scene.law).parameters().get(key, ("1", "option"))[0]
    return "1"


def input_unit(scene, section: str, key: str) -> str:
    """The unit string of the scene input ``section.key``."""
    return unit(scene.units, input_kind(scene, section, key))
