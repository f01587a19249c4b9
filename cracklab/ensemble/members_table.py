"""The member table at the root of an ensemble's store: ``write_member_table`` at the end
of every sweep, ``check_table`` against the member groups (``cracklab verify``)."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError, StoreError
from ..output import verify as V
from ..output.checkpoint import encoding
from .checks import put
from .lock import LOCK_NAME
from .read import member_coords, member_status
from .store import MEMBERS, consolidate, error_line, open_group, store_str
from ..output.stores import zarr_of


def write_member_table(store: str):
    """The member table at the root of the store, then the store's consolidated metadata:
    one array per coordinate along ``member`` (ids, swept parameters, status; as
    ``open_ensemble`` gives them), so that ``xarray.open_zarr(STORE)`` shows the members and
    their parameters as coordinates, and ``xarray.open_datatree(STORE)`` opens the whole
    store from its consolidated metadata. Written at the end of every sweep (local or
    URL stores alike); the root's attrs are kept."""
    import xarray as xr

    status = member_status(store)
    with warnings.catch_warnings():     # the sweep's lock file is not a Zarr node: zarr says so when listing
        warnings.filterwarnings("ignore", message=".*not recognized as a component of a Zarr hierarchy")
        root = open_group(store, "a", consolidated=False)
        attrs = {k: v for k, v in root.attrs.items() if k != "coordinates"}
        old = str(root.attrs.get("coordinates", "")).split() + ["member"]
        for name in old:                # the previous table
            if name in root and name != MEMBERS:
                del root[name]
        if status:
            coords = member_coords(status)
            table = xr.Dataset(coords=coords, attrs=attrs)
            table.to_zarr(zarr_of(store), mode="a", consolidated=False, zarr_format=3, encoding=encoding(table))
            names = " ".join(c for c in coords if c != "member")
            open_group(store, "a", consolidated=False).update_attributes({**attrs, "coordinates": names})
        else:
            open_group(store, "a", consolidated=False).attrs.put(attrs)
        consolidate(store)


def _values(da) -> list:
    vals = np.asarray(da.values)
    return [None if isinstance(v, float) and math.isnan(v) else v for v in vals.tolist()]


def check_table(store, report) -> None:
    """Add the damage of the member table at the root of ``store`` (what
    ``xr.open_zarr(STORE)`` shows) that does not say what the member groups say: other
    members, or another status or parameter of a member. Not while a sweep holds the
    store (it rewrites the table when it ends). ``store``: a local path, or a tree
    (``verify.store_tree``)."""
    import xarray as xr

    p = V.root_of(store)
    store = store_str(p) if isinstance(p, Path) else str(p)
    doc, _ = V.read_json(p / "zarr.json")
    if doc is None or "coordinates" not in (doc.get("attributes") or {}):
        return                              # no table yet (a first sweep killed): nothing to compare
    if (p / LOCK_NAME).exists():
        report.notes.append("a sweep holds the store (or was killed): the member table at its root is rewritten "
                            "when a sweep ends")
        return
    try:
        status = member_status(store)
    except (InputError, StoreError):
        return                              # named by the store's checks
    want = member_coords(status) if status else {}
    remedy = V.store_remedy(store)
    names = str(doc["attributes"]["coordinates"]).split()

    def damage(name, what):
        put(report, V.Damage(str(p / name), f"the member table {what}: that is what plain xarray "
                                             f"(xr.open_zarr) shows", None, remedy))

    try:
        table = xr.open_zarr(zarr_of(store), consolidated=False)
        listed = _values(table["member"]) if "member" in table.coords else []
    except Exception as exc:  # noqa: BLE001 - damaged arrays of the table
        return damage("member", f"cannot be read ({error_line(exc)})")
    ids = [s["id"] for s in status]
    if listed != ids:
        gone = [m for m in listed if m not in ids]
        new = [m for m in ids if m not in listed]
        what = (f"lists {len(gone)} member(s) not in the store ({', '.join(gone[:3])})" if gone else
                f"lacks {len(new)} member(s) of the store ({', '.join(new[:3])})" if new else
                "lists the members in another order than the store")
        damage("member", what)
    row = {m: i for i, m in enumerate(listed)}
    damaged = set(report.damaged_members())     # their groups are not to be believed
    for name, (_, values, _) in want.items():
        if name == "member":
            continue
        if name not in table.coords:
            damage(name, f"has no coordinate {name}")
            continue
        stored = _values(table[name])
        expected = [None if isinstance(v, float) and math.isnan(v) else v for v in np.asarray(values).tolist()]
        for mid, value in zip(ids, expected):
            if mid in row and mid not in damaged and stored[row[mid]] != value:
                damage(name, f"gives {name} = {stored[row[mid]]!r} for member {mid}, but its group gives {value!r}")
                break
    for name in names:
        if name not in want:
            damage(name, f"has a coordinate {name} that no member's parameters give")
