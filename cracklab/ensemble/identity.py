"""Canonical values and identities: the canonical JSON of parameters, member ids, scene
digests, and the coordinate names of parameters in ``open_ensemble``."""
from __future__ import annotations

import hashlib
import json
import math

import numpy as np

from ..errors import InputError

FORMAT = 1              # the ensemble format: of member ids and of the store's layout
ID_LENGTH = 16


def canonical(value, where="value"):
    """JSON-able canonical form: numpy -> Python, tuples/arrays -> lists, sorted dicts,
    non-finite floats as {"float": "inf"}."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else {"float": repr(v)}
    if isinstance(value, str):
        return value
    if value is None:
        return None
    if isinstance(value, np.ndarray):
        return canonical(value.tolist(), where)
    if isinstance(value, (list, tuple)):
        return [canonical(v, where) for v in value]
    if isinstance(value, dict):
        return {str(k): canonical(value[k], f"{where}.{k}") for k in sorted(value, key=str)}
    raise InputError(where, f"must be a number, string, boolean, list or table, got {type(value).__name__}")


def decode(value):
    """Undo ``canonical`` for the builder: {"float": "inf"} -> inf (recursively)."""
    if isinstance(value, dict):
        if set(value) == {"float"}:
            return float(value["float"])
        return {k: decode(v) for k, v in value.items()}
    if isinstance(value, list):
        return [decode(v) for v in value]
    return value


def canonical_json(obj) -> str:
    return json.dumps(canonical(obj), sort_keys=True, separators=(",", ":"), allow_nan=False)


def member_id(base_key: str, params: dict) -> str:
    text = canonical_json({"cracklab_member": FORMAT, "base": base_key, "params": params})
    return hashlib.sha256(text.encode()).hexdigest()[:ID_LENGTH]


def scene_digest(scene) -> str:
    """A digest of a scene's parameters and input arrays (identifies a Scene base)."""
    from ..model.scene_io import scene_to_json

    text, arrays = scene_to_json(scene)
    h = hashlib.sha256(text.encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:ID_LENGTH]


def coordinate_name(param: str) -> str:
    """Coordinate name of a parameter in ``open_ensemble``: dots become underscores."""
    return param.replace(".", "_")
