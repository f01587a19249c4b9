"""The kinds of storage: cracklab's own (``OWN``) and those of installed packages under the
entry-point group "cracklab.stores" (each a ``Store`` subclass); ``store_for`` picks the
one that takes a path's or URL's scheme."""
from __future__ import annotations

import os

from ...errors import StoreError
from .base import Store, is_url, scheme
from .fsspecstore import FsspecStore
from .local import LocalStore

ENTRY_POINT_GROUP = "cracklab.stores"
#: cracklab's own kinds of storage, asked last (an installed kind may take a scheme first)
OWN = (LocalStore, FsspecStore)


def _installed() -> dict:
    """{name: entry point} of the group "cracklab.stores"."""
    from importlib.metadata import entry_points

    try:
        return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    except Exception:  # noqa: BLE001 - broken package metadata: no installed kinds
        return {}


def kinds() -> dict:
    """{name: Store subclass} of every kind of storage, installed ones first, then
    cracklab's own ("local", "fsspec")."""
    out = {}
    for name, ep in _installed().items():
        cls = ep.load()
        if not (isinstance(cls, type) and issubclass(cls, Store)):
            raise StoreError(name, f"the entry point {ep.value!r} of the group {ENTRY_POINT_GROUP!r} is not a "
                                   f"cracklab.output.stores.Store subclass")
        out[name] = cls
    return {**out, **{cls.kind: cls for cls in OWN}}


def accepted() -> str:
    """What the kinds of storage accept, for messages."""
    return " and ".join(cls.accepts or name for name, cls in kinds().items())


def store_for(target) -> Store:
    """The ``Store`` of ``target`` (a local path or a URL), of the first kind that takes its
    scheme; a StoreError naming the scheme and what is accepted when none does."""
    s = os.fspath(target)
    sch = scheme(s)
    for cls in kinds().values():
        if cls.handles(sch):
            return cls(s)
    raise StoreError(s, f"no store for the scheme '{sch}://': cracklab writes to {accepted()}; check the URL")


def zarr_of(target):
    """What zarr and xarray are given to read or write the store, or a group in it, at
    ``target``: a local path as its text, a URL through its ``Store.zarr_store`` (no
    listings cache: what another client wrote or deleted is seen at once; the writes
    checked by the guard of the member running, ``guarded``). Every reader and writer of
    an ensemble store opens it through here."""
    s = os.fspath(target)
    return store_for(s).zarr_store() if is_url(s) else s


__all__ = ["ENTRY_POINT_GROUP", "OWN", "accepted", "is_url", "kinds", "scheme", "store_for", "zarr_of"]
