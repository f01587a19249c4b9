"""The member table at the root of an ensemble's store (``write_member_table``)."""
from __future__ import annotations

import warnings

from ..output.checkpoint import encoding
from .read import member_coords, member_status
from .store import MEMBERS, consolidate, open_group


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
            table.to_zarr(store, mode="a", consolidated=False, zarr_format=3, encoding=encoding(table))
            names = " ".join(c for c in coords if c != "member")
            open_group(store, "a", consolidated=False).update_attributes({**attrs, "coordinates": names})
        else:
            open_group(store, "a", consolidated=False).attrs.put(attrs)
        consolidate(store)
