"""The store lock: one sweep at a time into a store (``store_lock``, ``StoreLocked``); each
kind of storage holds it its own way (``cracklab.output.stores``: a hard-linked lock file
on a local disk)."""
from __future__ import annotations

from ..output.stores import StoreLocked, store_for
from ..output.stores.local import LOCK_GRACE_S, LOCK_NAME  # noqa: F401  (ensemble.lock.LOCK_NAME as before)


def store_lock(store: str):
    """Hold the sweep lock of ``store`` (``Store.lock``): a second sweep into the same
    local store raises ``StoreLocked`` naming the holder; a lock left by a killed sweep
    (same host, process gone) is taken over. A URL store is not locked (yields None)."""
    return store_for(store).lock()


__all__ = ["LOCK_NAME", "StoreLocked", "store_lock"]
