"""A member's parameters checked against the member itself: their digest against its id,
its scene paths against its own scene (``check_params``); ``check_member`` adds this to
``cracklab.output.verify.check_member`` (the member's run, its consolidated metadata)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..output import verify as V
from .identity import decode, member_id
from .planning import TOP_LEVEL

_BASES: dict = {}      # {(root zarr.json, mtime, size): base key} of the last local store asked


def put(report, damage) -> None:
    """Add ``damage``; it replaces a line about the same file found from the consolidated
    metadata (this one says what is wrong), and is dropped when the file is named already."""
    stale = [d for d in report.damage if d.path == damage.path and "the consolidated metadata of" in d.what]
    if stale:
        report.damage[report.damage.index(stale[0])] = damage
    else:
        V.add(report, damage)


def _base_key(store, params: dict):
    """The base part of the member ids of ``store`` (a local path or a tree,
    ``verify.store_tree``; see ``identity.member_id``): "builder" for members of a
    builder, "scene:<digest>" for a sweep over a Scene; None when the store does not
    record it (a study over a scene file)."""
    if "builder" in params:
        return "builder"
    root = V.root_of(store) / "zarr.json"
    if not isinstance(root, Path):      # at a URL: read each time (no modification time to key a cache)
        return _base_of(V.read_json(root)[0])
    try:
        stamp = (str(root), root.stat().st_mtime_ns, root.stat().st_size)
    except OSError:
        return None
    if stamp not in _BASES:            # the root's zarr.json (with the consolidated metadata) read once
        _BASES.clear()
        _BASES[stamp] = _base_of(V.read_json(root)[0])
    return _BASES[stamp]


def _base_of(doc):
    try:
        base = json.loads((doc or {}).get("attributes", {}).get("study", "{}")).get("base")
    except (ValueError, AttributeError, TypeError):
        base = None
    digest = base.get("scene_digest") if isinstance(base, dict) else None
    return f"scene:{digest}" if isinstance(digest, str) else None


def _same(given, stored) -> bool:
    """Whether a parameter's value and the scene's value agree (numbers as numbers; lists,
    tables and input arrays are not compared: their forms in a scene differ)."""
    number = (int, float)
    if isinstance(given, bool) or isinstance(stored, bool):
        return not (isinstance(given, bool) and isinstance(stored, bool)) or given == stored
    if isinstance(given, number) and isinstance(stored, number):
        return float(given) == float(stored) or (math.isnan(float(given)) and math.isnan(float(stored)))
    if isinstance(given, str) and isinstance(stored, str):
        return given == stored
    return True


def check_params(store, mid: str, report) -> None:
    """Add the damage of member ``mid`` whose parameters (attr ``member_params``) are not
    those it ran with: their digest is not its id, or a scene path among them is not its
    scene's value. ``store``: a local path or a tree (``verify.store_tree``)."""
    store = V.root_of(store)
    meta = store / V.MEMBERS / mid / "zarr.json"
    doc, _ = V.read_json(meta)
    if doc is None:
        return                              # named by the run's checks
    attrs = doc.get("attributes", {}) or {}
    remedy = V.member_remedy(str(store))

    def damage(what):
        put(report, V.Damage(str(meta), f"{what}: changed after the run", mid, remedy))

    try:
        params = json.loads(attrs["member_params"])
        if not isinstance(params, dict):
            raise TypeError
    except (KeyError, TypeError, ValueError):
        return damage("its attribute member_params is not the member's parameters as JSON")
    if attrs.get("member_id", mid) != mid:
        return damage(f"its attribute member_id is {attrs.get('member_id')!r}, not its group's name {mid}")
    key = _base_key(store, params)
    if key is not None and member_id(key, params) != mid:
        return damage(f"its parameters (attribute member_params) do not give its id {mid} (an id is the digest of "
                      f"the parameters)")
    try:
        scene = json.loads(attrs["scene"])
    except (KeyError, TypeError, ValueError):
        return                              # named by the run's checks
    for name, value in params.items():
        if "." in name:
            section, _, field = name.partition(".")
            table = scene.get(section)
            if not isinstance(table, dict) or field not in table:
                continue
            stored = table[field]
        elif name in TOP_LEVEL and "builder" not in params and name in scene:
            stored = scene[name]
        else:
            continue                        # a builder's argument: in the id
        if not _same(decode(value), stored):
            return damage(f"its parameter {name} = {value!r} (attribute member_params) is not its scene's "
                          f"{name} = {stored!r}")


def check_member(store, mid: str, *, read: bool = True):
    """``cracklab.output.verify.check_member`` and the member's parameters (``check_params``)."""
    report = V.check_member(store, mid, read=read)
    if report.ok:
        check_params(store, mid, report)
    return report
