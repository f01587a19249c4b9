"""Scene <-> plain data (JSON-able dict plus named arrays), for attrs and stores."""
from __future__ import annotations

import dataclasses
import json

import numpy as np

from .errors import InputError
from .grid import Grid
from .laws import LAWS, law_parameters
from .loading import Loading
from .material import Material
from .record import Record

SECTIONS = ("material", "grid", "law", "loading", "record", "numerics")


def scene_to_data(scene) -> tuple[dict, dict]:
    """Split a scene into a JSON-able dict and {name: array} for its spatial fields."""
    arrays = {}

    def plain(section, obj):
        out = {}
        items = law_parameters(obj) if section == "law" else {f.name: getattr(obj, f.name)
                                                               for f in dataclasses.fields(obj)}
        for key, value in items.items():
            if isinstance(value, np.ndarray) and value.ndim > 0:
                name = f"input_{section}_{key}"
                arrays[name] = value
                out[key] = {"array": name}
            elif isinstance(value, np.generic):
                out[key] = value.item()
            elif isinstance(value, float) and not np.isfinite(value):
                out[key] = {"float": repr(value)}
            elif isinstance(value, tuple):
                out[key] = list(value)
            else:
                out[key] = value
        return out

    data = {s: plain(s, getattr(scene, s)) for s in SECTIONS}
    data["law"] = {"kind": scene.law.kind, **data["law"]}
    data.update(t_end=scene.t_end, beta=scene.beta, units=dict(scene.units), name=scene.name)
    return data, arrays


def scene_from_data(data: dict, arrays: dict | None = None):
    """Inverse of scene_to_data; unknown keys raise InputError naming them."""
    from .scene import Numerics, Scene

    arrays = arrays or {}
    data = dict(data)
    allowed = set(SECTIONS) | {"t_end", "beta", "units", "name"}
    for key in data:
        if key not in allowed:
            raise InputError(key, f"unknown key; accepted: {', '.join(sorted(allowed))}")

    def value(section, key, v):
        if isinstance(v, dict) and set(v) == {"array"}:
            return np.asarray(arrays[v["array"]])
        if isinstance(v, dict) and set(v) == {"float"}:
            return float(v["float"])
        if isinstance(v, list) and section in ("law", "loading") and key != "origin":
            try:
                arr = np.asarray(v, dtype=bool if key in ("bonded", "initial_crack") else float)
            except (TypeError, ValueError):
                raise InputError(f"{section}.{key}", "must be a number or an (n1, n3) array") from None
            return arr
        return v

    def build(section, cls, d):
        d = dict(d or {})
        names = {f.name for f in dataclasses.fields(cls)}
        for key in d:
            if key not in names:
                raise InputError(f"{section}.{key}", f"unknown key; accepted: {', '.join(sorted(names))}")
        kwargs = {k: value(section, k, v) for k, v in d.items()}
        if section == "record" and kwargs.get("stations"):
            kwargs["stations"] = {k: tuple(v) for k, v in kwargs["stations"].items()}
        if section == "record" and kwargs.get("region"):
            kwargs["region"] = {k: tuple(v) for k, v in kwargs["region"].items()}
        if section == "law" and "origin" in kwargs:
            kwargs["origin"] = tuple(kwargs["origin"])
        try:
            return cls(**kwargs)
        except TypeError as exc:
            raise InputError(section, str(exc)) from None

    if "law" not in data or "kind" not in dict(data["law"]):
        raise InputError("law.kind", f"is required; accepted: {', '.join(sorted(LAWS))}")
    law_data = dict(data["law"])
    kind = law_data.pop("kind")
    if kind not in LAWS:
        raise InputError("law.kind", f"must be one of {', '.join(sorted(LAWS))}, got {kind!r}")
    for required in ("material", "grid", "t_end"):
        if required not in data:
            raise InputError(required, "is required")
    return Scene(
        material=build("material", Material, data["material"]),
        grid=build("grid", Grid, data["grid"]),
        law=build("law", LAWS[kind], law_data),
        loading=build("loading", Loading, data.get("loading")),
        record=build("record", Record, data.get("record")),
        numerics=build("numerics", Numerics, data.get("numerics")),
        t_end=data["t_end"], beta=data.get("beta", 0.5),
        units=data.get("units", {"length": "1", "time": "1", "stress": "1"}),
        name=data.get("name", "scene"),
    )


def scene_to_json(scene) -> tuple[str, dict]:
    data, arrays = scene_to_data(scene)
    return json.dumps(data, default=_json_default), arrays


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"cannot serialise {type(obj).__name__}")
