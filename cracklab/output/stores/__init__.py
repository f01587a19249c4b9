"""Where runs and ensembles are stored: one ``Store`` (base.py) per kind of storage, each in
a file of its own (local.py: Zarr on a local disk; fsspecstore.py: fsspec URLs), chosen
from the path or URL by ``store_for`` (registry.py; further kinds by the entry-point
group "cracklab.stores")."""
from .base import Store, SweepLockLost, current_guard, guarded, is_url, scheme
from .local import LocalStore, StoreLocked
from .fsspecstore import FsspecStore
from .registry import ENTRY_POINT_GROUP, accepted, kinds, store_for, zarr_of

__all__ = ["ENTRY_POINT_GROUP", "FsspecStore", "LocalStore", "Store", "StoreLocked", "SweepLockLost", "accepted",
           "current_guard", "guarded", "is_url", "kinds", "scheme", "store_for", "zarr_of"]
