"""The attrs of a run's variables: long names and units of the recorded fields and of the
scene inputs stored as ``input_<section>_<key>``."""
from __future__ import annotations

from ..model.units import input_unit, unit

LONG_NAMES = {
    "delta_1": ("slip along x1", "length"), "delta_2": ("opening", "length"),
    "delta_3": ("slip along x3", "length"), "v_1": ("slip rate along x1", "velocity"),
    "v_2": ("opening rate", "velocity"), "v_3": ("slip rate along x3", "velocity"),
    "tau_1": ("shear traction along x1", "stress"), "tau_2": ("normal traction (tension positive)", "stress"),
    "tau_3": ("shear traction along x3", "stress"), "strength": ("strength of the interface", "stress"),
    **{f"{k}_{c}_{side}": (f"{what} along x{c} of the {side} face (x2 = 0{'+' if side == 'top' else '-'})", kind)
       for k, what, kind in (("u", "displacement", "length"), ("v", "velocity", "velocity"))
       for side in ("top", "bottom") for c in (1, 2, 3)},
}


def field_attrs(scene, name):
    if name in LONG_NAMES:
        long_name, kind = LONG_NAMES[name]
    else:  # a state variable of the law
        long_name, kind = type(scene.law).state_variables[name]
    return {"long_name": long_name, "units": unit(scene.units, kind)}


def input_attrs(scene, name):
    """Attrs of a scene input field stored as ``input_<section>_<key>``."""
    section, key = name[len("input_"):].split("_", 1)
    attrs = {"long_name": f"scene input {section}.{key}", "units": input_unit(scene, section, key)}
    source = scene.sources.get(f"{section}.{key}")
    if source:
        attrs["source"] = source   # the field file it was read from (cracklab.model.field_files)
    return attrs
