"""Imported by a `cracklab sweep` process of the tests (``--import quick_lock``): the sweep
lock of a store at a URL beats every 0.5 s and is an orphan's after 3 s without a beat
(``LOCK_STALE_S / 2``), and the members read it before a write at most every 0.5 s; the
members carry these numbers to the workers with their guard
(cracklab/output/stores/fsspecstore.py). The defaults (30 s, 90 s, 5 s) would make a test
of orphaned members wait minutes."""
from cracklab.output.stores import fsspecstore

fsspecstore.LOCK_HEARTBEAT_S = 0.5
fsspecstore.LOCK_STALE_S = 6.0
fsspecstore.GUARD_EVERY_S = 0.5
