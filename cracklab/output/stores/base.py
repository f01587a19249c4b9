"""The store protocol: what cracklab asks of the storage a run or an ensemble is written to.

A ``Store`` is one place (a local path or a URL) on one kind of storage. It checks the
place before anything runs (``check``), gives zarr the store object every write of a run
goes through (``zarr_store``: one seam, where a test injects a fault), holds a
sweep's exclusive use of the place (``lock``), and keeps a run's checkpoint
(``write_checkpoint``, ``checkpoint_file``, ``remove_checkpoint``: committed atomically,
so that a kill leaves the previous checkpoint or the new one, never a torn one). Each kind
of storage is one subclass in a file of its own, chosen from the path or URL by
``cracklab.output.stores.store_for``."""
from __future__ import annotations

import contextlib
import contextvars
import os
from abc import ABC, abstractmethod
from pathlib import Path
from typing import Callable, ClassVar

from ...errors import StoreError

#: the group of a run's store that holds its checkpoint (a Zarr group: readers ignore it)
CHECKPOINT_GROUP = "_checkpoint"
CHECKPOINT_GROUP_DOC = '{"zarr_format": 3, "node_type": "group", "attributes": {}}'


class SweepLockLost(StoreError):
    """The sweep a member was started by no longer holds the store's lock (it was killed,
    or another sweep took the lock over): the member stops before its next write."""


#: the guard of the writes of the member running in this thread (``guarded``): every write
#: into a store at a URL made through ``Store.zarr_store`` while it is set checks it first
_GUARD: contextvars.ContextVar = contextvars.ContextVar("cracklab_write_guard", default=None)


@contextlib.contextmanager
def guarded(guard):
    """Run the block with ``guard`` (an object with ``check(force=False)``, raising
    ``SweepLockLost``) checked before the writes of the stores it opens; None: unguarded."""
    token = _GUARD.set(guard)
    try:
        yield guard
    finally:
        _GUARD.reset(token)


def current_guard():
    """The guard set by ``guarded`` in this thread (None when there is none)."""
    return _GUARD.get()


def is_url(store) -> bool:
    """True for a store given as a URL (text with ``://``); the one test of it."""
    return isinstance(store, (str, os.PathLike)) and "://" in os.fspath(store)


def scheme(target) -> str:
    """The scheme of a URL in lower case (``"s3"``); ``""`` for a local path."""
    s = os.fspath(target)
    return s.split("://", 1)[0].lower() if is_url(s) else ""


class Store(ABC):
    """A run's or an ensemble's storage at ``target`` (a local path or a URL, as given).

    ``kind``: the name it is registered under; ``local``: True when the store is a
    directory of the local file system (``path``), where checkpoints, the disk check and
    the atomic rename of a member live; ``accepts``: what it accepts, for messages."""

    kind: ClassVar[str]
    local: ClassVar[bool] = False
    accepts: ClassVar[str] = ""
    #: whether runs into this kind of storage checkpoint (and so resume after a kill)
    checkpoints: ClassVar[bool] = False

    def __init__(self, target):
        self.target = os.fspath(target)

    def __str__(self) -> str:
        return self.target

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.target!r})"

    @classmethod
    @abstractmethod
    def handles(cls, scheme: str) -> bool:
        """True when this kind of storage takes targets of ``scheme`` (``""``: a path)."""

    @property
    def path(self) -> Path | None:
        """The local directory of the store (None for a store that is not local)."""
        return None

    @abstractmethod
    def check(self, *, exists: bool = False) -> None:
        """Raise one StoreError naming the store when it cannot be used (and, with
        ``exists``, when no Zarr store is there), before anything is written."""

    @abstractmethod
    def zarr_store(self):
        """What zarr and xarray are given to read and write the store: every write of a
        run goes through it."""

    def lock(self):
        """A context holding this store for one sweep at a time; yields what holds it
        (None: this kind of storage is not locked)."""
        return contextlib.nullcontext()

    def write_guard(self, lock):
        """What a sweep's members check before they write (``guarded``): that the sweep
        holding ``lock`` (what ``lock()`` returned, entered) still holds the store; None
        where members cannot be orphaned from their sweep's lock."""
        return None

    # -- the layout of a run: what the resume of a killed run needs ----------------------
    def tree(self):
        """A read-only, path-like view of the store (``/``, ``exists``, ``read_text``,
        ``subdirs`` or a directory's entries) for ``cracklab.output.verify``."""
        raise NotImplementedError

    def children(self) -> list[str] | None:
        """The names right below the store's root (None: nothing is there)."""
        raise NotImplementedError

    def remove(self, name: str) -> None:
        """Delete the entry ``name`` right below the store's root, and all it holds."""
        raise NotImplementedError

    def clear(self) -> None:
        """Delete the store and all it holds (a run started over)."""
        raise NotImplementedError

    # -- checkpoints --------------------------------------------------------------------
    def _no_checkpoints(self):
        from ...errors import StoreError

        return StoreError(self.target, f"a {self.kind} store keeps no checkpoints: run without resume, or write "
                                       f"to a local path")

    def write_checkpoint(self, fill: Callable, before_commit: Callable | None = None) -> None:
        """Write a new checkpoint: ``fill(fh)`` writes its bytes to a binary file; it
        replaces the previous one atomically (``before_commit()`` runs with the new bytes
        stored, before they become the checkpoint: a test hook)."""
        raise self._no_checkpoints()

    def checkpoint_file(self):
        """A context yielding a local file that holds the store's checkpoint, its
        integrity checked (None when there is none); a StoreError when it is unreadable."""
        raise self._no_checkpoints()

    def remove_checkpoint(self) -> None:
        """Delete the checkpoint (the run is complete)."""
        raise self._no_checkpoints()

    def clean(self) -> None:
        """Delete what a killed writer left behind that is no part of the store
        (temporary files, checkpoint bytes that never became the checkpoint)."""
