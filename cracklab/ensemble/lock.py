"""The store lock: one sweep at a time into a store (``store_lock``, ``StoreLocked``); each
kind of storage holds it its own way (``cracklab.output.stores``: a hard-linked lock file
on a local disk, a lock object created by a conditional write on an object store)."""
from __future__ import annotations

from ..output.stores import StoreLocked, store_for
from ..output.stores.local import LOCK_GRACE_S, LOCK_NAME  # noqa: F401  (ensemble.lock.LOCK_NAME as before)


def store_lock(store: str):
    """Hold the sweep lock of ``store`` (``Store.lock``): a second sweep into the same
    store raises ``StoreLocked`` naming the holder; a lock left by a killed sweep (same
    host, process gone; at a URL also one whose heartbeat stopped) is taken over."""
    return store_for(store).lock()


__all__ = ["LOCK_NAME", "StoreLocked", "store_lock"]
